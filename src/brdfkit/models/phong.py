"""Phong: a diffuse term plus a cosine-power lobe around the mirror direction.

References:
  B. T. Phong, "Illumination for computer generated pictures",
  Communications of the ACM 18(6), 1975 (the lighting-equation term).
  R. R. Lewis, "Making shaders more physically plausible",
  Computer Graphics Forum 13(2), 1994 (the normalised, reciprocal BRDF).

With ``r = reflect(wi) = 2 (n·wi) n − wi`` (the mirror direction of the light,
n = +z) and ``x = max(0, r·wo)``:

    f_r = kd/π + ks · lobe

    normalized=True  (Lewis 1994):  lobe = (s + 2)/(2π) · x^s
    normalized=False (Phong 1975):  lobe = x^s / max(n·wi, 1e-4)

**Normalized.** The factor (s+2)/(2π) makes the lobe's directional albedo
exactly 1 at normal incidence: ∫ (s+2)/(2π) (r·wo)^s cos θo dωo = 1 for
wi = n, and smaller at every other incidence (part of the lobe falls below
the horizon), so the model is energy conserving whenever kd + ks ≤ 1 per
channel. It is symmetric in wi and wo (r·wo = reflect(wo)·wi), hence
reciprocal.

**Unnormalized.** Phong's illumination model adds ``ks (r·v)^s I`` to the
reflected radiance for a light of intensity I; that light delivers the
irradiance I cos θi, so read as a BRDF (radiance = f_r I cos θi) the term is
``ks (r·v)^s / cos θi``. It is neither
reciprocal (the 1/cos θi is not symmetric) nor energy conserving (the
albedo grows without bound toward grazing light). The 1/cos θi diverges
at grazing light; to keep every value finite as the contract requires,
cos θi is clamped to a floor of 1e-4 (θi ≈ 89.994°): f_r·cos θi then equals
the lighting-equation term exactly for every light above that angle.

At s = 0 the lobe is the step "1 where r·wo > 0" (``max(0, x)^0`` is taken as
0 where x ≤ 0). Large s is evaluated without overflow; x^s simply
underflows to 0 away from the mirror direction.

==========  ======  =======  ============  ==========================================
parameter   kind    default  range         meaning
==========  ======  =======  ============  ==========================================
kd          rgb     0.5      [0, 1]        diffuse albedo (kd/π)
ks          rgb     0.3      [0, 1]        specular weight (normalized: lobe albedo
                                           at normal incidence)
shininess   scalar  32       [0, 1e5]      Phong exponent s (fitted within [1, 1e5])
normalized  bool    true     true | false  Lewis's (s+2)/(2π) form, else the raw
                                           lighting-equation term / cos θi
==========  ======  =======  ============  ==========================================
"""

from __future__ import annotations

import math

from ..engine import jit
from ..params import Param, exponent_param, kd_param, ks_param
from ..registry import register
from .base import BRDF

#: floor on cos θi in the unnormalized forms (keeps 1/(n·l) finite at grazing light)
NL_FLOOR = 1e-4


def phong_family_spec(ks_doc: str, shininess_doc: str, normalized_doc: str) -> tuple[Param, ...]:
    """The parameters shared by ``phong`` and ``blinn-phong``: kd, ks, shininess, normalized."""
    return (
        kd_param(0.5),
        ks_param(0.3, ks_doc),
        exponent_param("shininess", 32.0, shininess_doc),
        Param("normalized", "bool", True, doc=normalized_doc, fit=False),
    )


@jit
def phong_family_lobe(lobe, wiz, normalized, norm):
    """The family's two forms of the lobe: ``normalized`` scales it by ``norm``; the raw
    lighting-equation form divides it by cos θi (floored at :data:`NL_FLOOR`)."""
    if normalized:
        return lobe * norm
    return lobe / max(wiz, NL_FLOOR)


#: 2^1023 (a float32 twin maps it to its cap, 2^126: the step is still exactly 0 or 1)
_TWO_1023 = 2.0 ** 1023


@jit
def cos_power(x, s):
    """``max(0, x)^s`` with 0 (not 1) where ``x <= 0``, also for ``s = 0``.

    Written for the vectorised loop (:mod:`brdfkit.engine.vecmath`): the power is taken for every
    lane, of 1 where ``x <= 0`` (libmvec's pow takes a slow path, 4x, for a base <= 0, which about
    half of the pairs have), and multiplied by a step that is exactly 0 or 1, ``min(max(x, 0)·2^2046, 1)``
    (the smallest subnormal times 2^2046 is 2^972): a select on ``x <= 0`` instead would let LLVM
    take the power of ``x`` itself in every lane, the discarded ones included.
    """
    step = min(max(x, 0.0) * _TWO_1023 * _TWO_1023, 1.0)
    return (x if x > 0.0 else 1.0) ** s * step


@jit
def phong_kernel(wix, wiy, wiz, wox, woy, woz, p, c):
    """kd/π + ks·lobe, lobe = (r·wo)^s with r = reflect(wi) about +z; Lewis's (s+2)/(2π) or raw/(n·wi).

    ``p = [kd(3), ks(3), shininess]``, ``c = [normalized]``.
    """
    rv = min(wiz * woz - wix * wox - wiy * woy, 1.0)  # r·wo
    s = p[6]
    lobe = phong_family_lobe(cos_power(rv, s), wiz, c[0], (s + 2.0) / (2.0 * math.pi))
    return p[0] / math.pi + p[3] * lobe, p[1] / math.pi + p[4] * lobe, p[2] / math.pi + p[5] * lobe


@register
class Phong(BRDF):
    name = "phong"
    title = "Phong: kd/π + ks·cosine-power lobe around the mirror direction (Lewis-normalised or raw)"
    reference = (
        "Phong, Illumination for computer generated pictures, CACM 18(6), 1975; "
        "Lewis, Making shaders more physically plausible, CGF 13(2), 1994"
    )
    isotropic = True
    spec = phong_family_spec(
        ks_doc="specular weight (normalized: the lobe's albedo at normal incidence)",
        shininess_doc="Phong exponent s of (r·wo)^s",
        normalized_doc="true: Lewis 1994 (s+2)/(2π) lobe (reciprocal, energy conserving); "
        "false: the lighting-equation term divided by cos θi (neither)",
    )

    kernel = staticmethod(phong_kernel)

    def kernel_args(self):
        return self._pack(("kd", "ks", "shininess"), ("normalized",))
