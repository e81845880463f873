"""float32 twins of the kernels, built from the same Python source (issue 9).

numba types a Python float literal, a float module global and ``math.pi`` as
float64, so a kernel written with ``0.5 * x`` computes in float64 even for
float32 arguments. :func:`float32_twin` rebuilds a jitted function from its own
bytecode with those constants retyped as ``numpy.float32`` (the function's
``co_consts``, its float globals, and ``math`` replaced by a copy whose float
constants are float32), recursively for every jitted function it calls by a
global name — the same rebuild the reference engine does
(:func:`brdfkit.engine.reference.pure`), with other constants. With float32
arguments numba then infers float32 throughout (``math.sqrt``/``exp``/``erfc``
of a float32 are the float32 functions), and LLVM vectorises twice the lanes.
No formula is copied: the twin runs the same lines.

Constants outside float32's normal range keep their role rather than their
value (:func:`f32_constant`): a floor such as ``1e-150`` or ``1e-300`` — there so
that a product of two floored quantities stays a normal number — becomes
``sqrt(float32 tiny) ≈ 1.1e-19`` (the product of two is still normal), and a cap
such as ``1e300`` becomes ``float32 max / 4 ≈ 8.5e37`` (the values the GLSL
twins use), and float64's smallest normal number (``brdfkit.geometry.NORMAL_MIN``, which keeps
a reciprocal finite) becomes float32's. ``inf`` and ``nan`` stay what they are. Parameters are not mapped: a
parameter set that does not fit float32 (:func:`fits_float32`) is computed in float64.

The builtin ``float(x)`` becomes a float32 cast in the twin. Integer constants and
arguments (choice indices, loop counters) stay int64, and ``int op float32``
promotes to float64 in numba, so a source mixing them writes ``float(i)``;
:func:`float64_variables` lists the float64 variables numba inferred, which the
tests require to be none.
"""

from __future__ import annotations

import math
import types
from typing import Callable

import numba
import numpy as np

from .reference import _is_jitted

_F32 = np.finfo(np.float32)
_F64_NORMAL_MIN = float(np.finfo(np.float64).tiny)
#: what a float64 floor below float32's normal range becomes: two of them multiplied stay normal
F32_FLOOR = np.float32(math.sqrt(float(_F32.tiny)))
#: what a float64 cap above float32's range becomes
F32_CAP = np.float32(float(_F32.max) / 4.0)


def f32_constant(v: float) -> np.float32:
    """``v`` as a float32 constant, floors and caps outside float32's normal range mapped to :data:`F32_FLOOR` / :data:`F32_CAP`."""
    a = abs(v)
    if v != v or math.isinf(v) or v == 0.0:
        return np.float32(v)
    if a == _F64_NORMAL_MIN:  # the role "smallest normal number" (brdfkit.geometry.NORMAL_MIN)
        return np.float32(math.copysign(float(_F32.tiny), v))
    if a < float(_F32.tiny):
        return np.float32(math.copysign(float(F32_FLOOR), v))
    if a > float(F32_CAP):
        return np.float32(math.copysign(float(F32_CAP), v))
    return np.float32(v)


def fits_float32(p: np.ndarray) -> bool:
    """True when every parameter rounds to float32 as a normal number (or 0, ±inf): the twin may run.

    Otherwise (schlick's ``p`` down to 5e-324, a weight of 1e-154) the float32 twin would see 0 or
    a changed magnitude where the float64 kernel sees the value, so the driver computes in float64.
    """
    a = np.abs(np.asarray(p, dtype=np.float64))
    finite = a[np.isfinite(a)]
    return not bool(np.any((finite > 0.0) & (finite < float(_F32.tiny))) or np.any(finite > float(F32_CAP)))


def _convert(value):
    if isinstance(value, float):  # bool and int are not float; np.float64 is
        return f32_constant(float(value))
    if isinstance(value, tuple) and value and all(isinstance(x, float) for x in value):
        return tuple(f32_constant(float(x)) for x in value)
    return value


def _math32() -> types.ModuleType:
    m = types.ModuleType("math")  # numba resolves math.sqrt & co. by the function objects, copied here
    for name in dir(math):
        if not name.startswith("__"):
            setattr(m, name, _convert(getattr(math, name)))
    return m


_MATH32 = _math32()
#: LLVM fast-math flags of the float32 twins and drivers: only ``contract`` (a·b + c may become one
#: fused multiply-add, rounded once: never less accurate, no change to NaN/inf/zero semantics; ~40 % of
#: a vectorised kernel's instructions were separate multiplies and adds). No ``arcp``/``afn``: those
#: would turn ``x/y`` into ``x·(1/y)`` (inf·0 = NaN where ``y`` is subnormal) and approximate sqrt.
FLOAT32_FASTMATH = frozenset({"contract"})
_TWINS: dict[tuple[int, bool], Callable] = {}


def _rebuild(py: types.FunctionType) -> types.FunctionType:
    code = py.__code__
    code = code.replace(co_consts=tuple(_convert(c) for c in code.co_consts))
    g = dict(py.__globals__)
    for name in code.co_names:
        obj = g.get(name)
        if name == "float" and obj is None:  # the builtin float(): a float32 cast in the twin
            g[name] = numba.float32
        elif obj is math:
            g[name] = _MATH32
        elif obj is not None and _is_jitted(obj):
            g[name] = float32_twin(obj)
        elif obj is not None:
            g[name] = _convert(obj)
    out = types.FunctionType(code, g, py.__name__, py.__defaults__, py.__closure__)
    out.__doc__ = py.__doc__
    out.__qualname__ = py.__qualname__ + "[float32]"
    return out


def float32_twin(fn: Callable, inline: bool | None = None) -> Callable:
    """The numba dispatcher of ``fn``'s source with float32 constants (memoised; see the module docstring).

    ``inline``: numba IR inlining of the twin into its callers; default: as ``fn`` was jitted.
    """
    if inline is None:
        inline = getattr(fn, "targetoptions", {}).get("inline", "never") == "always"
    key = (id(fn), inline)
    hit = _TWINS.get(key)
    if hit is not None:
        return hit
    py = getattr(fn, "py_func", fn)
    opts = dict(error_model="numpy", nogil=True, fastmath=set(FLOAT32_FASTMATH))
    if inline:
        opts["inline"] = "always"
    twin = numba.njit(**opts)(_rebuild(py))
    _TWINS[key] = twin
    return twin


def float64_variables(kernel: Callable) -> list[str]:
    """Variables numba types as float64 in ``kernel``'s float32 twin called with float32 directions.

    Compiles the twin (inlined callees included, so their variables are listed too) for the
    driver's argument types: six float32 components, ``p`` a float32 array, ``c`` an int64 array.
    """
    twin = float32_twin(kernel, inline=False)
    f32, arr32, arr64 = numba.float32, numba.float32[::1], numba.int64[::1]
    sig = (f32,) * 6 + (arr32, arr64)
    twin.compile(sig)
    found = set()
    for other in list(_TWINS.values()):  # the kernel and every callee compiled out of line for it
        for cres in other.overloads.values():
            for name, t in cres.type_annotation.typemap.items():
                if "float64" in str(t):
                    found.add(f"{other.py_func.__qualname__}: {name}: {t}")
    return sorted(found)


__all__ = ["float32_twin", "FLOAT32_FASTMATH", "f32_constant", "fits_float32", "float64_variables", "F32_FLOOR", "F32_CAP"]
