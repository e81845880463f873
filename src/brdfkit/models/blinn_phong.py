"""Blinn-Phong: a diffuse term plus a cosine-power lobe of the half vector.

References:
  J. F. Blinn, "Models of light reflection for computer synthesized pictures",
  SIGGRAPH 1977 (the half-vector form of Phong's highlight).
  OpenGL 2.1 specification §2.14.1 (the fixed-function specular term
  ``(n·h)^shininess``, the lecture's "half-angle vector" formula).
  T. Akenine-Möller, E. Haines, N. Hoffman, *Real-Time Rendering*, 3rd ed.,
  2008, §7.6 (the normalisation factor (s+8)/(8π)).

With ``h = normalize(wi + wo)`` and ``x = max(0, n·h)`` (n = +z):

    f_r = kd/π + ks · lobe

    normalized=True:   lobe = (s + 8)/(8π) · x^s
    normalized=False:  lobe = x^s / max(n·wi, 1e-4)

**Normalized.** The lecture notes that Blinn-Phong "is not reciprocal or
energy conserving unless we reformulate"; this is the usual reformulation.
It is symmetric in wi and wo, hence reciprocal. The factor (s+8)/(8π) is an
*approximation* of the factor that gives the lobe unit albedo; it is not
exact. At normal incidence the lobe's directional albedo is, exactly,

    (s+8)(2^(−s/2) + s) / ((s+2)(s+4))

which is 1 at s = 0, 1.0625 at s = 4, peaks at ≈ 1.0752 near s ≈ 8.8 and
tends to 1 + 2/s for large s; away from normal incidence the albedo falls
(e.g. ≈ 0.79 at θi = 0.5 rad for s = 100). So the model conserves energy
only up to that ≤ 7.6 % overshoot of the lobe at near-normal incidence:
kd + 1.0752·ks ≤ 1 per channel is sufficient.

**Unnormalized.** OpenGL adds ``ks (n·h)^s I`` to the reflected radiance for a
light of intensity I, whose irradiance is I cos θi; read as a BRDF that is
``ks (n·h)^s / cos θi``: neither reciprocal nor energy conserving. The
1/cos θi diverges at grazing light; cos θi is clamped to a floor of 1e-4
(θi ≈ 89.994°) so every value stays finite, and f_r·cos θi reproduces the
OpenGL term exactly for every light above that angle.

At s = 0 the lobe is 1 wherever n·h > 0 (always, for directions above the
horizon), i.e. the normalised lobe is Lambertian, 1/π.

==========  ======  =======  ============  ==========================================
parameter   kind    default  range         meaning
==========  ======  =======  ============  ==========================================
kd          rgb     0.5      [0, 1]        diffuse albedo (kd/π)
ks          rgb     0.3      [0, 1]        specular weight
shininess   scalar  32       [0, 1e5]      exponent s of (n·h)^s (fitted within [1, 1e5])
normalized  bool    true     true | false  (s+8)/(8π) form, else the raw OpenGL term
                                           / cos θi
==========  ======  =======  ============  ==========================================
"""

from __future__ import annotations

import math

from ..engine import jit
from ..geometry import half_vector_c
from ..registry import register
from .base import BRDF
from .phong import phong_family_lobe, phong_family_spec


@jit
def blinn_phong_kernel(wix, wiy, wiz, wox, woy, woz, p, c):
    """kd/π + ks·lobe, lobe = (n·h)^s, (s+8)/(8π)-normalised or raw/(n·wi).

    ``p = [kd(3), ks(3), shininess]``, ``c = [normalized]``.
    """
    hx, hy, hz = half_vector_c(wix, wiy, wiz, wox, woy, woz)
    nh = min(max(hz, 0.0), 1.0)
    s = p[6]
    lobe = phong_family_lobe(nh ** s, wiz, c[0], (s + 8.0) / (8.0 * math.pi))
    return p[0] / math.pi + p[3] * lobe, p[1] / math.pi + p[4] * lobe, p[2] / math.pi + p[5] * lobe


@register
class BlinnPhong(BRDF):
    name = "blinn-phong"
    title = "Blinn-Phong: kd/π + ks·(n·h)^s lobe, (s+8)/(8π)-normalised or the raw OpenGL term"
    reference = (
        "Blinn, Models of light reflection for computer synthesized pictures, SIGGRAPH 1977; "
        "Akenine-Möller, Haines, Hoffman, Real-Time Rendering 3rd ed. (2008) §7.6"
    )
    isotropic = True
    spec = phong_family_spec(
        ks_doc="specular weight",
        shininess_doc="exponent s of (n·h)^s",
        normalized_doc="true: (s+8)/(8π)·(n·h)^s (reciprocal; lobe albedo ≤ 1.0752); "
        "false: OpenGL's (n·h)^s divided by cos θi (neither reciprocal nor energy conserving)",
    )

    kernel = staticmethod(blinn_phong_kernel)

    def kernel_args(self):
        return self._pack(("kd", "ks", "shininess"), ("normalized",))
