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
  ``exp((m − m_c)(ln g + T/(m·m_c)) − [ln(m!·m) − ln(m_c!·m_c)])``, with ln(m!·m) from a
  table built at import (m < 32768, which holds every window over the parameter range; Stirling's
  series above), so nothing overflows and the loop over m is a reduction of independent terms; the
  peak's own term is computed without cancellation ("Evaluation in bulk" below). **Thinning:** where the peak is wide, only every h-th
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

**Evaluation in bulk.** The per-pair kernel, :func:`htsg_kernel`, runs the series of one pair
at a time; its loop over m has a length that varies from pair to pair, so LLVM cannot vectorise
across pairs there. The compiled engine runs :func:`htsg_span` instead: the same functions composed
block by block of pairs, each step one loop over the block (set-up, the t-th term of every window at
once, values), each vectorised across pairs, the windows' terms taken longest window first so that
a term is computed only for the pairs that have one; the choices inside the functions are
:func:`brdfkit.engine.select` (no branch around a math call). Its math functions are the vector math
library's (4 ulp), which the value must not amplify: the peak's term ``(m−1) ln g − g − ln(m!·m) −
T/m`` is a difference of numbers of ~m ln m (up to ~4e4) and would carry m times the error of ln g;
it is computed instead as ``−ln g − bd0(m, g) − [ln m! − m ln m + m] − ln m − T/m`` with Loader's
deviance ``bd0`` (:func:`poisson_deviance`, :func:`stirling_remainder`), whose parts are all small,
and the other terms relative to it (:func:`term_rel`). The two engines agree to 1e-12 (measured:
≤ 2.3e-13 over 48 × 1500 random pairs and random parameters, tails included; the old form with the
vector library's ln g differed by 1.4e-11 far in the tail).

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

import decimal
import math
from fractions import Fraction
from math import comb, factorial

import numpy as np

from ..engine import jit, select, vectorize
from ..engine.driver import SPAN_VECTOR_WIDTH
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
_HALF_LN_2PI = 0.5 * math.log(2.0 * math.pi)
_TINY = 1e-300
#: cap on S(θ)/cos θ: reached only for cos θ < 1e-150 with σ0 below ~1e-150 (no shadowing left to
#: cancel the 1/cos); with it the product S_i S_o |v|⁴/(cos θi cos θr) stays finite, never 0·∞
SHADOW_OVER_COS_CAP = 1e150
_LN_8PI = math.log(8.0 * math.pi)
#: the smallest positive double: ln of it keeps Newton's step finite should W's start round to 0
_W_FLOOR = 5e-324


# ---------------------------------------------------------------------------
# Lambert W (principal branch, real argument z >= 0), given ln z
# ---------------------------------------------------------------------------
@jit(inline=True)
def exp_by_halves(x):
    """``e^x`` for x ≤ 1400 as ``(e^(x/2))²``, the half's argument kept at or above −700: glibc's vector exp
    redoes an argument below ~−708 (a subnormal or zero result) by a scalar call, lane by lane (measured in a
    compiled loop: 17–77 ns per element against 1.4–1.6 in range). Below −1400 the square is 0, as e^x is
    in doubles (below e^−744.4)."""
    half = math.exp(max(0.5 * x, -700.0))
    return half * half


@jit(inline=True)
def lambertw_log(lz, iterations):
    """W(z) for ``z = exp(lz)`` ≥ 0 (``lz = -inf`` gives 0), without forming z when it would overflow.

    Newton's method on ``h(w) = w + ln w − ln z`` (concave, increasing), started at
    ``ln(1 + z) ≥ W(z)`` for z ≤ e (the first step lands in (0, W(z)]) and at
    ``ln z − ln ln z ≤ W(z)`` for z > e; from the left Newton converges monotonically and
    quadratically. 5 iterations reach machine precision for every ``lz`` in [-700, 1e300]
    (tested); below −700, W(z) = z to double precision. Both starts and the small-z value are
    computed for every ``lz`` and the right one selected (no branch around a math call: a loop
    over pairs calling this vectorises, :func:`htsg_span`); each math call's argument is kept
    in its domain, so the discarded ones stay finite.
    """
    z = max(lz, -700.0)  # below, the small-z value is selected: the iteration runs on finite numbers
    big = max(z, 1.0)
    w = select(z <= 1.0, math.log1p(math.exp(min(z, 1.0))), big - math.log(big))
    for _ in range(int(iterations)):
        w = w - (w + math.log(max(w, _W_FLOOR)) - z) * w / (w + 1.0)
    return select(lz < -700.0, exp_by_halves(min(lz, -700.0)), w)  # W(z) = z below


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


@jit(inline=True)
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
LN_TABLE_SIZE = 32768
_LN_FACT_M = np.array([0.0] + [math.lgamma(m + 1.0) + math.log(m) for m in range(1, LN_TABLE_SIZE)])
#: the direct sum takes every h-th term where ``var·(1 − cos(2π/h)) ≥ THIN_MARGIN`` (module docstring)
THIN_MARGIN = 30.0
#: Newton iterations of W for the saddle point (the window's position: m* to 5e-5 relative)
SADDLE_W_ITERATIONS = 2.0


#: :func:`stirling_remainder` sums Stirling's series from this m on (below, a table)
STIRLING_SERIES_FROM = 64


def _stirling_remainders(n: int) -> np.ndarray:
    """``ln m! − (m + ½) ln m + m − ½ ln 2π`` for m = 0..n−1 (0 unused) in 40-digit decimal arithmetic, each
    rounded once to a double."""
    out = np.zeros(n)
    with decimal.localcontext() as ctx:
        ctx.prec = 40
        D = decimal.Decimal
        half_ln_2pi = (D(2) * D("3.141592653589793238462643383279502884197")).ln() / 2
        lnfact = D(0)
        for m in range(1, n):
            lnm = D(m).ln()
            lnfact += lnm
            out[m] = float(lnfact - (D(m) + D("0.5")) * lnm + D(m) - half_ln_2pi)
    return out


#: Stirling's remainder below STIRLING_SERIES_FROM, where its series does not converge fast enough
_STIRLERR_SMALL = _stirling_remainders(STIRLING_SERIES_FROM)


@jit(inline=True)
def stirling_remainder(m):
    """``ln m! − [(m + ½) ln m − m + ½ ln 2π]`` for an integer-valued m ≥ 1: small (1/(12m)), so it keeps its
    accuracy where ln m! would not. A table below :data:`STIRLING_SERIES_FROM`, Stirling's series from there (terms
    to 1/(1188 m⁹); the next, 691/(360360 m¹¹), is below 3e-23 there)."""
    x = max(m, STIRLING_SERIES_FROM)
    r = 1.0 / (x * x)
    series = (1.0 / 12.0 - r * (1.0 / 360.0 - r * (1.0 / 1260.0 - r * (1.0 / 1680.0 - r * (1.0 / 1188.0))))) / x
    return select(m < STIRLING_SERIES_FROM, _STIRLERR_SMALL[min(int(m), STIRLING_SERIES_FROM - 1)], series)


@jit(inline=True)
def stirling_ln_fact_times_m(m):
    """``ln(m!·m) = (m + 3/2) ln m − m + ½ ln 2π + stirling_remainder(m)`` (Stirling's formula with its
    remainder, :func:`stirling_remainder`), for m at and above LN_TABLE_SIZE."""
    return (m + 1.5) * math.log(m) - m + _HALF_LN_2PI + stirling_remainder(m)


@jit(inline=True)
def ln_fact_times_m(m):
    """``ln(m!·m)`` for an integer-valued m ≥ 1: the module table below LN_TABLE_SIZE, Stirling's series
    above (both computed, one selected: no branch, no libm lgamma, so a loop over it vectorises)."""
    return select(m < LN_TABLE_SIZE, _LN_FACT_M[min(int(m), LN_TABLE_SIZE - 1)], stirling_ln_fact_times_m(m))


#: :func:`poisson_deviance` sums its series where ``|m − g| < DEVIANCE_SERIES·(m + g)``
DEVIANCE_SERIES = 0.25


@jit(inline=True)
def poisson_deviance(m, g):
    """``m ln(m/g) + g − m`` ≥ 0 (m ≥ 1, g > 0) without cancellation (C. Loader, "Fast and accurate computation
    of binomial probabilities", 2000: its ``bd0``). With ``v = (m − g)/(m + g)``, ``ln(m/g) = 2 atanh v``
    gives ``(m − g)·v + 2m·v³·(1/3 + v²/5 + … + v²⁶/29)`` for |v| < :data:`DEVIANCE_SERIES` (the next term is
    below 2e-18 of it), and the plain form elsewhere (where its two parts cancel by at most a factor 5). The
    GLSL twin writes it as ``m·htsg_phi((g − m)/m)``, ``φ(x) = x − log1p(x)``, the same series in float32.
    Both are computed, one selected (no branch)."""
    d = m - g
    v = d / (m + g)
    v2 = v * v
    tail = 1.0 / 29.0
    for k in (27.0, 25.0, 23.0, 21.0, 19.0, 17.0, 15.0, 13.0, 11.0, 9.0, 7.0, 5.0, 3.0):
        tail = tail * v2 + 1.0 / k
    series = d * v + 2.0 * m * v * v2 * tail
    plain = m * math.log(m / g) + g - m
    return select(abs(v) < DEVIANCE_SERIES, series, plain)


@jit(inline=True)
def log_term(m, lg, g, T):
    """ln of the m-th term of Σ/g, ``(m−1) ln g − g − ln(m!·m) − T/m`` (integer-valued m ≥ 1), as
    ``−ln g − bd0(m, g) − [ln m! − m ln m + m] − ln m − T/m`` (:func:`poisson_deviance`, :func:`stirling_remainder`):
    every part is small, so nothing cancels. Written as the first form, the parts are ~m ln m (up to ~4e4 over
    the parameter range) and their difference a few units: an error of δ in ln g moves it by m·δ."""
    return -lg - poisson_deviance(m, g) - stirling_remainder(m) - 1.5 * math.log(m) - _HALF_LN_2PI - T / m


@jit(inline=True)
def term_rel(m, ln_fm, mc, ln_fmc, lg, T):
    """ln of the m-th term of Σ/g relative to the mc-th: ``(m − mc)·(ln g + T/(m·mc)) − [ln(m!·m) − ln(mc!·mc)]``,
    with ``ln_fm = ln(m!·m)`` and ``ln_fmc = ln(mc!·mc)`` given (the table's values, or :func:`ln_fact_times_m`).
    An error of δ in ln g moves it by (m − mc)·δ: for the terms that count, a few σ_m."""
    return (m - mc) * (lg + T / (m * mc)) - (ln_fm - ln_fmc)


@jit(inline=True)
def thinning_step(var, edge):
    """The step h of the direct sum: the largest integer with ``var·(1 − cos(2π/h)) ≥ THIN_MARGIN``.

    ``var`` is the summand's variance σ_m², ``edge`` the log of its m = 1 term relative to the
    peak's. h = 1 (every term) unless the summand is negligible at m = 1 (``edge < −THIN_MARGIN``):
    cut off there, it is not a smooth peak and the lattice argument of the module docstring
    does not hold. (The arc cosine is taken for every var, of an argument kept in [−1, 1).)
    """
    x = 1.0 - THIN_MARGIN / max(var, 0.5 * THIN_MARGIN)
    step = max(math.floor(2.0 * math.pi / math.acos(x)), 1.0)
    return select(edge > -THIN_MARGIN or 2.0 * var <= THIN_MARGIN, 1.0, step)


@jit(inline=True)
def direct_window(g, T, lg):
    """The direct sum's window for g > 0, T ≥ 0 and ``lg = ln g``: ``(mc, h, jlo, jhi, peak)``.

    The terms are m = mc + j·h for j in [jlo, jhi] (every h-th, :func:`thinning_step`), around the
    saddle point m* = g exp(W(2T/g²)/2) (width σ_m = (1/m* + 2T/m*³)^(−1/2)); ``peak`` is ln of the
    term at ``m_c = round(m*)`` (:func:`log_term`, where ``lg = ln g`` only adds). Branch-free (a loop over
    pairs vectorises)."""
    w = lambertw_log(math.log(max(2.0 * T, _TINY)) - 2.0 * lg, SADDLE_W_ITERATIONS)  # not used for T = 0
    mstar = max(g * math.exp(0.5 * select(T > 0.0, w, 0.0)), 1.0)
    var = 1.0 / (1.0 / mstar + 2.0 * T / (mstar * mstar * mstar))
    sig = math.sqrt(max(var, 0.0))
    lo = max(math.floor(mstar - WINDOW_LEFT[0] * sig - WINDOW_LEFT[1]), 1.0)
    hi = math.ceil(mstar + WINDOW_RIGHT[0] * sig + WINDOW_RIGHT[1])
    mc = min(max(math.floor(mstar + 0.5), lo), hi)
    peak = log_term(mc, lg, g, T)
    h = thinning_step(var, -g - T - peak)  # log_term(1) = −g − T
    jlo = -math.floor((mc - lo) / h)
    jhi = math.floor((hi - mc) / h)
    return mc, h, jlo, jhi, peak


@jit(reassociate=True)
def direct_sum(lg, T, mc, h, jlo, jhi):
    """Σ_j exp(ln t_m − ln t_mc) over the window of :func:`direct_window`, in order of j.

    Each term is relative to the peak's (:func:`term_rel`: nothing overflows or underflows near it), with
    ln(m!·m) read from the module table where the whole window lies below its end. Compiled with
    ``reassociate`` (the terms are positive): LLVM vectorises the sum of one pair, 8 terms per
    vector exp (libmvec, :mod:`brdfkit.engine.vecmath`); :func:`htsg_span` sums many pairs at
    once instead, each in this order."""
    acc = 0.0
    ln_fmc = ln_fact_times_m(mc)
    if mc + jhi * h < LN_TABLE_SIZE:
        k0 = int(mc)
        ih = int(h)
        for j in range(int(jlo), int(jhi) + 1):  # ln(m!·m) read from the table (no branch)
            acc += math.exp(term_rel(mc + j * h, _LN_FACT_M[k0 + j * ih], mc, ln_fmc, lg, T))
    else:
        for j in range(int(jlo), int(jhi) + 1):
            m = mc + j * h
            acc += math.exp(term_rel(m, ln_fact_times_m(m), mc, ln_fmc, lg, T))
    return acc


@jit(inline=True)
def direct_finish(peak, h, acc):
    """ln(Σ/g) from the window's peak, step and sum: ``peak + ln(h·acc)`` (acc ≥ 1: the peak's own term)."""
    return peak + math.log(max(h * acc, _TINY))


@jit
def direct_log_ratio(g, T):
    """ln(Σ/g) by the windowed direct sum (g > 0, T ≥ 0): :func:`direct_window`, :func:`direct_sum`,
    :func:`direct_finish` (module docstring, "The series")."""
    lg = math.log(g)
    mc, h, jlo, jhi, peak = direct_window(g, T, lg)
    return direct_finish(peak, h, direct_sum(lg, T, mc, h, jlo, jhi))


@jit(inline=True)
def asymptotic_tier(g, T):
    """Whether ln(Σ/g) at (g, T) is taken from the asymptotic form (g ≥ 40, a = T/g ≤ 0.5 g^0.55)."""
    return g >= ASYMPTOTIC_G and T / g <= ASYMPTOTIC_A_SCALE * math.exp(ASYMPTOTIC_A_POWER * math.log(g))


@jit
def log_series_ratio(g, T):
    """``ln(Σ(g, T)/g)`` (finite for g ≥ 0, T ≥ 0; g = 0 gives −T, the limit): the two tiers."""
    g = max(g, _TINY)
    T = max(T, 0.0)
    if asymptotic_tier(g, T):
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
#: a window of more terms than this is not summed by :func:`htsg_span` (its pair's value is then
#: that of an empty sum). Over the whole parameter range the direct sum's window holds at most 86
#: terms (tested: ``test_htsg.py``); more, or a NaN count, only comes of directions that are not unit
#: vectors, which ``eval`` rejects after evaluating: the cap bounds that work and keeps it finite.
WINDOW_CAP = 4096.0


@jit(inline=True)
def span_channel(lam_nm, eta, k, ks, sigma, tau, vz, vxy2, cl):
    """One channel's ``(g, T, weight)`` for :func:`htsg_span`, step 1: g and T as :func:`log_series_ratio`
    takes them (:func:`channel_gT`), and ``weight = ks·F·scale`` (:func:`channel_value`)."""
    g, T, scale = channel_gT(lam_nm, sigma, tau, vz, vxy2)
    return max(g, _TINY), max(T, 0.0), ks * f_conductor(cl, eta, k) * scale


@jit(inline=True)
def span_window(g, T, ok):
    """One channel's series set-up for :func:`htsg_span`, step 1: ``(lg, T, base, h, count, mc, ln_fmc, peak,
    asym)``.

    The direct sum's window (:func:`direct_window`) as its first term ``base``, step ``h``, ``count`` of
    terms (0 where nothing is to be summed: the pair is below the horizon, the asymptotic form applies, or the
    count is beyond :data:`WINDOW_CAP`; such a pair's other numbers are replaced by harmless values, its
    terms being masked), its peak's ``mc`` and ``ln(mc!·mc)``, and the asymptotic form's ln(Σ/g) where it
    applies (NaN elsewhere)."""
    lg = math.log(g)
    asym = asymptotic_tier(g, T)
    av = asymptotic_log_ratio(max(g, ASYMPTOTIC_G), T)
    mc, h, jlo, jhi, peak = direct_window(g, T, lg)
    count = jhi - jlo + 1.0
    live = ok and not asym and count <= WINDOW_CAP  # False for a NaN count
    mc = select(live, mc, 1.0)
    return (select(live, lg, 0.0), select(live, T, 0.0), select(live, mc + jlo * h, 1.0), select(live, h, 1.0),
            select(live, count, 0.0), mc, ln_fact_times_m(mc), select(live, peak, 0.0), select(asym, av, math.nan))


#: :func:`span_terms` runs the loop over pairs to a multiple of this many, the surplus lanes masked, so it has
#: no scalar remainder: the span drivers' vector width on AVX-512 (8 doubles; on AVX2 the cost model's 2 × 4)
SPAN_LANES = SPAN_VECTOR_WIDTH
#: :func:`span_terms` sorts the counts 0 .. SORT_BINS − 1 (every window over the parameter range: at most 86)
SORT_BINS = 128


# inlined (numba IR) into htsg_span, which only a span driver compiles (under its LLVM options): as a function of
# its own its code was disk-cached by whichever process compiled it first, with or without those options (a
# direct call compiles it without), and then linked into span drivers compiled later (a suspected cause of the
# serial and parallel span drivers' last-bit differences, tests/test_engine.py)
@jit(inline=True)
def span_terms(LG, TT, BASE, H, CNT, MC, LFC, ACC, m, S, order, bins):
    """Sum the windows' terms of one channel into ``ACC[:m]``, the t-th term of the block's ``m`` pairs at once
    (:func:`htsg_span`, step 2), each pair's in the order of :func:`direct_sum`.

    The pairs are taken longest window first (a counting sort of the counts, up to :data:`SORT_BINS` − 1 and
    those above in any order, the numbers copied into the scratch ``S``, ``order`` an integer scratch): at the
    t-th term only a prefix of them has one, and the loop over pairs stops there (rounded up to
    :data:`SPAN_LANES`, the lanes past it masked; a pair is left out only once its count is at most t, so the
    sums do not depend on the order). Windows vary from 1 to ~86 terms, so in the order of
    the pairs every term was computed for as many pairs as the block's longest window has terms (47 for an
    average of 31 at the default parameters, 55 for 14 at σ0 = 0.8); each pair's own sum is the same."""
    nb = S.shape[1]
    bins[:] = 0
    for i in range(m):
        bins[min(int(CNT[i]), SORT_BINS - 1)] += 1
    start = 0
    for b in range(SORT_BINS - 1, -1, -1):  # bins[b]: where count b's pairs start, longest first
        c = bins[b]
        bins[b] = start
        start += c
    for i in range(m):
        b = min(int(CNT[i]), SORT_BINS - 1)
        order[bins[b]] = i
        bins[b] += 1
    S[:, m:] = 0.0  # past m: a harmless, empty window (BASE, H, MC 1)
    S[2, m:] = 1.0
    S[3, m:] = 1.0
    S[5, m:] = 1.0
    S[7, :] = 0.0  # the sums
    table = True  # every window within the ln(m!·m) table
    for r in range(m):
        i = order[r]
        S[0, r] = LG[i]
        S[1, r] = TT[i]
        S[2, r] = BASE[i]
        S[3, r] = H[i]
        S[4, r] = CNT[i]
        S[5, r] = MC[i]
        S[6, r] = LFC[i]
        table = table and BASE[i] + (CNT[i] - 1.0) * H[i] < LN_TABLE_SIZE
    SLG, STT, SBASE, SH, SCNT, SMC, SLFC, SACC = S[0], S[1], S[2], S[3], S[4], S[5], S[6], S[7]
    live = m
    for t in range(int(SCNT[0]) if m > 0 else 0):
        tf = float(t)
        while live > 0 and SCNT[live - 1] <= tf:
            live -= 1
        n = min(-(-live // SPAN_LANES) * SPAN_LANES, nb)
        if table:
            for r in range(n):
                mm = SBASE[r] + tf * SH[r]
                x = term_rel(mm, _LN_FACT_M[min(int(mm), LN_TABLE_SIZE - 1)], SMC[r], SLFC[r], SLG[r], STT[r])
                SACC[r] += select(tf < SCNT[r], math.exp(select(tf < SCNT[r], x, 0.0)), 0.0)
        else:
            for r in range(n):
                mm = SBASE[r] + tf * SH[r]
                x = term_rel(mm, ln_fact_times_m(mm), SMC[r], SLFC[r], SLG[r], STT[r])
                SACC[r] += select(tf < SCNT[r], math.exp(select(tf < SCNT[r], x, 0.0)), 0.0)
    for r in range(m):
        ACC[order[r]] = SACC[r]


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
