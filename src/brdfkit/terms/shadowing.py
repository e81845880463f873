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
"""

from __future__ import annotations

import numpy as np

from .distributions import distribution as _distribution


def _dt(x):
    x = np.asarray(x)
    return np.dtype(np.float32) if x.dtype == np.float32 else np.dtype(np.float64)


def v_groove(n_h, n_v, n_l, v_h, l_h):
    """Cook-Torrance / Torrance-Sparrow V-groove ``min(1, 2(n·h)(n·v)/(v·h), 2(n·h)(n·l)/(l·h))``.

    Arguments are the cosines (broadcasting arrays). Negative cosines are treated
    as 0 (the configuration is fully masked); a zero ``v·h`` or ``l·h`` leaves
    the corresponding term out (it is then +inf, so min picks the others).
    """
    n_h, n_v, n_l, v_h, l_h = np.broadcast_arrays(*(np.asarray(a) for a in (n_h, n_v, n_l, v_h, l_h)))
    dt = np.result_type(n_h.dtype, n_v.dtype, n_l.dtype, v_h.dtype, l_h.dtype, np.float32)
    zero, one, two = dt.type(0), dt.type(1), dt.type(2)
    n_h, n_v, n_l, v_h, l_h = (np.maximum(a.astype(dt, copy=False), zero) for a in (n_h, n_v, n_l, v_h, l_h))
    big = dt.type(np.inf)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        g_mask = np.where(v_h > 0, two * n_h * n_v / np.where(v_h > 0, v_h, one), big)
        g_shadow = np.where(l_h > 0, two * n_h * n_l / np.where(l_h > 0, l_h, one), big)
    g = np.minimum(one, np.minimum(g_mask, g_shadow))
    return np.maximum(g, zero)


def g1_from_lambda(lam):
    """Smith masking ``G1 = 1/(1 + Λ)`` (Λ = +inf gives 0)."""
    lam = np.asarray(lam)
    dt = _dt(lam)
    return dt.type(1) / (dt.type(1) + lam.astype(dt, copy=False))


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


__all__ = ["v_groove", "g1_from_lambda", "smith_g1", "smith_g_separable", "smith_g_correlated"]
