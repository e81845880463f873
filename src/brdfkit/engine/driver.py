"""The runner: which compiled driver a ``BRDF.eval`` call runs, how, and with what bookkeeping.

:func:`run` evaluates a model's scalar kernel over flat ``(n, 3)`` direction arrays with a driver
generated from :mod:`.templates` and loaded by :mod:`.generated`:

* up to :data:`CHUNK` pairs, or a ``p`` that holds a table (longer than :data:`MAX_TUPLE`), the
  generic driver (choices read at run time; a single chunk runs inline, without the thread pool);
* more, the driver specialised for the call's choice combination (lazily generated, cached on disk),
  whose loop LLVM vectorises; Fortran-ordered ``(n, 3)`` arrays run its structure-of-arrays form.
  Its chunks run in parallel, or serially on the calling thread when numba has one thread or the
  call's work, estimated from the driver's earlier calls, is small (:mod:`.cost`);
* a model with a *span* (HTSG) runs it for calls of more than :data:`SPAN_MIN_PAIRS` pairs, the same
  way. The reference engine runs the per-pair kernel (:mod:`.reference`).

A call that may compile (the first with its argument types) sets LLVM's options for the compile
(:mod:`.llvm_options`). Every call returns the per-chunk squared-length statistics of the directions
for the unit check of ``BRDF.eval`` (:mod:`.unit`).

The templates and the generated modules were once part of this module: the names tests and other
modules import from here (``CHUNK``, the templates, ``driver_for`` and its kin, ``SPAN_VECTOR_WIDTH``)
are kept here too.
"""

from __future__ import annotations

import contextlib
import threading
import time
from typing import Callable

import numpy as np

from . import cost, vecmath
from .cost import _PAIR_COST, PARALLEL_MIN_S  # noqa: F401  (kept importable from here)
from .generated import (_DRIVERS, _SERIAL, _span_key, _special_key, _stem, driver_for,  # noqa: F401
                        elementwise_driver_for, span_driver_for, special_driver_for)
from .llvm_options import (F32_VECTOR_WIDTH, LLVM_UNROLL_THRESHOLD, SPAN_UNROLL_THRESHOLD, SPAN_VECTOR_WIDTH,  # noqa: F401
                           SPECIAL_INTERLEAVE, compile_options, on_avx512, sigint_deferred)
from .precision import fits_float32
from .templates import CHUNK, SOA_TEMPLATE, SPAN_TEMPLATE, SPECIAL_TEMPLATE, TEMPLATE  # noqa: F401
from .threads import THREAD_SAFE_LAYERS, THREADING_LAYER
from .unit import UNIT_TOL, _sq_stats

#: the specialised driver passes ``p`` as a tuple; kernels with longer ``p`` (tables) keep the generic one
MAX_TUPLE = 64
#: one parallel launch at a time where numba's layer is workqueue (not reentrant across threads);
#: TBB and OpenMP are thread-safe: no lock (brdfkit.engine.threads)
_RUN_LOCK = contextlib.nullcontext() if THREADING_LAYER in THREAD_SAFE_LAYERS else threading.Lock()
#: the (driver, argument types) of the calls made so far: a call with new argument types compiles (or loads)
#: a specialisation, for which the driver's LLVM options must be set (:func:`_compile_key`)
_COMPILED: set = set()
_NO_OPTIONS = contextlib.nullcontext()


def _compile_key(drive: Callable, pt: tuple, *arrays: np.ndarray) -> tuple:
    """What decides the specialisation a driver call runs: numba compiles one per signature of argument types;
    the flat input arrays :func:`run` passes are always read-only (:func:`read_only`), so those vary only by
    dtype, the tuple ``p`` by its length."""
    return (drive, len(pt)) + tuple(a.dtype for a in arrays)


def _first_call_options(first: bool, width: int = 0, unroll: int = LLVM_UNROLL_THRESHOLD, interleave: int = 0):
    """LLVM's options for a call that may compile (:func:`.llvm_options.compile_options`), else nothing."""
    return compile_options(width, unroll, interleave) if first else _NO_OPTIONS


def may_compile(ck: tuple):
    """For a call without LLVM options that may compile (its :func:`_compile_key` not yet seen): Ctrl-C
    held until it returns (:func:`.llvm_options.sigint_deferred`), and the key noted; else nothing."""
    if ck in _COMPILED:
        return _NO_OPTIONS
    _COMPILED.add(ck)  # noted first: a call that raises is not retried with the signal held again
    return sigint_deferred()


def nchunks(n: int) -> int:
    return max(1, (n + CHUNK - 1) // CHUNK)


#: the squared-length statistics of a call whose every direction is within the unit tolerance
_ALL_UNIT = (1.0, 1.0, 0.0, 1.0, 1.0, 0.0)


def unit_band(dtype, ft) -> tuple:
    """``(lo2, hi2)``: a band of squared lengths safely inside ``|w|`` in ``[1 − tol, 1 + tol]`` (``tol`` the
    unit tolerance of the output ``dtype``), in the working precision ``ft``: the margin is far above the
    rounding of x² + y² + z² in that precision (and of the band's own rounding to it)."""
    tol = UNIT_TOL[dtype]
    margin = 1e-5 if ft is np.float32 else 1e-9
    return ft((1.0 - tol) * (1.0 - tol) * (1.0 + margin)), ft((1.0 + tol) * (1.0 + tol) * (1.0 - margin))


def _after_call(key: tuple, ck: tuple, first: bool, elapsed: float, serial: bool, threads: int, n: int,
                bad: np.ndarray, wi: np.ndarray, wo: np.ndarray, nrm: np.ndarray) -> np.ndarray:
    """The bookkeeping after a specialised or span driver's call: the compiled specialisation noted, or the
    driver's one-thread seconds per pair (a parallel call's time times its threads, an upper bound; calls of
    more than :data:`CHUNK` pairs), and ``nrm`` filled: all within tolerance, or the exact statistics (the
    generic driver's formula) for ``check_unit`` and its message."""
    if first:
        _COMPILED.add(ck)
    else:
        cost.record(key, elapsed, serial, threads, n)
    if not bad.any():
        nrm[:] = _ALL_UNIT
    else:
        nrm[:] = [*_sq_stats(np.ascontiguousarray(wi)), *_sq_stats(np.ascontiguousarray(wo))]
    return nrm


#: a call of at most this many pairs runs a span model's per-pair kernel (the generic driver), not its span:
#: a span call costs ~25 µs more before its first pair (its scratch, its Python), the per-pair kernel ~1.8 µs
#: per pair more after it (HTSG, measured: 5 against 32 µs for one pair, 18 against 30 for 8, 75 against 56
#: for 32). Both compute the same functions; the values differ by the vector math library's rounding (1e-13).
SPAN_MIN_PAIRS = 16


def _run_span(span: Callable, wi: np.ndarray, wo: np.ndarray, p: np.ndarray, c: np.ndarray, out: np.ndarray,
              soa: bool) -> np.ndarray:
    """:func:`run` for a model with a span: float64 computation on rows or Fortran-ordered arrays."""
    n = wi.shape[0]
    nrm = np.empty((nchunks(n), 6), dtype=np.float64)
    drive = span_driver_for(span)
    key = _span_key(span)
    serial, threads = cost.serially(key, n)
    serial = serial or n <= CHUNK
    if serial:
        drive = _SERIAL[key]
    lim = np.float64(np.finfo(out.dtype).max)
    lo2, hi2 = unit_band(out.dtype, np.float64)
    bad = np.zeros(nrm.shape[0], dtype=np.int64)
    pt = param_tuple(p)
    ck = _compile_key(drive, pt, wi, wo)
    first = ck not in _COMPILED
    flat = (lambda x: x.T.reshape(-1)) if soa else (lambda x: x.reshape(-1))
    cs, ps = (n, 1) if soa else (1, 3)
    lock = contextlib.nullcontext() if serial else _RUN_LOCK
    with lock, _first_call_options(first, on_avx512(SPAN_VECTOR_WIDTH), SPAN_UNROLL_THRESHOLD), \
            vecmath.compiling():
        t0 = time.perf_counter()
        drive(flat(wi), flat(wo), pt, c, flat(out), lim, lo2, hi2, bad, cs, ps, n)
        elapsed = time.perf_counter() - t0
    return _after_call(key, ck, first, elapsed, serial, threads, n, bad, wi, wo, nrm)


def runs_soa(n: int, p: np.ndarray) -> bool:
    """Whether :func:`run` takes Fortran-ordered ``(n, 3)`` arrays for ``n`` pairs with parameters ``p``
    (the specialised drivers only: more than :data:`CHUNK` pairs, no table in ``p``)."""
    return n > CHUNK and len(p) <= MAX_TUPLE


def param_tuple(p: np.ndarray, ft=np.float64) -> tuple[float, ...]:
    """``p`` as a tuple (values LLVM keeps in registers: an array might alias the output), zero-padded
    to a power of two >= 32 so that one compiled specialisation serves every length up to it
    (a kernel's dead branches may index past a short ``p``). ``ft=np.float32``: float32 values."""
    n = len(p)
    size = max(32, 1 << max(0, n - 1).bit_length())
    if ft is np.float32:
        return tuple(np.asarray(p, dtype=np.float32)) + (np.float32(0.0),) * (size - n)
    return tuple(p.tolist()) + (0.0,) * (size - n)


def read_only(a: np.ndarray) -> np.ndarray:
    """``a``, or a read-only view of it (no copy).

    numba specialises a function on each array argument's writability too, so a frozen array (the
    albedo plan's, :mod:`brdfkit.analysis.albedo`) and a writable one would each compile, cache and,
    in every new process, load their own copy of a driver: half of ``check --all``'s cache loads were
    such twins. :func:`run` passes every input array read-only, so each driver has one.
    """
    if not a.flags.writeable:
        return a
    v = a.view()
    v.flags.writeable = False
    return v


def run(kernel: Callable, wi: np.ndarray, wo: np.ndarray, p: np.ndarray, c: np.ndarray, out: np.ndarray,
        f32: bool = False, soa: bool = False, span: Callable | None = None) -> np.ndarray:
    """Evaluate ``kernel`` into ``out`` (flat ``(n, 3)``); returns the ``(nchunks, 6)`` squared-length statistics.

    Up to :data:`CHUNK` pairs: the generic driver (choices read at run time; one compile per
    kernel and dtype). More: the driver specialised for this choice combination, compiled on
    first use and cached on disk, whose loop LLVM vectorises: in parallel, or on the calling thread
    (its serial twin, without the launch lock) when numba has one thread or the work estimated from
    the driver's earlier calls is below :data:`PARALLEL_MIN_S`. ``f32`` (float32 arrays only):
    run the kernel's float32 twin, ``p`` rounded to float32 — unless a parameter does not fit
    float32 (:func:`.precision.fits_float32`), then the float64 kernel runs. ``soa`` (only where
    :func:`runs_soa`): ``wi``, ``wo`` and ``out`` are Fortran-ordered ``(n, 3)`` arrays, read and
    written in place by the structure-of-arrays driver (the same values: float64 bit for bit, float32
    to the rounding of its fused multiply-adds). ``span``: the model's span (module docstring), which
    then runs instead of ``kernel`` for every call of more than :data:`SPAN_MIN_PAIRS` pairs, in float64.
    """
    n = wi.shape[0]
    wi, wo, p, c = read_only(wi), read_only(wo), read_only(p), read_only(c)  # one specialisation per driver
    if soa and not runs_soa(n, p):
        raise ValueError(f"driver.run: soa=True needs more than {CHUNK} pairs and no table in p (got {n} pairs, "
                         f"{len(p)} parameters)")
    nrm = np.empty((nchunks(n), 6), dtype=np.float64)
    if n == 0:
        nrm[:] = _ALL_UNIT
        return nrm
    if span is not None and n > SPAN_MIN_PAIRS:
        return _run_span(span, wi, wo, p, c, out, soa)
    if f32 and out.dtype == np.float32:
        f32 = fits_float32(p)  # parameters outside float32's normal range: computed in float64
    else:
        f32 = False
    ft = np.float32 if f32 else np.float64
    lim = ft(np.finfo(out.dtype).max)
    if f32:
        p = read_only(p.astype(np.float32))
    if n <= CHUNK:  # a single chunk runs inline, no thread pool: no lock needed
        gd = driver_for(kernel, f32)._drive
        with may_compile(_compile_key(gd, p, wi, wo)), vecmath.compiling():
            gd(wi, wo, p, c, out, lim, nrm)  # a compile meanwhile calls libmvec (.vecmath)
        return nrm
    if len(p) > MAX_TUPLE:  # a table in p (measured data): the generic driver, p stays an array
        gd = driver_for(kernel, f32)._drive
        with _RUN_LOCK, may_compile(_compile_key(gd, p, wi, wo)), vecmath.compiling():
            gd(wi, wo, p, c, out, lim, nrm)
        return nrm
    choices = tuple(int(v) for v in c)
    drive = special_driver_for(kernel, choices, f32, soa)
    key = _special_key(kernel, choices, f32, soa)
    serial, threads = cost.serially(key, n)
    if serial:
        drive = _SERIAL[key]
    lo2, hi2 = unit_band(out.dtype, ft)
    bad = np.zeros(nrm.shape[0], dtype=np.int64)
    pt = param_tuple(p, ft)
    ck = _compile_key(drive, pt, wi, wo)
    first = ck not in _COMPILED  # this call may compile (or load) a specialisation of the driver
    lock = contextlib.nullcontext() if serial else _RUN_LOCK  # a serial call launches no thread pool
    with lock, _first_call_options(first, F32_VECTOR_WIDTH if f32 else 0, interleave=on_avx512(SPECIAL_INTERLEAVE)), \
            vecmath.compiling():
        t0 = time.perf_counter()
        if soa:  # the transposes of Fortran-ordered (n, 3) arrays are C-contiguous: flat views, no copy
            drive(wi.T.reshape(-1), wo.T.reshape(-1), pt, out.T.reshape(-1), lim, lo2, hi2, bad)
        else:
            drive(wi.reshape(-1), wo.reshape(-1), pt, out.reshape(-1), lim, lo2, hi2, bad)
        elapsed = time.perf_counter() - t0
    return _after_call(key, ck, first, elapsed, serial, threads, n, bad, wi, wo, nrm)


__all__ = ["CHUNK", "PARALLEL_MIN_S", "TEMPLATE", "SPECIAL_TEMPLATE", "SOA_TEMPLATE", "SPAN_TEMPLATE", "driver_for",
           "special_driver_for", "span_driver_for", "elementwise_driver_for",
           "param_tuple", "read_only", "run", "runs_soa", "nchunks"]
