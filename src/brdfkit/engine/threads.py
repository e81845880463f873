"""numba's threading layer for the compiled drivers: TBB where it loads, else workqueue.

numba's parallel loops run on its TBB threading layer where it loads (brdfkit depends on PyPI's
tbb): thread-safe (the explorer's server threads evaluate at once) and fork-safe (process pools:
`check --all --jobs`, batch fitting), and its workers spin a moment before they sleep, so that
the many short parallel calls of the engine find them awake (GGX on 2^20 pairs: median 480 M
evals/s against 200 on workqueue on the 2-vCPU development machine, where waking a sleeping
vCPU appears to take about a millisecond: inferred from those timings, not measured directly).
Otherwise "workqueue", which also survives fork() but is not reentrant: the driver then
serialises calls from several Python threads with a lock. GNU OpenMP, numba's other choice
here, aborts a forked child. An explicit NUMBA_THREADING_LAYER wins. Set when this module is
imported (``brdfkit.engine`` imports it first).
"""

from __future__ import annotations

import os
import sys


def _load_tbb() -> bool:
    """True when numba's TBB threading layer can run here (PyPI's ``tbb`` wheel, installed with brdfkit).

    The wheel puts ``libtbb.so.12`` in the environment's ``lib/``, which the dynamic loader does
    not search: it is loaded here first (by its path, globally), so that numba's ``tbbpool``
    finds it; numba's own version check must pass too. False on any failure: workqueue then.
    """
    import ctypes
    import glob
    from importlib.metadata import PackageNotFoundError, files

    try:
        candidates = [str(f.locate()) for f in files("tbb") or () if f.name.startswith("libtbb.so.12")]
    except PackageNotFoundError:  # not installed by pip: perhaps in the environment's lib/ anyway
        candidates = []
    candidates += sorted(glob.glob(os.path.join(sys.prefix, "lib", "libtbb.so.12*")))
    for path in candidates:
        try:
            ctypes.CDLL(path, mode=ctypes.RTLD_GLOBAL)
            break
        except OSError:
            continue
    try:
        from numba.np.ufunc import parallel as _parallel
        from numba.np.ufunc import tbbpool  # noqa: F401  (fails without libtbb)

        _parallel._check_tbb_version_compatible()  # a numba internal: any failure means workqueue
    except Exception:  # ImportError, or numba without the check: not TBB
        return False
    return True


#: numba's threading layer for the compiled drivers (set at import unless NUMBA_THREADING_LAYER is)
THREADING_LAYER = os.environ.get("NUMBA_THREADING_LAYER", "")

if not THREADING_LAYER:
    import numba as _numba

    THREADING_LAYER = "tbb" if _load_tbb() else "workqueue"
    _numba.config.THREADING_LAYER = THREADING_LAYER

#: layers whose parallel launches may come from several Python threads at once (no lock needed)
THREAD_SAFE_LAYERS = ("tbb", "safe", "threadsafe", "omp")

__all__ = ["THREADING_LAYER", "THREAD_SAFE_LAYERS"]
