"""Fresnel reflectance: the fraction of light a smooth interface reflects.

All functions take the cosine ``c`` of the angle between the incident direction
and the (micro)facet normal — for a microfacet model ``c = v·h`` — and broadcast
over it. RGB parameters broadcast against ``c[..., None]`` when the caller adds
the axis; the functions themselves are plain elementwise numpy.

* :func:`fresnel_dielectric_cook` — the exact unpolarised dielectric Fresnel
  term in the form Cook & Torrance (1982, eq. 8) and the lecture give it:
  ``F = ½ (g−c)²/(g+c)² · (1 + (c(g+c)−1)²/(c(g−c)+1)²)`` with
  ``g² = n² + c² − 1``. When ``g² < 0`` (total internal reflection, only for
  n < 1) the result is 1.
* :func:`fresnel_conductor` — exact unpolarised Fresnel for a complex index
  ``eta + i·k`` (Born & Wolf; the form of pbrt-v4's ``FrComplex``).
  ``k = 0`` reduces to the dielectric case.
* :func:`fresnel_schlick` — Schlick's (1994) approximation
  ``F0 + (1 − F0)(1 − c)⁵``.
* :func:`f0_from_ior` — normal-incidence reflectance ``((n−1)/(n+1))²``.
"""

from __future__ import annotations

import numpy as np


def fresnel_dielectric_cook(c, n):
    """Exact dielectric Fresnel reflectance in Cook-Torrance's form (relative index ``n``)."""
    c = np.clip(np.asarray(c), 0.0, 1.0)
    g2 = n * n + c * c - 1.0
    tir = g2 < 0
    g = np.sqrt(np.where(tir, 0.0, g2))
    a = (g - c) / (g + c)
    num = c * (g + c) - 1.0
    den = c * (g - c) + 1.0
    F = 0.5 * a * a * (1.0 + (num / den) ** 2)
    # g + c == 0 only when n == 0 and c == 0, excluded by parameter ranges; den > 0
    # for c in [0, 1] since c (g − c) ≥ −c² ≥ −1 with equality only at n = 0.
    return np.where(tir, 1.0, np.clip(F, 0.0, 1.0))


def fresnel_conductor(c, eta, k):
    """Exact unpolarised Fresnel reflectance of a conductor with complex index ``eta + i·k``.

    Computed with complex arithmetic: ``sin²θt = sin²θi / η²``, ``cos θt = sqrt(1 − sin²θt)``,
    ``r_s = (cos θi − η cos θt)/(cos θi + η cos θt)``, ``r_p = (η cos θi − cos θt)/(η cos θi + cos θt)``,
    ``F = (|r_s|² + |r_p|²)/2``.
    """
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0)
    eta_c = np.asarray(eta, dtype=np.float64) + 1j * np.asarray(k, dtype=np.float64)
    sin2_i = 1.0 - c * c
    sin2_t = sin2_i / (eta_c * eta_c)
    cos_t = np.sqrt(1.0 - sin2_t)
    r_s = (c - eta_c * cos_t) / (c + eta_c * cos_t)
    r_p = (eta_c * c - cos_t) / (eta_c * c + cos_t)
    F = 0.5 * (np.abs(r_s) ** 2 + np.abs(r_p) ** 2)
    return np.clip(F.real, 0.0, 1.0)


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
