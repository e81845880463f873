"""Shared numeric helpers for tests that evaluate models on sampled directions.

* :func:`lifted_pairs`: random direction pairs kept off the horizon by lifting z;
* :func:`hemisphere_pairs`: direction pairs uniform on the hemisphere above ``z = zmin``;
* :func:`peak_pairs`: uniform pairs plus pairs near the mirror direction (a lobe's peak), float32;
* :func:`float32_spread`: how much a float64 value moves when its inputs move by float32 ulps
  (the budget a float32 twin, GLSL or otherwise, cannot beat);
* :func:`load_or_one_line_error`: a reader on a (damaged) file gives a model or one line of
  ``ValueError``, and how much memory it took.
"""

from __future__ import annotations

import tracemalloc
from typing import Any, Callable

import numpy as np

from brdfkit.geometry import random_unit_vectors


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


def hemisphere_pairs(n: int, seed: int, zmin: float = 0.02) -> tuple[np.ndarray, np.ndarray]:
    """``n`` pairs (wi, wo) of unit vectors, ``z`` uniform in ``[zmin, 1]`` and the azimuth uniform
    (uniform in solid angle above ``zmin``; a negative ``zmin`` reaches below the horizon)."""
    rng = np.random.default_rng(seed)

    def dirs():
        z = rng.uniform(zmin, 1.0, n)
        p = rng.uniform(-np.pi, np.pi, n)
        s = np.sqrt(1 - z * z)
        return np.stack([s * np.cos(p), s * np.sin(p), z], axis=1)

    return dirs(), dirs()


def peak_pairs(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` uniform pairs then ``n // 2`` pairs near the mirror direction (``wi`` = the mirror of
    ``wo`` moved by normal draws of scale 0.002, 0.02 or 0.1: the peak of a lobe, where a table's
    finest bins are), as float32."""
    rng = np.random.default_rng(seed)
    wi, wo = random_unit_vectors(n, rng), random_unit_vectors(n, rng)
    wo2 = random_unit_vectors(n // 2, rng)
    wi2 = wo2 * [-1.0, -1.0, 1.0] + rng.normal(size=wo2.shape) * rng.choice([0.002, 0.02, 0.1], size=(n // 2, 1))
    wi2[:, 2] = np.abs(wi2[:, 2]) + 1e-4
    wi2 /= np.linalg.norm(wi2, axis=1, keepdims=True)
    return np.concatenate([wi, wi2]).astype(np.float32), np.concatenate([wo, wo2]).astype(np.float32)


def load_or_one_line_error(load: Callable[[str], Any], path) -> tuple[Any, int]:
    """``(load(path), peak)``, or ``(None, peak)`` when it raises a ``ValueError`` of one line (any
    other exception, or a message of several lines, fails the test); ``peak`` is the most memory
    (bytes, tracemalloc) the call held at once."""
    tracemalloc.start()
    try:
        try:
            m = load(path)
        except ValueError as e:
            assert "\n" not in str(e)
            m = None
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return m, peak


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
