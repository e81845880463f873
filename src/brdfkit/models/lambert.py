"""Lambert: the ideal diffuse reflector.

Reference: J. H. Lambert, *Photometria*, 1760.

    f_r(wi, wo) = kd / π

so that the directional albedo ∫ f_r cos θi dωi equals ``kd`` exactly. The
lecture writes the reflected radiance, (cos θi / π) kd, which is this BRDF
times the cosine.

=========  =====  =======  ========  ===========================
parameter  kind   default  range     meaning
=========  =====  =======  ========  ===========================
kd         rgb    0.5      [0, 1]    diffuse albedo
=========  =====  =======  ========  ===========================
"""

from __future__ import annotations

import numpy as np

from ..params import kd_param
from ..registry import register
from .base import BRDF


@register
class Lambert(BRDF):
    name = "lambert"
    title = "ideal diffuse reflector, kd/π"
    reference = "Lambert, Photometria (1760)"
    spec = (kd_param(0.5),)

    def _eval(self, wi, wo, p):
        kd = p["kd"]
        return np.broadcast_to(kd / kd.dtype.type(np.pi), wi.shape)
