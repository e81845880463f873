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

import math

from ..engine import jit
from ..geometry import half_vector_c
from ..params import Param, kd_param, ks_param
from ..registry import register
from ..terms.distributions import d_beckmann_slopes
from ..terms.fresnel import f_dielectric
from ..terms.shadowing import g_vgroove
from .base import BRDF

#: floor on n·l and n·v in the 1/((n·l)(n·v)) factor (kernels compute in float64)
COS_FLOOR = 1e-150


@jit
def cook_torrance_kernel(wix, wiy, wiz, wox, woy, woz, p, c):
    """kd/π + ks·(F/π)·D·G/((n·l)(n·v)) (Cook & Torrance 1982), per RGB channel.

    D = exp(−tan²α/m²)/(m² cos⁴α) (no 1/π), F exact dielectric at c = v·h, G V-groove.
    ``p = [kd(3), ks(3), m, ior(3)]``, ``c`` unused.
    """
    hx, hy, hz = half_vector_c(wix, wiy, wiz, wox, woy, woz)
    l_h = wix * hx + wiy * hy + wiz * hz
    v_h = wox * hx + woy * hy + woz * hz
    cc = min(max(0.5 * (l_h + v_h), 0.0), 1.0)  # = v·h = l·h, symmetric
    m = p[6]
    D = d_beckmann_slopes(hx, hy, hz, m, m)
    G = g_vgroove(hz, woz, wiz, v_h, l_h)
    geo = G / (max(wiz, COS_FLOOR) * max(woz, COS_FLOOR))
    sr = (p[3] * (f_dielectric(cc, p[7]) / math.pi) * D) * geo
    sg = (p[4] * (f_dielectric(cc, p[8]) / math.pi) * D) * geo
    sb = (p[5] * (f_dielectric(cc, p[9]) / math.pi) * D) * geo
    return sr + p[0] / math.pi, sg + p[1] / math.pi, sb + p[2] / math.pi


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

    kernel = staticmethod(cook_torrance_kernel)

    def kernel_args(self):
        return self._pack(("kd", "ks", "m", "ior"))


__all__ = ["CookTorrance"]
