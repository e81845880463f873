"""LLVM's process-wide options while a generated driver compiles: vector width, interleave, unroll threshold.

llvmlite sets LLVM's "command-line" options for the whole process, so :func:`compile_options` sets them
only while holding numba's compiler lock (an internal of numba, ``numba.core.compiler_lock``), which every
numba compile takes, and resets them to LLVM's values before releasing it. The values below were measured
on the development machine (docs/speed.md); they change how fast a driver runs, never its values (each
lane still evaluates its own pair).

Guarded: where this numba has no such lock, or llvmlite refuses an option (raises), the drivers compile
with LLVM's defaults instead — the same values, only slower — after one :class:`RuntimeWarning`
(:func:`brdfkit.engine.notes.note_once`). An option LLVM does not know is ignored by llvmlite silently
(tested on llvmlite 0.50): the defaults again.
"""

from __future__ import annotations

import contextlib
import signal
import threading

from . import vecmath
from .llvm_remarks import without_llvm_remarks
from .notes import note_once

#: LLVM's loop-vectoriser width for the float32 specialised drivers: 16 lanes (one AVX-512 register).
#: Its cost model picks 8 for them on this CPU (interleaved (n, 3) loads), which measured half the
#: speed of 16 (docs/speed.md); float64 keeps the cost model's choice (16 measured slower there).
F32_VECTOR_WIDTH = 16
#: LLVM's loop-vectoriser interleave count for the specialised drivers on a CPU with AVX-512: 2 vector
#: iterations in flight per loop trip (0: the cost model's choice, which is 1 for these loop bodies). A
#: pair's evaluation is one long chain of dependent operations (square roots, divisions, the exact
#: Fresnel), so one vector iteration at a time leaves the units waiting on latency; two independent ones
#: fill them. Measured here (one thread, 2^20 pairs, GGX conductor, medians of 6 alternating rounds,
#: ns per pair, cost model → 2): float32 8.9 → 7.2 (row-major) and 8.1 → 7.1 (column-major), float64
#: 29.2 → 24.0 and 25.7 → 22.2; every model, 2^19 pairs, time ratio cost model / 2: 1.07-1.38 in float32
#: and 1.01-1.28 in float64 except Ashikhmin-Shirley and Lafortune in float32 (0.96, 0.94) and Lafortune
#: in float64 (0.97); 3 and 4 measured no better than 2. The values are bit for bit the same (each lane
#: still evaluates its own pair). Without AVX-512 (unmeasured) the cost model chooses.
SPECIAL_INTERLEAVE = 2
#: LLVM's loop-unroll threshold while a span driver compiles: a span's loops over pairs vectorise only
#: once the small loops of constant length inside them (HTSG's asymptotic series, 6 × up to 8 terms)
#: are fully unrolled, which LLVM's default threshold (300 at -O3) does not do
SPAN_UNROLL_THRESHOLD = 1000
#: LLVM's own value of that threshold at numba's -O3, set for every other driver
LLVM_UNROLL_THRESHOLD = 300
#: LLVM's vector width for the span drivers where the CPU has AVX-512: 8 float64 lanes. Its cost model
#: takes 4 (LLVM prefers 256-bit vectors there); HTSG's series set-up and terms measured 141 against
#: 194 ns per series with 8 (random directions, aluminium defaults, one thread, this machine)
SPAN_VECTOR_WIDTH = 8

#: why this process compiles with LLVM's defaults (None: the options are set); a note was given
_off: str | None = None


def on_avx512(option: int) -> int:
    """An LLVM option's value measured on AVX-512 (:data:`SPAN_VECTOR_WIDTH`, :data:`SPECIAL_INTERLEAVE`):
    ``option`` on a CPU with AVX-512, else 0 (the cost model's choice)."""
    return option if "avx512f" in vecmath.cpu_features() else 0


def compiler_lock():
    """numba's global compiler lock (``numba.core.compiler_lock``, an internal), or None where numba lacks it."""
    try:
        from numba.core.compiler_lock import global_compiler_lock
    except ImportError:
        return None
    return global_compiler_lock


def set_option(option: str) -> None:
    """Set one LLVM option for the process (llvmlite's ``set_option``; raises where llvmlite refuses it)."""
    import llvmlite.binding as ll

    ll.set_option("", option)


def _turn_off(reason: str) -> None:
    """Compile with LLVM's defaults from now on in this process, and say so once."""
    global _off
    _off = reason
    note_once("llvm-options", f"LLVM options for the drivers not set ({reason}); drivers compile with LLVM's "
                              "defaults: the same values, possibly slower")


def _set_all(width: int, unroll: int, interleave: int) -> bool:
    """The three options set (True), or LLVM's values restored as far as they can be and the options off."""
    try:
        set_option(f"-unroll-threshold={unroll}")
        set_option(f"-force-vector-width={width}")
        set_option(f"-force-vector-interleave={interleave}")
        return True
    except Exception as exc:  # a refused option: compile with the defaults
        _turn_off(f"llvmlite refused an option: {exc!r}")
        _restore()
        return False


def _restore() -> None:
    """LLVM's own values of the three options (best effort: a refusal here turns the options off)."""
    try:
        set_option("-force-vector-width=0")
        set_option("-force-vector-interleave=0")
        set_option(f"-unroll-threshold={LLVM_UNROLL_THRESHOLD}")
    except Exception as exc:
        if _off is None:
            _turn_off(f"llvmlite refused an option: {exc!r}")


@contextlib.contextmanager
def sigint_deferred():
    """Ctrl-C while a driver compiles: held until the compile is over, then delivered (to the handler
    that was in place). numba compiles through llvmlite, which calls back into Python (its object
    cache); a KeyboardInterrupt raised in such a ctypes callback is printed and dropped by ctypes,
    and LLVM goes on with a broken buffer: a batch interrupted mid-compile died of SIGSEGV
    (tests/test_measured_batch.py, the interrupt test, in a fresh-clone CI run). Only the main
    thread receives signals; elsewhere, nothing to do."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    got: list[int] = []
    try:
        old = signal.signal(signal.SIGINT, lambda signum, frame: got.append(signum))
    except ValueError:  # pragma: no cover - not the main interpreter
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)
        if got:
            signal.raise_signal(signal.SIGINT)


@contextlib.contextmanager
def compile_options(width: int = 0, unroll: int = LLVM_UNROLL_THRESHOLD, interleave: int = 0):
    """LLVM's options for a driver call that may compile: ``-force-vector-width`` and
    ``-force-vector-interleave`` (0: the cost model's choice) and ``-unroll-threshold``. They are process-wide,
    so they are set while holding numba's compiler lock, which every numba compile takes, and reset to
    LLVM's values before it is released: no compile on another thread runs with this call's options, nor
    this one with another's. (Set outside the lock, a compile waiting for it ran with the options another
    thread had set meanwhile, or with the defaults another thread's reset had restored, and was cached so:
    the serial and parallel HTSG span drivers then vectorised differently and differed in the last bit in
    full test runs.) The call runs under the lock too (a driver compiles on its first call); only first
    calls come here. Without the lock, or with an option refused: the call runs with LLVM's defaults
    (module docstring). Ctrl-C meanwhile waits for the compile (:func:`sigint_deferred`)."""
    lock = None if _off else compiler_lock()
    if lock is None:
        if _off is None:
            _turn_off("numba.core.compiler_lock.global_compiler_lock not found")
        with sigint_deferred():
            yield
        return
    with sigint_deferred(), lock:
        if not _set_all(width, unroll, interleave):
            yield
            return
        try:
            with (without_llvm_remarks() if width else contextlib.nullcontext()):
                yield
        finally:
            _restore()


__all__ = ["F32_VECTOR_WIDTH", "SPECIAL_INTERLEAVE", "SPAN_UNROLL_THRESHOLD", "LLVM_UNROLL_THRESHOLD",
           "SPAN_VECTOR_WIDTH", "compile_options", "compiler_lock", "sigint_deferred", "on_avx512", "set_option"]
