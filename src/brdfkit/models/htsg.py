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
bracket. W is computed by Newton's method on ``w + ln w = ln z`` (robust: it
never forms z, which overflows at grazing angles), started at ln(1+z) for
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
|wi_xy + wo_xy|²`` is evaluated by :func:`htsg_series` (internally as
``ln(Σ/g)``, which stays finite as g → 0) for every g ≥ 0 and T ≥ 0. Two
tiers:

* **Direct sum** (g < 40, or far in the tail: a = T/g above the bound below).
  The summand is a smooth, single-peaked function of m; its peak is the
  saddle point ``m* = g·exp(W(2T/g²)/2)`` (the root of ln(m/g) = T/m²; for
  T = 0 it is the Poisson mean g, in the tail it moves to larger m) and its
  width ``σ_m = (1/m* + 2T/m*³)^(−1/2)``. **Truncation:** the sum runs over
  ``m ∈ [m* − 6σ_m, m* + 7σ_m + 3] ∩ [1, ∞)``; the terms left out are
  below 1e-9 of the sum (measured against the same sum over a window twice as wide, at 20000
  random (g, T): ≤ 7.8e-10, the same as with the previous, two terms wider window; the GLSL
  twin keeps that one). Each term is
  computed directly relative to the one at m_c = round(m*),
  ``exp((m − m_c) ln g − [ln(m!·m) − ln(m_c!·m_c)] − T/m + T/m_c)``, with ln(m!·m) from a
  table built at import (m < 8192; lgamma above), so nothing overflows and the loop over m is
  a reduction of independent terms. **Thinning:** where the peak is wide, only every h-th
  term is taken and the sum multiplied by h. By Poisson summation, ``h Σ_j t(a + jh)``
  differs from ``Σ_m t(m)`` by the summand's lattice characteristic function at ν = k/h,
  k = 1..h−1; for a Poisson(g) summand that is ``exp(−g(1 − cos 2πk/h))``. The step is the
  largest h with ``σ_m² (1 − cos(2π/h)) ≥ 30`` (bound 2e^(−30) ≈ 2e-13 in the Poisson case),
  and h = 1 wherever the m = 1 term exceeds e^(−30) of the peak (the summand is cut off
  there, and the 1/m factor's pole at m = 0 then leaves a slowly decaying remainder of order
  g ln g e^(−g)). Measured against the long sum at 6000 random (g, T), 1e-4 ≤ g ≤ 2e4:
  ≤ 1.3e-9 (the long sum's own rounding at g > 1e3 is of that order). About 13σ_m/h + 3 terms:
  a few dozen for g < 30, ~16 for wide peaks whatever g.
* **Asymptotic form** (g ≥ 40 and ``a = T/g ≤ 0.5·g^0.55``, i.e. large g,
  in and around the lobe): writing ``e^(−T/m)/m`` as a Laplace transform,
  ``Σ = ∫₀^∞ J0(2√(Tt)) (e^(−g(1−e^(−t))) − e^(−g)) dt``; expanding about
  t = 0 in powers of 1/g and integrating term by term with
  ``∫ e^(−s) s^k J0(2√(as)) ds = k! e^(−a) L_k(a)`` (Laguerre polynomials)
  gives, after taking the logarithm,

      Σ ≈ (e^(−a)/g) · exp(Σ_{n=1}^{6} Q_n(a)/g^n),   Q_1 = 1 − 2a + a²/2, …

  (Q_n has degree n+1; the coefficients are derived exactly with rationals at
  import, :func:`asymptotic_coefficients`, ``ASYMPTOTIC_ORDER = 6``). The
  leading term is Beckmann's rough-surface limit. Its relative error in its
  region is at most 1.6e-7, at its lower corner (g = 40, T ≈ 152; 1.2e-7 at g = 41.5,
  9.8e-8 near g ≈ 43; checked against mpmath in ``tests/test_reliability_docs.py``),
  falling fast with g.

**Accuracy** (tests): relative error ≤ 1e-6 (measured: ≤ 1.6e-7, at g = 40) against a long
log-space sum over every m and against 40-digit mpmath sums, for
1e-4 ≤ g ≤ 1e5 and any T ≥ 0 (tested where Σ/g ≥ 1e-300; ``ln(Σ/g)`` stays
accurate below that, only the value itself underflows to 0 far outside the lobe). These g cover the whole
parameter range: g ≤ (4π σ0/λ)² ≤ 1.6e4 for σ0 ≤ 2 µm, λ ≥ 200 nm.

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
from fractions import Fraction
from math import comb, factorial

import numpy as np

from ..engine import jit, vectorize
from ..params import Param
from ..registry import register
from ..terms.fresnel import f_conductor, fresnel_conductor
from .base import BRDF

#: g at and above which the asymptotic form may be used
ASYMPTOTIC_G = 40.0
#: number of correction orders Q_1..Q_N in the asymptotic form
ASYMPTOTIC_ORDER = 6
#: the asymptotic form is used for a = T/g <= ASYMPTOTIC_A_SCALE * g**ASYMPTOTIC_A_POWER
ASYMPTOTIC_A_SCALE = 0.5
ASYMPTOTIC_A_POWER = 0.55
#: window of the direct sum, in units of the peak width σ_m, left and right of the saddle point
WINDOW_LEFT = (6.0, 0.0)  # m* − 6 σ_m
WINDOW_RIGHT = (7.0, 3.0)  # m* + 7 σ_m + 3

_SQRT_PI = math.sqrt(math.pi)
_TINY = 1e-300
#: cap on S(θ)/cos θ: reached only for cos θ < 1e-150 with σ0 below ~1e-150 (no shadowing left to
#: cancel the 1/cos); with it the product S_i S_o |v|⁴/(cos θi cos θr) stays finite, never 0·∞
SHADOW_OVER_COS_CAP = 1e150
_LN_8PI = math.log(8.0 * math.pi)


# ---------------------------------------------------------------------------
# Lambert W (principal branch, real argument z >= 0), given ln z
# ---------------------------------------------------------------------------
@jit
def lambertw_log(lz, iterations):
    """W(z) for ``z = exp(lz)`` ≥ 0 (``lz = -inf`` gives 0), without forming z when it would overflow.

    Newton's method on ``h(w) = w + ln w − ln z`` (concave, increasing), started at
    ``ln(1 + z) ≥ W(z)`` for z ≤ e (the first step lands in (0, W(z)]) and at
    ``ln z − ln ln z ≤ W(z)`` for z > e; from the left Newton converges monotonically and
    quadratically. 5 iterations reach machine precision for every ``lz`` in [-700, 1e300]
    (tested); below −700, W(z) = z to double precision.
    """
    if lz < -700.0:
        return math.exp(lz)
    if lz <= 1.0:
        w = math.log1p(math.exp(lz))
    else:
        w = lz - math.log(lz)
    for _ in range(int(iterations)):
        w = w - (w + math.log(w) - lz) * w / (w + 1.0)
    return w


_lambertw_v = vectorize(lambertw_log, 2)


def lambertw_from_log(lz, iterations: int = 5) -> np.ndarray:
    """Array form of :func:`lambertw_log` (float64, broadcasting)."""
    return _lambertw_v(lz, float(iterations))


# ---------------------------------------------------------------------------
# The asymptotic expansion's coefficients, derived exactly
# ---------------------------------------------------------------------------
def _poly_mul(p, q, order):
    out: dict = {}
    for (n1, k1), c1 in p.items():
        for (n2, k2), c2 in q.items():
            n = n1 + n2
            if n <= order:
                out[(n, k1 + k2)] = out.get((n, k1 + k2), 0) + c1 * c2
    return out


def asymptotic_coefficients(order: int = ASYMPTOTIC_ORDER) -> list[list[Fraction]]:
    """``Q_n(a)`` coefficients (index = power of a), n = 0..order, of ln(g Σ e^a) = Σ_n Q_n(a)/g^n.

    With t = s/g: ``g(1 − e^(−s/g)) = s − Σ_{j≥2} (−1)^j s^j/(j! g^(j−1))``, so the
    integrand is ``e^(−s) exp(E)``, ``E = Σ_{j≥2} (−1)^j s^j ε^(j−1)/j!``, ε = 1/g;
    exp(E) is expanded in ε, each ``s^k`` integrates to ``k! L_k(a)`` (times e^(−a)),
    and the logarithm of the resulting series in ε gives Q_n.
    """
    E = {(j - 1, j): Fraction((-1) ** j, factorial(j)) for j in range(2, order + 2)}
    exp_e: dict = {(0, 0): Fraction(1)}
    term: dict = {(0, 0): Fraction(1)}
    for r in range(1, order + 1):
        term = {key: c / r for key, c in _poly_mul(term, E, order).items()}
        for key, c in term.items():
            exp_e[key] = exp_e.get(key, 0) + c
    # P_n(a) = Σ_k c_{n,k} k! L_k(a),  L_k(a) = Σ_i C(k,i) (−a)^i / i!
    P = [[Fraction(0)] * (2 * order + 1) for _ in range(order + 1)]
    for (n, k), c in exp_e.items():
        for i in range(k + 1):
            P[n][i] += c * factorial(k) * comb(k, i) * Fraction((-1) ** i, factorial(i))
    X = {(n, i): c for n in range(1, order + 1) for i, c in enumerate(P[n]) if c}
    Q: dict = {}
    power: dict = {(0, 0): Fraction(1)}
    for r in range(1, order + 1):
        power = _poly_mul(power, X, order)
        for key, c in power.items():
            Q[key] = Q.get(key, 0) + c * Fraction((-1) ** (r + 1), r)
    out = [[Fraction(0)] * (n + 2) for n in range(order + 1)]
    for (n, i), c in Q.items():
        if c:
            out[n][i] += c  # degree of Q_n is n + 1 (higher powers cancel exactly)
    return out


#: Q_0..Q_N as float arrays (index = power of a); the GLSL twin's htsg_q<n> hold the same numbers
_Q = [np.array([float(c) for c in q]) for q in asymptotic_coefficients(ASYMPTOTIC_ORDER)]
#: the same, flattened (a tuple, a compile-time constant for numba): Q_n's coefficients (power of
#: a ascending) start at _Q_OFF[n] and number n + 2
_Q_FLAT = tuple(float(c) for q in _Q for c in q)
_Q_OFF = tuple(int(x) for x in np.cumsum([0] + [len(q) for q in _Q])[:-1])


@jit
def asymptotic_log_ratio(g, T):
    """ln(Σ/g) from the asymptotic form ``Σ ≈ (e^(−a)/g)·exp(Σ_n Q_n(a)/g^n)``, a = T/g (module docstring)."""
    a = T / g
    eps = 1.0 / g
    corr = 0.0
    for n in range(ASYMPTOTIC_ORDER, 0, -1):
        off = _Q_OFF[n]
        poly = _Q_FLAT[off + n + 1]
        for i in range(n, -1, -1):
            poly = poly * a + _Q_FLAT[off + i]
        corr = (corr + poly) * eps
    return -a - 2.0 * math.log(g) + corr


# ---------------------------------------------------------------------------
# The directional-diffuse series
# ---------------------------------------------------------------------------
#: ln(m!·m) is tabulated for m below this (the direct sum's terms need no lgamma there)
LN_TABLE_SIZE = 8192
_LN_FACT_M = np.array([0.0] + [math.lgamma(m + 1.0) + math.log(m) for m in range(1, LN_TABLE_SIZE)])
#: the direct sum takes every h-th term where ``var·(1 − cos(2π/h)) ≥ THIN_MARGIN`` (module docstring)
THIN_MARGIN = 30.0
#: Newton iterations of W for the saddle point (the window's position: m* to 5e-5 relative)
SADDLE_W_ITERATIONS = 2.0


@jit
def ln_fact_times_m(m):
    """``ln(m!·m)`` for an integer-valued m ≥ 1: the module table below LN_TABLE_SIZE, lgamma above."""
    if m < LN_TABLE_SIZE:
        return _LN_FACT_M[int(m)]
    return math.lgamma(m + 1.0) + math.log(m)


@jit
def log_term(m, lg, g, T):
    """ln of the m-th term of Σ/g: (m−1) ln g − g − ln(m!·m) − T/m (integer-valued m ≥ 1)."""
    return (m - 1.0) * lg - g - ln_fact_times_m(m) - T / m


@jit
def thinning_step(var, edge):
    """The step h of the direct sum: the largest integer with ``var·(1 − cos(2π/h)) ≥ THIN_MARGIN``.

    ``var`` is the summand's variance σ_m², ``edge`` the log of its m = 1 term relative to the
    peak's. h = 1 (every term) unless the summand is negligible at m = 1 (``edge < −THIN_MARGIN``):
    cut off there, it is not a smooth peak and the lattice argument of the module docstring
    does not hold.
    """
    if edge > -THIN_MARGIN or 2.0 * var <= THIN_MARGIN:
        return 1.0
    return max(math.floor(2.0 * math.pi / math.acos(1.0 - THIN_MARGIN / var)), 1.0)


@jit(reassociate=True)
def direct_log_ratio(g, T):
    """ln(Σ/g) by the windowed direct sum (g > 0, T ≥ 0).

    The window ``[lo, hi]`` surrounds the saddle point m* = g exp(W(2T/g²)/2) (width
    σ_m = (1/m* + 2T/m*³)^(−1/2)). Every h-th term (:func:`thinning_step`) is taken, each
    directly relative to the term at ``m_c = round(m*)``, ``exp(ln t_m − ln t_(m_c))``, with
    ln(m!·m) from the module table: the iterations are independent (a reduction), and
    nothing overflows or underflows near the peak. Compiled with ``reassociate`` (the terms are
    positive): LLVM vectorises the sum, 8 terms per vector exp (libmvec, :mod:`brdfkit.engine.vecmath`).
    """
    lg = math.log(g)
    w = lambertw_log(math.log(2.0 * T) - 2.0 * lg, SADDLE_W_ITERATIONS) if T > 0.0 else 0.0
    mstar = max(g * math.exp(0.5 * w), 1.0)
    var = 1.0 / (1.0 / mstar + 2.0 * T / (mstar * mstar * mstar))
    sig = math.sqrt(var)
    lo = max(math.floor(mstar - WINDOW_LEFT[0] * sig - WINDOW_LEFT[1]), 1.0)
    hi = math.ceil(mstar + WINDOW_RIGHT[0] * sig + WINDOW_RIGHT[1])
    mc = min(max(math.floor(mstar + 0.5), lo), hi)
    peak = log_term(mc, lg, g, T)
    h = thinning_step(var, -g - T - peak)  # log_term(1) = −g − T
    jlo = -math.floor((mc - lo) / h)
    jhi = math.floor((hi - mc) / h)
    acc = 0.0
    if mc + jhi * h < LN_TABLE_SIZE:
        k0 = int(mc)
        ih = int(h)
        for j in range(int(jlo), int(jhi) + 1):  # log_term(m) − peak, ln(m!·m) read from the table (no branch)
            m = mc + j * h
            acc += math.exp((m - 1.0) * lg - g - _LN_FACT_M[k0 + j * ih] - T / m - peak)
    else:
        for j in range(int(jlo), int(jhi) + 1):
            acc += math.exp(log_term(mc + j * h, lg, g, T) - peak)
    return peak + math.log(h * acc)


@jit
def log_series_ratio(g, T):
    """``ln(Σ(g, T)/g)`` (finite for g ≥ 0, T ≥ 0; g = 0 gives −T, the limit): the two tiers."""
    g = max(g, _TINY)
    T = max(T, 0.0)
    if g >= ASYMPTOTIC_G and T / g <= ASYMPTOTIC_A_SCALE * math.exp(ASYMPTOTIC_A_POWER * math.log(g)):
        return asymptotic_log_ratio(g, T)
    return direct_log_ratio(g, T)


_asymptotic_log_ratio = vectorize(asymptotic_log_ratio, 2)
_direct_log_ratio = vectorize(direct_log_ratio, 2)
htsg_log_series_ratio = vectorize(log_series_ratio, 2)
htsg_log_series_ratio.__doc__ = "``ln(Σ(g, T)/g)`` elementwise, float64 (array form of :func:`log_series_ratio`)."


def htsg_series(g, T) -> np.ndarray:
    """``Σ_{m≥1} e^(−g) g^m / (m!·m) · e^(−T/m)`` (HTSG eq. 78's sum), elementwise, float64."""
    g = np.asarray(g, dtype=np.float64)
    return g * np.exp(htsg_log_series_ratio(g, T))


# ---------------------------------------------------------------------------
# Shadowing and effective roughness
# ---------------------------------------------------------------------------
@jit
def shadowing_over_cos_c(c, sigma0, tau):
    """``S(θ)/cos θ`` (eqs. 24–25 with the erratum), finite down to cos θ = 0 for σ0 > 0.

    With ``a = τ cot θ/(2σ0)``: ``(1 + Λ) cos θ = c (1 − ½ erfc a) + σ0 s e^(−a²)/(√π τ)``
    (no 1/a, positive), so ``S/cos θ = (1 − ½ erfc a)/((1 + Λ) cos θ)``.
    """
    c = min(max(c, 0.0), 1.0)
    if sigma0 <= 0.0:
        return min(1.0 / max(c, _TINY), SHADOW_OVER_COS_CAP)
    s = math.sqrt(max(0.0, (1.0 - c) * (1.0 + c)))
    if s > 0.0:
        a = tau * c / (2.0 * sigma0) / s  # 2σ0·s would underflow to 0 for tiny σ0
        ea = math.exp(-min(a * a, 1e300))
        ec = math.erfc(a)
    else:
        ea = 0.0
        ec = 0.0
    den = c * (1.0 - 0.5 * ec) + sigma0 * s * ea / (_SQRT_PI * tau)
    return min((1.0 - 0.5 * ec) / max(den, _TINY), SHADOW_OVER_COS_CAP)


@jit
def shadowing_c(c, sigma0, tau):
    """Smith shadowing ``S(θ)`` of HTSG eqs. 24–25 (with the e^(−a²) erratum), from cos θ."""
    c = min(max(c, 0.0), 1.0)
    return min(max(shadowing_over_cos_c(c, sigma0, tau) * c, 0.0), 1.0)


@jit
def roughness_K(c, sigma0, tau):
    """``K = tan θ · erfc(τ/(2 σ0 tan θ))`` of eqs. 80–83 (0 at normal incidence)."""
    c = min(max(c, 0.0), 1.0)
    s = math.sqrt(max(0.0, (1.0 - c) * (1.0 + c)))
    t = s / max(c, 1e-150)
    if t > 0.0:
        return t * math.erfc(tau / (2.0 * sigma0) / t)  # 2σ0·t would underflow to 0 for tiny σ0
    return 0.0


@jit
def z0_ratio_squared_c(cos_i, cos_r, sigma0, tau):
    """``(z0/σ0)²`` solving eqs. 80–83: ``x² e^(x²) = (K_i + K_r)²/(8π)``, so ``x² = W((K_i + K_r)²/(8π))``."""
    if sigma0 <= 0.0:
        return 0.0
    kk = roughness_K(cos_i, sigma0, tau) + roughness_K(cos_r, sigma0, tau)
    if kk <= 0.0:
        return 0.0
    return lambertw_log(2.0 * math.log(kk) - _LN_8PI, 5.0)


@jit
def effective_roughness_c(cos_i, cos_r, sigma0, tau):
    """σ = σ0 / sqrt(1 + (z0/σ0)²) of eqs. 80–83 (µm), from the two cosines."""
    return sigma0 / math.sqrt(1.0 + z0_ratio_squared_c(cos_i, cos_r, sigma0, tau))


shadowing_over_cos = vectorize(shadowing_over_cos_c, 3)
shadowing = vectorize(shadowing_c, 3)
z0_ratio_squared = vectorize(z0_ratio_squared_c, 4)
effective_roughness = vectorize(effective_roughness_c, 4)


@jit
def directional_diffuse_channel(lam_nm, eta, k, ks, sigma, tau, vz, vxy2, cos_local, geo):
    """ρ_dd of one channel (eqs. 76–84): ``ks·|F|²·G·S·D/(π cos θi cos θr)`` as

    ``ks · F · geo · (2πσ/λ)² (πτ/(2λ))² · (Σ/g)`` with ``geo = |v|⁴ S_i/ci · S_o/co / π``,
    g = (2πσ/λ)² vz², T = (πτ/λ)² v_xy² (λ in µm).
    """
    lam = lam_nm * 1e-3
    k2 = (2.0 * math.pi * sigma / lam) * (2.0 * math.pi * sigma / lam)
    g = k2 * vz * vz
    T = (math.pi * tau / lam) * (math.pi * tau / lam) * vxy2
    ratio = math.exp(min(log_series_ratio(g, T), 700.0))
    F = f_conductor(cos_local, eta, k)
    q = math.pi * tau / (2.0 * lam)
    # the bounded factors first (ratio may underflow to 0), the large geometric one last
    return (ks * F * k2 * (q * q) * ratio) * geo


@jit
def htsg_kernel(wix, wiy, wiz, wox, woy, woz, p, c):
    """HTSG per pair (engine protocol, :mod:`brdfkit.engine`): ρ_dd + kd/π.

    ``p`` = [sigma0, tau, eta (3), k (3), wavelengths (3), kd (3), ks (3)]; ``c`` unused.
    """
    sigma0 = p[0]
    tau = p[1]
    d0 = p[11] / math.pi
    d1 = p[12] / math.pi
    d2 = p[13] / math.pi
    if sigma0 <= 0.0:
        return d0, d1, d2
    ci = min(max(wiz, 0.0), 1.0)
    co = min(max(woz, 0.0), 1.0)
    vx = wix + wox
    vy = wiy + woy
    vz = ci + co
    vxy2 = vx * vx + vy * vy
    v2 = vxy2 + vz * vz  # |wi + wo|²
    sigma = effective_roughness_c(ci, co, sigma0, tau)
    geo = v2 * v2 * shadowing_over_cos_c(ci, sigma0, tau) * shadowing_over_cos_c(co, sigma0, tau) / math.pi
    cos_local = min(max(0.5 * math.sqrt(v2), 0.0), 1.0)
    return (
        directional_diffuse_channel(p[8], p[2], p[5], p[14], sigma, tau, vz, vxy2, cos_local, geo) + d0,
        directional_diffuse_channel(p[9], p[3], p[6], p[15], sigma, tau, vz, vxy2, cos_local, geo) + d1,
        directional_diffuse_channel(p[10], p[4], p[7], p[16], sigma, tau, vz, vxy2, cos_local, geo) + d2,
    )


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
]
