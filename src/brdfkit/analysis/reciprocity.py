"""Helmholtz reciprocity: f_r(wi, wo) = f_r(wo, wi).

The lecture's first law of a BRDF, BRDF(L, E; N) = BRDF(E, L; N)
(von Helmholtz 1856; for BRDFs, Nicodemus et al. 1977). A model is tested on
a dense, deterministic set of direction pairs and the largest *relative*
asymmetry

    e = |f(a, b) − f(b, a)| / max(f(a, b), f(b, a))        (per RGB channel)

is reported, 0 for a reciprocal model (up to rounding, ~1e-15), up to 1 for
one that is zero in one direction and not in the other. Pairs where both
values are negligible (below 1e-12 of the largest value seen) are skipped:
their ratio is rounding noise.

The tolerance follows the precision the model is evaluated in
(:func:`evaluation_precision`): :data:`RECIPROCITY_TOL` (1e-6) for float64,
:data:`RECIPROCITY_TOL_FLOAT32` (8192 float32 ulps, 9.8e-4) for a model that
computes in float32 — a BRDF Explorer ``.brdf`` shader runs as float32 GLSL,
and near grazing its rounding alone makes a symmetric formula asymmetric by
up to 7.6e-5 (``tests/data/ggx.brdf``, alpha = 0.3; the engine's float32
twins: up to 3.3e-5, Schlick). A model that breaks the law does so by far
more (the unnormalized Phong lobe: order 1).

The direction set (:func:`direction_pairs`) combines

* every pair of a grid of 18 polar angles (0° to 89.9°, grazing ones
  included) × 24 azimuths (anisotropic models are tested off the axes too);
* near-mirror pairs: b = reflect(a) tilted by 0°, ±0.3°, ±1°, ±3° in θ and φ,
  where sharp specular lobes are non-zero;
* 20 000 pairs drawn uniformly from the hemisphere with a fixed seed.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

from ..engine import jit
from ..geometry import spherical_to_vector

#: a model evaluated in float64 is called reciprocal when its relative asymmetry is at most this
RECIPROCITY_TOL = 1e-6

#: the same for a model evaluated in float32: 2^13 float32 ulps (9.8e-4), ten times the largest
#: rounding asymmetry measured for a symmetric float32 formula (7.6e-5, see the module docstring)
RECIPROCITY_TOL_FLOAT32 = 2.0**13 * float(np.finfo(np.float32).eps)

_TOLERANCE = {"float64": RECIPROCITY_TOL, "float32": RECIPROCITY_TOL_FLOAT32}

_THETA_DEG = (0.0, 0.5, 2.0, 5.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 75.0, 80.0, 85.0, 88.0, 89.0, 89.5, 89.9)
_N_PHI = 24
_TILTS_DEG = (0.0, 0.3, -0.3, 1.0, -1.0, 3.0, -3.0)


@functools.lru_cache(maxsize=4)
def direction_pairs(n_random: int = 20000, seed: int = 20241) -> tuple[np.ndarray, np.ndarray]:
    """The deterministic test set: arrays ``(a, b)`` of shape (N, 3), unit, upper hemisphere."""
    th = np.radians(np.asarray(_THETA_DEG))
    ph = 2 * math.pi * np.arange(_N_PHI) / _N_PHI + 0.1  # off-axis offset
    T, P = np.meshgrid(th[1:], ph, indexing="ij")
    grid = np.concatenate([spherical_to_vector(T.ravel(), P.ravel()), [[0.0, 0.0, 1.0]]])
    ia, ib = np.triu_indices(len(grid), k=1)
    a_list = [grid[ia]]
    b_list = [grid[ib]]
    # near-mirror pairs
    tilt = np.radians(np.asarray(_TILTS_DEG))
    TT, PT = np.meshgrid(tilt, tilt, indexing="ij")
    A = np.repeat(grid, TT.size, axis=0)
    ta = np.repeat(np.arccos(np.clip(grid[:, 2], -1, 1)), TT.size)
    pa = np.repeat(np.arctan2(grid[:, 1], grid[:, 0]), TT.size)
    tb = np.clip(ta + np.tile(TT.ravel(), len(grid)), 1e-4, math.radians(89.95))
    pb = pa + math.pi + np.tile(PT.ravel(), len(grid))
    a_list.append(A)
    b_list.append(spherical_to_vector(tb, pb))
    # random pairs
    rng = np.random.default_rng(seed)
    for out in (a_list, b_list):
        u = rng.random((n_random, 2))
        z = u[:, 0]
        r = np.sqrt(1 - z * z)
        out.append(np.stack([r * np.cos(2 * math.pi * u[:, 1]), r * np.sin(2 * math.pi * u[:, 1]), z], -1))
    a = np.concatenate(a_list)
    b = np.concatenate(b_list)
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = b / np.linalg.norm(b, axis=-1, keepdims=True)
    a.setflags(write=False)
    b.setflags(write=False)
    return a, b


@jit
def worst_asymmetry(fab, fba):
    """``(e, i)``: the largest relative asymmetry ``|a − b| / max(|a|, |b|)`` over the entries of two
    equal-shape float64 arrays (flattened; 0 where both are at most 1e-12 of the largest magnitude, or
    1e-300) and the flat index of its first occurrence (0 if none). One compiled pass for the
    maximum, one for the ratio: numpy's version of the same took eleven passes (~6 ms of
    :func:`reciprocity_report`'s ~9 for 123 477 pairs)."""
    a = fab.ravel()
    b = fba.ravel()
    top = 0.0
    for i in range(a.size):
        top = max(top, abs(a[i]), abs(b[i]))
    floor = max(1e-12 * top, 1e-300)
    worst = 0.0
    at = 0
    for i in range(a.size):
        big = max(abs(a[i]), abs(b[i]))
        if big > floor:
            r = abs(a[i] - b[i]) / big
            if r > worst:
                worst = r
                at = i
    return worst, at


def evaluation_precision(*values: np.ndarray) -> str:
    """``"float32"`` if every non-zero value (of float64 arrays a model returned for float64
    directions) is a float32 number, else ``"float64"``.

    A model that computes in float32 (a ``.brdf`` shader on the GL context) can only return such
    values; a float64 computation returns one by chance about once in 2^29 values, and the test
    set has hundreds of thousands. Fewer than :data:`MIN_DISTINCT` distinct non-zero values (a
    constant, a step function of exact numbers such as 1 and 2) say nothing of the precision:
    ``"float64"``, the stricter tolerance.
    """
    nz = np.concatenate([np.asarray(v, dtype=np.float64).ravel() for v in values])
    nz = nz[nz != 0]
    if np.unique(nz).size < MIN_DISTINCT:
        return "float64"
    return "float32" if np.array_equal(nz.astype(np.float32).astype(np.float64), nz) else "float64"


#: distinct non-zero values :func:`evaluation_precision` needs before it calls a model float32
MIN_DISTINCT = 64


def reciprocity_tolerance(precision: str) -> float:
    """The largest relative asymmetry a model evaluated in ``precision`` may show and be called reciprocal."""
    if precision not in _TOLERANCE:
        raise ValueError(f"precision must be one of {', '.join(_TOLERANCE)}, got {precision!r}")
    return _TOLERANCE[precision]


def reciprocity_report(model: Any, *, n_random: int = 20000, seed: int = 20241) -> dict[str, Any]:
    """Largest relative asymmetry and where it occurs.

    Returns ``{"error", "reciprocal", "precision", "tolerance", "worst": {"wi_deg": [θ, φ],
    "wo_deg": [θ, φ], "f_wi_wo": rgb, "f_wo_wi": rgb}, "pairs": N}``: ``reciprocal`` is
    ``error <= tolerance``, the tolerance of the model's evaluation ``precision``.
    """
    a, b = direction_pairs(n_random, seed)
    fab = np.asarray(model.eval(a, b), dtype=np.float64)
    fba = np.asarray(model.eval(b, a), dtype=np.float64)
    if not (np.all(np.isfinite(fab)) and np.all(np.isfinite(fba))):
        raise ValueError(f"{getattr(model, 'name', 'model')}: eval returned NaN or Inf; reciprocity undefined")
    precision = evaluation_precision(fab, fba)
    tol = reciprocity_tolerance(precision)
    err, flat = worst_asymmetry(np.ascontiguousarray(fab), np.ascontiguousarray(fba))
    k, ch = divmod(int(flat), 3)
    err = float(err)

    def deg(v: np.ndarray) -> list[float]:
        return [
            round(math.degrees(math.acos(max(-1.0, min(1.0, float(v[2]))))), 4),
            round(math.degrees(math.atan2(float(v[1]), float(v[0]))) % 360.0, 4),
        ]

    return {
        "error": err,
        "reciprocal": bool(err <= tol),
        "precision": precision,
        "tolerance": tol,
        "worst": {
            "wi_deg": deg(a[k]),
            "wo_deg": deg(b[k]),
            "channel": "rgb"[ch],
            "f_wi_wo": [float(x) for x in fab[k]],
            "f_wo_wi": [float(x) for x in fba[k]],
        },
        "pairs": int(len(a)),
    }


def reciprocity_error(model: Any, *, n_random: int = 20000, seed: int = 20241) -> float:
    """Largest relative asymmetry |f(a,b) − f(b,a)| / max(f(a,b), f(b,a)) over the test set.

    0 (to rounding) for a reciprocal model; see :func:`reciprocity_report` for
    the pair where it occurs. The model is called reciprocal when this is at
    most :data:`RECIPROCITY_TOL` (1e-6), or :data:`RECIPROCITY_TOL_FLOAT32` for a
    model evaluated in float32.
    """
    return float(reciprocity_report(model, n_random=n_random, seed=seed)["error"])


__all__ = [
    "reciprocity_error", "reciprocity_report", "direction_pairs", "evaluation_precision", "reciprocity_tolerance",
    "RECIPROCITY_TOL", "RECIPROCITY_TOL_FLOAT32",
]
