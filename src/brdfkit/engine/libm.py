"""``libm_log(x)``: the natural logarithm by glibc's own scalar ``log``, also in compiled loops.

The compiled drivers call glibc's vector math (libmvec, :mod:`.vecmath`) for the loops LLVM
vectorises: accurate to 4 ulp where libm's ``log`` is correctly rounded to within 0.5 ulp. Where a
logarithm is multiplied by a large number, that difference is multiplied too: HTSG's series takes
``(m − 1)·ln g`` with m up to ~10⁴, so 4 ulp of ``ln g`` become ~1e-11 of the result, ten times
the engine's 1e-12 parity with the reference engine (which runs Python's ``math.log``, glibc's
``log``). ``libm_log`` calls glibc's ``log`` under its ISO C23 / TS 18661-3 alias ``logf64`` (the
same function, one address; glibc >= 2.27), a name :mod:`.vecmath` does not give vector versions:
the call stays scalar, and its result is bit for bit Python's ``math.log``. A loop that calls it does
not vectorise; call it in a loop of its own. Elsewhere than glibc (no ``logf64``), the compiled
form is numba's ``math.log``.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import math

from numba import types
from numba.extending import overload


def _has_logf64() -> bool:
    try:
        lib = ctypes.CDLL(ctypes.util.find_library("m") or "libm.so.6")
    except OSError:
        return False
    return hasattr(lib, "logf64")


#: glibc exports ``logf64`` (the compiled ``libm_log`` calls it)
HAVE_LOGF64 = _has_logf64()
_logf64 = types.ExternalFunction("logf64", types.float64(types.float64))


def libm_log(x):
    """ln x by glibc's scalar ``log`` (x > 0; Python: ``math.log``)."""
    return math.log(x)


@overload(libm_log, jit_options={"cache": True})
def _libm_log_overload(x):
    if HAVE_LOGF64:
        def impl(x):
            return _logf64(x)
    else:  # pragma: no cover - not glibc
        def impl(x):
            return math.log(x)
    return impl


__all__ = ["HAVE_LOGF64", "libm_log"]
