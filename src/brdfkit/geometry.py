"""Directions, frames and the angle parameterisations BRDFs are written in.

Conventions (SPEC.md): local shading frame with normal ``n = +z``, tangent
``t = +x`` (the anisotropy axis), bitangent ``+y``. ``wi`` points from the
surface toward the light, ``wo`` toward the viewer. All functions broadcast
over leading axes: vectors have shape ``(..., 3)``, angles shape ``(...)``.
Angles are radians.

Rusinkiewicz (1998) half/difference angles: with ``h = normalize(wi + wo)``,
``(theta_h, phi_h)`` are the spherical angles of ``h``; the difference vector
``d`` is ``wi`` expressed in the frame of ``h`` (rotate by ``-phi_h`` about
``z``, then by ``-theta_h`` about ``y``), ``(theta_d, phi_d)`` its angles.
"""

from __future__ import annotations

import math

import numpy as np

from .engine import jit

_TINY = 1e-300
#: float64's smallest normal number (a float32 twin uses float32's: brdfkit.engine.precision)
NORMAL_MIN = 2.2250738585072014e-308


# ------------------------------------------------ scalar forms for the kernels


@jit
def dot3(ax, ay, az, bx, by, bz):
    """``a·b`` of two vectors given by components."""
    return ax * bx + ay * by + az * bz


@jit
def hypot_c(a, b):
    """``√(a² + b²)`` without underflow or overflow of the squares; the kernels' hypot.

    As ``m·√(1 + (n/m)²)`` with ``m, n`` the larger and smaller magnitude: one division and one
    square root, no branch, so a loop calling it vectorises, where ``math.hypot`` is an opaque
    libm call that keeps the whole loop scalar. Exact where one argument is 0 (``hypot(0, c) = |c|``:
    the dielectric Fresnel of n = 1 stays exactly 0); within 2 ulp of ``math.hypot`` for finite
    input (tests/test_geometry.py).
    """
    x = abs(a)
    y = abs(b)
    m = max(x, y)
    q = min(x, y) / (m if m > 0.0 else 1.0)
    return m * math.sqrt(1.0 + q * q)


@jit
def scaled_sum_c(ix, iy, iz, ox, oy, oz):
    """``(S_x, S_y, S_z, m)``: ``S = (wi + wo)/m`` with ``m`` the largest absolute component; scalar twin of :func:`scaled_sum`.

    ``|S|`` lies in ``[1, √3]`` (for a subnormal largest component, ``m`` is the smallest normal
    number and ``|S|`` smaller, never near underflow), so normalising it neither underflows nor
    overflows; ``S = +z``, ``m = 0`` where ``wi == −wo``.
    """
    sx = ix + ox
    sy = iy + oy
    sz = iz + oz
    m = max(abs(sx), max(abs(sy), abs(sz)))
    if m == 0.0:
        return 0.0, 0.0, 1.0, 0.0
    # one reciprocal, three products (a division is the costliest instruction of a vectorised
    # kernel); m is raised to the smallest normal number first, so that 1/m stays finite: a
    # subnormal m then gives |S| < 1, still far from underflow, and S·m is still wi + wo
    m = max(m, NORMAL_MIN)
    r = 1.0 / m
    return sx * r, sy * r, sz * r, m


@jit
def half_vector_c(ix, iy, iz, ox, oy, oz):
    """``normalize(wi + wo)`` in component form, robust at grazing angles: the scalar twin of :func:`half_vector`."""
    sx, sy, sz, m = scaled_sum_c(ix, iy, iz, ox, oy, oz)
    r = 1.0 / math.sqrt(sx * sx + sy * sy + sz * sz)  # |S| in [1, √3]: one reciprocal, three products
    return sx * r, sy * r, sz * r


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot product over the last axis."""
    return np.einsum("...i,...i->...", a, b)


def normalize(v: np.ndarray) -> np.ndarray:
    """Unit vectors along ``v`` (zero vectors stay zero)."""
    v = np.asarray(v)
    n = np.sqrt(dot(v, v))
    return v / np.where(n > 0, n, 1)[..., None]


def spherical_to_vector(theta, phi) -> np.ndarray:
    """Unit vector from polar angle ``theta`` (from +z) and azimuth ``phi`` (from +x toward +y)."""
    theta = np.asarray(theta, dtype=np.float64)
    phi = np.asarray(phi, dtype=np.float64)
    st = np.sin(theta)
    return np.stack(np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)), axis=-1)


def vector_to_spherical(v) -> tuple[np.ndarray, np.ndarray]:
    """``(theta, phi)`` of (not necessarily unit) vectors; ``phi`` in ``[0, 2π)``."""
    v = np.asarray(v, dtype=np.float64)
    r = np.sqrt(dot(v, v))
    theta = np.arccos(np.clip(v[..., 2] / np.where(r > 0, r, 1), -1.0, 1.0))
    phi = np.mod(np.arctan2(v[..., 1], v[..., 0]), 2 * np.pi)
    return theta, phi


def scaled_sum(wi, wo) -> tuple[np.ndarray, np.ndarray]:
    """``(S, m)`` with ``S = (wi + wo) / m`` and ``m`` the largest absolute component of ``wi + wo``.

    ``S`` has the direction of the half vector and a length in ``[1, √3]``, so
    normalising it neither underflows nor overflows: a pair like
    ``(1, 0, 1e-300)``, ``(−1, 0, 1e-300)`` gives ``+z`` instead of 0/0 (the
    naive ``normalize(wi + wo)`` fails there). Ratios of components of ``H =
    wi + wo`` (Ward's exponent) can be taken from ``S`` directly; ``|H| =
    m·|S|``. Where ``wi == −wo`` (``m == 0``) ``S`` is ``+z``.
    """
    h = np.asarray(wi) + np.asarray(wo)
    m = np.max(np.abs(h), axis=-1)
    zero = m == 0
    s = h / np.where(zero, 1, m)[..., None]
    if np.any(zero):
        s = np.where(zero[..., None], np.array([0, 0, 1], dtype=s.dtype), s)
    return s, m


def half_vector(wi, wo) -> np.ndarray:
    """``normalize(wi + wo)``, robust at grazing angles (see :func:`scaled_sum`); ``+z`` where ``wi == −wo``.

    Every model that needs the half vector calls this one function.
    """
    s, _ = scaled_sum(wi, wo)
    return s / np.sqrt(dot(s, s))[..., None]


def reflect(w, n=None) -> np.ndarray:
    """Mirror reflection of ``w`` about ``n`` (default ``+z``): ``2 (w·n) n − w``."""
    w = np.asarray(w)
    if n is None:
        out = -w.copy()
        out[..., 2] = w[..., 2]
        return out
    n = np.asarray(n)
    return 2 * dot(w, n)[..., None] * n - w


def rotate_z(v, a):
    """Rotate vectors ``v`` by angle ``a`` (radians) about +z."""
    c, s = np.cos(a), np.sin(a)
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([c * x - s * y, s * x + c * y, z], axis=-1)


def _rotate_y(v, a):
    """Rotate vectors ``v`` by angle ``a`` (radians) about +y."""
    c, s = np.cos(a), np.sin(a)
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([c * x + s * z, y, -s * x + c * z], axis=-1)


def to_rusinkiewicz(wi, wo):
    """``(theta_h, phi_h, theta_d, phi_d)`` of direction pairs (Rusinkiewicz 1998)."""
    wi = np.asarray(wi, dtype=np.float64)
    wo = np.asarray(wo, dtype=np.float64)
    h = half_vector(wi, wo)
    theta_h, phi_h = vector_to_spherical(h)
    d = _rotate_y(rotate_z(wi, -phi_h), -theta_h)
    theta_d, phi_d = vector_to_spherical(d)
    return theta_h, phi_h, theta_d, phi_d


def from_rusinkiewicz(theta_h, phi_h, theta_d, phi_d):
    """Inverse of :func:`to_rusinkiewicz`: returns ``(wi, wo)``."""
    h = spherical_to_vector(theta_h, phi_h)
    d = spherical_to_vector(theta_d, phi_d)
    th, ph = np.broadcast_arrays(np.asarray(theta_h, float), np.asarray(phi_h, float))
    wi = rotate_z(_rotate_y(d, th), ph)
    wo = 2 * dot(wi, h)[..., None] * h - wi
    return wi, wo


def frame_from_normal(n) -> tuple[np.ndarray, np.ndarray]:
    """An orthonormal tangent and bitangent for unit normals ``n`` (Duff et al. 2017)."""
    n = np.asarray(n, dtype=np.float64)
    sign = np.where(n[..., 2] >= 0, 1.0, -1.0)
    a = -1.0 / (sign + n[..., 2])
    b = n[..., 0] * n[..., 1] * a
    t = np.stack([1 + sign * n[..., 0] ** 2 * a, sign * b, -sign * n[..., 0]], axis=-1)
    bt = np.stack([b, sign + n[..., 1] ** 2 * a, -n[..., 1]], axis=-1)
    return t, bt


def to_local(v, t, b, n) -> np.ndarray:
    """Express world vectors ``v`` in the frame (t, b, n)."""
    return np.stack([dot(v, t), dot(v, b), dot(v, n)], axis=-1)


def from_local(v, t, b, n) -> np.ndarray:
    """World vectors from local coordinates in the frame (t, b, n)."""
    v = np.asarray(v)
    return v[..., 0:1] * t + v[..., 1:2] * b + v[..., 2:3] * n


def random_unit_vectors(n: int, rng: np.random.Generator, hemisphere: bool = True) -> np.ndarray:
    """``n`` uniformly distributed unit vectors (upper hemisphere by default)."""
    u = rng.random((n, 2))
    z = u[:, 0] if hemisphere else 2 * u[:, 0] - 1
    r = np.sqrt(np.maximum(0.0, 1 - z * z))
    phi = 2 * np.pi * u[:, 1]
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


__all__ = [
    "dot",
    "normalize",
    "spherical_to_vector",
    "vector_to_spherical",
    "scaled_sum",
    "half_vector",
    "rotate_z",
    "reflect",
    "to_rusinkiewicz",
    "from_rusinkiewicz",
    "frame_from_normal",
    "to_local",
    "from_local",
    "random_unit_vectors",
]
