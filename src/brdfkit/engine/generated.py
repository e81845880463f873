"""The generated driver modules: written into the cache folder, imported from there, memoised per key.

A driver's source is one of :mod:`.templates`, formatted for a kernel (and a choice combination, a
layout, a span, a scalar term). :func:`_load` writes it to ``<cache_dir>/drivers/<stem>.py`` and imports it
(:func:`brdfkit.engine.cache.load_generated`: written only when the text changed, atomically, executed
with numba's cache folder set to :func:`brdfkit.engine.cache.cache_dir`), so a new process of the same package source loads every
compiled driver from disk. The folder's name holds a hash of the package source, the file's name the
kernel's module and name, its precision and whether it calls libmvec (:func:`_stem`), so a cached driver
is only ever reused for the source and vector-math setting it was compiled from.

:data:`_DRIVERS` holds each loaded ``drive`` by key, :data:`_SERIAL` its serial twin ``drive_serial``
where the template has one; the keys (:func:`_special_key`, :func:`_span_key`) are also those of the
work estimates of :mod:`.cost`.
"""

from __future__ import annotations

import re
import threading
from collections import Counter
from typing import Callable

from . import vecmath
from .cache import load_generated
from .templates import (CHUNK, ELEMENTWISE_TEMPLATE, FASTMATH, FTYPE, KERNEL_LINE, SOA_TEMPLATE, SPAN_TEMPLATE,
                        SPECIAL_TEMPLATE, TEMPLATE)

#: every ``drive`` loaded in this process, by key
_DRIVERS: dict[tuple, Callable] = {}
#: the serial twin (``drive_serial``) of each specialised or span driver, by the same key
_SERIAL: dict[tuple, Callable] = {}
_LOCK = threading.Lock()


def _load(key: tuple, stem: str, src: str) -> Callable:
    """The ``drive`` of the generated module ``src`` (file ``<stem>.py``), loaded once per process by ``key``."""
    d = _DRIVERS.get(key)
    if d is not None:
        return d
    with _LOCK:
        d = _DRIVERS.get(key)
        if d is not None:
            return d
        mod = load_generated("drivers", stem, src, "brdfkit._engine_drivers")
        if hasattr(mod, "drive_serial"):
            _SERIAL[key] = mod.drive_serial
        _DRIVERS[key] = mod.drive
        return mod.drive


def _ident(py) -> str:
    """A Python function's module and name as one identifier, for a generated module's file name."""
    return re.sub(r"[^A-Za-z0-9_]", "_", f"{py.__module__}_{py.__name__}")


def _stem(py, f32: bool = False) -> str:
    # drivers that call libmvec (.vecmath) have their own files: a process without it never loads one
    return "drv_" + _ident(py) + ("__f32" if f32 else "") + ("__vm" if vecmath.available() else "")


class _Stats:
    """numba's cache statistics summed over every driver of one kernel loaded in this process."""

    def __init__(self, drivers):
        self.cache_hits = Counter()
        self.cache_misses = Counter()
        for d in drivers:
            self.cache_hits.update(d.stats.cache_hits)
            self.cache_misses.update(d.stats.cache_misses)


class KernelDriver:
    """``driver_for(kernel)``: the generic ``drive`` (callable) and ``stats`` over all of the kernel's drivers."""

    def __init__(self, key: tuple, drive: Callable) -> None:
        self._key = key
        self._drive = drive

    def __call__(self, *args):
        return self._drive(*args)

    @property
    def stats(self) -> _Stats:
        return _Stats([d for k, d in list(_DRIVERS.items()) if k[:2] == self._key[:2]])


_GENERIC: dict[tuple, KernelDriver] = {}


def driver_for(kernel: Callable, f32: bool = False) -> KernelDriver:
    """The generic compiled ``drive`` for ``kernel`` (runtime choices; generated, imported and memoised).

    ``f32``: the driver of the kernel's float32 twin (:mod:`.precision`), for float32 arrays.
    """
    kd = _GENERIC.get((kernel, f32))
    if kd is None:
        py = getattr(kernel, "py_func", kernel)
        key = (py.__module__, py.__name__, f32)
        src = TEMPLATE.format(module=py.__module__, name=py.__name__, chunk=CHUNK,
                              kernel_line=KERNEL_LINE[f32], F=FTYPE[f32], FM=FASTMATH[f32])
        kd = _GENERIC[(kernel, f32)] = KernelDriver(key, _load(key, _stem(py, f32), src))
    return kd


def _special_key(kernel: Callable, choices: tuple[int, ...], f32: bool, soa: bool = False) -> tuple:
    """The key of a specialised driver (and of its serial twin and work estimate)."""
    py = getattr(kernel, "py_func", kernel)
    return (py.__module__, py.__name__, f32, choices) + (("soa",) if soa else ())


def special_driver_for(kernel: Callable, choices: tuple[int, ...], f32: bool = False, soa: bool = False) -> Callable:
    """The ``drive`` of ``kernel`` compiled for one combination of choice values (generated lazily, cached on disk).

    ``soa``: the driver for Fortran-ordered ``(n, 3)`` arrays (:data:`SOA_TEMPLATE`).
    """
    py = getattr(kernel, "py_func", kernel)
    key = _special_key(kernel, choices, f32, soa)
    d = _DRIVERS.get(key)
    if d is not None:
        return d
    src = (SOA_TEMPLATE if soa else SPECIAL_TEMPLATE).format(
        module=py.__module__, name=py.__name__, chunk=CHUNK, choices=repr(choices),
        kernel_line=KERNEL_LINE[f32], F=FTYPE[f32], FM=FASTMATH[f32])
    stem = _stem(py, f32) + "__c" + "_".join(str(v) for v in choices) + ("__soa" if soa else "")
    return _load(key, stem, src)


def elementwise_driver_for(scalar: Callable, nargs: int) -> Callable:
    """``drive(a0, …, a{nargs−1}, out)``: ``out[i] = scalar(a0[i], …)`` over 1-D float64 arrays (any strides, a
    stride of 0 for a broadcast value; ``out`` contiguous), for :class:`brdfkit.engine.cache.vectorize`.

    A generated module like the drivers, compiled for that one signature (layout ``A``) and cached on disk, so a
    new process only loads it (3–4 ms). A numba ufunc (``numba.vectorize``, what this replaces) caches its kernel
    but builds and compiles its wrapper anew in every process: 65–86 ms per function, measured at the first
    call in a fresh process, three in each ``check --all`` worker that checks HTSG. Compiled without the vector math
    library: the values are libm's, as the ufunc's were."""
    py = getattr(scalar, "py_func", scalar)
    key = ("elementwise", py.__module__, py.__name__, nargs)
    d = _DRIVERS.get(key)
    if d is not None:
        return d
    names = [f"a{k}" for k in range(nargs)]
    src = ELEMENTWISE_TEMPLATE.format(module=py.__module__, name=py.__name__, nargs=nargs,
                                      arrays=", ".join(["IN"] * nargs), args=", ".join(names),
                                      items=", ".join(f"{n}[i]" for n in names))
    return _load(key, "vec_" + _ident(py), src)


def _span_key(span: Callable) -> tuple:
    """The key of a span's driver (and of its serial twin and work estimate)."""
    py = getattr(span, "py_func", span)
    return ("span", py.__module__, py.__name__)


def span_driver_for(span: Callable) -> Callable:
    """The ``drive`` of a model's span (:data:`SPAN_TEMPLATE`; generated, imported and memoised)."""
    py = getattr(span, "py_func", span)
    key = _span_key(span)
    d = _DRIVERS.get(key)
    if d is not None:
        return d
    src = SPAN_TEMPLATE.format(module=py.__module__, name=py.__name__, chunk=CHUNK)
    return _load(key, _stem(py) + "__span", src)


__all__ = ["driver_for", "special_driver_for", "span_driver_for", "elementwise_driver_for", "KernelDriver"]
