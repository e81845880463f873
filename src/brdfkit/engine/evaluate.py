"""``BRDF.eval`` through the engine: broadcasting, dtype, the unit check, then kernel or fallback."""

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


def _flat(a: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """``a`` broadcast to ``shape`` as a C-contiguous ``(n, 3)`` array: a view when ``a`` already has the shape."""
    if a.shape != shape:
        a = np.broadcast_to(a, shape)
    return np.ascontiguousarray(a).reshape(-1, 3)


def prepare(name: str, wi, wo) -> tuple[np.ndarray, np.ndarray, tuple[int, ...], np.dtype]:
    """``(fi, fo, shape, dtype)``: ``wi`` and ``wo`` in the working dtype, broadcast to ``shape`` and
    flattened to C-contiguous ``(n, 3)`` arrays (the first steps of :func:`evaluate`; no unit check)."""
    wi = np.asarray(wi)
    wo = np.asarray(wo)
    if wi.shape[-1:] != (3,) or wo.shape[-1:] != (3,):
        raise ValueError(f"{name}: directions must have a last axis of length 3, got {wi.shape} and {wo.shape}")
    dtype = np.dtype(np.float32) if (wi.dtype == np.float32 and wo.dtype == np.float32) else np.dtype(np.float64)
    wi = wi.astype(dtype, copy=False)
    wo = wo.astype(dtype, copy=False)
    try:
        shape = np.broadcast_shapes(wi.shape, wo.shape)
    except ValueError:
        raise ValueError(f"{name}: wi of shape {wi.shape} and wo of shape {wo.shape} do not broadcast") from None
    return _flat(wi, shape), _flat(wo, shape), shape, dtype


def check_unit_flat(name: str, fi: np.ndarray, fo: np.ndarray, dtype) -> None:
    """The unit-direction check of flat direction arrays (:func:`prepare`'s), without evaluating."""
    check_unit(name, "wi", *_length_stats_np(fi), dtype)
    check_unit(name, "wo", *_length_stats_np(fo), dtype)


def check_driver_stats(name: str, nrm: np.ndarray, dtype) -> None:
    """The unit-direction check from the compiled driver's per-chunk squared-length statistics
    (``(nchunks, 6)``: wi min, max, NaN count, wo min, max, NaN count; :func:`brdfkit.engine.driver.run`)."""
    check_unit(name, "wi", math.sqrt(nrm[:, 0].min()), math.sqrt(nrm[:, 1].max()), int(nrm[:, 2].sum()), dtype)
    check_unit(name, "wo", math.sqrt(nrm[:, 3].min()), math.sqrt(nrm[:, 4].max()), int(nrm[:, 5].sum()), dtype)


def run_kernel(model, kernel, args, fi: np.ndarray, fo: np.ndarray, fout: np.ndarray,
               soa: bool = False) -> np.ndarray | None:
    """``kernel`` with ``args = (p, c)`` on flat directions into the flat ``fout``, by the active engine.

    Returns the compiled driver's squared-length statistics (``None`` under the reference engine,
    which evaluates without them). ``soa``: Fortran-ordered ``(n, 3)`` arrays, for the compiled
    engine's structure-of-arrays driver (only where :func:`brdfkit.engine.driver.runs_soa`)."""
    from . import engine
    from . import driver, reference

    p, c = args
    if engine() == "compiled":
        return driver.run(kernel, fi, fo, p, c, fout, f32=getattr(type(model), "kernel_float32", False), soa=soa,
                          span=getattr(type(model), "kernel_span", None))
    reference.run(kernel, fi, fo, p, c, fout)
    return None


def _fortran_pair(wi, wo) -> bool:
    """Both directions Fortran-ordered ``(n, 3)`` arrays (each component contiguous) of one float dtype."""
    return (isinstance(wi, np.ndarray) and isinstance(wo, np.ndarray) and wi.ndim == 2 and wi.shape == wo.shape
            and wi.shape[1] == 3 and wi.dtype == wo.dtype and wi.dtype in (np.float32, np.float64)
            and wi.flags.f_contiguous and wo.flags.f_contiguous
            and not (wi.flags.c_contiguous and wo.flags.c_contiguous))


def evaluate(model, wi, wo) -> np.ndarray:
    """The whole ``BRDF.eval`` contract for ``model`` (see :mod:`brdfkit.models.base`).

    Fortran-ordered ``(n, 3)`` directions (structure of arrays, as a renderer or Dr.Jit keeps them)
    are read in place by the compiled engine's structure-of-arrays driver where it applies
    (:func:`brdfkit.engine.driver.runs_soa`), and the result is then Fortran-ordered too; elsewhere
    they are copied to rows first, as any other layout. The values are the same either way: float64
    bit for bit, float32 to the rounding of its fused multiply-adds (LLVM may fuse the two loops'
    products differently: 1 ulp on a few values, tested).
    """
    name = model.name
    kernel = getattr(type(model), "kernel", None)
    args = model.kernel_args() if kernel is not None else None
    if args is not None and _fortran_pair(wi, wo):
        from . import driver, engine

        if engine() == "compiled" and driver.runs_soa(wi.shape[0], args[0]):
            out = np.empty(wi.shape, dtype=wi.dtype, order="F")
            check_driver_stats(name, run_kernel(model, kernel, args, wi, wo, out, soa=True), wi.dtype)
            return out
    fi, fo, shape, dtype = prepare(name, wi, wo)
    if args is not None:
        out = np.empty(shape, dtype=dtype)
        fout = out.reshape(-1, 3)
        from . import engine

        if engine() != "compiled":  # the reference engine: checked before the (slow) evaluation
            check_unit_flat(name, fi, fo, dtype)
        nrm = run_kernel(model, kernel, args, fi, fo, fout)
        if nrm is not None:
            check_driver_stats(name, nrm, dtype)
        return out
    check_unit_flat(name, fi, fo, dtype)
    return _fallback(model, fi.reshape(shape), fo.reshape(shape), dtype)


def _fallback(model, wi: np.ndarray, wo: np.ndarray, dtype) -> np.ndarray:
    """A model without a kernel: its numpy ``_eval`` on directions above the horizon (both engines)."""
    valid = (wi[..., 2] > 0) & (wo[..., 2] > 0)
    all_valid = bool(valid.all())
    if not all_valid:
        up = np.zeros(3, dtype=dtype)
        up[2] = 1
        wi = np.where(valid[..., None], wi, up)
        wo = np.where(valid[..., None], wo, up)
    p = model._typed_params(dtype.type)
    with np.errstate(all="ignore"):
        f = model._eval(wi, wo, p)
    f = np.broadcast_to(np.asarray(f, dtype=dtype), wi.shape)
    if not all_valid:
        f = np.where(valid[..., None], f, dtype.type(0))
    return np.ascontiguousarray(f)


__all__ = ["evaluate", "check_unit", "UNIT_TOL"]  # prepare, check_unit_flat, run_kernel: for brdfkit.measured.fit
