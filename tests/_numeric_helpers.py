"""Shared numeric helpers for tests that evaluate models on sampled directions.

* :func:`lifted_pairs`: random direction pairs kept off the horizon by lifting z;
* :func:`float32_spread`: how much a float64 value moves when its inputs move by float32 ulps
  (the budget a float32 twin, GLSL or otherwise, cannot beat).
"""

from __future__ import annotations

import numpy as np


def lifted_pairs(n: int, seed: int, lift: float) -> tuple[np.ndarray, np.ndarray]:
    """``n`` pairs (wi, wo) of unit vectors: normal draws with ``z = |z| + lift``, then normalised."""
    rng = np.random.default_rng(seed)
    wi = rng.normal(size=(n, 3))
    wo = rng.normal(size=(n, 3))
    wi[:, 2] = np.abs(wi[:, 2]) + lift
    wo[:, 2] = np.abs(wo[:, 2]) + lift
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    return wi, wo


def float32_spread(model, wi: np.ndarray, wo: np.ndarray, seed: int) -> np.ndarray:
    """Largest change of ``model.eval(wi, wo)`` when the inputs move by up to 4 float32 ulps
    (four random draws from ``seed``)."""
    f = model.eval(wi, wo)
    rng = np.random.default_rng(seed)
    out = np.zeros_like(f)
    for _ in range(4):
        di = 1 + rng.uniform(-4, 4, wi.shape) * 2.0**-24
        do = 1 + rng.uniform(-4, 4, wo.shape) * 2.0**-24
        out = np.maximum(out, np.abs(model.eval(wi * di, wo * do) - f))
    return out
