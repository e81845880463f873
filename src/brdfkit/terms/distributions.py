"""Microfacet normal distributions D(h) and their Smith Λ functions.

Everything here works in the local shading frame (normal ``+z``, tangent ``+x``,
SPEC.md). Vector arguments (``h``, ``w``) have shape ``(..., 3)`` and need not be
exactly unit length only where stated; roughness arguments are scalars or arrays
that broadcast against ``h[..., 0]``. Results have shape ``h.shape[:-1]`` and the
dtype of the inputs (float32 stays float32). Roughness must be > 0.

Distributions
-------------
* :func:`beckmann_cook` — the Beckmann distribution exactly as Cook & Torrance
  (1982, eq. 4) and the lecture write it, **without** a 1/π::

      D = exp(−(tan α / m)²) / (m² cos⁴ α)

  (α the angle between n and h, m the RMS slope). It integrates to
  ``∫ D (n·h) dω_h = π``; the Cook-Torrance formula's ``F/π`` supplies the 1/π.

* :func:`beckmann` — the normalised Beckmann distribution (Walter et al. 2007,
  eq. 25; anisotropic form e.g. Heitz 2014, eq. 71)::

      D(h) = exp(−(h_x²/α_x² + h_y²/α_y²)/h_z²) / (π α_x α_y h_z⁴)

  with ``∫ D(h) (n·h) dω_h = 1``. ``normalized=False`` drops the 1/π (for
  α_x = α_y = m this is :func:`beckmann_cook`).

* :func:`ggx` — GGX / Trowbridge-Reitz (Trowbridge & Reitz 1975; Walter et al.
  2007, eq. 33; anisotropic form Heitz 2014, eq. 85)::

      D(h) = 1 / (π α_x α_y (h_x²/α_x² + h_y²/α_y² + h_z²)²)

Smith Λ (Heitz 2014, "Understanding the masking-shadowing function in
microfacet-based BRDFs", §5.1-5.2; Walter et al. 2007, eqs. 27, 34)
----------------------------------------------------------------------
With the projected roughness of a direction ``w`` (θ its polar angle, φ its
azimuth) ``α(w)² = α_x² cos²φ + α_y² sin²φ``, so that
``α(w) tan θ = sqrt(w_x² α_x² + w_y² α_y²) / w_z``:

* Beckmann, exact: ``a = 1/(α(w) tan θ)``,
  ``Λ = (erf(a) − 1)/2 + exp(−a²)/(2 a √π)``
* GGX, exact: ``Λ = (−1 + sqrt(1 + α(w)² tan² θ))/2``

``Λ = 0`` at normal incidence (tan θ = 0) and ``Λ → ∞`` at the horizon, where
the Smith masking ``G1 = 1/(1 + Λ)`` (see :mod:`brdfkit.terms.shadowing`) goes
to 0. Both are evaluated in forms that do not cancel catastrophically and
never produce NaN: Beckmann via ``erfc``, GGX as
``s² / (2 w_z (sqrt(w_z² + s²) + w_z))`` with ``s = sqrt(w_x² α_x² + w_y² α_y²)``.

Numerics of D
-------------
The exponent ``tan²θ/α²`` can be huge (small α, grazing h) while ``cos⁴θ``
underflows; the scalar sources compute in float64 and return 0 where ``h_z⁴``
underflows (the exponential is 0 there already), so D is never ``0/0`` or
``inf/inf``, for float32 as for float64 results. For ``h_z <= 0`` every D here
returns 0.

One source per formula
----------------------
Each formula is written once, as a scalar function in component form
(``d_ggx(hx, hy, hz, ax, ay)``, ``lambda_beckmann(wx, wy, wz, ax, ay)``),
compiled by :func:`brdfkit.engine.jit` and called by the model kernels; the
array functions (``ggx(h, ax, ay)``, ``beckmann_lambda(w, ax, ay)``, ...) are
thin wrappers that apply the same scalar source element-wise
(:class:`brdfkit.engine.vectorize`). They return the dtype of the direction
argument (float32 stays float32: computed in float64, rounded once).
"""

from __future__ import annotations

import math

import numpy as np

from ..engine import jit, vectorize
from ..geometry import NORMAL_MIN

_SQRT_PI = math.sqrt(math.pi)

# ------------------------------------------------------------ scalar sources


@jit
def slope2(hx, hy, ax, ay):
    """``h_x²/α_x² + h_y²/α_y²`` (= tan²θ_h/α(h)² · h_z²)."""
    u = hx * (1.0 / ax)  # a reciprocal of the constant roughness (hoisted out of a loop), not a division per pair
    v = hy * (1.0 / ay)
    return u * u + v * v


@jit
def d_beckmann_slopes(hx, hy, hz, ax, ay):
    """Beckmann D without the 1/π: ``exp(−(h_x²/α_x² + h_y²/α_y²)/h_z²) / (α_x α_y h_z⁴)``.

    Cook & Torrance (1982, eq. 4) for α_x = α_y = m. 0 for ``h_z <= 0``, and 0
    where the denominator ``α_x α_y h_z⁴`` underflows (the exponential has underflowed
    long before: for α ≤ 1 and h_z < 1e-70, e > 1e140), so never 0/0. The test is on
    the whole denominator, not on ``h_z⁴`` alone: in the float32 twin ``h_z⁴`` of a
    grazing half vector (h_z ~ 5e-12) is a subnormal that ``α_x α_y`` then rounds to 0
    (issue 31: NaN at z = 1e-12).
    """
    hz2 = hz * hz
    den = ax * ay * (hz2 * hz2)
    if hz <= 0.0 or den <= 0.0:
        return 0.0
    e = slope2(hx, hy, ax, ay) / hz2
    return math.exp(-e) / den


@jit
def d_beckmann(hx, hy, hz, ax, ay):
    """Normalised Beckmann D (Walter et al. 2007, eq. 25; anisotropic: Heitz 2014, eq. 71)."""
    return d_beckmann_slopes(hx, hy, hz, ax, ay) / math.pi


@jit
def d_beckmann_cook(cos_h, m):
    """Cook & Torrance's (1982, eq. 4) ``exp(−(tan α/m)²)/(m² cos⁴α)`` from ``cos α``; 0 for ``cos α <= 0``."""
    c = min(cos_h, 1.0)
    c2 = c * c
    den = m * m * (c2 * c2)
    if c <= 0.0 or den <= 0.0:
        return 0.0  # the exponential has underflowed long before m² cos⁴α does (m ≤ 1)
    t2 = (1.0 - c2) / c2
    return math.exp(-t2 / (m * m)) / den


@jit
def d_ggx(hx, hy, hz, ax, ay):
    """GGX / Trowbridge-Reitz ``1/(π α_x α_y (h_x²/α_x² + h_y²/α_y² + h_z²)²)`` (Walter 2007, eq. 33; Heitz 2014, eq. 85)."""
    if hz <= 0.0:
        return 0.0
    q = slope2(hx, hy, ax, ay) + hz * hz  # >= 1 for a unit h and α <= 1
    den = math.pi * ax * ay * q * q
    if den <= 0.0:
        return math.inf  # only for a non-unit, vanishing h (never from a kernel)
    return 1.0 / den


@jit
def projected_slope2(wx, wy, ax, ay):
    """``s² = w_x² α_x² + w_y² α_y²`` (the square of :func:`projected_slope`, without its sqrt)."""
    u = wx * ax
    v = wy * ay
    return u * u + v * v


@jit
def projected_slope(wx, wy, ax, ay):
    """``s = sqrt(w_x² α_x² + w_y² α_y²)``, so that ``α(w) tan θ = s / w_z`` (Heitz 2014, eq. 80)."""
    u = wx * ax
    v = wy * ay
    return math.sqrt(u * u + v * v)


@jit
def lambda_floor(wz):
    """``w_z`` for Smith's Λ: a subnormal ``w_z`` (below 2.2e-308; 1.2e-38 in a float32 twin) raised to the
    smallest normal number. Λ ~ α(w)/(2 w_z) (GGX; Beckmann's is √π smaller) grows without bound as
    w_z → 0, and so does its derivative with respect to α: from a subnormal w_z both overflowed, and
    ``G = 1/(1 + Λi + Λo)``'s derivative came out as inf·0 = NaN (issue 31's gradients). With the floor
    Λ and its derivative stay below 2.3e307 (float32: 4.3e37) for α ≤ 1, twice that summed; the value
    changes only where G1 ≈ 1/Λ is already at the bottom of the float range. ``w_z <= 0`` passes through
    (Λ = +inf there)."""
    return max(wz, NORMAL_MIN) if wz > 0.0 else wz


@jit
def lambda_beckmann(wx, wy, wz, ax, ay):
    """Exact Smith Λ of Beckmann: ``a = w_z/s``, ``Λ = (exp(−a²)/(a√π) − erfc(a))/2`` (Walter 2007, eq. 27; Heitz 2014, eq. 72).

    0 at normal incidence (s = 0), +inf for ``w_z <= 0``, never NaN or negative. A subnormal ``w_z``
    counts as the smallest normal number (:func:`lambda_floor`).
    """
    wz = lambda_floor(wz)
    s = projected_slope(wx, wy, ax, ay)
    # computed for every direction, the cases selected after (no branch around erfc: a loop over
    # this function vectorises, erfc included, see brdfkit.engine.vecmath); guarded divisions
    a = wz / (s if s > 0.0 else 1.0)
    den = a * _SQRT_PI
    lam = max(0.5 * (math.exp(-a * a) / (den if den > 0.0 else 1.0) - math.erfc(a)), 0.0)
    lam = math.inf if den <= 0.0 else lam  # a underflowed (w_z ~ 5e-324): fully masked, G1 = 0
    lam = 0.0 if s <= 0.0 else lam
    return math.inf if wz <= 0.0 else lam


@jit
def lambda_ggx_parts(wx, wy, wz, ax, ay):
    """``(num, den)`` with the GGX Smith ``Λ = num/den = s²/(2 w_z (sqrt(w_z² + s²) + w_z))`` (Walter 2007, eq. 34).

    The ratio left undivided, so that a caller forming ``G1 = 1/(1 + Λ) = den/(den + num)`` (or a
    product of two) divides once (a division is the costliest instruction of a vectorised kernel).
    ``den >= 0``; ``den = 0`` (``w_z <= 0``, or an underflow at ``w_z ~ 5e-324``) means Λ = +inf.
    """
    if wz <= 0.0:
        return 1.0, 0.0
    s2 = projected_slope2(wx, wy, ax, ay)
    return s2, max(2.0 * wz * (math.sqrt(wz * wz + s2) + wz), 0.0)


@jit
def lambda_ggx(wx, wy, wz, ax, ay):
    """Exact Smith Λ of GGX, ``(−1 + sqrt(1 + s²/w_z²))/2`` as ``s²/(2 w_z (sqrt(w_z² + s²) + w_z))`` (Walter 2007, eq. 34).

    0 at normal incidence, +inf for ``w_z <= 0``; no cancellation. A subnormal ``w_z`` counts as the
    smallest normal number (:func:`lambda_floor`).
    """
    num, den = lambda_ggx_parts(wx, wy, lambda_floor(wz), ax, ay)
    if den <= 0.0:
        return math.inf  # below the horizon, or the denominator underflowed: fully masked, G1 = 0
    return num / den


#: ``distribution`` choice indices used by the kernels (the order of microfacet's ``choices``)
BECKMANN = 0
GGX = 1


@jit(inline=True)
def d_of(dist, hx, hy, hz, ax, ay):
    """The normalised D of distribution index ``dist`` (:data:`BECKMANN` or :data:`GGX`)."""
    if dist == 0:
        return d_beckmann(hx, hy, hz, ax, ay)
    return d_ggx(hx, hy, hz, ax, ay)


@jit(inline=True)
def lambda_of(dist, wx, wy, wz, ax, ay):
    """The Smith Λ of distribution index ``dist``."""
    if dist == 0:
        return lambda_beckmann(wx, wy, wz, ax, ay)
    return lambda_ggx(wx, wy, wz, ax, ay)


# ------------------------------------------------------ array API (wrappers)

_v_beckmann = vectorize(d_beckmann, 5)
_v_beckmann_slopes = vectorize(d_beckmann_slopes, 5)
_v_beckmann_cook = vectorize(d_beckmann_cook, 2)
_v_ggx = vectorize(d_ggx, 5)
_v_slope = vectorize(projected_slope, 4)
_v_lambda_beckmann = vectorize(lambda_beckmann, 5)
_v_lambda_ggx = vectorize(lambda_ggx, 5)


def _dtype_of(x):
    """Working dtype: float32 for float32 input, float64 otherwise (roughness follows)."""
    x = np.asarray(x)
    return np.dtype(np.float32) if x.dtype == np.float32 else np.dtype(np.float64)


def _split(h, alpha_x, alpha_y):
    h = np.asarray(h)
    dt = _dtype_of(h)
    ax = np.asarray(alpha_x, dtype=np.float64)
    ay = ax if alpha_y is None else np.asarray(alpha_y, dtype=np.float64)
    return h[..., 0], h[..., 1], h[..., 2], ax, ay, dt


def beckmann(h, alpha_x, alpha_y=None, normalized=True):
    """Beckmann distribution D(h) of local half vectors ``h`` (unit, ``(..., 3)``).

    ``D = exp(−(h_x²/α_x² + h_y²/α_y²)/h_z²) / (π α_x α_y h_z⁴)`` (Beckmann &
    Spizzichino 1963; Walter et al. 2007, eq. 25; anisotropic: Heitz 2014, eq. 71).
    ``alpha_y=None`` means isotropic (α_y = α_x); α is the RMS slope, α_x along
    the tangent +x. ``normalized=False`` omits the 1/π, which gives the
    Cook-Torrance (1982) / lecture form (see :func:`beckmann_cook`).
    Returns 0 for ``h_z <= 0``; underflows to 0 (never NaN/Inf) for tiny ``h_z``.
    Scalar source: :func:`d_beckmann`, :func:`d_beckmann_slopes`.
    """
    hx, hy, hz, ax, ay, dt = _split(h, alpha_x, alpha_y)
    f = _v_beckmann if normalized else _v_beckmann_slopes
    return f(hx, hy, hz, ax, ay, dtype=dt)


def beckmann_cook(cos_h, m):
    """The lecture's / Cook & Torrance's (1982, eq. 4) Beckmann D from ``cos α = n·h``.

    ``D = exp(−(tan α/m)²) / (m² cos⁴ α)`` — no 1/π; ``∫ D cos α dω = π``.
    ``tan² α`` is formed as ``(1 − cos²α)/cos²α`` (for half vectors prefer
    ``beckmann(h, m, normalized=False)``, which uses ``h_x, h_y`` and is more
    accurate near the peak). Returns 0 for ``cos α <= 0``. Scalar source: :func:`d_beckmann_cook`.
    """
    return _v_beckmann_cook(cos_h, m, dtype=_dtype_of(cos_h))


def ggx(h, alpha_x, alpha_y=None):
    """GGX / Trowbridge-Reitz distribution D(h) of local half vectors ``h``.

    ``D = 1 / (π α_x α_y (h_x²/α_x² + h_y²/α_y² + h_z²)²)`` (Trowbridge & Reitz
    1975; Walter et al. 2007, eq. 33; anisotropic: Heitz 2014, eq. 85).
    ``alpha_y=None`` means isotropic. Returns 0 for ``h_z <= 0``. Scalar source: :func:`d_ggx`.
    """
    hx, hy, hz, ax, ay, dt = _split(h, alpha_x, alpha_y)
    return _v_ggx(hx, hy, hz, ax, ay, dtype=dt)


def _cos_to_h(cos_h):
    c = np.asarray(cos_h)
    dt = _dtype_of(c)
    c = np.clip(c.astype(dt, copy=False), dt.type(-1), dt.type(1))
    s = np.sqrt(np.maximum(dt.type(0), dt.type(1) - c * c))
    return np.stack([s, np.zeros_like(s), c], axis=-1)


def beckmann_iso(cos_h, alpha):
    """Normalised isotropic Beckmann D from ``cos θ_h``: ``exp(−tan²θ/α²)/(π α² cos⁴θ)``."""
    return beckmann(_cos_to_h(cos_h), alpha)


def ggx_iso(cos_h, alpha):
    """Isotropic GGX D from ``cos θ_h``: ``α² / (π cos⁴θ (α² + tan²θ)²)``."""
    return ggx(_cos_to_h(cos_h), alpha)


def projected_roughness_tan(w, alpha_x, alpha_y=None):
    """``(s, w_z)`` with ``s = sqrt(w_x² α_x² + w_y² α_y²)``, so ``α(w) tan θ = s / w_z``.

    ``α(w) = sqrt(α_x² cos²φ + α_y² sin²φ)`` is the roughness of the 1-D slope
    distribution seen along the azimuth of ``w`` (Heitz 2014, eq. 80). Scalar source: :func:`projected_slope`.
    """
    wx, wy, wz, ax, ay, dt = _split(w, alpha_x, alpha_y)
    return _v_slope(wx, wy, ax, ay, dtype=dt), wz.astype(dt, copy=False)


def beckmann_lambda(w, alpha_x, alpha_y=None):
    """Exact Smith Λ of the Beckmann distribution for local directions ``w`` (unit).

    ``a = 1/(α(w) tan θ) = w_z / sqrt(w_x² α_x² + w_y² α_y²)``,
    ``Λ = (erf(a) − 1)/2 + exp(−a²)/(2 a √π) = (exp(−a²)/(a √π) − erfc(a))/2``
    (Walter et al. 2007, eq. 27 with G1 = 1/(1+Λ); Heitz 2014, eq. 72).
    Λ = 0 at normal incidence, +inf for ``w_z <= 0`` (G1 = 0 there); never NaN.
    Scalar source: :func:`lambda_beckmann`.
    """
    wx, wy, wz, ax, ay, dt = _split(w, alpha_x, alpha_y)
    return _v_lambda_beckmann(wx, wy, wz, ax, ay, dtype=dt)


def ggx_lambda(w, alpha_x, alpha_y=None):
    """Exact Smith Λ of the GGX distribution for local directions ``w`` (unit).

    ``Λ = (−1 + sqrt(1 + α(w)² tan²θ))/2``, evaluated as
    ``s² / (2 w_z (sqrt(w_z² + s²) + w_z))`` with ``s = α(w) tan θ · w_z``
    (Walter et al. 2007, eq. 34; Heitz 2014, eq. 86). Λ = 0 at normal incidence,
    +inf for ``w_z <= 0``; never NaN. Scalar source: :func:`lambda_ggx`.
    """
    wx, wy, wz, ax, ay, dt = _split(w, alpha_x, alpha_y)
    return _v_lambda_ggx(wx, wy, wz, ax, ay, dtype=dt)


def beckmann_lambda_iso(cos_t, alpha):
    """Isotropic Beckmann Λ from ``cos θ`` (see :func:`beckmann_lambda`)."""
    return beckmann_lambda(_cos_to_h(cos_t), alpha)


def ggx_lambda_iso(cos_t, alpha):
    """Isotropic GGX Λ from ``cos θ`` (see :func:`ggx_lambda`)."""
    return ggx_lambda(_cos_to_h(cos_t), alpha)


#: name -> (D(h, alpha_x, alpha_y=None), Λ(w, alpha_x, alpha_y=None)), normalised D.
DISTRIBUTIONS = {
    "beckmann": (beckmann, beckmann_lambda),
    "ggx": (ggx, ggx_lambda),
}


def distribution(name):
    """``(D, Lambda)`` functions for ``"beckmann"`` or ``"ggx"``; ValueError otherwise."""
    try:
        return DISTRIBUTIONS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown microfacet distribution {name!r}; valid: {', '.join(DISTRIBUTIONS)}") from None


__all__ = [
    "slope2",
    "d_beckmann_slopes",
    "d_beckmann",
    "d_beckmann_cook",
    "d_ggx",
    "projected_slope",
    "lambda_beckmann",
    "lambda_floor",
    "lambda_ggx",
    "lambda_ggx_parts",
    "d_of",
    "lambda_of",
    "BECKMANN",
    "GGX",
    "beckmann",
    "beckmann_cook",
    "beckmann_iso",
    "ggx",
    "ggx_iso",
    "projected_roughness_tan",
    "beckmann_lambda",
    "ggx_lambda",
    "beckmann_lambda_iso",
    "ggx_lambda_iso",
    "DISTRIBUTIONS",
    "distribution",
]
