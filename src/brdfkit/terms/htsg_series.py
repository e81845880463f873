"""The Beckmann–Kirchhoff series of HTSG's directional-diffuse term, ``Σ(g, T)``, in two tiers.

References: X. D. He, K. E. Torrance, F. X. Sillion, D. P. Greenberg, "A Comprehensive Physical Model
for Light Reflection", SIGGRAPH '91 (eq. 78's sum, the model in :mod:`brdfkit.models.htsg`); the series
itself is P. Beckmann's, in P. Beckmann, A. Spizzichino, *The Scattering of Electromagnetic Waves from
Rough Surfaces*, Pergamon 1963 (Kirchhoff's approximation for a Gaussian surface with Gaussian
correlation). The special functions it needs (Lambert W, ln m!, Stirling's series, Loader's deviance)
are in :mod:`brdfkit.terms.special`.

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

**Evaluation in bulk.** The per-pair kernel, :func:`brdfkit.models.htsg.htsg_kernel`, runs the series of
one pair at a time; its loop over m has a length that varies from pair to pair, so LLVM cannot vectorise
across pairs there. The compiled engine runs :func:`brdfkit.models.htsg.htsg_span` instead (with
:func:`span_window` and :func:`span_terms` from here): the same functions composed block by block of
pairs, each step one loop over the block (set-up, the t-th term of every window at once, values), each vectorised across pairs, the windows' terms taken longest window first so that
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
"""

from __future__ import annotations

import math
from fractions import Fraction
from math import comb, factorial

import numpy as np

from ..engine import jit, select, vectorize
from ..engine.llvm_options import SPAN_VECTOR_WIDTH
from .special import (
    HALF_LN_2PI,
    LN_FACT_TIMES_M,
    LN_TABLE_SIZE,
    lambertw_log,
    ln_fact_times_m,
    poisson_deviance,
    stirling_remainder,
)

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

_TINY = 1e-300


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
# The direct sum, and the two tiers
# ---------------------------------------------------------------------------
#: the direct sum takes every h-th term where ``var·(1 − cos(2π/h)) ≥ THIN_MARGIN`` (module docstring)
THIN_MARGIN = 30.0
#: Newton iterations of W for the saddle point (the window's position: m* to 5e-5 relative)
SADDLE_W_ITERATIONS = 2.0


@jit(inline=True)
def log_term(m, lg, g, T):
    """ln of the m-th term of Σ/g, ``(m−1) ln g − g − ln(m!·m) − T/m`` (integer-valued m ≥ 1), as
    ``−ln g − bd0(m, g) − [ln m! − m ln m + m] − ln m − T/m`` (:func:`poisson_deviance`, :func:`stirling_remainder`):
    every part is small, so nothing cancels. Written as the first form, the parts are ~m ln m (up to ~4e4 over
    the parameter range) and their difference a few units: an error of δ in ln g moves it by m·δ."""
    return -lg - poisson_deviance(m, g) - stirling_remainder(m) - 1.5 * math.log(m) - HALF_LN_2PI - T / m


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
    ln(m!·m) read from the table (:data:`brdfkit.terms.special.LN_FACT_TIMES_M`) where the whole window
    lies below its end. Compiled with ``reassociate`` (the terms are positive): LLVM vectorises the sum of
    one pair, 8 terms per vector exp (libmvec, :mod:`brdfkit.engine.vecmath`);
    :func:`brdfkit.models.htsg.htsg_span` sums many pairs at once instead, each in this order."""
    acc = 0.0
    ln_fmc = ln_fact_times_m(mc)
    if mc + jhi * h < LN_TABLE_SIZE:
        k0 = int(mc)
        ih = int(h)
        for j in range(int(jlo), int(jhi) + 1):  # ln(m!·m) read from the table (no branch)
            acc += math.exp(term_rel(mc + j * h, LN_FACT_TIMES_M[k0 + j * ih], mc, ln_fmc, lg, T))
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
# The series in bulk: the pieces of brdfkit.models.htsg.htsg_span
# ---------------------------------------------------------------------------
#: a window of more terms than this is not summed by :func:`span_terms` (its pair's value is then
#: that of an empty sum). Over the whole parameter range the direct sum's window holds at most 86
#: terms (tested: ``test_htsg.py``); more, or a NaN count, only comes of directions that are not unit
#: vectors, which ``eval`` rejects after evaluating: the cap bounds that work and keeps it finite.
WINDOW_CAP = 4096.0


@jit(inline=True)
def span_window(g, T, ok):
    """One channel's series set-up for :func:`brdfkit.models.htsg.htsg_span`, step 1:
    ``(lg, T, base, h, count, mc, ln_fmc, peak, asym)``.

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


# inlined (numba IR) into brdfkit.models.htsg.htsg_span, which only a span driver compiles (under its LLVM
# options): as a function of its own its code was disk-cached by whichever process compiled it first, with or
# without those options (a direct call compiles it without), and then linked into span drivers compiled later
# (a suspected cause of the serial and parallel span drivers' last-bit differences, tests/test_engine.py)
@jit(inline=True)
def span_terms(LG, TT, BASE, H, CNT, MC, LFC, ACC, m, S, order, bins):
    """Sum the windows' terms of one channel into ``ACC[:m]``, the t-th term of the block's ``m`` pairs at once
    (:func:`brdfkit.models.htsg.htsg_span`, step 2), each pair's in the order of :func:`direct_sum`.

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
                x = term_rel(mm, LN_FACT_TIMES_M[min(int(mm), LN_TABLE_SIZE - 1)], SMC[r], SLFC[r], SLG[r], STT[r])
                SACC[r] += select(tf < SCNT[r], math.exp(select(tf < SCNT[r], x, 0.0)), 0.0)
        else:
            for r in range(n):
                mm = SBASE[r] + tf * SH[r]
                x = term_rel(mm, ln_fact_times_m(mm), SMC[r], SLFC[r], SLG[r], STT[r])
                SACC[r] += select(tf < SCNT[r], math.exp(select(tf < SCNT[r], x, 0.0)), 0.0)
    for r in range(m):
        ACC[order[r]] = SACC[r]


__all__ = [
    "ASYMPTOTIC_G",
    "ASYMPTOTIC_ORDER",
    "ASYMPTOTIC_A_SCALE",
    "ASYMPTOTIC_A_POWER",
    "asymptotic_coefficients",
    "asymptotic_log_ratio",
    "asymptotic_tier",
    "direct_window",
    "direct_sum",
    "direct_finish",
    "direct_log_ratio",
    "log_series_ratio",
    "log_term",
    "term_rel",
    "thinning_step",
    "htsg_log_series_ratio",
    "htsg_series",
    "span_window",
    "span_terms",
    "WINDOW_CAP",
    "SORT_BINS",
    "SPAN_LANES",
]
