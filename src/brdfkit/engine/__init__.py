"""The evaluation engine: one Python source per model, compiled (numba) or run as the reference.

``bk.set_engine("compiled" | "reference")`` and the environment variable
``BRDFKIT_ENGINE`` (read once, at import) pick how ``m.eval`` runs; ``bk.engine()``
says which one is active (SPEC.md, "Evaluation engine"). Default: ``compiled``.

* ``compiled`` — the model's scalar kernel, compiled by numba (nopython,
  ``error_model="numpy"``, no fastmath but HTSG's series sum, see :func:`jit`), run by a
  parallel driver over flat views of the direction arrays (chunked ``prange``), float32
  or float64 in and out, output allocated once. Where the driver's loop vectorises, its
  math functions (exp, erfc, pow, atan2, ...) are glibc's libmvec vector functions
  (:mod:`.vecmath`; write kernels without branches around them, so that they do). float32
  input runs the kernel's float32 twin (:mod:`.precision`), compiled with LLVM's ``contract``
  flag only (fused multiply-adds). Kernels are cached on disk (see :mod:`.cache`), so a new
  process pays no compile.
* ``reference`` — THE SAME kernel functions, uncompiled: every numba dispatcher
  the kernel calls is replaced by its original Python function
  (:func:`brdfkit.engine.reference.pure`), evaluated pair by pair in Python
  float64 (the result is then rounded to the input dtype). Slow (~10 µs per
  pair), exact-source, and what the tests compare the compiled engine against.

The two agree to 1e-12 relative in float64 (``tests/test_engine*.py``).

How a model is converted (the kernel protocol)
----------------------------------------------
1. Write each physical term once as a small **scalar** function in component
   form — floats in, floats (or a tuple of floats) out — decorated with
   :func:`brdfkit.engine.jit`, in :mod:`brdfkit.terms` (shared terms) or in the
   model module (terms only that model uses). Use only what numba nopython
   compiles AND what plain Python runs without raising: ``math.*``,
   arithmetic, ``min``/``max``, ``if``, simple loops; write ``x * x``, not
   ``x ** 2`` (Python's ``**`` raises OverflowError where numba gives inf), and
   guard every division and ``math.log``/``math.sqrt`` argument (Python raises
   ZeroDivisionError / ValueError where numba gives inf/nan — the reference
   engine would then fail, which is how the tests find an unguarded spot).
   Cite the paper in the docstring, name the function after the term
   (``d_ggx``, ``lambda_beckmann``, ``f_conductor``), keep it readable beside
   its GLSL twin in ``render/shaders/``.
2. Compose the model's kernel, also decorated with :func:`jit`, with EXACTLY
   this signature::

       @jit
       def kernel(wix, wiy, wiz, wox, woy, woz, p, c):
           ...
           return r, g, b

   ``wi``/``wo`` components are float64, and the kernel is called only for
   ``wiz > 0`` and ``woz > 0`` (the driver writes the zero below the horizon).
   ``p`` is a float64 1-D array of the numeric parameters, ``c`` an int64 1-D
   array of the choice/bool parameters (choices as ints: the index in the
   ``Param.choices`` tuple). Document the layout of ``p`` and ``c`` in the
   kernel's docstring. Call the terms by their imported names (``d_ggx(...)``,
   not ``distributions.d_ggx(...)``): the reference engine swaps names bound in
   the kernel's module globals. Return finite, non-negative values; the driver
   only clamps overflow to the dtype's largest finite value.
3. On the model class set ``kernel = staticmethod(<your kernel>)`` and
   implement ``kernel_args(self) -> (p, c)`` returning the two arrays (build them
   once from ``self.params``; the base class caches nothing for you here, so
   cache them in ``_setup``). Delete ``_eval`` or keep it — a model with a
   ``kernel`` never has its ``_eval`` called. A model without ``kernel`` keeps
   working through its numpy ``_eval`` (the fallback; both engines use it).
4. Keep the array API of ``terms`` working as thin wrappers over the scalar
   source: :func:`brdfkit.engine.vectorize` turns a scalar term into a ufunc-like
   function (float32 stays float32, computed in float64), never a second copy
   of the formula.
5. Mixing an int with a float (``x * (n - 1)``) promotes to float64 in numba also in the
   float32 twin: write ``float(n - 1)`` (a float32 cast there); ``tests/test_engine_models.py``
   fails on any float64 variable in a twin. ``kernel_float32 = False`` on the class keeps
   float64 computation for float32 input.
6. Add the model to ``tests/test_engine_models.py`` (compiled vs reference for
   every choice parameter) — or add its choice grid there.

``BRDF.eval`` also enforces the unit-direction rule of SPEC.md for every model,
whatever the engine: ``|wi|`` and ``|wo|`` within 1e-4 of 1 (float64) or 1e-3
(float32), else ``ValueError`` naming the model, the argument and the worst
length found.

Numerics note: for float32 input the compiled engine runs each kernel's float32
twin (:mod:`.precision`: the same source rebuilt with float32 constants, so numba
infers float32 throughout and LLVM vectorises 16 lanes), within a stated,
condition-aware tolerance of the float64 reference (``tests/test_engine_models.py``).
HTSG, the measured models, and parameter sets that do not fit float32 compute in
float64 and round the result once. The reference engine always computes in float64.
"""

from __future__ import annotations

import sys as _sys
import types as _types

from . import active as _active
from .active import ENGINES, ENV_VAR, engine, set_engine
from .threads import THREADING_LAYER  # sets numba's threading layer, before any parallel driver runs


def skip_blas_probe() -> bool:
    """Import numba's ``numba.np.arraymath`` with ``scipy.linalg`` held back; for the console script only.

    That module probes for BLAS when it is imported (during numba's first compile or cache load) by
    importing ``scipy.linalg.cython_blas``, which imports all of ``scipy.linalg``: 0.3 s of the 2.2 s
    of ``brdfkit eval`` on the slower development host (measured with cProfile). brdfkit's kernels
    call no BLAS. Held back (a ``None`` entry in ``sys.modules``, Python's "not importable"), the
    probe finds no BLAS and numba's ``np.dot`` of two 1-D float arrays in jitted code uses its own
    loop instead (nothing of brdfkit's does that); every other linear-algebra function of numba's
    imports scipy when it is compiled. ``scipy.linalg`` itself imports normally afterwards (a fit
    needs it). The brdfkit command calls this before it runs; a library user's process keeps numba's
    default. False (nothing done) where either module was already imported.
    """
    if "numba.np.arraymath" in _sys.modules or "scipy.linalg" in _sys.modules:
        return False
    _sys.modules["scipy.linalg"] = None  # type: ignore[assignment]
    try:
        import numba.np.arraymath  # noqa: F401
    except ImportError:  # pragma: no cover - a numba whose arraymath needs scipy.linalg: its normal import later
        return False
    finally:
        if _sys.modules.get("scipy.linalg", 0) is None:
            del _sys.modules["scipy.linalg"]
    return True


class _CallableModule(_types.ModuleType):
    """``brdfkit.engine`` is this package and, called, the SPEC's ``bk.engine()``."""

    def __call__(self) -> str:
        return _active._current


_sys.modules[__name__].__class__ = _CallableModule

from .cache import jit  # noqa: E402
from .vectorize import vectorize  # noqa: E402
from .evaluate import evaluate, check_unit  # noqa: E402
from .select import select  # noqa: E402

__all__ = ["ENGINES", "ENV_VAR", "set_engine", "engine", "jit", "vectorize", "evaluate", "check_unit", "select"]
