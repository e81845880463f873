"""Shared helpers for the tests of the classic (non-microfacet) models (test_model_*.py)."""

from __future__ import annotations

import math

import numpy as np


def vec(theta_deg: float, phi_deg: float) -> np.ndarray:
    """Unit vector from polar/azimuth angles in degrees, by plain trigonometry."""
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def rotate_z(v: np.ndarray, deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    v = np.asarray(v, dtype=np.float64)
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1], v[..., 2]], axis=-1)


def random_upper(n: int, seed: int) -> np.ndarray:
    """``n`` random unit vectors strictly above the horizon."""
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 1e-3
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def hemisphere_grid(n_mu: int = 400, n_phi: int = 800):
    """Quadrature over the upper hemisphere: directions ``(N, 3)`` and weights for ∫ g cos θ dω.

    Gauss-Legendre in μ = cos θ on (0, 1) and the periodic trapezoid rule in φ;
    the weights include the cosine, so ``sum(w * f)`` is the directional albedo of f.
    """
    x, wx = np.polynomial.legendre.leggauss(n_mu)
    mu = 0.5 * (x + 1.0)
    wmu = 0.5 * wx
    phi = (np.arange(n_phi) + 0.5) * (2 * np.pi / n_phi)
    MU, PHI = np.meshgrid(mu, phi, indexing="ij")
    S = np.sqrt(1 - MU * MU)
    dirs = np.stack([S * np.cos(PHI), S * np.sin(PHI), MU], axis=-1).reshape(-1, 3)
    w = (wmu[:, None] * MU * (2 * np.pi / n_phi)).reshape(-1)
    return dirs, w


def albedo(model, wi: np.ndarray, n_mu: int = 400, n_phi: int = 800) -> np.ndarray:
    """Directional albedo ∫ f(wi, wo) cos θo dωo (RGB) by quadrature."""
    dirs, w = hemisphere_grid(n_mu, n_phi)
    f = model.eval(np.asarray(wi, dtype=np.float64)[None, :], dirs)
    return (w[:, None] * f).sum(axis=0)


def special_directions(dtype) -> np.ndarray:
    """Directions where a formula may divide by ~0: the normal, three grazing ones (z = the dtype's
    smallest normal-sized number), two mirror-symmetric ones, one a hair off the normal, and,
    last, one straight below the horizon."""
    g = 1e-300 if dtype == np.float64 else 1e-38
    return np.array(
        [[0, 0, 1], [1, 0, g], [-1, 0, g], [0, 1, g], [0.6, 0, 0.8], [-0.6, 0, 0.8], [1e-20, 0, 1], [0, 0, -1]],
        dtype=dtype,
    )


def assert_finite_at_all_pairs(model, D: np.ndarray) -> None:
    """f over every pair of ``D`` keeps D's dtype, is finite and ≥ 0, and is 0 wherever either
    direction is the last of ``D`` (one on or below the horizon)."""
    f = model.eval(D[:, None, :], D[None, :, :])
    assert f.dtype == D.dtype
    assert np.all(np.isfinite(f)) and np.all(f >= 0)
    assert np.all(f[:, -1] == 0) and np.all(f[-1, :] == 0)


def assert_reciprocal_only_with_cosines(model, wi: np.ndarray, wo: np.ndarray, gap: float) -> None:
    """An unnormalised lobe: f(wi, wo) and f(wo, wi) differ by more than ``gap`` of the larger,
    yet f(wi, wo) cos θi = f(wo, wi) cos θo (to 1e-13)."""
    f, g = model.eval(wi, wo)[0], model.eval(wo, wi)[0]
    assert abs(f - g) > gap * max(f, g)
    assert math.isclose(f * wi[2], g * wo[2], rel_tol=1e-13)
