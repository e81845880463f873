"""Fresnel reflectance: the fraction of light a smooth interface reflects.

All functions take the cosine ``c`` of the angle between the incident direction
and the (micro)facet normal — for a microfacet model ``c = v·h`` — and broadcast
over it. RGB parameters broadcast against ``c[..., None]`` when the caller adds
the axis; the functions themselves are plain elementwise numpy.

* :func:`fresnel_dielectric_cook` — the exact unpolarised dielectric Fresnel
  term in the form Cook & Torrance (1982, eq. 8) and the lecture give it:
  ``F = ½ (g−c)²/(g+c)² · (1 + (c(g+c)−1)²/(c(g−c)+1)²)`` with
  ``g² = n² + c² − 1``. When ``g² < 0`` (total internal reflection, only for
  n < 1) the result is 1. ``n = 1`` at ``c = 0`` (no interface, 0/0) gives 0.
* :func:`fresnel_conductor` — exact unpolarised Fresnel for a complex index
  ``eta + i·k`` (Born & Wolf), computed with the complex ``g = sqrt(η² − 1 + c²)``.
  ``k = 0`` reduces to the dielectric case; real arithmetic, float32 stays float32.
* :func:`fresnel_schlick` — Schlick's (1994) approximation
  ``F0 + (1 − F0)(1 − c)⁵``.
* :func:`f0_from_ior` — normal-incidence reflectance ``((n−1)/(n+1))²``.

Each formula is written once as a scalar function (``f_dielectric(c, n)``,
``f_conductor(c, eta, k)``, ``f_schlick(f0, c)``), compiled by
:func:`brdfkit.engine.jit` for the model kernels; the array functions are thin
element-wise wrappers over the same source (:class:`brdfkit.engine.vectorize`).
"""

from __future__ import annotations

import math

import numpy as np

from ..engine import jit, vectorize
from ..geometry import hypot_c

# ------------------------------------------------------------ scalar sources


@jit
def f_dielectric(c, n):
    """Exact dielectric Fresnel in Cook & Torrance's (1982, eq. 8) form, relative index ``n``, ``c = v·h``.

    ``F = ½ (g−c)²/(g+c)² · (1 + (c(g+c)−1)²/(c(g−c)+1)²)``, ``g² = n² + c² − 1``;
    1 under total internal reflection (g² < 0), 0 for the non-interface n = 1 at c = 0.
    """
    c = min(max(c, 0.0), 1.0)
    d = n * n - 1.0
    g2 = d + c * c
    # with e = sqrt(|n² − 1|): g = hypot(e, c) for n >= 1 (c² cannot underflow away), and
    # g = sqrt((c − e)(c + e)) for n < 1 (no cancellation; 0 under TIR, selected away below).
    # Every branch of this function is a select: both sides are computed, each with a
    # non-negative square root argument in every lane, so a loop over it vectorises without
    # raising the invalid-operation flag (numpy would warn for the array form)
    e = math.sqrt(abs(d))
    g = hypot_c(e, c) if d >= 0.0 else math.sqrt(max((c - e) * (c + e), 0.0))
    gc = g + c
    a = (g - c) / (gc if gc != 0.0 else 1.0)  # gc = 0 only for n = 1 at c = 0: a = 0, F = 0
    num = c * gc - 1.0
    den = c * (g - c) + 1.0  # > 0 for c in [0, 1] unless n == 0
    q = num / (den if den != 0.0 else 1.0)
    F = min(max(0.5 * a * a * (1.0 + q * q), 0.0), 1.0)
    return 1.0 if g2 < 0.0 else F  # total internal reflection


@jit(inline=True)
def f_conductor(c, eta, k):
    """Exact unpolarised Fresnel of a conductor, complex index ``η = eta + i·k``, at ``c = cos θ``.

    Born & Wolf §14.2 with ``g = sqrt(η² − 1 + c²)`` (Im g ≥ 0);
    ``|r_s| = |η² − 1|/|c + g|²``, ``|r_p| = |η² − 1| |(η² + 1)c² − 1|/|η²c + g|²``,
    ``F = (|r_s|² + |r_p|²)/2``: no cancellation, exact 0 for an index-1
    "interface", accurate for eta near 1 (see :func:`fresnel_conductor`).
    """
    c = min(max(c, 0.0), 1.0)
    m1 = (eta - 1.0) * (eta + 1.0) - k * k  # Re(η² − 1)
    Q = 2.0 * eta * k  # Im η² (>= 0)
    # moduli as sqrt(x² + y²), not hypot: computed in float64 from bounded parameters
    # (eta ≤ 10, k ≤ 20), the squares neither overflow nor underflow to a wrong result,
    # and sqrt is an LLVM intrinsic that the compiler hoists and vectorises (hypot is a libm call)
    qa = math.sqrt(m1 * m1 + Q * Q)  # |η² − 1|
    c2 = c * c
    A = m1 + c2  # Re g²
    mod = math.sqrt(A * A + Q * Q)  # |g²|
    big = math.sqrt(0.5 * (mod + abs(A)))  # the larger of Re g, Im g
    small = 0.5 * abs(Q) / big if big > 0.0 else 0.0
    if A >= 0.0:
        u = big
        v = small
    else:
        u = small
        v = big
    ds = (c + u) * (c + u) + v * v  # |c + g|²
    t = (m1 + 1.0) * c + u
    w = Q * c + v
    dp = t * t + w * w  # |η² c + g|²
    if ds == 0.0 or dp == 0.0:
        return 0.0
    rs = qa / ds
    br = (m1 + 2.0) * c2 - 1.0  # Re((η² + 1) c² − 1)
    bi = Q * c2
    qp = qa / dp
    F = 0.5 * (rs * rs + qp * qp * (br * br + bi * bi))  # |r_p|² without the modulus's sqrt
    return min(max(F, 0.0), 1.0)


@jit
def f_schlick(f0, c):
    """Schlick (1994) ``F0 + (1 − F0)(1 − c)⁵``."""
    m = 1.0 - min(max(c, 0.0), 1.0)
    m2 = m * m
    return f0 + (1.0 - f0) * (m2 * m2 * m)


# ------------------------------------------------------ array API (wrappers)

_v_dielectric = vectorize(f_dielectric, 2)
_v_conductor = vectorize(f_conductor, 3)
_v_schlick = vectorize(f_schlick, 2)


def _dt(*args):
    dt = np.result_type(*[np.asarray(a) for a in args], np.float32)
    return np.dtype(np.float32) if dt == np.float32 else np.dtype(np.float64)


def fresnel_dielectric_cook(c, n):
    """Exact dielectric Fresnel reflectance in Cook-Torrance's form (relative index ``n``). Source: :func:`f_dielectric`."""
    return _v_dielectric(c, n, dtype=_dt(c, n))


def fresnel_conductor(c, eta, k):
    """Exact unpolarised Fresnel reflectance of a conductor with complex index ``η = eta + i·k``.

    With ``g = η cos θt = sqrt(η² − 1 + c²)`` (the root with Im g ≥ 0; Born & Wolf
    §14.2, written like Cook-Torrance's ``g``)::

        r_s = (c − g)/(c + g),   r_p = (η² c − g)/(η² c + g),   F = (|r_s|² + |r_p|²)/2

    evaluated in real arithmetic and without cancellation: since
    ``(c − g)(c + g) = 1 − η²`` and ``(η²c − g)(η²c + g) = (η² − 1)((η² + 1)c² − 1)``,
    ``|r_s| = |η² − 1| / |c + g|²`` and
    ``|r_p| = |η² − 1| |(η² + 1)c² − 1| / |η²c + g|²``, with ``η² − 1`` formed as
    ``(eta − 1)(eta + 1) − k² + 2i·eta·k``. ``g = u + i v`` from ``A = Re g²``,
    ``B = Im g² = 2 eta k``: ``u, v = sqrt((|g²| ± A)/2)``, the smaller one as
    ``|B|/(2·larger)``. An index-1 "interface" gives exactly 0; ``k = 0`` is the
    dielectric case. float32 inputs (``c``, ``eta``, ``k``) give a float32 result.
    Scalar source: :func:`f_conductor`.
    """
    return _v_conductor(c, eta, k, dtype=_dt(c, eta, k))


def fresnel_schlick(f0, c):
    """Schlick (1994) approximation ``F0 + (1 − F0)(1 − c)⁵``. Scalar source: :func:`f_schlick`."""
    return _v_schlick(f0, c, dtype=_dt(f0, c))


def f0_from_ior(n):
    """Reflectance at normal incidence of a dielectric with relative index ``n``."""
    n = np.asarray(n)
    return ((n - 1.0) / (n + 1.0)) ** 2


__all__ = [
    "f_dielectric",
    "f_conductor",
    "f_schlick",
    "fresnel_dielectric_cook",
    "fresnel_conductor",
    "fresnel_schlick",
    "f0_from_ior",
]
