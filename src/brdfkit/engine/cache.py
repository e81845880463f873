"""numba compilation with an on-disk cache keyed by the package source.

:func:`jit` is ``numba.njit(cache=True, error_model="numpy")`` with one
difference: the cache lives in brdfkit's own folder, one sub-folder per content
hash of every ``.py`` file of the package. numba's own cache is keyed by the
source file of each function only, so a changed term in ``terms/`` would
otherwise leave a stale compiled kernel of ``models/`` in use; with the hash in
the path, any source change means a fresh compile, and an unchanged package
loads every kernel from disk (a new process pays no compile).

Folder: ``$BRDFKIT_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/brdfkit`` (default
``~/.cache/brdfkit``), then ``numba-<hash>/``. If it cannot be created, numba
falls back to its usual ``__pycache__`` locations. When a process creates the folder
of a new source version, folders of older versions unused for an hour are deleted
(the most recent one is kept; :func:`prune`). The folder also holds ``albedo-plans/``: the
quadrature plan every ``check`` integrates over (:mod:`brdfkit.analysis.albedo`, ``_build_plan``),
keyed by the same source hash.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import os
import sys
import types
from pathlib import Path
from typing import Callable, Iterator

import numba

from ..fileio import write_text

_PKG = Path(__file__).resolve().parent.parent


def source_hash() -> str:
    """A short content hash of every ``.py`` file of the brdfkit package (sorted by path)."""
    h = hashlib.sha1()
    h.update(numba.__version__.encode())
    for f in sorted(_PKG.rglob("*.py")):
        try:
            data = f.read_bytes()
        except OSError:
            continue
        h.update(str(f.relative_to(_PKG)).encode())
        h.update(data)
    return h.hexdigest()[:16]


def cache_root() -> Path:
    base = os.environ.get("BRDFKIT_CACHE_DIR")
    if base:
        return Path(base)
    xdg = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(xdg) / "brdfkit"


_DIR: Path | None = None


#: cache folders of other source versions are deleted once unused for this long (seconds) ...
PRUNE_AFTER_S = 3600.0
#: ... except this many of the most recently used ones besides the current
KEEP_PREVIOUS = 1


def cache_dir() -> Path:
    """This source tree's numba cache folder (created on first use; see :func:`prune`)."""
    global _DIR
    if _DIR is None:
        d = cache_root() / f"numba-{source_hash()}"
        created = False
        try:
            d.mkdir(parents=True)
            created = True
        except FileExistsError:
            with contextlib.suppress(OSError):
                os.utime(d)  # the folder's mtime says when a process last used it
        except OSError:
            pass
        _DIR = d
        if created:  # a new source version: the moment old folders may have gone stale
            with contextlib.suppress(OSError):
                prune(d)
    return _DIR


def prune(current: Path, now: float | None = None) -> list[Path]:
    """Delete the stale ``numba-*`` folders beside ``current``; returns those deleted.

    Kept: ``current``, the :data:`KEEP_PREVIOUS` most recently used others, and every folder
    used (its mtime, touched by each process that opens it) within :data:`PRUNE_AFTER_S` —
    so a process of another source version that is running (another checkout, an old
    server) keeps its kernels. A folder is first renamed to a hidden name (atomic: of two
    processes pruning at once one wins, the other skips it), then removed; a process that
    still opens the old name just recompiles into a fresh folder.
    """
    import shutil
    import time

    now = time.time() if now is None else now
    root = current.parent
    others = []
    for d in root.glob("numba-*"):
        if d == current or not d.is_dir():
            continue
        try:
            others.append((d.stat().st_mtime, d))
        except OSError:
            continue
    others.sort(reverse=True)
    deleted = []
    for mtime, d in others[KEEP_PREVIOUS:]:
        if now - mtime < PRUNE_AFTER_S:
            continue
        trash = root / f".trash-{d.name}-{os.getpid()}"
        try:
            os.rename(d, trash)
        except OSError:
            continue
        shutil.rmtree(trash, ignore_errors=True)
        deleted.append(d)
    return deleted


@contextlib.contextmanager
def in_cache_dir() -> Iterator[None]:
    """numba's ``CACHE_DIR`` set to :func:`cache_dir` while functions are decorated, then restored."""
    old = getattr(numba.config, "CACHE_DIR", "")  # numba's setting (NUMBA_CACHE_DIR); "" where a numba lacks it
    numba.config.CACHE_DIR = str(cache_dir())
    try:
        yield
    finally:
        numba.config.CACHE_DIR = old


def load_generated(folder: str, stem: str, src: str, package: str) -> types.ModuleType:
    """The module of generated source ``src``, file ``<cache_dir>/<folder>/<stem>.py``, imported as
    ``<package>.<stem>`` once per process: the file is written (atomically) only when its text changed,
    and executed with numba's cache folder set to :func:`cache_dir`, so its ``cache=True`` functions'
    machine code is reused by every process of the same package source. Used by the generated drivers
    (:mod:`.generated`) and the forward twins (:mod:`.forward`)."""
    modname = f"{package}.{stem}"
    mod = sys.modules.get(modname)
    if mod is not None:
        return mod
    where = cache_dir() / folder
    where.mkdir(parents=True, exist_ok=True)
    path = where / f"{stem}.py"
    try:
        current = path.read_text()
    except OSError:
        current = None
    if current != src:
        write_text(path, src)
    spec = importlib.util.spec_from_file_location(modname, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[modname] = mod  # first: a function compiled (or loaded) while it executes finds its module
    try:
        with in_cache_dir():
            spec.loader.exec_module(mod)
    except BaseException:
        del sys.modules[modname]
        raise
    return mod


JIT_OPTIONS = dict(cache=True, error_model="numpy", nogil=True)


def jit(fn: Callable | None = None, *, inline: bool = False, reassociate: bool = False,
        parallel: bool = False) -> Callable:
    """Decorator for scalar terms and kernels: nopython, cached, ``error_model="numpy"``, no fastmath (but ``reassociate``).

    ``@jit(inline=True)`` also inlines the function into its numba callers (numba IR
    inlining, ``inline="always"``): for the small dispatchers over a choice index
    (``fresnel_of``, ``d_of``, ...), so that a driver compiled with constant choices
    folds their branches away (LLVM's own inliner leaves a function called three
    times per pair out of line).

    ``@jit(reassociate=True)`` lets LLVM reorder the function's floating-point sums (the
    ``reassoc`` fast-math flag, nothing else): a reduction loop then vectorises. Only for a sum
    of terms of one sign (HTSG's series), where the order changes the rounding by a few ulp and
    nothing else (no NaN, inf or signed-zero change).

    ``@jit(parallel=True)``: numba's ``parallel=True`` (a ``numba.prange`` loop runs on its thread pool),
    for a whole-array helper such as :func:`brdfkit.engine.grad`'s scatter, not for a kernel.
    """
    if fn is None:
        return lambda f: jit(f, inline=inline, reassociate=reassociate, parallel=parallel)
    opts = dict(JIT_OPTIONS, inline="always") if inline else dict(JIT_OPTIONS)
    if reassociate:
        opts["fastmath"] = {"reassoc"}
    if parallel:
        opts["parallel"] = True
    with in_cache_dir():
        return numba.njit(**opts)(fn)


__all__ = ["jit", "cache_dir", "prune", "source_hash", "in_cache_dir", "load_generated", "JIT_OPTIONS"]
