"""He-Torrance-Sillion-Greenberg (HTSG): the physical-optics reflectance model.

Reference: X. D. He, K. E. Torrance, F. X. Sillion, D. P. Greenberg,
"A Comprehensive Physical Model for Light Reflection", Computer Graphics
(SIGGRAPH '91) 25(4), 175–186, 1991. Equation numbers below are the paper's.
Corrections follow the published errata as summarised by Pacanowski &
Holzschuch ("Demystifying the He, Torrance, Sillion and Greenberg BRDF") and
the Cornell reference implementation by Westin et al.

The surface is a random, isotropic, Gaussian height field with RMS height
``sigma0`` (σ0) and Gaussian autocorrelation length ``tau`` (τ), both in µm,
lit at wavelength λ. The BRDF is the sum of three parts,

    ρ = ρ_sp + ρ_dd + ρ_ud

**Specular** (a delta around the mirror direction)::

    ρ_sp = |F(θi)|² · e^(−g) · S / (cos θi dωi) · Δ

It cannot be returned by ``eval`` (a delta has no finite value); the fraction
of the incident power it reflects, ``|F|² e^(−g) S`` at the mirror direction,
is :meth:`HTSG.specular_reflectance`.

**Directional diffuse** (eqs. 76–84)::

    ρ_dd = |F|²/π · G · S · D / (cos θi cos θr)

    D = (π² τ² / (4 λ²)) · Σ_{m≥1} g^m e^(−g)/(m!·m) · exp(−τ² v_xy² / (4m))

with ``k_i = −wi`` (the incident propagation direction), ``k_r = wo``,
``v = (2π/λ)(k_r − k_i)`` (the scattering wave vector), ``v_xy`` its
component in the mean plane and

    g = (2π σ / λ)² (cos θi + cos θr)²                       (eq. 79)

**Uniform diffuse**: the paper's constant a(λ) (subsurface and multiple
scattering), written ``kd/π`` so that kd is its albedo as everywhere in
brdfkit; 0 for clean metals. HTSG does not couple it to the surface
reflection: keep kd ≤ 1 − (specular + directional-diffuse albedo).

Pieces
------
*Shadowing* (eqs. 24–25, Smith 1967 for a Gaussian surface with Gaussian
correlation), with ``S = S(θi) S(θr)`` and, for ``a = τ cot θ / (2σ0)``::

    S(θ) = (1 − ½ erfc(a)) / (Λ(a) + 1),   Λ(a) = ½ (e^(−a²)/(√π a) − erfc(a))

The ``e^(−a²)`` in Λ is missing in the printed paper (erratum; without it
Λ is not Smith's function and S is 10–15 % off).

*Effective roughness* (eqs. 80–83): shadowing hides the lowest parts of the
surface, so the roughness the light sees is

    σ = σ0 / sqrt(1 + (z0/σ0)²),
    √(π/2) · z0 = (σ0/4) (K_i + K_r) · exp(−z0²/(2σ0²)),
    K = tan θ · erfc(τ / (2 σ0 tan θ)).

With ``x = z0/σ0`` the equation is ``x² e^(x²) = (K_i + K_r)² / (8π)``, so
``x² = W((K_i + K_r)²/(8π))`` with Lambert's W (principal branch): the
equation has exactly one root and this closed form finds it without a
bracket. W (:func:`brdfkit.terms.special.lambertw_log`) is computed by Newton's
method on ``w + ln w = ln z`` (robust: it never forms z, which overflows at
grazing angles), started at ln(1+z) for
z ≤ e and at ln z − ln ln z otherwise, 5 iterations; it agrees with
``scipy.special.lambertw`` to 1e-13 relative (tested), and substituting the
root back into the paper's equation leaves a relative residual < 1e-10
(tested).

*Geometric factor* (eq. 76): with unit vectors, ``G = (v̂·v̂ / v̂_z)² ·
[(ŝ_r·k_i)² + (p̂_r·k_i)²][(ŝ_i·k_r)² + (p̂_i·k_r)²] / |k_r × k_i|⁴``.
Like most implementations we use the **unpolarised** model: unpolarised
light, the unpolarised Fresnel average ``(R_s + R_p)/2`` at the local
incidence angle. Since (ŝ, p̂, k̂) is an orthonormal triple, each bracket
equals ``1 − (k_i·k_r)² = |k_r × k_i|²`` and the polarisation factor is
exactly 1, leaving ``G = (v̂·v̂ / v̂_z)² = |wi + wo|⁴ / (cos θi + cos θr)²``.

*Fresnel* at the local incidence, the angle between ``k_i`` and the local
bisector ``v̂``: ``cos = |wi + wo| / 2``, via
:func:`brdfkit.terms.fresnel.fresnel_conductor` (``k = 0`` is a dielectric).

Units in the sum: the paper prints ``exp(−v_xy² τ²/(4m))`` with unit vectors,
which is not dimensionless; the wave vector ``v = (2π/λ)(k_r − k_i)`` of
Beckmann's derivation (and Westin et al.'s code) makes it so, and it is the
form whose rough limit is the microfacet model with a Beckmann distribution of
RMS slope ``m = 2σ/τ``: for large g, ``Σ → e^(−a)/g`` with
``a = τ² v_xy²/(4g) = tan²α / m²`` and ρ_dd becomes
``F · D_Beckmann · S / (4 cos θi cos θr)`` (tested).

The series
----------
``Σ(g, T) = Σ_{m≥1} e^(−g) g^m / (m!·m) · e^(−T/m)`` with ``T = (πτ/λ)²
|wi_xy + wo_xy|²`` (eq. 78's sum) is evaluated as ``ln(Σ/g)`` by
:mod:`brdfkit.terms.htsg_series`, for every g ≥ 0 and T ≥ 0: a windowed,
thinned direct sum for g < 40 and far in the tail, an asymptotic expansion in
1/g with exact rational coefficients (its leading term Beckmann's rough-surface
limit) in and around the lobe of large g. Relative error ≤ 1e-6 (measured:
≤ 1.6e-7, at g = 40) over 1e-4 ≤ g ≤ 1e5, which covers the parameter range
(g ≤ (4π σ0/λ)² ≤ 1.6e4 for σ0 ≤ 2 µm, λ ≥ 200 nm). Its special functions
(Lambert W, ln m!, Stirling's series, Loader's deviance) are in
:mod:`brdfkit.terms.special`.

The per-pair kernel is :func:`htsg_kernel` (the reference engine runs it, the
compiled one for a few pairs); for more, the compiled engine runs
:func:`htsg_span`, the same functions composed block by block of pairs so that
LLVM vectorises across pairs (the series module's "Evaluation in bulk"). The
two engines agree to 1e-12.

Parameters
----------
==============  ======  ====================  ===============  =============================================
parameter       kind    default               range            meaning
==============  ======  ====================  ===============  =============================================
sigma0          scalar  0.18                  [0, 2] µm        RMS surface height σ0 (0: a perfect mirror);
                                                               fitted in [0.005, 1.5] µm
tau             scalar  3.0                   [0.05, 100] µm   autocorrelation length τ; fitted in [0.3, 30] µm
                                                               (log scale), so slopes 2σ0/τ up to 10
eta             rgb     1.49, 0.96, 0.62      [0.01, 10]       refractive index n per channel
k               rgb     7.82, 6.69, 5.46      [0, 20]          extinction coefficient per channel (0: dielectric)
wavelengths     rgb     650, 550, 450         [200, 2000] nm   wavelength each RGB channel is evaluated at
kd              rgb     0                     [0, 1]           uniform-diffuse albedo (kd/π)
ks              rgb     1                     [0, 10]          scale of the surface reflection (directional
                                                               diffuse and specular); 1 is the physical model
==============  ======  ====================  ===============  =============================================

``ks`` is not part of the 1991 model (which is ks = 1): measured materials
(paints, plastics) reflect less or more at their surface than the Fresnel factor
of one set of optical constants predicts, and a fitter needs that freedom, as
Ngan et al. (2005) give every lobe model an RGB weight. It multiplies ρ_dd and
the coherent specular part alike, so the two stay in the ratio the physics sets.

The defaults are the paper's aluminium example (σ0 = 0.18 µm, τ = 3 µm) with
approximate optical constants of aluminium at the three wavelengths (after Rakić 1995).
"""

from __future__ import annotations

import math

import numpy as np

from ..engine import jit, select, vectorize
from ..params import Param
from ..registry import register
from ..terms.fresnel import f_conductor, fresnel_conductor
from ..terms.htsg_series import (
    ASYMPTOTIC_A_POWER,
    ASYMPTOTIC_A_SCALE,
    ASYMPTOTIC_G,
    ASYMPTOTIC_ORDER,
    SORT_BINS,
    asymptotic_coefficients,
    direct_finish,
    htsg_log_series_ratio,
    htsg_series,
    log_series_ratio,
    span_terms,
    span_window,
)
from ..terms.special import exp_by_halves, lambertw_from_log, lambertw_log
from .base import BRDF

_SQRT_PI = math.sqrt(math.pi)
_TINY = 1e-300
#: cap on S(θ)/cos θ: reached only for cos θ < 1e-150 with σ0 below ~1e-150 (no shadowing left to
#: cancel the 1/cos); with it the product S_i S_o |v|⁴/(cos θi cos θr) stays finite, never 0·∞
SHADOW_OVER_COS_CAP = 1e150
_LN_8PI = math.log(8.0 * math.pi)


# ---------------------------------------------------------------------------
# Shadowing and effective roughness
# ---------------------------------------------------------------------------
@jit(inline=True)
def shadowing_over_cos_c(c, sigma0, tau):
    """``S(θ)/cos θ`` (eqs. 24–25 with the erratum), finite down to cos θ = 0 for σ0 > 0.

    With ``a = τ cot θ/(2σ0)``: ``(1 + Λ) cos θ = c (1 − ½ erfc a) + σ0 s e^(−a²)/(√π τ)``
    (no 1/a, positive), so ``S/cos θ = (1 − ½ erfc a)/((1 + Λ) cos θ)``. σ0 = 0 (a mirror, no
    shadowing) gives 1/cos θ. Every case is computed and one selected (no branch around a math call).
    """
    c = min(max(c, 0.0), 1.0)
    mirror = min(1.0 / max(c, _TINY), SHADOW_OVER_COS_CAP)
    s = math.sqrt(max(0.0, (1.0 - c) * (1.0 + c)))
    # a = τ c/(2σ0)/s (2σ0·s would underflow to 0 for tiny σ0); the divisors of the cases not
    # selected (σ0 = 0, s = 0) are replaced by 1
    a = tau * c / select(sigma0 > 0.0, 2.0 * sigma0, 1.0) / select(s > 0.0, s, 1.0)
    # a² ≤ 700, a ≤ 28: beyond, e^(−a²) is below 1e-304 of what it is added to, and erfc(a) is 0 in
    # doubles (the vector math library redoes arguments out of its range by scalar calls)
    ea = select(s > 0.0, math.exp(-min(a * a, 700.0)), 0.0)
    ec = select(s > 0.0, math.erfc(min(a, 28.0)), 0.0)
    den = c * (1.0 - 0.5 * ec) + sigma0 * s * ea / (_SQRT_PI * tau)
    rough = min((1.0 - 0.5 * ec) / max(den, _TINY), SHADOW_OVER_COS_CAP)
    return select(sigma0 <= 0.0, mirror, rough)


@jit
def shadowing_c(c, sigma0, tau):
    """Smith shadowing ``S(θ)`` of HTSG eqs. 24–25 (with the e^(−a²) erratum), from cos θ."""
    c = min(max(c, 0.0), 1.0)
    return min(max(shadowing_over_cos_c(c, sigma0, tau) * c, 0.0), 1.0)


@jit(inline=True)
def roughness_K(c, sigma0, tau):
    """``K = tan θ · erfc(τ/(2 σ0 tan θ))`` of eqs. 80–83 (0 at normal incidence, and for σ0 = 0)."""
    c = min(max(c, 0.0), 1.0)
    s = math.sqrt(max(0.0, (1.0 - c) * (1.0 + c)))
    t = s / max(c, 1e-150)
    # 2σ0·t would underflow to 0 for tiny σ0; the divisors of the cases not selected are replaced by 1
    # (t = 0 gives K = 0·erfc(…) = 0 by itself)
    k = t * math.erfc(min(tau / select(sigma0 > 0.0, 2.0 * sigma0, 1.0) / select(t > 0.0, t, 1.0), 28.0))  # 0 beyond 28
    return select(sigma0 > 0.0, k, 0.0)


@jit(inline=True)
def z0_ratio_squared_c(cos_i, cos_r, sigma0, tau):
    """``(z0/σ0)²`` solving eqs. 80–83: ``x² e^(x²) = (K_i + K_r)²/(8π)``, so ``x² = W((K_i + K_r)²/(8π))``
    (0 where K_i + K_r = 0: at normal incidence, or σ0 = 0)."""
    kk = roughness_K(cos_i, sigma0, tau) + roughness_K(cos_r, sigma0, tau)
    # K_i + K_r below 1e-300 (0 included) gives W(< 1e-600) = 0 to double precision
    return lambertw_log(2.0 * math.log(max(kk, _TINY)) - _LN_8PI, 5.0)


@jit(inline=True)
def effective_roughness_c(cos_i, cos_r, sigma0, tau):
    """σ = σ0 / sqrt(1 + (z0/σ0)²) of eqs. 80–83 (µm), from the two cosines."""
    return sigma0 / math.sqrt(max(1.0 + z0_ratio_squared_c(cos_i, cos_r, sigma0, tau), 1.0))


shadowing_over_cos = vectorize(shadowing_over_cos_c, 3)
shadowing = vectorize(shadowing_c, 3)
z0_ratio_squared = vectorize(z0_ratio_squared_c, 4)
effective_roughness = vectorize(effective_roughness_c, 4)


@jit(inline=True)
def scattering_vector(wix, wiy, wiz, wox, woy, woz):
    """``(vz, vxy2)`` of ``v = wi + wo`` (the scattering vector over 2π/λ), the cosines clamped to [0, 1] in vz."""
    vx = wix + wox
    vy = wiy + woy
    return min(max(wiz, 0.0), 1.0) + min(max(woz, 0.0), 1.0), vx * vx + vy * vy


@jit(inline=True)
def pair_geometry(wix, wiy, wiz, wox, woy, woz, sigma0, tau):
    """What a pair's three channels share, but for the effective roughness: ``(vz, vxy2, geo, cos_local)``.

    :func:`scattering_vector`, the geometric factor ``geo = |v|⁴ S_i/ci · S_o/co / π`` (eq. 76 unpolarised,
    times the shadowing, module docstring) and the cosine of the local incidence angle ``|v|/2`` for
    the Fresnel term.
    """
    vz, vxy2 = scattering_vector(wix, wiy, wiz, wox, woy, woz)
    v2 = vxy2 + vz * vz  # |wi + wo|²
    geo = (v2 * v2 * shadowing_over_cos_c(min(max(wiz, 0.0), 1.0), sigma0, tau)
           * shadowing_over_cos_c(min(max(woz, 0.0), 1.0), sigma0, tau) / math.pi)
    cos_local = min(max(0.5 * math.sqrt(max(v2, 0.0)), 0.0), 1.0)
    return vz, vxy2, geo, cos_local


@jit(inline=True)
def pair_roughness(wiz, woz, sigma0, tau):
    """The pair's effective roughness σ (eqs. 80–83, :func:`effective_roughness_c`) from the two z components."""
    return effective_roughness_c(min(max(wiz, 0.0), 1.0), min(max(woz, 0.0), 1.0), sigma0, tau)


@jit(inline=True)
def channel_gT(lam_nm, sigma, tau, vz, vxy2):
    """``(g, T, scale)`` of one wavelength (nm): g = (2πσ/λ)² vz² (eq. 79), T = (πτ/λ)² v_xy², and
    ``scale = (2πσ/λ)² (πτ/(2λ))²``, the factor of ρ_dd outside the series (λ in µm)."""
    lam = lam_nm * 1e-3
    k2 = (2.0 * math.pi * sigma / lam) * (2.0 * math.pi * sigma / lam)
    q = math.pi * tau / (2.0 * lam)
    return k2 * vz * vz, (math.pi * tau / lam) * (math.pi * tau / lam) * vxy2, k2 * (q * q)


@jit(inline=True)
def channel_value(weight, log_ratio, geo):
    """ρ_dd of one channel from ``weight = ks·F·scale``, ``ln(Σ/g)`` and ``geo``: the bounded factors
    first (the series ratio may underflow to 0), the large geometric one last."""
    return (weight * exp_by_halves(min(log_ratio, 700.0))) * geo


@jit
def directional_diffuse_channel(lam_nm, eta, k, ks, sigma, tau, vz, vxy2, cos_local, geo):
    """ρ_dd of one channel (eqs. 76–84): ``ks·|F|²·G·S·D/(π cos θi cos θr)`` as

    ``ks · F · (2πσ/λ)² (πτ/(2λ))² · (Σ/g) · geo`` with ``geo = |v|⁴ S_i/ci · S_o/co / π``
    (:func:`pair_geometry`, :func:`channel_gT`, :func:`channel_value`).
    """
    g, T, scale = channel_gT(lam_nm, sigma, tau, vz, vxy2)
    return channel_value(ks * f_conductor(cos_local, eta, k) * scale, log_series_ratio(g, T), geo)


@jit
def htsg_kernel(wix, wiy, wiz, wox, woy, woz, p, c):
    """HTSG per pair (engine protocol, :mod:`brdfkit.engine`): ρ_dd + kd/π.

    ``p`` = [sigma0, tau, eta (3), k (3), wavelengths (3), kd (3), ks (3)]; ``c`` unused. The
    compiled engine runs :func:`htsg_span` instead, the same functions composed across pairs.
    """
    sigma0 = p[0]
    tau = p[1]
    d0 = p[11] / math.pi
    d1 = p[12] / math.pi
    d2 = p[13] / math.pi
    if sigma0 <= 0.0:
        return d0, d1, d2
    sigma = pair_roughness(wiz, woz, sigma0, tau)
    vz, vxy2, geo, cl = pair_geometry(wix, wiy, wiz, wox, woy, woz, sigma0, tau)
    return (
        directional_diffuse_channel(p[8], p[2], p[5], p[14], sigma, tau, vz, vxy2, cl, geo) + d0,
        directional_diffuse_channel(p[9], p[3], p[6], p[15], sigma, tau, vz, vxy2, cl, geo) + d1,
        directional_diffuse_channel(p[10], p[4], p[7], p[16], sigma, tau, vz, vxy2, cl, geo) + d2,
    )


#: pairs per block of :func:`htsg_span` (its scratch: 11 arrays of 3 × SPAN_BLOCK values)
SPAN_BLOCK = 64


@jit(inline=True)
def span_channel(lam_nm, eta, k, ks, sigma, tau, vz, vxy2, cl):
    """One channel's ``(g, T, weight)`` for :func:`htsg_span`, step 1: g and T as :func:`log_series_ratio`
    takes them (:func:`channel_gT`), and ``weight = ks·F·scale`` (:func:`channel_value`)."""
    g, T, scale = channel_gT(lam_nm, sigma, tau, vz, vxy2)
    return max(g, _TINY), max(T, 0.0), ks * f_conductor(cl, eta, k) * scale


@jit(inline=True)
def span_value(asym, peak, h, acc, weight, geo, kd, ok, lim):
    """A channel's value in :func:`htsg_span`, step 3: ρ_dd + kd/π (at most ``lim``; 0 where not ``ok``)."""
    lr = select(asym == asym, asym, direct_finish(peak, h, acc))
    return select(ok, min(channel_value(weight, lr, geo) + kd / math.pi, lim), 0.0)


@jit
def htsg_span(a, b, o, cs, ps, lo, hi, p, c, lim):
    """HTSG for the pairs ``lo`` .. ``hi − 1`` of flat direction arrays, into ``o``: the functions of
    :func:`htsg_kernel` composed across pairs, so that LLVM vectorises over pairs (the compiled
    engine's span protocol, :mod:`brdfkit.engine.driver`).

    Component ``k`` of pair ``j`` is at ``a[k·cs + j·ps]`` (rows: cs = 1, ps = 3; a structure of arrays:
    cs = n, ps = 1); the result is 0 where ``wi.z <= 0`` or ``wo.z <= 0`` and at most ``lim``. Block by
    block of :data:`SPAN_BLOCK` pairs, each step a loop over the block's pairs: (1) the geometry, the
    effective roughness, :func:`span_channel` and :func:`span_window` per channel; (2) :func:`span_terms`;
    (3) :func:`span_value` into scratch, then the strided stores (LLVM leaves a loop that writes to ``o``
    scalar: ``o`` may alias the directions). The three channels are written out in step 1, whose body is
    large (LLVM unrolls only small loops such as step 3's before it vectorises the loop around them). Per
    pair the numbers are those of :func:`htsg_kernel` up to the rounding of the vector math library (4 ulp,
    glibc's libmvec), which the forms of :func:`log_term` and :func:`term_rel` do not amplify (tested
    against the reference engine, which runs :func:`htsg_kernel`, to 1e-12, far in the tail included).
    """
    sigma0 = p[0]
    tau = p[1]
    nb = SPAN_BLOCK
    LG = np.empty((3, nb))
    TT = np.empty((3, nb))
    BASE = np.empty((3, nb))
    H = np.empty((3, nb))
    CNT = np.empty((3, nb))
    MC = np.empty((3, nb))
    LFC = np.empty((3, nb))
    PEAK = np.empty((3, nb))
    ASYM = np.empty((3, nb))
    W = np.empty((3, nb))
    ACC = np.empty((3, nb))
    V = np.empty((3, nb))
    S = np.empty((8, nb))  # span_terms' scratch
    ORDER = np.empty(nb, dtype=np.int64)
    BINS = np.empty(SORT_BINS, dtype=np.int64)
    GEO = np.empty(nb)
    OK = np.empty(nb, dtype=np.bool_)
    D = np.empty((6, nb))  # the block's directions, component by component (unit stride)
    for b0 in range(lo, hi, nb):
        m = min(nb, hi - b0)
        for i in range(m):
            j = b0 + i
            for k in range(3):
                D[k, i] = a[k * cs + j * ps]
                D[3 + k, i] = b[k * cs + j * ps]
        for i in range(m):  # (1) geometry, σ, g, T, the Fresnel weights and the series' windows, vectorised
            wiz = D[2, i]
            woz = D[5, i]
            ok = wiz > 0.0 and woz > 0.0 and sigma0 > 0.0  # sigma0 = 0: a mirror, only kd/π below
            OK[i] = ok
            vz, vxy2, geo, cl = pair_geometry(D[0, i], D[1, i], wiz, D[3, i], D[4, i], woz, sigma0, tau)
            GEO[i] = geo
            sigma = pair_roughness(wiz, woz, sigma0, tau)
            g, T, W[0, i] = span_channel(p[8], p[2], p[5], p[14], sigma, tau, vz, vxy2, cl)
            LG[0, i], TT[0, i], BASE[0, i], H[0, i], CNT[0, i], MC[0, i], LFC[0, i], PEAK[0, i], ASYM[0, i] = \
                span_window(g, T, ok)
            g, T, W[1, i] = span_channel(p[9], p[3], p[6], p[15], sigma, tau, vz, vxy2, cl)
            LG[1, i], TT[1, i], BASE[1, i], H[1, i], CNT[1, i], MC[1, i], LFC[1, i], PEAK[1, i], ASYM[1, i] = \
                span_window(g, T, ok)
            g, T, W[2, i] = span_channel(p[10], p[4], p[7], p[16], sigma, tau, vz, vxy2, cl)
            LG[2, i], TT[2, i], BASE[2, i], H[2, i], CNT[2, i], MC[2, i], LFC[2, i], PEAK[2, i], ASYM[2, i] = \
                span_window(g, T, ok)
        for k in range(3):  # (2) the terms
            span_terms(LG[k], TT[k], BASE[k], H[k], CNT[k], MC[k], LFC[k], ACC[k], m, S, ORDER, BINS)
        for i in range(m):  # (3) the values, vectorised (into scratch: o may alias the directions for LLVM)
            ok = OK[i]
            above = D[2, i] > 0.0 and D[5, i] > 0.0
            for k in range(3):
                V[k, i] = span_value(ASYM[k, i], PEAK[k, i], H[k, i], ACC[k, i], select(ok, W[k, i], 0.0), GEO[i],
                                     p[11 + k], above, lim)
        for i in range(m):
            j = b0 + i
            o[j * ps] = V[0, i]
            o[cs + j * ps] = V[1, i]
            o[2 * cs + j * ps] = V[2, i]


# ---------------------------------------------------------------------------
# The model
# ---------------------------------------------------------------------------
_AL_ETA = (1.49, 0.96, 0.62)
_AL_K = (7.82, 6.69, 5.46)


@register
class HTSG(BRDF):
    name = "htsg"
    title = "He-Torrance-Sillion-Greenberg: physical optics (Kirchhoff) model of a rough Gaussian surface"
    reference = (
        "He, Torrance, Sillion, Greenberg, A Comprehensive Physical Model for Light Reflection, "
        "SIGGRAPH 1991 (Computer Graphics 25(4))"
    )
    isotropic = True
    spec = (
        Param("sigma0", "scalar", 0.18, (0.0, 2.0), "µm", "RMS surface height σ0 (0 is a perfect mirror)",
              fit_range=(0.005, 1.5)),
        Param("tau", "scalar", 3.0, (0.05, 100.0), "µm", "autocorrelation length τ of the surface heights",
              fit_range=(0.3, 30.0), log_scale=True),
        Param("eta", "rgb", _AL_ETA, (0.01, 10.0), "", "refractive index n per channel (default: aluminium)"),
        Param("k", "rgb", _AL_K, (0.0, 20.0), "", "extinction coefficient per channel (0 for a dielectric)"),
        Param("wavelengths", "rgb", (650.0, 550.0, 450.0), (200.0, 2000.0), "nm",
              "wavelength at which each RGB channel is evaluated", fit=False),
        Param("kd", "rgb", 0.0, (0.0, 1.0), "", "uniform-diffuse albedo (the term kd/π)"),
        Param("ks", "rgb", 1.0, (0.0, 10.0), "", "scale of the surface reflection (directional diffuse and "
              "specular; 1 = the 1991 model)", fit_range=(0.0, 3.0)),
    )

    def _setup(self) -> None:
        p = self.params
        self._sigma0 = float(p["sigma0"])
        self._tau = float(p["tau"])
        self._lam = np.asarray(p["wavelengths"], dtype=np.float64) * 1e-3  # µm
        self._eta = np.asarray(p["eta"], dtype=np.float64)
        self._k = np.asarray(p["k"], dtype=np.float64)
        self._kd = np.asarray(p["kd"], dtype=np.float64)
        self._ks = np.asarray(p["ks"], dtype=np.float64)

    # -- parts -------------------------------------------------------------
    kernel = staticmethod(htsg_kernel)
    kernel_span = staticmethod(htsg_span)  # the compiled engine's loop order (the same functions)
    kernel_float32 = False  # the series (and its accuracy against mpmath) needs float64 also for float32 input

    def kernel_args(self):
        return self._pack(("sigma0", "tau", "eta", "k", "wavelengths", "kd", "ks"))

    def directional_diffuse(self, wi, wo) -> np.ndarray:
        """ρ_dd(wi, wo) (1/sr, RGB, float64): the kernel with kd = 0."""
        wi = np.asarray(wi, dtype=np.float64)
        wo = np.asarray(wo, dtype=np.float64)
        if self._sigma0 <= 0:
            return np.zeros(np.broadcast_shapes(wi.shape, wo.shape))
        return self.with_params(kd=0.0).eval(wi, wo)

    def delta_reflectance(self, w) -> np.ndarray:
        """The coherent mirror part (see :meth:`specular_reflectance`), for albedo and energy checks."""
        return self.specular_reflectance(w)

    def specular_reflectance(self, wi) -> np.ndarray:
        """Fraction of the incident power in the coherent mirror reflection: ``ks·|F(θi)|² e^(−g) S(θi)²``.

        ``wi`` (..., 3) toward the light; returns (..., 3) RGB (0 where ``wi.z <= 0``); float32 in
        gives float32 out. The reflected direction is :meth:`specular_direction`.
        """
        wi = np.asarray(wi)
        if wi.shape[-1:] != (3,):
            raise ValueError(f"{self.name}: directions must have a last axis of length 3, got {wi.shape}")
        dtype = np.float32 if wi.dtype == np.float32 else np.float64
        c = np.asarray(wi[..., 2], dtype=np.float64)
        valid = c > 0
        c = np.clip(c, 0.0, 1.0)
        F = fresnel_conductor(c[..., None], self._eta, self._k)
        if self._sigma0 <= 0:
            out = F
        else:
            sigma = effective_roughness(c, c, self._sigma0, self._tau)
            g = (2.0 * np.pi * sigma[..., None] / self._lam) ** 2 * (2.0 * c[..., None]) ** 2
            S = shadowing(c, self._sigma0, self._tau) ** 2
            out = F * np.exp(-g) * S[..., None]
        out = np.where(valid[..., None], self._ks * out, 0.0)
        return np.clip(out, 0.0, None).astype(dtype)

    @staticmethod
    def specular_direction(wi) -> np.ndarray:
        """The mirror direction of ``wi`` about the normal +z, where the specular delta lies."""
        wi = np.asarray(wi)
        out = -wi.copy()
        out[..., 2] = wi[..., 2]
        return out

    def uniform_diffuse(self, wi, wo) -> np.ndarray:
        """ρ_ud = kd/π, broadcast to (..., 3)."""
        shape = np.broadcast(np.asarray(wi), np.asarray(wo)).shape
        return np.broadcast_to(self._kd / np.pi, shape)


__all__ = [
    "HTSG",
    "htsg_kernel",
    "htsg_span",
    "htsg_series",
    "htsg_log_series_ratio",
    "lambertw_from_log",
    "asymptotic_coefficients",
    "shadowing",
    "shadowing_over_cos",
    "effective_roughness",
    "z0_ratio_squared",
    "ASYMPTOTIC_G",
    "ASYMPTOTIC_ORDER",
    "ASYMPTOTIC_A_SCALE",
    "ASYMPTOTIC_A_POWER",
]
