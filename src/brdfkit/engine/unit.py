"""The unit-direction rule of ``BRDF.eval`` (SPEC.md): ``|wi|`` and ``|wo|`` within a dtype's tolerance of 1.

The length statistics of flat ``(n, 3)`` arrays (compiled, :func:`_sq_stats` also for the drivers'
exact statistics, :mod:`.driver`) and the check that raises the SPEC's one-line ``ValueError``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .cache import jit

#: allowed deviation of a direction's length from 1, by working dtype (SPEC.md)
UNIT_TOL = {np.dtype(np.float64): 1e-4, np.dtype(np.float32): 1e-3}


@jit
def _sq_stats(w):
    """(min, max, NaN count) of the squared lengths of the rows of a C-contiguous ``(n, 3)`` array."""
    lmin = math.inf
    lmax = -math.inf
    nan = 0
    for j in range(w.shape[0]):
        x = numba.float64(w[j, 0])
        y = numba.float64(w[j, 1])
        z = numba.float64(w[j, 2])
        q = x * x + y * y + z * z
        nan += q != q
        lmin = min(lmin, q)
        lmax = max(lmax, q)
    return lmin, lmax, float(nan)


@jit
def _length_stats(w):
    """(min length, max length, NaN count) of the rows of a C-contiguous ``(n, 3)`` array."""
    qmin, qmax, nan = _sq_stats(w)
    return math.sqrt(qmin), math.sqrt(qmax), int(nan)


def _length_stats_np(w: np.ndarray) -> tuple[float, float, int]:
    if w.shape[0] == 0:
        return 1.0, 1.0, 0
    if w.dtype in (np.float32, np.float64) and w.flags.c_contiguous:
        lmin, lmax, nan = _length_stats(w)
        return float(lmin), float(lmax), int(nan)
    n = np.sqrt(np.einsum("...i,...i->...", w, w, dtype=np.float64))  # pragma: no cover
    return float(np.nanmin(n)), float(np.nanmax(n)), int(np.isnan(n).sum())  # pragma: no cover


def check_unit(name: str, arg: str, lmin: float, lmax: float, nan: int, dtype) -> None:
    """Raise the SPEC's ValueError unless every length lies within the dtype's tolerance of 1."""
    tol = UNIT_TOL[np.dtype(dtype)]
    if nan:
        worst = math.nan
    elif max(1.0 - lmin, lmax - 1.0) <= tol:
        return
    else:
        worst = lmin if (1.0 - lmin) >= (lmax - 1.0) else lmax
    raise ValueError(
        f"{name}: {arg} must be unit vectors (length within {tol:g} of 1 for {np.dtype(dtype).name}); "
        f"found length {worst:.6g} (normalise with bk.geometry.normalize)"
    )


def check_unit_flat(name: str, fi: np.ndarray, fo: np.ndarray, dtype) -> None:
    """The unit-direction check of flat direction arrays (:func:`prepare`'s), without evaluating."""
    check_unit(name, "wi", *_length_stats_np(fi), dtype)
    check_unit(name, "wo", *_length_stats_np(fo), dtype)


def check_driver_stats(name: str, nrm: np.ndarray, dtype) -> None:
    """The unit-direction check from the compiled driver's per-chunk squared-length statistics
    (``(nchunks, 6)``: wi min, max, NaN count, wo min, max, NaN count; :func:`brdfkit.engine.driver.run`)."""
    check_unit(name, "wi", math.sqrt(nrm[:, 0].min()), math.sqrt(nrm[:, 1].max()), int(nrm[:, 2].sum()), dtype)
    check_unit(name, "wo", math.sqrt(nrm[:, 3].min()), math.sqrt(nrm[:, 4].max()), int(nrm[:, 5].sum()), dtype)


__all__ = ["UNIT_TOL", "check_unit", "check_unit_flat", "check_driver_stats"]
