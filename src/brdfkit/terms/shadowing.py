"""Geometric attenuation (masking-shadowing) G of microfacet models.

Directions are local (normal ``+z``), shape ``(..., 3)``; results have shape
``(...)`` and the dtype of the direction arrays (float32 stays float32). Every
function returns values in ``[0, 1]`` and never NaN.

* :func:`v_groove` — Torrance & Sparrow (1967) / Cook & Torrance (1982, eq. 6)
  V-groove cavities, in the lecture's notation::

      G = min(1, G_mask, G_shadow)
      G_mask   = 2 (n·h)(n·v) / (v·h)
      G_shadow = 2 (n·h)(n·l) / (l·h)

* Smith (1967) masking with an uncorrelated microsurface profile, written with
  the distribution's Λ (:mod:`brdfkit.terms.distributions`; Walter et al.
  2007, §5; Heitz 2014, eq. 43)::

      G1(w) = χ⁺(w·h) / (1 + Λ(w))

* :func:`smith_g_separable` — the separable form ``G1(wi) G1(wo)`` (Walter et
  al. 2007, eq. 23).
* :func:`smith_g_correlated` — the height-correlated form
  ``χ⁺ / (1 + Λ(wi) + Λ(wo))`` (Heitz 2014, eq. 99), always ``>=`` the
  separable one.

Scalar sources (``g_vgroove``, ``g1_smith``) are compiled by
:func:`brdfkit.engine.jit` for the kernels; the array functions wrap them.
"""

from __future__ import annotations

import numpy as np

from ..engine import jit, vectorize
from .distributions import distribution as _distribution

# ------------------------------------------------------------ scalar sources


@jit
def g_vgroove(n_h, n_v, n_l, v_h, l_h):
    """Torrance-Sparrow / Cook-Torrance (1982, eq. 6) V-groove ``min(1, 2(n·h)(n·v)/(v·h), 2(n·h)(n·l)/(l·h))``.

    Negative cosines count as 0 (fully masked); a zero ``v·h`` or ``l·h`` leaves that term out.
    """
    n_h = max(n_h, 0.0)
    n_v = max(n_v, 0.0)
    n_l = max(n_l, 0.0)
    v_h = max(v_h, 0.0)
    l_h = max(l_h, 0.0)
    g = 1.0
    if v_h > 0.0:
        g = min(g, 2.0 * n_h * n_v / v_h)
    if l_h > 0.0:
        g = min(g, 2.0 * n_h * n_l / l_h)
    return max(g, 0.0)


@jit
def g1_smith(lam):
    """Smith masking ``G1 = 1/(1 + Λ)`` (Smith 1967; Walter et al. 2007, eq. 23 form); Λ = +inf gives 0."""
    return 1.0 / (1.0 + lam)


@jit
def g_smith_separable_parts(num_i, den_i, num_o, den_o):
    """Separable Smith ``G1(wi) G1(wo) = 1/((1 + Λi)(1 + Λo))`` from ``Λ = num/den`` pairs, with one division.

    ``= den_i den_o / ((den_i + num_i)(den_o + num_o))``; a zero ``den`` (Λ = +inf) gives 0. For a
    distribution whose Λ is a ratio (GGX: :func:`brdfkit.terms.distributions.lambda_ggx_parts`) this
    is three divisions fewer than ``g1_smith(Λi) · g1_smith(Λo)``, equal to rounding.
    """
    q = (den_i + num_i) * (den_o + num_o)
    if q <= 0.0:
        return 0.0
    return min((den_i * den_o) / q, 1.0)


# ------------------------------------------------------ array API (wrappers)

_v_vgroove = vectorize(g_vgroove, 5)
_v_g1 = vectorize(g1_smith, 1)


def _dt(*args):
    dt = np.result_type(*[np.asarray(a) for a in args], np.float32)
    return np.dtype(np.float32) if dt == np.float32 else np.dtype(np.float64)


def v_groove(n_h, n_v, n_l, v_h, l_h):
    """Cook-Torrance / Torrance-Sparrow V-groove ``min(1, 2(n·h)(n·v)/(v·h), 2(n·h)(n·l)/(l·h))``.

    Arguments are the cosines (broadcasting arrays). Negative cosines are treated
    as 0 (the configuration is fully masked); a zero ``v·h`` or ``l·h`` leaves
    the corresponding term out (it is then +inf, so min picks the others).
    Scalar source: :func:`g_vgroove`.
    """
    return _v_vgroove(n_h, n_v, n_l, v_h, l_h, dtype=_dt(n_h, n_v, n_l, v_h, l_h))


def g1_from_lambda(lam):
    """Smith masking ``G1 = 1/(1 + Λ)`` (Λ = +inf gives 0). Scalar source: :func:`g1_smith`."""
    lam = np.asarray(lam)
    return _v_g1(lam, dtype=np.float32 if lam.dtype == np.float32 else np.float64)


def _chi(w, h):
    if h is None:
        return None
    return np.einsum("...i,...i->...", np.asarray(w), np.asarray(h)) > 0


def smith_g1(w, alpha_x, alpha_y=None, distribution="ggx", h=None):
    """Smith masking ``G1(w) = χ⁺(w·h)/(1 + Λ(w))`` for ``"ggx"`` or ``"beckmann"``.

    ``alpha_y=None`` means isotropic; ``h`` (optional microfacet normals) adds
    the one-sidedness factor χ⁺(w·h) (Walter et al. 2007, eq. 23).
    """
    _, lam_fn = _distribution(distribution)
    g = g1_from_lambda(lam_fn(w, alpha_x, alpha_y))
    c = _chi(w, h)
    return g if c is None else np.where(c, g, g.dtype.type(0))


def smith_g_separable(wi, wo, alpha_x, alpha_y=None, distribution="ggx", h=None):
    """Separable Smith ``G = G1(wi) G1(wo)`` (Walter et al. 2007, eq. 23)."""
    return smith_g1(wi, alpha_x, alpha_y, distribution, h) * smith_g1(wo, alpha_x, alpha_y, distribution, h)


def smith_g_correlated(wi, wo, alpha_x, alpha_y=None, distribution="ggx", h=None):
    """Height-correlated Smith ``G = χ⁺(wi·h) χ⁺(wo·h) / (1 + Λ(wi) + Λ(wo))`` (Heitz 2014, eq. 99)."""
    _, lam_fn = _distribution(distribution)
    g = g1_from_lambda(lam_fn(wi, alpha_x, alpha_y) + lam_fn(wo, alpha_x, alpha_y))
    if h is not None:
        g = np.where(_chi(wi, h) & _chi(wo, h), g, g.dtype.type(0))
    return g


__all__ = ["g_vgroove", "g1_smith", "g_smith_separable_parts", "v_groove", "g1_from_lambda", "smith_g1", "smith_g_separable", "smith_g_correlated"]
