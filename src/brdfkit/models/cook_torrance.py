"""Cook-Torrance (1982), exactly as the lecture writes it.

Reference: R. L. Cook, K. E. Torrance, "A Reflectance Model for Computer
Graphics", ACM Transactions on Graphics 1(1), 1982 (eqs. 4, 6, 8 and the
specular term R_s = F/π · D G/((N·L)(N·V))).

    f_r(wi, wo) = kd/π + ks · (F/π) · D · G / ((n·l)(n·v))

with ``l = wi`` (toward the light), ``v = wo`` (toward the viewer),
``h = normalize(l + v)`` and ``α`` the angle between ``n`` and ``h``:

* Beckmann facet distribution, as in the paper and the lecture (no 1/π; it
  integrates to ``∫ D cos α dω = π``, which the ``F/π`` accounts for)::

      D = exp(−(tan α / m)²) / (m² cos⁴ α)

* exact unpolarised dielectric Fresnel term with ``c = v·h`` and
  ``g² = n² + c² − 1``::

      F = ½ (g − c)²/(g + c)² · (1 + (c(g + c) − 1)²/(c(g − c) + 1)²)

* V-groove geometric attenuation::

      G = min(1, 2(n·h)(n·v)/(v·h), 2(n·h)(n·l)/(l·h))

The paper models metals by choosing ``n`` from the measured normal-incidence
reflectance, ``n = (1 + √F0)/(1 − √F0)`` (F0 = 0.9 gives n ≈ 37), hence the
wide range of ``ior``. The diffuse part is Lambert ``kd/π`` (the paper's
``d·R_d`` with ``R_d`` the albedo over π).

=========  ======  =======  ===========  ==========================================
parameter  kind    default  range        meaning
=========  ======  =======  ===========  ==========================================
kd         rgb     0.5      [0, 1]       diffuse albedo (kd/π)
ks         rgb     0.5      [0, 1]       specular weight (the paper's s)
m          scalar  0.2      [0.001, 1]   Beckmann RMS slope of the facets
ior        rgb     1.5      [1, 1000]    relative refractive index n in F
=========  ======  =======  ===========  ==========================================

m below 0.001 is refused for the same reason as the microfacet model's α (the
lobe would be narrower than float32 resolves near the normal).
"""

from __future__ import annotations

import numpy as np

from ..geometry import half_vector
from ..params import Param, kd_param, ks_param
from ..registry import register
from ..terms.distributions import beckmann
from ..terms.fresnel import fresnel_dielectric_cook
from ..terms.shadowing import v_groove
from .base import BRDF

_COS_FLOOR = {np.dtype(np.float32): 1e-18, np.dtype(np.float64): 1e-150}


@register
class CookTorrance(BRDF):
    name = "cook-torrance"
    title = "Cook-Torrance 1982: Beckmann D, exact dielectric Fresnel, V-groove G"
    reference = "Cook, Torrance, A Reflectance Model for Computer Graphics, ACM TOG 1(1), 1982"
    isotropic = True
    spec = (
        kd_param(0.5),
        ks_param(0.5, "specular weight (the paper's s)"),
        Param("m", "scalar", 0.2, (1e-3, 1.0), "", "Beckmann RMS slope of the facets", log_scale=True),
        Param("ior", "rgb", 1.5, (1.0, 1000.0), "",
              "relative refractive index n of the exact Fresnel term (metals: n = (1+√F0)/(1−√F0))",
              log_scale=True, fit_range=(1.0, 200.0)),
    )

    def _eval(self, wi, wo, p):
        dt = wi.dtype
        floor = dt.type(_COS_FLOOR[dt])
        h = half_vector(wi, wo)
        n_l = wi[..., 2]
        n_v = wo[..., 2]
        n_h = h[..., 2]
        l_h = np.einsum("...i,...i->...", wi, h)
        v_h = np.einsum("...i,...i->...", wo, h)
        c = np.clip(dt.type(0.5) * (l_h + v_h), dt.type(0), dt.type(1))  # = v·h = l·h, symmetric

        D = beckmann(h, p["m"], normalized=False)  # exp(−tan²α/m²)/(m² cos⁴α)
        G = v_groove(n_h, n_v, n_l, v_h, l_h)
        F = fresnel_dielectric_cook(c[..., None], p["ior"]).astype(dt, copy=False)

        geo = G / (np.maximum(n_l, floor) * np.maximum(n_v, floor))
        spec = (p["ks"] * (F / dt.type(np.pi)) * D[..., None]) * geo[..., None]
        spec = np.minimum(spec, np.finfo(dt).max)
        return spec + p["kd"] / dt.type(np.pi)


__all__ = ["CookTorrance"]
