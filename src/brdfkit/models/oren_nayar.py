"""Oren-Nayar: rough diffuse reflection from V-cavities of Lambertian facets, and its energy-preserving EON form.

Reference: M. Oren and S. K. Nayar, "Generalization of Lambert's Reflectance
Model", SIGGRAPH 1994, pp. 239-246 — the functional approximation of the
single-scattering radiance L_r^1 (coefficients C1, C2, C3), the
interreflection component L_r^2, and the "qualitative model" with A and B.

Verification (formula audit): the paper's own text was not available to us,
so its equation numbers are NOT cited here. The formulas below were checked,
constant by constant (0.5, 0.33, 0.45, 0.09, 0.125, (4αβ/π²)², (2β/π)³ in the
cos Δφ < 0 branch of C2, 0.17, 0.13, (2β/π)²), against two independent
restatements that agree with each other and with this module:

* the appendix "Oren-Nayar Diffuse Reflectance Model" (studylib.net document
  18316725), which restates L_r^1 (its eqs. 1-6), L_r^2 (its eq. 7) and their
  sum (its eq. 8) — those numbers are the appendix's, not the paper's;
* Mitsuba 0.5 `src/bsdfs/roughdiffuse.cpp` (full model and its
  `useFastApprox` A, B model; it rescales its roughness input by 1/sqrt(2)
  before using it as σ, which we do not: our σ is the paper's, the standard
  deviation of the facet slope angle in radians).

The qualitative A, B model agrees with the lecture, with Mitsuba and with the
Wikipedia statement of the model. No disagreement between these sources and
this module was found; nothing was changed.

Angles: θi, θo polar angles of wi and wo, Δφ = φo − φi, α = max(θi, θo),
β = min(θi, θo), σ the standard deviation of the facet slope angle (radians),
ρ = kd the facet albedo. The paper writes radiances for a source of
irradiance E0 at normal incidence, L = (…)·E0 cos θi; the BRDF is the bracket
without E0 cos θi.

variant="qualitative" (the lecture's formula):

    f_r = (ρ/π) (A + B · max(0, cos Δφ) · sin α · tan β)
    A = 1 − 0.5 σ²/(σ² + 0.33),   B = 0.45 σ²/(σ² + 0.09)

variant="full" (the paper's model with interreflections):

    f_r = f1 + f2
    f1 = (ρ/π) [C1 + cos Δφ · C2 · tan β + (1 − |cos Δφ|) · C3 · tan((α+β)/2)]
    f2 = 0.17 (ρ²/π) σ²/(σ² + 0.13) · [1 − cos Δφ · (2β/π)²]
    C1 = 1 − 0.5 σ²/(σ² + 0.33)
    C2 = 0.45 σ²/(σ² + 0.09) · sin α                    if cos Δφ ≥ 0
         0.45 σ²/(σ² + 0.09) · (sin α − (2β/π)³)        otherwise
    C3 = 0.125 σ²/(σ² + 0.09) · (4αβ/π²)²

variant="eon" (Portsmouth, Kutz & Hill, "EON: A Practical Energy-Preserving
Rough Diffuse BRDF", JCGT 14(1), 2025; the formulas and their numerics are in
:mod:`brdfkit.models.eon`):

    f_r = (ρ/π) A (1 + r s/t) + (ρ_ms/π) (1 − E(μi)) (1 − E(μo)) / (1 − Ē)
    A = 1/(1 + (1/2 − 2/(3π)) r),  s = wi·wo − μi μo,  t = max(μi, μo) if s > 0 else 1
    E = the closed-form albedo of the first term (ρ = 1), Ē its mean,
    ρ_ms = ρ² Ē/(1 − ρ(1 − Ē)),     r = min(σ, 1)

    The roughness r ∈ [0, 1] of EON is taken from ``sigma`` as r = min(σ, 1): σ
    itself, as Fujii's FON form (EON's first term) uses the Oren-Nayar σ to match
    the full 1994 model, and as MaterialX 1.39's ``oren_nayar_diffuse_bsdf`` feeds one
    ``roughness`` input both to its qualitative model (as σ) and to its EON (as r).
    EON is defined for r ≤ 1 only (its first term would turn negative beyond), so
    every σ in [1, π/2) gives the EON of r = 1. The exports write r as OpenPBR's
    ``base_diffuse_roughness``, MaterialX's ``roughness`` and glTF's
    ``diffuseRoughnessFactor``.

    Unlike the two 1994 variants it conserves energy exactly and loses none: for
    kd = 1 the directional albedo is 1 at every angle (up to the horizon), and for
    any kd it is kd E(μ) + ρ_ms (1 − E(μ)) in closed form. Reciprocal (symmetric in
    wi, wo). Its multiple-scattering term is not linear in kd (ρ_ms is not).

σ = 0 gives A = C1 = 1 and B = C2 = C3 = f2 = 0: exactly Lambert, kd/π (and so does
variant="eon": r = 0).

The two 1994 variants are symmetric in (wi, wo) (α, β and |Δφ| are), hence
reciprocal. Neither is exactly energy conserving: they are fits to a
V-cavity model, and tan β grows without bound when both directions approach
the horizon. Measured directional albedo with kd = 1: qualitative σ = 0.1
reaches 1.008 at θi = 89.9° (σ = 0.3: 1.005; σ = 0.5: ≤ 0.95); full σ = 0.3
reaches 1.05 (σ = 0.1: 1.015; σ = 0.5: 1.025) — a few percent over 1 near
grazing incidence, below 1 elsewhere. The full variant's f2 is quadratic in ρ, so its RGB response is
not proportional to kd.

The full model's fit can go *negative*: for cos Δφ < 0 the C2 term is
subtracted and grows like tan β, e.g. σ = 1.5, θ = 80° and 89°, Δφ = π gives
C1 + cos Δφ·C2·tan β ≈ 0.56 − 0.73 < 0. We clamp the bracket of f1 at 0
(a radiance cannot be negative); values where it is positive are untouched.

Numerics: the polar angles come from ``arctan2(sin θ, cos θ)`` (accurate near
the normal); cos Δφ is computed from the normalised projections onto the
tangent plane and taken as 0 when either direction is the normal (φ is then
undefined, and every term that multiplies cos Δφ vanishes there anyway because
β = 0). tan β = sin β / cos β and tan((α+β)/2) = (sin α + sin β)/(cos α + cos β)
use a floor of 1e-6 on cos β and on cos α + cos β, which only alters values
when both directions are within 0.00006° of the horizon; this keeps every
value finite (the exact model diverges there).

=========  ======  ===========  =====================  ==================================
parameter  kind    default      range                  meaning
=========  ======  ===========  =====================  ==================================
kd         rgb     0.8          [0, 1]                 facet albedo ρ (σ = 0: kd/π)
sigma      scalar  0.3          [0, π/2)  rad          std. dev. of the facet slope angle
                                                       (eon: its roughness r = min(σ, 1))
variant    choice  qualitative  qualitative | full     the A,B model, the full model or
                                | eon                  the energy-preserving EON (2025)
=========  ======  ===========  =====================  ==================================
"""

from __future__ import annotations

import math

import numpy as np

from ..engine import jit
from ..geometry import hypot_c
from ..params import Param, kd_param
from ..registry import register
from .base import BRDF
from .eon import eon_avg_albedo, eon_channel, eon_ms_shape, fon_g, fon_single

#: floor on cos β and on cos α + cos β (keeps tan β and tan((α+β)/2) finite)
COS_FLOOR = 1e-6


@jit
def polar_angles(x, y, z):
    """sin θ, cos θ, θ and the unit azimuth vector (cos φ, sin φ) of a direction (zeros at the normal)."""
    st = hypot_c(x, y)
    theta = math.atan2(st, z)
    if st > 0.0:
        return st, z, theta, x / st, y / st
    return st, z, theta, 0.0, 0.0


@jit
def oren_nayar_qualitative(sig2, cos_dphi, sin_a, tan_b):
    """The lecture's A + B·max(0, cos(φi − φo))·sin α·tan β (Oren & Nayar 1994, eq. 30)."""
    A = 1.0 - 0.5 * sig2 / (sig2 + 0.33)
    B = 0.45 * sig2 / (sig2 + 0.09)
    return A + B * max(cos_dphi, 0.0) * sin_a * tan_b


@jit
def oren_nayar_direct(sig2, cos_dphi, alpha, beta, sin_a, sin_b, cos_a, cos_b, tan_b):
    """The full model's direct term C1 + cos Δφ C2 tan β + (1 − |cos Δφ|) C3 tan((α+β)/2), floored at 0."""
    two_b_pi = 2.0 * beta / math.pi
    C1 = 1.0 - 0.5 * sig2 / (sig2 + 0.33)
    k2 = 0.45 * sig2 / (sig2 + 0.09)
    if cos_dphi >= 0.0:
        C2 = k2 * sin_a
    else:
        C2 = k2 * (sin_a - two_b_pi * two_b_pi * two_b_pi)
    q = 4.0 * alpha * beta / (math.pi * math.pi)
    C3 = 0.125 * sig2 / (sig2 + 0.09) * (q * q)
    tan_half = (sin_a + sin_b) / max(cos_a + cos_b, COS_FLOOR)
    g1 = C1 + cos_dphi * C2 * tan_b + (1.0 - abs(cos_dphi)) * C3 * tan_half
    return max(g1, 0.0)  # the fit dips below 0 for large σ, grazing, Δφ ≈ π


@jit
def oren_nayar_interreflection(sig2, cos_dphi, beta):
    """The full model's interreflection factor 0.17 σ²/(σ² + 0.13) (1 − cos Δφ (2β/π)²), times ρ²/π."""
    two_b_pi = 2.0 * beta / math.pi
    return 0.17 * sig2 / (sig2 + 0.13) * (1.0 - cos_dphi * two_b_pi * two_b_pi)


@jit
def eon_roughness(sigma):
    """EON's roughness r ∈ [0, 1] from the Oren-Nayar σ: r = min(σ, 1) (see the module docstring)."""
    return min(sigma, 1.0)


@jit
def eon(wix, wiy, wiz, wox, woy, woz, si, ti, so, to, p):
    """f_EON (Portsmouth, Kutz & Hill 2025; :mod:`brdfkit.models.eon`), RGB, ``p = [kd(3), sigma]``."""
    r = eon_roughness(p[3])
    s = wix * wox + wiy * woy  # wi·wo − μi μo, without the cancellation
    single = fon_single(r, s, wiz, woz)
    shape = eon_ms_shape(r, fon_g(si, wiz, ti), fon_g(so, woz, to))
    e_avg = eon_avg_albedo(r)
    return (
        eon_channel(p[0], single, shape, e_avg),
        eon_channel(p[1], single, shape, e_avg),
        eon_channel(p[2], single, shape, e_avg),
    )


@jit
def oren_nayar_kernel(wix, wiy, wiz, wox, woy, woz, p, c):
    """Oren & Nayar (1994) and EON (2025): ``p = [kd(3), sigma]``, ``c = [variant]`` (0 qualitative, 1 full, 2 eon)."""
    sig2 = p[3] * p[3]
    si, ci, ti, cpi, spi = polar_angles(wix, wiy, wiz)
    so, co, to, cpo, spo = polar_angles(wox, woy, woz)
    if c[0] == 2:
        return eon(wix, wiy, wiz, wox, woy, woz, si, ti, so, to, p)
    cos_dphi = min(max(cpi * cpo + spi * spo, -1.0), 1.0)
    sin_a = max(si, so)  # α = max(θi, θo): the larger sine, the smaller cosine
    cos_a = min(ci, co)
    sin_b = min(si, so)
    cos_b = max(ci, co)
    tan_b = sin_b / max(cos_b, COS_FLOOR)
    if c[0] == 0:
        g = oren_nayar_qualitative(sig2, cos_dphi, sin_a, tan_b)
        return p[0] / math.pi * g, p[1] / math.pi * g, p[2] / math.pi * g
    alpha = max(ti, to)
    beta = min(ti, to)
    g1 = oren_nayar_direct(sig2, cos_dphi, alpha, beta, sin_a, sin_b, cos_a, cos_b, tan_b)
    g2 = oren_nayar_interreflection(sig2, cos_dphi, beta)
    return (
        (p[0] / math.pi) * g1 + (p[0] * p[0] / math.pi) * g2,
        (p[1] / math.pi) * g1 + (p[1] * p[1] / math.pi) * g2,
        (p[2] / math.pi) * g1 + (p[2] * p[2] / math.pi) * g2,
    )


@register
class OrenNayar(BRDF):
    name = "oren-nayar"
    title = "Oren-Nayar rough diffuse (qualitative A,B model, the full 1994 model, or the energy-preserving EON)"
    reference = (
        "Oren and Nayar, Generalization of Lambert's Reflectance Model, SIGGRAPH 1994; "
        "Portsmouth, Kutz and Hill, EON: A Practical Energy-Preserving Rough Diffuse BRDF, JCGT 14(1), 2025"
    )
    isotropic = True
    spec = (
        kd_param(0.8, "facet albedo ρ (σ = 0 gives Lambert kd/π)"),
        Param(
            "sigma",
            "scalar",
            0.3,
            (0.0, float(np.pi / 2)),
            "rad",
            "standard deviation σ of the facet slope angle (0 = Lambert); eon: roughness r = min(σ, 1)",
            open_hi=True,
        ),
        Param(
            "variant",
            "choice",
            "qualitative",
            doc="qualitative: the lecture's A, B formula; full: C1, C2, C3 and the interreflection term; "
            "eon: the energy-preserving Oren-Nayar of Portsmouth, Kutz & Hill 2025 (OpenPBR's diffuse)",
            choices=("qualitative", "full", "eon"),
            fit=False,
        ),
    )

    kernel = staticmethod(oren_nayar_kernel)

    def kernel_args(self):
        return self._pack(("kd", "sigma"), ("variant",))
