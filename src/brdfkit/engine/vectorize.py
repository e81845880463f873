"""``vectorize(scalar, nargs)``: the array form of a scalar term (the array API of :mod:`brdfkit.terms`).

The scalar source stays the one formula: compiled, it runs in an elementwise driver generated and cached
on disk (:func:`brdfkit.engine.generated.elementwise_driver_for`); under the reference engine, the
uncompiled Python function (:func:`brdfkit.engine.reference.pure`) through ``np.frompyfunc``.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from .active import engine
from .reference import pure


class vectorize:
    """An array function over a scalar term: broadcasting, float64 computation, any output dtype.

    ``vectorize(d_ggx)(hx, hy, hz, ax, ay)`` applies the scalar source element-wise: compiled, a
    loop generated for it and cached on disk (:func:`brdfkit.engine.generated.elementwise_driver_for`,
    loaded at the first call); under the reference engine the uncompiled Python function via
    ``np.frompyfunc``. The result is float64; pass ``dtype=np.float32`` to round it once to float32.
    """

    def __init__(self, scalar: Callable, nargs: int) -> None:
        self.scalar = scalar
        self.nargs = nargs
        self._drive = None
        self.__doc__ = getattr(scalar, "__doc__", None)
        self.__name__ = getattr(scalar, "__name__", "vectorized")

    def _compiled(self, arrs: list[np.ndarray]) -> np.ndarray:
        if self._drive is None:
            from .generated import elementwise_driver_for  # numba's drivers load only when first called

            self._drive = elementwise_driver_for(self.scalar, self.nargs)
        shape = np.broadcast_shapes(*(a.shape for a in arrs))
        # 1-D views where numpy can give one (a contiguous array as is, a single value as stride 0), else copies
        flat = [np.broadcast_to(a, shape).reshape(-1) for a in arrs]
        out = np.empty(math.prod(shape))
        self._drive(*flat, out)
        return out.reshape(shape)

    def __call__(self, *args, dtype=np.float64) -> np.ndarray:
        if len(args) != self.nargs:
            raise TypeError(f"{self.__name__} takes {self.nargs} arguments, got {len(args)}")
        arrs = [np.asarray(a, dtype=np.float64) for a in args]
        if engine() == "reference":
            f = np.frompyfunc(pure(self.scalar), self.nargs, 1)
            out = np.asarray(f(*arrs), dtype=np.float64)
        else:
            out = self._compiled(arrs)
        with np.errstate(over="ignore"):
            return np.asarray(out).astype(dtype, copy=False)


__all__ = ["vectorize"]
