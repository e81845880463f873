"""Special functions of the HTSG series, written once for both engines (scalar, branch-free where it matters).

Each is a small scalar function decorated with :func:`brdfkit.engine.jit` (the compiled engine compiles it
into the kernels that call it; the reference engine runs this Python source), with an array form where the
tests or the model need one. :mod:`brdfkit.terms.htsg_series` and :mod:`brdfkit.models.htsg` use them; the
GLSL twins are in ``render/shaders/htsg.glsl``.

* :func:`exp_by_halves` — ``e^x`` kept off glibc's slow path for very negative arguments.
* :func:`lambertw_log`, :func:`lambertw_from_log` — Lambert's W (principal branch) of ``z = e^lz``, by
  Newton's method on ``w + ln w = ln z``. R. M. Corless, G. H. Gonnet, D. E. G. Hare, D. J. Jeffrey,
  D. E. Knuth, "On the Lambert W function", Adv. Comput. Math. 5 (1996) 329–359: the defining equation
  ``W e^W = z`` (their eq. 1.5) and the asymptotic start ``ln z − ln ln z`` (their eq. 4.19).
* :func:`stirling_remainder`, :func:`stirling_ln_fact_times_m`, :func:`ln_fact_times_m` — ``ln m!`` and
  ``ln(m!·m)`` for integer-valued m: a table built at import (``math.lgamma``, and a 40-digit decimal
  table of Stirling's remainder), Stirling's series above it (M. Abramowitz, I. A. Stegun, *Handbook of
  Mathematical Functions*, 1964, eq. 6.1.41; the table-plus-series scheme is C. Loader's ``stirlerr``,
  "Fast and accurate computation of binomial probabilities", 2000).
* :func:`poisson_deviance` — Loader's (2000) ``bd0``, ``m ln(m/g) + g − m`` without cancellation.
"""

from __future__ import annotations

import decimal
import math

import numpy as np

from ..engine import jit, select, vectorize

#: ½ ln 2π, the constant of Stirling's formula
HALF_LN_2PI = 0.5 * math.log(2.0 * math.pi)
#: the smallest positive double: ln of it keeps Newton's step finite should W's start round to 0
_W_FLOOR = 5e-324


# ---------------------------------------------------------------------------
# exp without glibc's scalar slow path
# ---------------------------------------------------------------------------
@jit(inline=True)
def exp_by_halves(x):
    """``e^x`` for x ≤ 1400 as ``(e^(x/2))²``, the half's argument kept at or above −700: glibc's vector exp
    redoes an argument below ~−708 (a subnormal or zero result) by a scalar call, lane by lane (measured in a
    compiled loop: 17–77 ns per element against 1.4–1.6 in range). Below −1400 the square is 0, as e^x is
    in doubles (below e^−744.4)."""
    half = math.exp(max(0.5 * x, -700.0))
    return half * half


# ---------------------------------------------------------------------------
# Lambert W (principal branch, real argument z >= 0), given ln z (Corless et al. 1996)
# ---------------------------------------------------------------------------
@jit(inline=True)
def lambertw_log(lz, iterations):
    """W(z) for ``z = exp(lz)`` ≥ 0 (``lz = -inf`` gives 0), without forming z when it would overflow.

    Newton's method on ``h(w) = w + ln w − ln z`` (concave, increasing), started at
    ``ln(1 + z) ≥ W(z)`` for z ≤ e (the first step lands in (0, W(z)]) and at
    ``ln z − ln ln z ≤ W(z)`` for z > e; from the left Newton converges monotonically and
    quadratically. 5 iterations reach machine precision for every ``lz`` in [-700, 1e300]
    (tested); below −700, W(z) = z to double precision. Both starts and the small-z value are
    computed for every ``lz`` and the right one selected (no branch around a math call: a loop
    over pairs calling this vectorises, :func:`brdfkit.models.htsg.htsg_span`); each math call's argument is kept
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
# ln m! and ln(m!·m): a table, and Stirling's series above it
# ---------------------------------------------------------------------------
#: ln(m!·m) is tabulated for m below this (the HTSG series' direct sum needs no lgamma there)
LN_TABLE_SIZE = 32768
#: ln(m!·m) for m = 0..LN_TABLE_SIZE − 1 (m = 0 unused), from ``math.lgamma``
LN_FACT_TIMES_M = np.array([0.0] + [math.lgamma(m + 1.0) + math.log(m) for m in range(1, LN_TABLE_SIZE)])
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
    return (m + 1.5) * math.log(m) - m + HALF_LN_2PI + stirling_remainder(m)


@jit(inline=True)
def ln_fact_times_m(m):
    """``ln(m!·m)`` for an integer-valued m ≥ 1: :data:`LN_FACT_TIMES_M` below LN_TABLE_SIZE, Stirling's series
    above (both computed, one selected: no branch, no libm lgamma, so a loop over it vectorises)."""
    return select(m < LN_TABLE_SIZE, LN_FACT_TIMES_M[min(int(m), LN_TABLE_SIZE - 1)], stirling_ln_fact_times_m(m))


# ---------------------------------------------------------------------------
# The Poisson deviance (Loader's bd0)
# ---------------------------------------------------------------------------
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


__all__ = [
    "HALF_LN_2PI",
    "exp_by_halves",
    "lambertw_log",
    "lambertw_from_log",
    "LN_TABLE_SIZE",
    "LN_FACT_TIMES_M",
    "STIRLING_SERIES_FROM",
    "stirling_remainder",
    "stirling_ln_fact_times_m",
    "ln_fact_times_m",
    "DEVIANCE_SERIES",
    "poisson_deviance",
]
