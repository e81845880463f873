"""Vector math for the compiled drivers: glibc's libmvec behind the loops LLVM vectorises.

A driver's loop that calls ``math.erfc``, ``math.atan2``, ``x ** y`` & co. stays scalar (or
calls libm once per lane) unless LLVM knows a vector version of the function: numba's SVML path
needs an SVML-built llvmlite (PyPI's is not), and LLVM's ``-vector-library`` option does not reach
the pass pipelines llvmlite drives (tried). glibc's libmvec (on every x86-64 glibc >= 2.22) holds
vector versions under the x86 vector-function ABI names, ``_ZGV<isa>N<lanes><v per arg>_<name>``
(isa ``b`` SSE, ``d`` AVX2, ``e`` AVX-512; float32 names end in ``f``). While a driver compiles
(:func:`compiling`), its module (not those of the terms it calls, compiled meanwhile: their code is
linked into the driver's and optimised there again) is edited twice, as text:

* before optimisation (:func:`annotate`), each call of a scalar math function that libmvec holds
  gets LLVM's ``"vector-function-abi-variant"`` attribute naming its vector versions (the mechanism
  of OpenMP's ``declare simd``), and those are declared (kept by ``llvm.compiler.used``): the loop
  vectoriser then costs them as one call per vector and calls them directly;
* after optimisation (:func:`rewrite`), a vector intrinsic the vectoriser still wrote
  (``llvm.exp.v8f64``, which the code generator would split into 8 libm calls) is renamed to its
  libmvec function.

Only functions libmvec exports for an instruction set this CPU has are named. A libmvec function is
accurate to 4 ulp (glibc's manual, "Errors in Math Functions"; measured in ``tests/test_vecmath.py``)
where libm's is < 1 ulp: far inside the engine's 1e-12 parity with the reference engine. Drivers
compiled so have their own cache files (``generated._stem``), so a process with vector math off
(``BRDFKIT_VECTOR_MATH=0``, or no libmvec) never loads one.

The hook wraps numba's ``CPUCodeLibrary._optimize_final_module`` and edits the library's
``_final_module`` (internals of numba 0.6x, tested on 0.68): it acts only inside :func:`compiling`, on
the compiling thread, on the drivers' modules; any other numba compile in the process is unchanged.
Where numba lacks that class or method, or an edit fails (a numba whose library has changed), vector
math is off for the process — the drivers as without libmvec: the same values to libm's rounding, only
slower — with one :class:`RuntimeWarning` (:func:`brdfkit.engine.notes.note_once`).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import platform
import re
import sys
import threading

#: glibc's libmvec, by its soname
SONAME = "libmvec.so.1"
#: environment variable: "0" turns vector math off (read at import)
ENV_VAR = "BRDFKIT_VECTOR_MATH"
#: the scalar functions annotated before optimisation (libm names; numba calls exp, log, pow, sin and
#: cos as LLVM intrinsics, the others by their libm names), with their number of arguments
SCALAR_FUNCTIONS = {
    "exp": 1, "log": 1, "pow": 2, "sin": 1, "cos": 1, "erf": 1, "erfc": 1, "expm1": 1, "log1p": 1,
    "atan2": 2, "acos": 1, "asin": 1, "atan": 1, "tan": 1, "sinh": 1, "cosh": 1, "tanh": 1, "hypot": 2,
    "exp2": 1, "log2": 1, "log10": 1, "cbrt": 1,
}
#: the vector intrinsics renamed after optimisation (those LLVM writes for numba's exp, log, pow)
FUNCTIONS = {fn: SCALAR_FUNCTIONS[fn] for fn in ("exp", "log", "pow")}
#: the vector-function ABI widths: float64 on SSE/AVX2/AVX-512, float32 likewise
_WIDTHS = {"f64": (("b", 2), ("d", 4), ("e", 8)), "f32": (("b", 4), ("d", 8), ("e", 16))}
_LLTYPE = {"f64": "double", "f32": "float"}
#: (element type, lanes) -> the vector-function ABI's ISA letter
_ISA = {(ty, lanes): isa for ty, widths in _WIDTHS.items() for isa, lanes in widths}
#: the CPU feature (LLVM's name) each ISA letter needs
_ISA_FEATURE = {"b": "sse4.2", "d": "avx2", "e": "avx512f"}
_INTRINSIC = re.compile(r"@llvm\.(exp|log|pow)\.v(\d+)(f32|f64)\b")
_DECLARE = re.compile(r"declare [^@\n]*@(_ZGV\w+)\(")

_state = threading.local()
_names: dict[tuple[str, int, str], str] = {}
#: scalar symbol (``erfc``, ``llvm.pow.f64``, ``atan2f``) -> [(lanes, vector name)] that libmvec exports here
_variants: dict[str, list[tuple[int, str]]] = {}
#: scalar symbol -> (number of arguments, LLVM element type)
_signature: dict[str, tuple[int, str]] = {}
#: attribute-group numbers for the annotations (far above what numba's modules use)
_ATTR_BASE = 900000
_installed = False


def _abi_name(isa: str, lanes: int, fn: str, nargs: int, ty: str) -> str:
    """The x86 vector-function ABI name: ``_ZGV<isa>N<lanes><v per argument>_<fn>[f]`` (no mask)."""
    return f"_ZGV{isa}N{lanes}{'v' * nargs}_{fn}{'f' if ty == 'f32' else ''}"


def vector_name(fn: str, lanes: int, ty: str) -> str | None:
    """libmvec's name for ``fn`` on ``lanes`` elements of ``ty`` ("f32"/"f64"), or None (no such ISA)."""
    isa = _ISA.get((ty, lanes))
    if isa is None or fn not in FUNCTIONS:
        return None
    return _abi_name(isa, lanes, fn, FUNCTIONS[fn], ty)


def rewrite(ir: str, names: dict[tuple[str, int, str], str] | None = None) -> str:
    """``ir`` with each vector exp/log/pow intrinsic that ``names`` maps renamed to its libmvec function.

    The intrinsic's declaration is renamed with its calls (its attributes, ``memory(none)`` among
    them, hold for libmvec's functions too); widths or functions not in ``names`` are left alone.
    """
    table = _names if names is None else names

    def repl(m: re.Match) -> str:
        name = table.get((m.group(1), int(m.group(2)), m.group(3)))
        return f"@{name}" if name else m.group(0)

    out = _INTRINSIC.sub(repl, ir)
    if out == ir:
        return ir
    # a libmvec function :func:`annotate` declared already: its renamed intrinsic declaration goes
    lines, seen = [], set()
    for line in out.split("\n"):
        m = _DECLARE.match(line)
        if m:
            if m.group(1) in seen:
                continue
            seen.add(m.group(1))
        lines.append(line)
    return "\n".join(lines)


def _scalar_symbols(fn: str, ty: str) -> tuple[str, ...]:
    suffix = "f" if ty == "f32" else ""
    return (fn + suffix, f"llvm.{fn}.{ty}")


def annotate(ir: str, variants: dict[str, list[tuple[int, str]]] | None = None,
             signature: dict[str, tuple[int, str]] | None = None) -> str:
    """``ir`` with each call of a scalar math function in ``variants`` given LLVM's
    ``"vector-function-abi-variant"`` attribute, its vector versions declared and kept.

    Returns ``ir`` unchanged when it calls none of them, or when it already has an
    ``llvm.compiler.used`` list (this edit would have to merge with it: left alone instead).
    """
    variants = _variants if variants is None else variants
    signature = _signature if signature is None else signature
    if "@llvm.compiler.used" in ir:
        return ir
    present = [sym for sym in variants if f"@{sym}(" in ir and re.search(rf"call [^\n]*@{re.escape(sym)}\(", ir)]
    if not present:
        return ir
    tail, used = [], []
    for k, sym in enumerate(present):
        nargs, lltype = signature[sym]
        group = _ATTR_BASE + k
        mapping = ",".join(f"_ZGV_LLVM_N{lanes}{'v' * nargs}_{sym}({name})" for lanes, name in variants[sym])
        ir = re.sub(rf"(call [^\n]*@{re.escape(sym)}\((?:[^()\n]|\([^()\n]*\))*\))", rf"\1 #{group}", ir)
        tail.append(f'attributes #{group} = {{ "vector-function-abi-variant"="{mapping}" }}')
        for lanes, name in variants[sym]:
            if name in used or f"@{name}(" in ir:
                continue
            vt = f"<{lanes} x {lltype}>"
            tail.append(f"declare {vt} @{name}({', '.join([vt] * nargs)})")
            used.append(name)
    if used:
        refs = ", ".join(f"ptr @{u}" for u in used)
        tail.append(f'@llvm.compiler.used = appending global [{len(used)} x ptr] [{refs}], section "llvm.metadata"')
    return ir + "\n" + "\n".join(tail) + "\n"


def available() -> bool:
    """True when drivers compiled now call libmvec (library loaded, hook installed, not turned off)."""
    return _installed and bool(_names)


#: the name every generated driver's functions carry (their module is brdfkit._engine_drivers.*)
DRIVER_MARK = "_engine_drivers"


class _Compiling:
    """The context of :func:`compiling` (a class: entering costs ~0.2 µs, the one-pair path runs it too)."""

    __slots__ = ("prev", "scope")

    def __init__(self, scope: str) -> None:
        self.scope = scope

    def __enter__(self):
        self.prev = getattr(_state, "on", None)
        _state.on = self.scope
        return self

    def __exit__(self, *exc):
        _state.on = self.prev
        return False


def compiling(scope: str = "drivers") -> _Compiling:
    """A context: numba compiles on this thread meanwhile call libmvec (where LLVM vectorises).

    ``scope="drivers"`` (the engine's): only the generated drivers' own code modules, whose
    cache files are apart (``generated._stem``); the terms they call, compiled meanwhile, stay as
    numba writes them (their cache is shared with processes that have vector math off), and
    are vectorised inside the driver, where their code is linked in and optimised again.
    ``scope="all"``: every module compiled meanwhile (tests, experiments).
    """
    if scope not in ("drivers", "all"):
        raise ValueError(f"scope must be 'drivers' or 'all', not {scope!r}")
    return _Compiling(scope)


def _applies(library) -> bool:
    scope = getattr(_state, "on", None)
    if not scope or not _names:
        return False
    if scope == "all":
        return True
    return any(DRIVER_MARK in f.name for f in library._final_module.functions if not f.is_declaration)


def _open_library() -> tuple[str, ctypes.CDLL] | None:
    """libmvec's path and handle, or None (not Linux x86-64, or not found)."""
    if sys.platform != "linux" or platform.machine() not in ("x86_64", "AMD64"):
        return None
    # by its soname first: dlopen is immediate, find_library runs ldconfig (~5 ms)
    for path in (SONAME, ctypes.util.find_library("mvec")):
        if path:
            try:
                return path, ctypes.CDLL(path)
            except OSError:
                continue
    return None


_FEATURES: set[str] | None = None


def cpu_features() -> set[str]:
    """The host CPU's features as LLVM names them (``avx2``, ``avx512f``, ...); read once."""
    global _FEATURES
    if _FEATURES is None:
        import llvmlite.binding as ll

        try:
            feats = ll.get_host_cpu_features()
        except RuntimeError:  # pragma: no cover - LLVM cannot tell on this host
            feats = {}
        _FEATURES = {name for name, on in feats.items() if on}
    return _FEATURES


def _replace(library, edit) -> None:
    """Replace ``library``'s final module by ``edit`` of its text, where that changes it."""
    import llvmlite.binding as ll

    text = str(library._final_module)
    new = edit(text)
    if new != text:
        mod = ll.parse_assembly(new)
        mod.verify()
        library._final_module = mod


def _hook_owner():
    """numba's ``CPUCodeLibrary`` (an internal of ``numba.core.codegen``), or None where this numba lacks it."""
    try:
        from numba.core import codegen
    except ImportError:  # pragma: no cover - numba reorganised
        return None
    return getattr(codegen, "CPUCodeLibrary", None)


def _turn_off(reason: str) -> None:
    """Vector math off for the rest of the process (drivers compiled from now on call libm), said once."""
    global _installed
    _installed = False
    from .notes import note_once

    note_once("vecmath", f"vector math (libmvec) off: {reason}; the drivers compute the same values with libm, "
                         "possibly slower")


def _edited(library, edit) -> bool:
    """``edit`` applied to ``library``'s final module (:func:`_replace`); on any failure vector math goes off."""
    try:
        _replace(library, edit)
        return True
    except Exception as exc:  # a numba whose library differs, or an edit LLVM rejects: libm instead
        _turn_off(f"editing numba's module failed ({type(exc).__name__}: {exc})")
        return False


def _applies_safely(library) -> bool:
    """:func:`_applies`, False (and vector math off) where numba's library lacks what it reads."""
    if not _installed:
        return False
    try:
        return _applies(library)
    except Exception as exc:
        _turn_off(f"reading numba's module failed ({type(exc).__name__}: {exc})")
        return False


def _install_hook() -> bool:
    cls = _hook_owner()
    original = getattr(cls, "_optimize_final_module", None)
    if original is None:  # a numba without this class or method: vector math stays off
        _turn_off("this numba has no CPUCodeLibrary._optimize_final_module to hook")
        return False
    if getattr(original, "_brdfkit_vecmath", False):
        return True

    def _optimize_final_module(self):
        on = _applies_safely(self) and _edited(self, annotate)
        original(self)
        if on:
            _edited(self, rewrite)

    _optimize_final_module._brdfkit_vecmath = True
    cls._optimize_final_module = _optimize_final_module
    return True


def _setup() -> None:
    global _installed
    if os.environ.get(ENV_VAR, "1").strip() == "0":
        return
    opened = _open_library()
    if opened is None:
        return
    path, lib = opened
    try:
        import llvmlite.binding as ll

        ll.load_library_permanently(path)  # cached drivers resolve their libmvec calls through it
    except RuntimeError:  # pragma: no cover - opened by ctypes but not by LLVM
        return
    feats = cpu_features()
    # one pass over what libmvec exports for this CPU: the annotations' variants (by scalar
    # symbol) and, for exp/log/pow, the renames of the vector intrinsics (by function and width)
    for ty, widths in _WIDTHS.items():
        for fn, nargs in SCALAR_FUNCTIONS.items():
            found = [(lanes, _abi_name(isa, lanes, fn, nargs, ty)) for isa, lanes in widths
                     if _ISA_FEATURE[isa] in feats and hasattr(lib, _abi_name(isa, lanes, fn, nargs, ty))]
            if not found:
                continue
            for sym in _scalar_symbols(fn, ty):
                _variants[sym] = found
                _signature[sym] = (nargs, _LLTYPE[ty])
            if fn in FUNCTIONS:
                for lanes, name in found:
                    _names[(fn, lanes, ty)] = name
    if _names:
        _installed = _install_hook()


_setup()

__all__ = ["ENV_VAR", "FUNCTIONS", "SCALAR_FUNCTIONS", "annotate", "available", "compiling", "cpu_features", "rewrite",
           "vector_name"]
