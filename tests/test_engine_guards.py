"""The engine without numba's internals or LLVM's options: a newer numba may lack the private hook of
:mod:`brdfkit.engine.vecmath` or the compiler lock of :mod:`brdfkit.engine.llvm_options`, a newer
llvmlite may refuse an option. The engine then still evaluates, with the same values (libm's rounding
instead of libmvec's, LLVM's default vectorisation), after at most one note per cause."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

import brdfkit as bk

#: what the child process evaluates: the generic driver (100 pairs), the specialised drivers (float64 and
#: the float32 twin, 5000 pairs: these set LLVM's options on their first call), a Fortran-ordered call
EVAL = """
import json, sys, warnings
import numpy as np
warnings.simplefilter("always")
with warnings.catch_warnings(record=True) as caught:
    import brdfkit as bk
    from brdfkit.engine import vecmath
    from brdfkit.geometry import random_unit_vectors as r
    m = bk.model("microfacet", distribution="ggx", fresnel="conductor", alpha=0.3)
    g = np.random.default_rng(7)
    out = {}
    for n, dt in ((100, np.float64), (5000, np.float64), (5000, np.float32)):
        wi, wo = r(n, g).astype(dt), r(n, g).astype(dt)
        for k in range(2):
            out[f"{n}-{np.dtype(dt).name}"] = m.eval(wi, wo).tolist()
    wi, wo = r(5000, g), r(5000, g)
    f = m.eval(np.asfortranarray(wi), np.asfortranarray(wo))
    out["fortran"] = f.tolist()
    out["fortran_order"] = bool(f.flags.f_contiguous)
notes = [str(w.message) for w in caught if "brdfkit.engine" in str(w.message)]
print(json.dumps({"values": out, "notes": notes, "vecmath": vecmath.available()}))
"""


def _expected() -> dict:
    """The same evaluations in this process (the engine with its hook and options)."""
    from brdfkit.geometry import random_unit_vectors as r

    m = bk.model("microfacet", distribution="ggx", fresnel="conductor", alpha=0.3)
    g = np.random.default_rng(7)
    out = {}
    for n, dt in ((100, np.float64), (5000, np.float64), (5000, np.float32)):
        wi, wo = r(n, g).astype(dt), r(n, g).astype(dt)
        out[f"{n}-{np.dtype(dt).name}"] = m.eval(wi, wo)
    wi, wo = r(5000, g), r(5000, g)
    out["fortran"] = m.eval(np.asfortranarray(wi), np.asfortranarray(wo))
    return out


def _run_child(prelude: str, cache) -> dict:
    env = dict(os.environ, BRDFKIT_CACHE_DIR=str(cache), BRDFKIT_ENGINE="compiled")
    proc = subprocess.run([sys.executable, "-c", prelude + EVAL], env=env, capture_output=True, text=True,
                          timeout=1200)
    assert proc.returncode == 0, proc.stderr[-4000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _same_values(got: dict) -> None:
    old = bk.engine()
    bk.set_engine("compiled")
    try:
        want = _expected()
    finally:
        bk.set_engine(old)
    for key, w in want.items():
        g = np.asarray(got["values"][key], dtype=w.dtype)
        # libm against libmvec (4 ulp at most), LLVM's default vector width against the forced one (float32
        # multiply-adds may fuse differently: 1 ulp)
        rtol = 1e-6 if w.dtype == np.float32 else 1e-13
        np.testing.assert_allclose(g, w, rtol=rtol, atol=0, err_msg=key)
    assert got["values"]["fortran_order"]


#: numba without the hooked class (moved or renamed) and llvmlite refusing every option
NO_HOOK_NO_OPTIONS = """
import numba.core.codegen as _codegen
import llvmlite.binding as _ll
del _codegen.CPUCodeLibrary  # numba keeps working (its subclasses hold the class); brdfkit finds no hook
def _refuse(name, option):
    raise RuntimeError(f"unknown option {option}")
_ll.set_option = _refuse
"""

#: numba without the compiler lock where brdfkit looks for it (see test_compiler_lock_is_none_where_numba_lacks_it),
#: and the hook's edit of numba's module failing
NO_LOCK_EDIT_FAILS = """
import brdfkit.engine.llvm_options as _lo
_lo.compiler_lock = lambda: None  # what it returns where numba has no lock there (numba itself needs its own)
import brdfkit.engine.vecmath as _vm
def _fail(library, edit):
    raise AttributeError("'JITCodeLibrary' object has no attribute '_final_module'")
_vm._replace = _fail
"""


@pytest.mark.slow
def test_without_numbas_hook_and_with_llvm_options_refused_the_values_are_the_same(tmp_path):
    got = _run_child(NO_HOOK_NO_OPTIONS, tmp_path)
    assert got["vecmath"] is False
    notes = got["notes"]
    assert sum("vector math" in s for s in notes) == 1, notes  # said once, not per driver or call
    assert sum("LLVM options" in s for s in notes) == 1, notes
    assert len(notes) == 2, notes
    _same_values(got)


@pytest.mark.slow
def test_without_the_compiler_lock_and_with_the_module_edit_failing_the_values_are_the_same(tmp_path):
    got = _run_child(NO_LOCK_EDIT_FAILS, tmp_path)
    notes = got["notes"]
    assert sum("vector math" in s for s in notes) == 1, notes
    assert sum("LLVM options" in s for s in notes) == 1, notes
    assert got["vecmath"] is False  # turned off at the first failed edit, for the rest of the process
    _same_values(got)


def test_the_notes_are_given_once():
    from brdfkit.engine import notes

    key = "test-note-once"
    with pytest.warns(RuntimeWarning, match="brdfkit.engine: first"):
        assert notes.note_once(key, "first")
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert not notes.note_once(key, "again")  # no second warning (an error here if there were)


def test_an_option_refused_in_process_turns_the_options_off_and_the_call_still_runs(monkeypatch):
    """:func:`compile_options` with llvmlite refusing an option: the body runs (under the compiler lock), LLVM's
    defaults are restored as far as they can be, and later calls skip the options."""
    from brdfkit.engine import llvm_options

    calls = []

    def refuse(option):
        calls.append(option)
        raise RuntimeError("refused")

    monkeypatch.setattr(llvm_options, "set_option", refuse)
    monkeypatch.setattr(llvm_options, "_off", None)
    monkeypatch.setattr(llvm_options, "note_once", lambda key, msg: calls.append(("note", key)))
    ran = []
    with llvm_options.compile_options(16, interleave=2):
        ran.append(1)
    assert ran == [1] and ("note", "llvm-options") in calls and llvm_options._off
    calls.clear()
    with llvm_options.compile_options(16, interleave=2):
        ran.append(2)
    assert ran == [1, 2] and calls == []  # off: no further attempt, no further note


def test_compiler_lock_is_none_where_numba_lacks_it(monkeypatch):
    """Where ``numba.core.compiler_lock`` has no ``global_compiler_lock`` (a newer numba), the lookup gives None
    (and :func:`compile_options` then sets no option). Removed here only for the lookup: numba needs it."""
    import numba.core.compiler_lock as cl

    from brdfkit.engine import llvm_options

    assert llvm_options.compiler_lock() is cl.global_compiler_lock
    monkeypatch.delattr(cl, "global_compiler_lock")
    assert llvm_options.compiler_lock() is None


def test_ctrl_c_during_a_compile_waits_for_it_then_interrupts():
    """``sigint_deferred`` (every driver call that may compile runs in it): a SIGINT meanwhile does not
    interrupt the compile (a KeyboardInterrupt inside llvmlite's callbacks left LLVM broken and the
    process died of SIGSEGV), and is delivered, as a KeyboardInterrupt, when the compile is over."""
    import os
    import signal

    from brdfkit.engine.llvm_options import sigint_deferred

    before = signal.signal(signal.SIGINT, signal.default_int_handler)  # an xdist worker may ignore SIGINT
    try:
        reached = []
        with pytest.raises(KeyboardInterrupt):
            with sigint_deferred():
                os.kill(os.getpid(), signal.SIGINT)
                for _ in range(1000):  # bytecode boundaries at which Python would run a handler
                    pass
                reached.append("the end of the compile")
        assert reached == ["the end of the compile"]
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # the handler is back
        with sigint_deferred():  # no signal: nothing raised
            pass
    finally:
        signal.signal(signal.SIGINT, before)
