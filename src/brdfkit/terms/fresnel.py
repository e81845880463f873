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
"""

from __future__ import annotations

import numpy as np


def fresnel_dielectric_cook(c, n):
    """Exact dielectric Fresnel reflectance in Cook-Torrance's form (relative index ``n``)."""
    c = np.clip(np.asarray(c), 0.0, 1.0)
    d = n * n - 1.0
    g2 = d + c * c
    tir = g2 < 0
    # g = sqrt(n² − 1 + c²); for n ≥ 1 as hypot(sqrt(n² − 1), c) so that c² cannot underflow away
    g = np.where(d >= 0, np.hypot(np.sqrt(np.maximum(d, 0.0)), c), np.sqrt(np.where(tir, 0.0, g2)))
    # g + c == 0 only for n == 1 and c == 0 (no interface at all): F = 0 there,
    # the value it has for every other c. den > 0 for c in [0, 1] since
    # c (g − c) ≥ −c² ≥ −1 with equality only at n = 0.
    gc = g + c
    degenerate = gc == 0
    a = (g - c) / np.where(degenerate, 1.0, gc)
    num = c * gc - 1.0
    den = c * (g - c) + 1.0
    F = 0.5 * a * a * (1.0 + (num / den) ** 2)
    return np.where(tir, 1.0, np.where(degenerate, 0.0, np.clip(F, 0.0, 1.0)))


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
    """
    c = np.asarray(c)
    dt = np.result_type(c, np.asarray(eta), np.asarray(k), np.float32)
    zero, half, one, two = dt.type(0), dt.type(0.5), dt.type(1), dt.type(2)
    c = np.clip(c.astype(dt, copy=False), zero, one)
    eta = np.asarray(eta, dtype=dt)
    k = np.asarray(k, dtype=dt)
    m1 = (eta - one) * (eta + one) - k * k  # Re(η² − 1)
    Q = two * eta * k  # Im η² (>= 0)
    qa = np.hypot(m1, Q)  # |η² − 1|
    c2 = c * c
    A = m1 + c2  # Re g²
    mod = np.hypot(A, Q)  # |g²|
    with np.errstate(divide="ignore", invalid="ignore"):
        big = np.sqrt(half * (mod + np.abs(A)))  # the larger of u, v
        small = np.where(big > 0, half * np.abs(Q) / np.where(big > 0, big, one), zero)
    u = np.where(A >= 0, big, small)
    v = np.where(A >= 0, small, big)
    ds = (c + u) ** 2 + v * v  # |c + g|²
    dp = ((m1 + one) * c + u) ** 2 + (Q * c + v) ** 2  # |η² c + g|²
    b_re = (m1 + two) * c2 - one  # (η² + 1) c² − 1
    b_im = Q * c2
    # Both denominators vanish only for η == 1 at c == 0 (no interface): F = 0 there,
    # its value at every other c (|η² − 1| == 0 then anyway). Ratios are formed before
    # squaring so that tiny |c + g|² cannot underflow to 0/0.
    degenerate = (ds == 0) | (dp == 0)
    ds = np.where(degenerate, one, ds)
    dp = np.where(degenerate, one, dp)
    rs = qa / ds
    rp = qa * np.hypot(b_re, b_im) / dp
    F = half * (rs * rs + rp * rp)
    return np.where(degenerate, zero, np.clip(F, zero, one))


def fresnel_schlick(f0, c):
    """Schlick (1994) approximation ``F0 + (1 − F0)(1 − c)⁵``."""
    c = np.clip(np.asarray(c), 0.0, 1.0)
    m = 1.0 - c
    m2 = m * m
    return f0 + (1.0 - f0) * (m2 * m2 * m)


def f0_from_ior(n):
    """Reflectance at normal incidence of a dielectric with relative index ``n``."""
    n = np.asarray(n)
    return ((n - 1.0) / (n + 1.0)) ** 2


__all__ = ["fresnel_dielectric_cook", "fresnel_conductor", "fresnel_schlick", "f0_from_ior"]
