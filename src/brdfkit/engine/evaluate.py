"""``BRDF.eval`` through the engine: broadcasting, dtype, the unit check, then kernel or fallback."""

from __future__ import annotations

import numpy as np

from . import driver, reference
from .active import engine
from .unit import UNIT_TOL, check_driver_stats, check_unit, check_unit_flat  # noqa: F401  (this module's API too)


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


def run_kernel(model, kernel, args, fi: np.ndarray, fo: np.ndarray, fout: np.ndarray,
               soa: bool = False) -> np.ndarray | None:
    """``kernel`` with ``args = (p, c)`` on flat directions into the flat ``fout``, by the active engine.

    Returns the compiled driver's squared-length statistics (``None`` under the reference engine,
    which evaluates without them). ``soa``: Fortran-ordered ``(n, 3)`` arrays, for the compiled
    engine's structure-of-arrays driver (only where :func:`brdfkit.engine.driver.runs_soa`)."""
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
    give a Fortran-ordered result, at every size and under both engines. The compiled engine reads
    them in place with its structure-of-arrays driver where that applies
    (:func:`brdfkit.engine.driver.runs_soa`: more than one chunk of pairs, no table in ``p``) and
    writes the result in place; elsewhere they are copied to rows first, as any other layout, and
    the result is copied to Fortran order (at most :data:`~brdfkit.engine.driver.CHUNK` pairs, or a
    measured model's table lookups: small beside the evaluation). The values are the same either way:
    float64 bit for bit, float32 to the rounding of its fused multiply-adds (LLVM may fuse the two
    loops' products differently: 1 ulp on a few values, tested).
    """
    name = model.name
    kernel = getattr(type(model), "kernel", None)
    args = model.kernel_args() if kernel is not None else None
    fortran = _fortran_pair(wi, wo)
    if fortran and args is not None and engine() == "compiled" and driver.runs_soa(wi.shape[0], args[0]):
        out = np.empty(wi.shape, dtype=wi.dtype, order="F")
        check_driver_stats(name, run_kernel(model, kernel, args, wi, wo, out, soa=True), wi.dtype)
        return out
    out = _evaluate_rows(model, kernel, args, wi, wo)
    return np.asfortranarray(out) if fortran else out


def _evaluate_rows(model, kernel, args, wi, wo) -> np.ndarray:
    """:func:`evaluate` on directions copied (where they are not already) to C-contiguous rows."""
    name = model.name
    fi, fo, shape, dtype = prepare(name, wi, wo)
    if args is not None:
        out = np.empty(shape, dtype=dtype)
        fout = out.reshape(-1, 3)
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
