"""The reference engine: the kernels' own Python source, run uncompiled.

:func:`pure` rebuilds a jitted function from its original Python code with every
numba dispatcher it refers to by a global name replaced — recursively — by that
function's own uncompiled rebuild. So ``pure(microfacet_kernel)`` runs exactly
the source lines the compiled engine compiles, down to the last term, in Python
float64 arithmetic. :func:`run` evaluates a kernel pair by pair with it.
"""

from __future__ import annotations

import types
from typing import Callable

import numpy as np

try:  # numba's dispatcher type (the thing ``numba.njit`` returns)
    from numba.core.registry import CPUDispatcher as _Dispatcher
except Exception:  # pragma: no cover
    _Dispatcher = ()

_PURE: dict[int, Callable] = {}


def _is_jitted(obj) -> bool:
    return isinstance(obj, _Dispatcher) or hasattr(obj, "py_func")


def pure(fn: Callable) -> Callable:
    """The uncompiled twin of ``fn`` (a numba dispatcher or a plain function), memoised."""
    key = id(fn)
    hit = _PURE.get(key)
    if hit is not None:
        return hit
    py = getattr(fn, "py_func", fn)
    if not isinstance(py, types.FunctionType):
        return py
    g = dict(py.__globals__)
    out = types.FunctionType(py.__code__, g, py.__name__, py.__defaults__, py.__closure__)
    out.__doc__ = py.__doc__
    out.__qualname__ = py.__qualname__
    _PURE[key] = out  # before recursing: terms may be mutually recursive (they are not today)
    names = set(py.__code__.co_names)
    for name in names:
        obj = g.get(name)
        if obj is not None and _is_jitted(obj):
            g[name] = pure(obj)
    return out


def run(kernel: Callable, wi: np.ndarray, wo: np.ndarray, p: np.ndarray, c: np.ndarray, out: np.ndarray) -> None:
    """``out[j] = kernel(wi[j], wo[j], p, c)`` where both z > 0, else 0; flat ``(n, 3)`` arrays."""
    k = pure(kernel)
    pl = [float(x) for x in np.asarray(p, dtype=np.float64)]
    cl = [int(x) for x in np.asarray(c, dtype=np.int64)]
    lim = float(np.finfo(out.dtype).max)
    a = np.asarray(wi, dtype=np.float64).tolist()
    b = np.asarray(wo, dtype=np.float64).tolist()
    res = np.zeros((len(a), 3), dtype=np.float64)
    for j in range(len(a)):
        x, y = a[j], b[j]
        if x[2] > 0.0 and y[2] > 0.0:
            r, g_, bl = k(x[0], x[1], x[2], y[0], y[1], y[2], pl, cl)
            res[j, 0] = min(r, lim)
            res[j, 1] = min(g_, lim)
            res[j, 2] = min(bl, lim)
    out[...] = res


__all__ = ["pure", "run"]
