"""Schlick: the inexpensive rational-fraction BRDF model (single or double slab).

Reference: C. Schlick, "An Inexpensive BRDF Model for Physically-based
Rendering", Computer Graphics Forum 13(3) (Eurographics 1994), 233-246, §5.

Notation of the paper (n = +z, tangent T = +x, h = normalize(wi + wo)):
t = n·h, u = h·wi (= h·wo), v = n·wi, v' = n·wo, and w = cos of the azimuth
of h measured from T (w = hx / sqrt(hx² + hy²)).

Spectral factor (Schlick's Fresnel approximation, colour C = reflectance at
normal incidence):

    S(u) = C + (1 − C)(1 − u)⁵

Directional factor of one slab, with roughness r ∈ (0, 1] and isotropy
p ∈ (0, 1]:

    Z(t) = r / (1 + r t² − t²)²                 zenith factor (= π·GGX with α² = r)
    A(w) = sqrt(p / (p² − p² w² + w²))          azimuth factor
    G(v) = v / (r − r v + v)                    Smith-like self-shadowing

    D(t, v, v', w) = a/π + b · G(v) G(v') Z(t) A(w) / (4π v v')  [+ c · mirror]

split into a Lambertian part a, a glossy part b and an ideal-mirror part c
(a + b + c = 1) by the roughness alone:

    b = 4 r (1 − r),   a = 0 and c = 1 − b if r < 0.5,   a = 1 − b and c = 0 if r ≥ 0.5

so r → 0 is a perfect mirror, r = 0.5 purely glossy and r = 1 Lambertian.

Verification (formula audit; the paper's own text was not available to us):

* verified against two independent renderers and a third-party summary of
  the paper (an auto-generated, chunk-by-chunk digest of the PDF,
  "Schlick_1994_BRDF_Model - Extracted Summary", in the public repository
  pjt222/soap_bubble_simulation):
  S(u) = C + (1 − C)(1 − u)⁵; Z(t) = r/(1 + r t² − t²)²;
  A(w) = sqrt(p/(p² − p² w² + w²)); G(v) = v/(r − r v + v); the glossy
  product G(v) G(v') Z(t) A(w)/(4π v v'); the single slab S·D and the double
  slab S·D + (1 − S) S'·D' with parameter sets (C, r, p) and (C', r', p').
  The renderers are LuxCoreRender (`SchlickDistribution_SchlickZ/_SchlickA/
  _SchlickG`, Z A/π as the normal distribution) and RISE (an earlier
  version of its `SchlickBRDF.cpp`: Z A G G'/(4π v v')). The digest
  numbers the Fresnel approximation (15) in §4.2 (and the same formula with
  C as (24) in §5) and the §4.3 form of G,
  v/(v − k v + k) with k = sqrt(2m²/π), as (19); RISE cites "Eq. 31" for
  the §5 G(v)G(v') — second-hand numbers, not checked against the paper.
* the azimuth w: this module takes w = cos of the azimuth of h measured from
  the tangent +x (so p → 0 gives scratches along +x), as LuxCore does for a
  positive anisotropy; RISE measures it from its second tangent. The paper's
  choice of reference axis could not be checked; it only swaps x and y.
* NOT verified: the a/b/c split (b = 4r(1 − r), a or c = 1 − b). None of the
  sources available to us states it; it is as the previous author recalled
  it from the paper, and the auditor recalls the same form, but no document
  confirms it.

Material types:

    layers="single"  (a homogeneous material, one slab):
        f_r = S(u) · D(t, v, v', w)
    layers="double"  (a heterogeneous material: a slab (color, r, p) over a
                      second slab (color2, r2, p2), e.g. varnish over paint):
        f_r = S(u) · D(t, v, v', w) + (1 − S(u)) · S'(u) · D'(t, v, v', w)

What ``eval`` returns and what it does not:

* The ideal-mirror part c is a Dirac delta, which no finite BRDF value can
  represent; ``eval`` returns the Lambertian and glossy parts only, and
  :meth:`Schlick.mirror_reflectance` gives the delta's weight (the fraction of
  light from wi sent into reflect(wi)): c·S(cos θi), plus (1 − S)·S'·c' for
  the double slab.
* The paper also has a term that re-injects the energy lost to
  self-shadowing, weighted by 1 − G(v)G(v'). Its exact form stays
  unresolved, so it is **not** implemented. The sources disagree: the
  third-party digest writes D = G G' Z A/(4π v v') + (1 − G G')/(4π v v'),
  whose second term alone has the albedo (1/(4π v))∫(1 − G(v)G(v'))dω',
  which grows like 1/(2v) at grazing incidence (hardly what a paper that
  claims energy conservation would propose, so possibly a transcription
  slip); LuxCoreRender's optional "multibounce" term, which its source
  calls an "alternative", is clamp((1 − G G')/(4 v v'), 0, 1), without π;
  and the auditor recalls (1 − G G')/π, a Lambertian lobe, without a
  document to confirm it.

Properties: every factor is symmetric in wi and wo (u, t, w, and the product
G(v)G(v')), so the model is reciprocal. Energy: Z/π is a normalised
microfacet distribution, but A(w) is Schlick's approximation whose mean over
the azimuth is 1 only for p = 1 (measured: 0.97 at p = 0.5, 0.74 at p = 0.1),
and G is an approximation of Smith's function. Measured with color = 1
(eval's albedo plus the mirror part): ≤ 1 up to θi = 60° for
r ∈ {0.05, 0.3, 0.5, 0.8} and p ∈ {1, 0.3}, but 1.014 at θi = 85° and 1.12
at 89° for r = 0.05 — not strictly energy conserving at grazing incidence.
r = 1 with color = 1 is exactly Lambert (albedo 1).

Numerics: the glossy term is evaluated as
Z A / (4π (r + (1−r) v)(r + (1−r) v')) (G(v)/v simplified), and Z's
denominator as (hx² + hy²) + r t² (no cancellation for t → 1 and small r),
so it is finite and accurate for every direction: no floors are needed.
At h = n the azimuth w is undefined and A is taken as 1.

A(w) is largest for w = 0, i.e. for half vectors tilted toward ±y: with
p < 1 the facets are scratches along the tangent +x and the highlight is
stretched across them, along y.

=========  ======  =======  ===============  ==================================================
parameter  kind    default  range            meaning
=========  ======  =======  ===============  ==================================================
layers     choice  single   single | double  one slab, or slab (color, r, p) over (color2, r2, p2)
color      rgb     0.8      [0, 1]           C: reflectance at normal incidence of the (top) slab
r          scalar  0.3      (0, 1]           roughness (0 mirror, 0.5 glossy, 1 Lambertian)
p          scalar  1        (0, 1]           isotropy (1 isotropic, → 0 scratches along +x)
color2     rgb     0.5      [0, 1]           C' of the lower slab (double only)
r2         scalar  1        (0, 1]           roughness of the lower slab (double only)
p2         scalar  1        (0, 1]           isotropy of the lower slab (double only)
=========  ======  =======  ===============  ==================================================
"""

from __future__ import annotations

import numpy as np

from ..geometry import half_vector
from ..params import Param
from ..registry import register
from ..terms.fresnel import fresnel_schlick
from .base import BRDF


def split_weights(r: float) -> tuple[float, float, float]:
    """Schlick's Lambertian / glossy / mirror fractions ``(a, b, c)`` for roughness ``r``."""
    b = 4.0 * r * (1.0 - r)
    if r < 0.5:
        return 0.0, b, 1.0 - b
    return 1.0 - b, b, 0.0


def _half_terms(wi, wo):
    """``(t, s2, u, w2, at_n)``: n·h, 1 − (n·h)² (from hx² + hy², no cancellation), h·wi,
    w² = cos² of h's azimuth from +x, and ``h == n``."""
    h = half_vector(wi, wo)
    t = h[..., 2]
    u = np.clip(np.einsum("...i,...i->...", wi, h), 0, 1)
    s2 = h[..., 0] ** 2 + h[..., 1] ** 2
    at_n = s2 == 0
    w2 = np.where(at_n, 1, h[..., 0] ** 2 / np.where(at_n, 1, s2))
    return np.clip(t, 0, 1), s2, u, w2, at_n


def _slab_directional(t, s2, w2, at_n, v, v2, r, p, dt):
    """One slab's directional factor without the mirror part: a/π + b·G G' Z A/(4π v v')."""
    a, b, _ = split_weights(float(r))
    pi = dt(np.pi)
    # 1 + r t² − t² = (1 − t²) + r t², with 1 − t² = hx² + hy² (accurate for t → 1, small r)
    Z = r / (s2 + r * t * t) ** 2
    if p == 1:
        A = np.ones_like(t)
    else:
        # w is undefined at h = n: take the isotropic value 1 there
        A = np.where(at_n, dt(1), np.sqrt(p / (p * p - p * p * w2 + w2)))
    # G(v)G(v')/(v v') = 1/((r + (1-r) v)(r + (1-r) v'))
    gg = dt(1) / ((r + (dt(1) - r) * v) * (r + (dt(1) - r) * v2))
    return dt(a) / pi + dt(b) * Z * A * gg / (dt(4) * pi)


@register
class Schlick(BRDF):
    name = "schlick"
    title = "Schlick 1994 rational-fraction BRDF: single or double slab, roughness r, isotropy p"
    reference = "Schlick, An Inexpensive BRDF Model for Physically-based Rendering, CGF 13(3) (Eurographics 1994)"
    isotropic = False
    spec = (
        Param(
            "layers",
            "choice",
            "single",
            doc="single: f = S·D (homogeneous); double: f = S·D + (1−S)·S'·D' (a slab over a second slab)",
            choices=("single", "double"),
            fit=False,
        ),
        Param("color", "rgb", 0.8, (0.0, 1.0), "", "C: reflectance at normal incidence of the (top) slab"),
        Param(
            "r",
            "scalar",
            0.3,
            (0.0, 1.0),
            "",
            "roughness: 0 mirror, 0.5 purely glossy, 1 Lambertian",
            open_lo=True,
        ),
        Param("p", "scalar", 1.0, (0.0, 1.0), "", "isotropy: 1 isotropic, → 0 scratches along +x", open_lo=True),
        Param("color2", "rgb", 0.5, (0.0, 1.0), "", "C' of the lower slab (layers=double only)"),
        Param("r2", "scalar", 1.0, (0.0, 1.0), "", "roughness of the lower slab (layers=double only)", open_lo=True),
        Param("p2", "scalar", 1.0, (0.0, 1.0), "", "isotropy of the lower slab (layers=double only)", open_lo=True),
    )

    def _eval(self, wi, wo, p):
        dt = wi.dtype.type
        t, s2, u, w2, at_n = _half_terms(wi, wo)
        v, v2 = wi[..., 2], wo[..., 2]
        S = fresnel_schlick(p["color"], u[..., None])
        D = _slab_directional(t, s2, w2, at_n, v, v2, p["r"], p["p"], dt)[..., None]
        f = S * D
        if p["layers"] == "double":
            S2 = fresnel_schlick(p["color2"], u[..., None])
            D2 = _slab_directional(t, s2, w2, at_n, v, v2, p["r2"], p["p2"], dt)[..., None]
            f = f + (dt(1) - S) * S2 * D2
        return f

    def delta_reflectance(self, w) -> np.ndarray:
        """The ideal-mirror part (see :meth:`mirror_reflectance`), for albedo and energy checks."""
        return self.mirror_reflectance(w)

    def mirror_reflectance(self, wi) -> np.ndarray:
        """RGB weight of the ideal-mirror (Dirac) part for light from ``wi``, sent into reflect(wi).

        ``c·S(cos θi)`` for one slab, plus ``(1 − S)·S'(cos θi)·c'`` for two; 0 below the horizon.
        This part is not included in :meth:`eval`.
        """
        wi = np.asarray(wi, dtype=np.float64)
        cos_i = wi[..., 2]
        u = np.clip(cos_i, 0.0, 1.0)[..., None]
        S = fresnel_schlick(self.params["color"], u)
        out = split_weights(self.params["r"])[2] * S
        if self.params["layers"] == "double":
            S2 = fresnel_schlick(self.params["color2"], u)
            out = out + (1.0 - S) * S2 * split_weights(self.params["r2"])[2]
        return np.where((cos_i > 0)[..., None], out, 0.0)
