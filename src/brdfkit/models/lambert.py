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

import math

from ..engine import jit
from ..params import kd_param
from ..registry import register
from .base import BRDF


@jit
def lambert_kernel(wix, wiy, wiz, wox, woy, woz, p, c):
    """kd/π per channel; ``p = [kd_r, kd_g, kd_b]``, ``c`` unused."""
    return p[0] / math.pi, p[1] / math.pi, p[2] / math.pi


@register
class Lambert(BRDF):
    name = "lambert"
    title = "ideal diffuse reflector, kd/π"
    reference = "Lambert, Photometria (1760)"
    spec = (kd_param(0.5),)

    kernel = staticmethod(lambert_kernel)

    def kernel_args(self):
        return self._pack(("kd",))
