"""What the microfacet formulas predict for the surfaces of :mod:`brdfkit.microsurfaces.surfaces`.

The GGX surface there is a Gaussian scale mixture of Beckmann tiles (roughness ``α √W``,
``1/W ~ Exp(1)``). Each tile's single scattering is Walter et al. (2007, eq. 20) with Beckmann's
D and the height-correlated Smith G2 (Heitz 2014, eq. 99), so the mixture's is their average::

    f_mix(wi, wo) = E_W[ D_B(h; α√W) / (1 + Λ_B(wi; α√W) + Λ_B(wo; α√W)) ] / (4 cos θi cos θo)

Its D is GGX's exactly (the slope densities mix to GGX), its G1 is Smith's GGX G1 exactly (Λ is
linear in the slope density), but its G2 is not ``1/(1 + Λ_GGX(wi) + Λ_GGX(wo))``: a tile steep
enough to mask also shadows. ``f_mix`` is what the traced GGX surface must reproduce; its distance
from the ``microfacet`` GGX model is a property of the construction, not of the tracer.
"""

from __future__ import annotations

import numpy as np

from ..terms.distributions import beckmann, beckmann_lambda


def mixture_weights_quantiles(n: int) -> np.ndarray:
    """``n`` mid-point quantiles of ``W`` (``1/W ~ Exp(1)``), for quadrature over the mixture."""
    u = (np.arange(n) + 0.5) / n
    return 1.0 / -np.log1p(-u)


def ggx_mixture_single_scattering(wi, wo, alpha_x: float, alpha_y: float | None = None, n: int = 400) -> np.ndarray:
    """``f_mix`` above (F = 1), shape ``wi.shape[:-1]``, by an ``n``-point quantile rule over ``W``."""
    wi, wo = np.broadcast_arrays(np.asarray(wi, np.float64), np.asarray(wo, np.float64))
    alpha_y = alpha_x if alpha_y is None else alpha_y
    h = wi + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    acc = np.zeros(wi.shape[:-1])
    for w in mixture_weights_quantiles(n):
        ax, ay = alpha_x * np.sqrt(w), alpha_y * np.sqrt(w)
        acc += beckmann(h, ax, ay) / (1.0 + beckmann_lambda(wi, ax, ay) + beckmann_lambda(wo, ax, ay))
    cos = np.maximum(wi[..., 2], 0.0) * np.maximum(wo[..., 2], 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(cos > 0, acc / n / (4.0 * cos), 0.0)
