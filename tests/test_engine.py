"""The evaluation engine: selection, the unit-direction rule, the driver, the fallback, the reference twin."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys

import numba
import numpy as np
import pytest

import brdfkit as bk
from brdfkit import engine
from brdfkit.engine import cost, driver, llvm_options, reference
from brdfkit.geometry import random_unit_vectors
from brdfkit.models.base import BRDF
from brdfkit.params import kd_param


@pytest.fixture
def restore_engine():
    old = engine.engine()
    yield
    engine.set_engine(old)


def test_set_engine_and_query(restore_engine):
    assert bk.engine() in engine.ENGINES
    bk.set_engine("reference")
    assert bk.engine() == "reference"
    bk.set_engine("compiled")
    assert bk.engine() == "compiled"
    with pytest.raises(ValueError, match="unknown engine 'fast'.*compiled, reference"):
        bk.set_engine("fast")
    assert bk.engine() == "compiled"


@pytest.mark.parametrize("value,expect", [("reference", "reference"), ("compiled", "compiled"), ("", "compiled")])
def test_env_var_picks_the_engine(value, expect):
    env = dict(os.environ, BRDFKIT_ENGINE=value)
    out = subprocess.run([sys.executable, "-c", "import brdfkit as bk; print(bk.engine())"],
                         env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == expect


def test_env_var_rejects_unknown_engine():
    env = dict(os.environ, BRDFKIT_ENGINE="turbo")
    out = subprocess.run([sys.executable, "-c", "import brdfkit"], env=env, capture_output=True, text=True)
    assert out.returncode != 0 and "BRDFKIT_ENGINE='turbo' is not a valid engine" in out.stderr


def _pairs(n, seed=0, dtype=np.float64):
    rng = np.random.default_rng(seed)
    return random_unit_vectors(n, rng).astype(dtype), random_unit_vectors(n, rng).astype(dtype)


@pytest.mark.parametrize("eng", engine.ENGINES)
@pytest.mark.parametrize("name", ["microfacet", "lambert", "ward"])  # ward: a model still on the fallback (or not)
@pytest.mark.parametrize("dtype,tol", [(np.float64, 1e-4), (np.float32, 1e-3)])
def test_non_unit_directions_are_rejected(eng, name, dtype, tol, restore_engine):
    bk.set_engine(eng)
    m = bk.model(name)
    wi, wo = _pairs(50, dtype=dtype)
    for scale, arg in ((0.5, "wi"), (2.0, "wo")):
        a, b = (wi * dtype(scale), wo) if arg == "wi" else (wi, wo * dtype(scale))
        with pytest.raises(ValueError) as e:
            m.eval(a, b)
        msg = str(e.value)
        assert msg.startswith(f"{name}: {arg} must be unit vectors") and f"found length {scale:g}" in msg
        assert "\n" not in msg
    # just inside the tolerance is accepted, just outside is not
    ok = wi * dtype(1 + 0.5 * tol)
    assert np.all(np.isfinite(m.eval(ok, wo)))
    bad = wi.copy()
    bad[7] *= dtype(1 + 3 * tol)
    with pytest.raises(ValueError, match="wi must be unit"):
        m.eval(bad, wo)
    nan = wo.copy()
    nan[3, 0] = np.nan
    with pytest.raises(ValueError, match="wo must be unit vectors.*found length nan"):
        m.eval(wi, nan)
    # a zero vector is not a direction either, below the horizon or not
    zero = wi.copy()
    zero[0] = 0
    with pytest.raises(ValueError, match="found length 0"):
        m.eval(zero, wo)


def test_worst_length_is_reported_across_chunks():
    m = bk.model("microfacet")
    n = 5 * driver.CHUNK + 17
    wi, wo = _pairs(n)
    wi[3 * driver.CHUNK + 5] *= 1.3
    wi[10] *= 0.9
    with pytest.raises(ValueError, match="found length 1.3"):
        m.eval(wi, wo)


@pytest.mark.parametrize("n", [0, 1, 7, driver.CHUNK, driver.CHUNK + 1, 3 * driver.CHUNK + 5])
def test_driver_sizes_and_horizon(n):
    m = bk.model("microfacet", kd=0.3)
    rng = np.random.default_rng(n)
    wi = random_unit_vectors(n, rng, hemisphere=False)
    wo = random_unit_vectors(n, rng, hemisphere=False)
    f = m.eval(wi, wo)
    assert f.shape == (n, 3) and f.dtype == np.float64
    below = (wi[:, 2] <= 0) | (wo[:, 2] <= 0)
    assert np.all(f[below] == 0)
    assert np.all(f[~below] >= 0.3 / np.pi * (1 - 1e-15))
    for j in range(0, n, max(1, n // 5)):  # chunk boundaries: equal to one-pair calls
        assert np.array_equal(f[j], m.eval(wi[j], wo[j]))


def test_shapes_broadcast_and_views():
    m = bk.model("microfacet", alpha_x=0.1, alpha_y=0.4)
    wi, wo = _pairs(12, seed=2)
    table = m.eval(wi[:, None, :], wo[None, :6, :])
    assert table.shape == (12, 6, 3)
    assert np.array_equal(table[4, 5], m.eval(wi[4], wo[5]))
    # a non-contiguous view in, the same numbers out
    big = np.zeros((12, 6))
    big[:, ::2] = wi
    assert np.array_equal(m.eval(big[:, ::2], wo), m.eval(wi, wo))
    assert m.eval(wi[0], wo[0]).shape == (3,)
    with pytest.raises(ValueError, match="do not broadcast"):
        m.eval(wi[:5], wo[:4])


def test_float32_in_float32_out_and_clamped():
    wi, wo = _pairs(1000, seed=5, dtype=np.float32)
    m = bk.model("microfacet", alpha=1e-3)
    f = m.eval(wi, wo)
    assert f.dtype == np.float32 and np.all(np.isfinite(f))
    # computed in float32 (the kernel's float32 twin): close to the float64 value of the same directions,
    # not that value rounded once (test_engine_models.py states the tolerance per model)
    f64 = m.eval(wi.astype(np.float64), wo.astype(np.float64))
    np.testing.assert_allclose(f, f64, rtol=1e-3, atol=1e-30)
    assert not np.array_equal(f, f64.astype(np.float32))


def test_reference_runs_the_same_source_uncompiled():
    from brdfkit.models.microfacet import microfacet_kernel
    from brdfkit.terms import distributions as D

    k = reference.pure(microfacet_kernel)
    assert k.__code__ is microfacet_kernel.py_func.__code__
    # every jitted name the kernel calls is replaced by its Python twin, recursively
    assert not hasattr(k.__globals__["d_of"], "py_func")
    assert k.__globals__["d_of"].__code__ is D.d_of.py_func.__code__
    assert not hasattr(k.__globals__["d_of"].__globals__["d_ggx"], "py_func")
    # and it runs on plain Python floats
    r, g, b = k(0.0, 0.0, 1.0, 0.0, 0.0, 1.0, [0.2, 0.2] + [1.5] * 3 + [0.0] * 3 + [0.04] * 3 + [0.0] * 3 + [1.0] * 3, [1, 0, 2, 0])
    assert isinstance(r, float) and r == pytest.approx(0.04 / (4 * np.pi * 0.04), rel=1e-12)


class _NumpyOnly(BRDF):
    """A model in today's numpy ``_eval`` style (as third-party models are written): served by the fallback."""

    name = "_numpy_only"
    spec = (kd_param(0.5),)

    def _eval(self, wi, wo, p):
        return p["kd"] / np.pi * (1 + 0 * wi[..., :1])


@pytest.mark.parametrize("eng", engine.ENGINES)
def test_models_without_a_kernel_use_their_numpy_eval(eng, restore_engine):
    bk.set_engine(eng)
    m = _NumpyOnly(kd=(0.1, 0.2, 0.3))
    wi, wo = _pairs(20, seed=1)
    wo[:5, 2] *= -1
    f = m.eval(wi, wo)
    assert np.all(f[:5] == 0)
    assert np.allclose(f[5:], np.array([0.1, 0.2, 0.3]) / np.pi, rtol=1e-15)
    assert m.eval(wi.astype(np.float32), wo.astype(np.float32)).dtype == np.float32
    with pytest.raises(ValueError, match="_numpy_only: wo must be unit"):
        m.eval(wi, wo * 3)


def _hits_and_misses_in_two_processes(code: str, cache: "os.PathLike") -> tuple[list[str], list[str]]:
    """What ``code`` prints (numba's cache hits and misses) in a first and then a second fresh process that
    share the brdfkit cache folder ``cache``."""
    env = dict(os.environ, BRDFKIT_CACHE_DIR=str(cache))
    runs = [subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
            for _ in range(2)]
    return runs[0].stdout.split(), runs[1].stdout.split()


def test_kernels_are_cached_on_disk(tmp_path):
    """A fresh process with a warm cache compiles nothing (numba reports cache hits, no misses)."""
    code = (
        "import numpy as np, brdfkit as bk\n"
        "from brdfkit.engine import driver\n"
        "from brdfkit.models.microfacet import microfacet_kernel\n"
        "m = bk.model('microfacet')\n"
        "w = np.array([[0.0, 0.6, 0.8]] * 5000)\n"
        "m.eval(w, w); m.eval(w.astype(np.float32), w.astype(np.float32))\n"
        "s = driver.driver_for(microfacet_kernel).stats\n"
        "print(sum(s.cache_hits.values()), sum(s.cache_misses.values()))\n"
    )
    assert _hits_and_misses_in_two_processes(code, tmp_path) == (["0", "2"], ["2", "0"])  # float64 and float32
    from brdfkit.engine import vecmath

    stem = "drv_brdfkit_models_microfacet_microfacet_kernel" + ("__vm" if vecmath.available() else "")
    assert any(tmp_path.glob(f"numba-*/drivers/{stem}.py"))


def test_scalar_half_vector_matches_the_array_one_at_grazing():
    """geometry.half_vector (numpy, for array callers) and half_vector_c (kernels) give the same h."""
    from brdfkit import geometry as g

    wi, wo = _pairs(200, seed=9)
    extra_i = np.array([[1.0, 0.0, 1e-300], [0.6, 0.8, 0.0], [0.0, 0.0, 1.0], [0.3, 0.4, np.sqrt(0.75)]])
    extra_o = np.array([[-1.0, 0.0, 1e-300], [-0.6, -0.8, 0.0], [0.0, 0.0, 1.0], [-0.3, -0.4, np.sqrt(0.75)]])
    wi = np.concatenate([wi, extra_i])
    wo = np.concatenate([wo, extra_o])
    h = g.half_vector(wi, wo)
    pure = reference.pure(g.half_vector_c)
    for j in range(len(wi)):
        hc = g.half_vector_c(*wi[j], *wo[j])
        assert np.allclose(hc, h[j], rtol=1e-15, atol=1e-16), (wi[j], wo[j], hc, h[j])
        assert pure(*map(float, wi[j]), *map(float, wo[j])) == hc


def test_half_vector_of_a_subnormal_sum_is_the_normal_in_both_precisions():
    """wi + wo with a subnormal largest component: the reciprocal 1/m of the scaled sum stays finite
    (m is raised to the smallest normal number, float32's in the twin), so h is +z, never NaN."""
    from brdfkit import geometry as g
    from brdfkit.engine.precision import float32_twin

    twin = float32_twin(g.half_vector_c)
    for ft, z in ((np.float64, 5e-324), (np.float64, 1e-310), (np.float32, 1.4e-45), (np.float32, 1e-40)):
        f = g.half_vector_c if ft is np.float64 else twin
        args = [ft(v) for v in (1.0, 0.0, z, -1.0, 0.0, z)]
        assert ft(z) > 0 and ft(z) < np.finfo(ft).tiny
        h = f(*args)
        assert h == (0.0, 0.0, 1.0), (ft, z, h)
        sx, sy, sz, m = (g.scaled_sum_c if ft is np.float64 else float32_twin(g.scaled_sum_c))(*args)
        assert m == np.finfo(ft).tiny and 0 < sz < 1 and sx == sy == 0.0
        assert np.isclose(float(sz) * float(m), 2 * float(ft(z)), rtol=1e-6)  # S·m is still wi + wo


def test_term_array_wrappers_run_the_scalar_source_on_both_engines(restore_engine):
    """terms.* array functions: compiled elementwise loops and, under the reference engine, the same Python functions."""
    from brdfkit.terms import distributions as D
    from brdfkit.terms import fresnel as F
    from brdfkit.terms import shadowing as S

    h = random_unit_vectors(300, np.random.default_rng(1))
    calls = [
        lambda: D.ggx(h, 0.2, 0.3),
        lambda: D.beckmann(h, 0.05, 0.5),
        lambda: D.beckmann_lambda(h, 0.2, 0.5),
        lambda: D.ggx_lambda(h, 0.7),
        lambda: F.fresnel_conductor(h[:, 2], np.float64(1.0001), 0.0),
        lambda: F.fresnel_dielectric_cook(h[:, 2], 1.5),
        lambda: S.v_groove(h[:, 2], h[:, 2], np.abs(h[:, 1]), np.abs(h[:, 0]), h[:, 2]),
    ]
    bk.set_engine("compiled")
    a = [f() for f in calls]
    bk.set_engine("reference")
    b = [f() for f in calls]
    for x, y in zip(a, b):
        assert x.dtype == y.dtype == np.float64
        np.testing.assert_allclose(x, y, rtol=1e-13, atol=0)
    # float32 in, float32 out (the float64 value rounded once)
    h32 = h.astype(np.float32)
    bk.set_engine("compiled")
    g32 = D.ggx(h32, np.float32(0.2))
    assert g32.dtype == np.float32
    assert np.array_equal(g32, D.ggx(h32.astype(np.float64), float(np.float32(0.2))).astype(np.float32))


def test_term_array_wrappers_broadcast_like_numpy_on_any_layout(restore_engine):
    """``engine.vectorize`` (the generated elementwise loop): numpy's broadcasting of scalars, partial shapes
    and 0-d arguments, read-only and strided views as given, the bits of the reference engine's
    ``np.frompyfunc`` over the same scalar source; a wrong argument count is a clear error."""
    from brdfkit.terms import fresnel as F

    rng = np.random.default_rng(4)
    c = rng.uniform(0.0, 1.0, (5, 4))
    c.setflags(write=False)
    eta = np.array([1.5, 0.2, 1.0001, 7.0])  # (4,): broadcast along the rows
    k_col = rng.uniform(0.0, 5.0, (5, 1))  # (5, 1): a partial broadcast, copied
    cases = [
        (c, eta, k_col),
        (c[:, ::2], 1.3, 0.0),  # a strided view and two scalars (stride-0 views)
        (c.T, eta[:, None], k_col.T),  # Fortran-ordered
        (np.float64(0.3), 1.5, 2.0),  # every argument 0-d
        (c[0, 0], eta, 2.0),  # a 0-d against a vector
    ]
    for args in cases:
        bk.set_engine("compiled")
        got = F.fresnel_conductor(*args)
        bk.set_engine("reference")
        want = F.fresnel_conductor(*args)
        assert got.shape == want.shape == np.broadcast_shapes(*(np.shape(a) for a in args))
        assert np.array_equal(got, want)
    bk.set_engine("compiled")
    with pytest.raises(TypeError, match="takes 3 arguments, got 2"):
        F._v_conductor(c, eta)


def test_term_array_wrappers_load_from_the_disk_cache_in_a_new_process(tmp_path):
    """The elementwise loop of ``engine.vectorize`` is compiled once and loaded by later processes (a numba
    ufunc compiled its wrapper in every process: 65-86 ms per function)."""
    code = (
        "import numpy as np\n"
        "from brdfkit.terms import fresnel as F\n"
        "from brdfkit.engine import driver\n"
        "F.fresnel_conductor(np.linspace(0, 1, 7), 1.5, 2.0)\n"
        "d = driver.elementwise_driver_for(F.f_conductor, 3)\n"
        "print(sum(d.stats.cache_hits.values()), sum(d.stats.cache_misses.values()))\n"
    )
    assert _hits_and_misses_in_two_processes(code, tmp_path) == (["0", "1"], ["1", "0"])
    assert any(tmp_path.glob("numba-*/drivers/vec_brdfkit_terms_fresnel_f_conductor.py"))


def test_prune_deletes_stale_cache_folders_only(tmp_path):
    """Old numba-* folders go once unused for PRUNE_AFTER_S; the current one, the newest other one and
    recently used ones (another process of another version may be running) stay."""
    from brdfkit.engine import cache

    now = 1_000_000.0
    cur = tmp_path / "numba-current"
    cur.mkdir()
    ages = {"numba-a": 10 * 3600.0, "numba-b": 5 * 3600.0, "numba-c": 60.0, "numba-d": 20 * 3600.0}
    for name, age in ages.items():
        (tmp_path / name / "drivers").mkdir(parents=True)
        (tmp_path / name / "drivers" / "x.py").write_text("x")
        os.utime(tmp_path / name, (now - age, now - age))
    (tmp_path / "env").mkdir()  # not a cache folder: never touched
    os.utime(tmp_path / "env", (now - 1e6, now - 1e6))
    deleted = cache.prune(cur, now=now)
    # numba-c is the newest other (kept as the previous version); numba-b is next, but stale: deleted
    assert sorted(d.name for d in deleted) == ["numba-a", "numba-b", "numba-d"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["env", "numba-c", "numba-current"]
    # a folder used within the grace period survives even when it is not the newest other
    (tmp_path / "numba-e").mkdir()
    os.utime(tmp_path / "numba-e", (now - 120.0, now - 120.0))
    (tmp_path / "numba-f").mkdir()
    os.utime(tmp_path / "numba-f", (now - 30.0, now - 30.0))
    assert cache.prune(cur, now=now) == []


def test_a_new_source_version_prunes_on_first_use(tmp_path):
    """A process that creates its version's folder deletes stale ones (end to end, a fresh process)."""
    old = tmp_path / "numba-0000000000000000"
    old.mkdir()
    newer = tmp_path / "numba-1111111111111111"
    newer.mkdir()
    os.utime(old, (1.0, 1.0))
    os.utime(newer, (2.0, 2.0))
    env = dict(os.environ, BRDFKIT_CACHE_DIR=str(tmp_path))
    code = "from brdfkit.engine import cache; print(cache.cache_dir().name)"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == sorted([newer.name, out.stdout.strip()])  # the stale older one is gone, the newest other kept


def test_forced_width_compile_hides_llvm_remarks_only():
    """LLVM's "loop not vectorized" remarks during a forced-width compile never reach the user's
    stderr; any other line written meanwhile still does (C-level fd 2, as LLVM writes it)."""
    code = (
        "import os\n"
        "from brdfkit.engine.llvm_remarks import without_llvm_remarks\n"
        "with without_llvm_remarks():\n"
        "    os.write(2, b'remark: <unknown>:0:0: loop not vectorized: call instruction cannot be vectorized\\n')\n"
        "    os.write(2, b'a real warning\\n')\n"
        "os.write(2, b'after\\n')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "remark:" not in out.stderr
    assert out.stderr.splitlines() == ["a real warning", "after"]


def test_compile_options_are_set_only_under_numbas_compiler_lock():
    """A driver's first call sets LLVM's process-wide options (vector width, unroll threshold) only while it
    holds numba's compiler lock: a compile on another thread (which holds that lock) never sees them change
    under it, and this call's compile never runs with another thread's. Here a thread holds the lock; the
    options context waits until it is released."""
    import threading
    import time

    from numba.core.compiler_lock import global_compiler_lock

    held, entered = threading.Event(), []

    def holder():
        with global_compiler_lock:
            held.set()
            time.sleep(0.3)
            entered.append(("holder releases", time.perf_counter()))

    t = threading.Thread(target=holder)
    t.start()
    held.wait()
    with llvm_options.compile_options(8, llvm_options.SPAN_UNROLL_THRESHOLD, interleave=2):
        entered.append(("options set", time.perf_counter()))
        assert global_compiler_lock.is_locked()
    t.join()
    assert [e[0] for e in entered] == ["holder releases", "options set"]


@pytest.mark.parametrize("name", ["microfacet", "htsg"])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_specialised_driver_runs_serially_or_in_parallel_with_the_same_bits(name, dtype, monkeypatch):
    """A call whose estimated work is below PARALLEL_MIN_S runs the serial twin of the specialised driver
    (no thread-pool launch), or of the span driver for a model with a span (HTSG); both give the same
    values bit for bit (a span's: to 1e-12, see below), and the same unit-length error."""
    import math

    m = bk.model(name)
    n = 3 * driver.CHUNK + 17
    wi, wo = _pairs(n, seed=3, dtype=dtype)
    p, c = m.kernel_args()
    f32 = dtype == np.float32 and type(m).kernel_float32
    py = type(m).kernel.py_func
    span = getattr(type(m), "kernel_span", None)
    key = driver._span_key(span) if span is not None else (py.__module__, py.__name__, f32, tuple(int(v) for v in c))
    m.eval(wi, wo)  # loads (or compiles) the drivers; the estimate of the work starts with the next call
    calls = []
    serial = driver._SERIAL[key]
    monkeypatch.setitem(driver._SERIAL, key, lambda *a: (calls.append(1), serial(*a))[1])
    if numba.get_num_threads() > 1:
        monkeypatch.setattr(cost, "PARALLEL_MIN_S", 0.0)
        par = m.eval(wi, wo)
        assert calls == []  # in parallel
    else:  # one thread: always serial
        par = m.eval(wi, wo)
        calls.clear()
    assert key in driver._PAIR_COST and driver._PAIR_COST[key] > 0
    monkeypatch.setattr(cost, "PARALLEL_MIN_S", math.inf)
    ser = m.eval(wi, wo)
    assert calls == [1]
    assert ser.dtype == par.dtype == dtype
    if span is None:
        assert np.array_equal(ser, par)
    else:
        # a span's serial and parallel drivers are two compiled functions whose callees (span_terms' loops,
        # vectorised with libmvec) may have been compiled in different processes of a cold-cache run; they agree
        # bit for bit in nearly every run, but differed in the last bits in three full-suite runs since
        # 2026-12-02 (never reproduced alone): held to the engine's documented parity, what differed in the message
        diff = ser != par
        rel = np.abs(ser - par)[diff] / np.maximum(np.abs(par[diff]), 1e-300)
        assert not diff.any() or rel.max() <= 1e-12, (int(diff.sum()), float(rel.max()), np.argwhere(diff)[:5])
    bad = wi.copy()
    bad[n - 5] *= 1.01
    with pytest.raises(ValueError, match="wi must be unit"):
        m.eval(bad, wo)
    assert calls == [1, 1]


def test_threading_layer_is_tbb_here_and_calls_from_threads_agree():
    """brdfkit depends on PyPI's tbb: numba's TBB layer loads (its library found by path) and
    is used; calls from several Python threads at once (the explorer's server) give the bits of
    the same calls made one after another."""
    import platform
    import threading

    import numba

    from brdfkit.engine import driver

    if "NUMBA_THREADING_LAYER" not in os.environ and platform.machine() == "x86_64":
        assert engine.THREADING_LAYER == "tbb"
    m = bk.model("microfacet", distribution="beckmann")
    pairs = [_pairs(20000 + 1000 * k, seed=k) for k in range(6)]
    want = [m.eval(wi, wo) for wi, wo in pairs]
    assert numba.threading_layer() == engine.THREADING_LAYER
    got = [None] * len(pairs)

    def work(k):
        for _ in range(3):
            got[k] = m.eval(*pairs[k])

    threads = [threading.Thread(target=work, args=(k,)) for k in range(len(pairs))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for a, b in zip(got, want):
        np.testing.assert_array_equal(a, b)
    if engine.THREADING_LAYER == "tbb":
        assert isinstance(driver._RUN_LOCK, type(contextlib.nullcontext()))


def test_a_forked_child_evaluates_after_the_parent_ran_parallel_calls():
    """TBB's pool is shut down around fork() by numba: a forked worker (check --all --jobs) works."""
    code = (
        "import concurrent.futures as cf, multiprocessing as mp, numpy as np, brdfkit as bk\n"
        "from brdfkit.geometry import random_unit_vectors as r\n"
        "g = np.random.default_rng(0); wi, wo = r(50000, g), r(50000, g)\n"
        "m = bk.model('ward')\n"
        "a = m.eval(wi, wo)\n"
        "def child(_):\n"
        "    return m.eval(wi, wo)\n"
        "with cf.ProcessPoolExecutor(2, mp_context=mp.get_context('fork')) as ex:\n"
        "    res = list(ex.map(child, range(2)))\n"
        "print(all(np.array_equal(a, b) for b in res))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "True"


def test_the_console_script_skips_numbas_blas_probe_and_scipy_linalg_still_imports(tmp_path):
    """brdfkit.cli.run() first imports numba's arraymath with scipy.linalg held back (its BLAS probe
    imported all of scipy.linalg, 0.1-0.3 s per command): a model then evaluates with the same bits,
    scipy.linalg was not imported for it, imports normally afterwards (a fit needs it), and numba's
    1-D np.dot in jitted code still computes (its own loop). In a process that imported either module
    before, nothing is done."""
    code = (
        "import sys, numpy as np, numba\n"
        "from brdfkit.engine import skip_blas_probe\n"
        "assert skip_blas_probe() is True\n"
        "assert skip_blas_probe() is False\n"  # arraymath is imported now: a second call does nothing
        "import brdfkit as bk\n"
        "from brdfkit.geometry import random_unit_vectors as r\n"
        "g = np.random.default_rng(3); wi, wo = r(5000, g), r(5000, g)\n"
        "v = bk.model('microfacet').eval(wi, wo)\n"
        "print('linalg' if 'scipy.linalg' in sys.modules else 'no-linalg')\n"
        "import scipy.linalg, scipy.optimize\n"
        "print(float(scipy.linalg.norm([3.0, 4.0])))\n"
        "d = numba.njit(lambda a, b: np.dot(a, b))(np.arange(4.0), np.ones(4))\n"
        "print(d)\n"
        "np.save(sys.argv[1], v)\n"
    )
    path = tmp_path / "v.npy"
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split() == ["no-linalg", "5.0", "6.0"]
    g = np.random.default_rng(3)
    wi, wo = random_unit_vectors(5000, g), random_unit_vectors(5000, g)
    np.testing.assert_array_equal(np.load(path), bk.model("microfacet").eval(wi, wo))
    # this test process imported numba's arraymath long ago: nothing to do
    from brdfkit.engine import skip_blas_probe

    assert skip_blas_probe() is False


def test_select_is_a_choice_in_python_and_compiled():
    from brdfkit.engine import jit, select

    @jit
    def pick(c, a, b):
        return select(c, a, b)

    @jit
    def pick_mixed(x):
        return select(x > 0.0, x, 0)  # int and float: unified to float

    assert pick(True, 1.5, 2.5) == 1.5 and pick(False, 1.5, 2.5) == 2.5
    assert pick.py_func(True, 1.5, 2.5) == 1.5 and select(False, 1, 2) == 2
    assert pick_mixed(-3.0) == 0.0 and pick_mixed(2.0) == 2.0
    assert pick(True, 3, 4) == 3


@pytest.mark.parametrize("n", [100, 3 * driver.CHUNK])
def test_writable_and_read_only_inputs_share_one_specialisation(n):
    """numba types a read-only array apart from a writable one; the driver passes every input read-only, so a
    frozen array (the albedo plan's) and a writable one run the same compiled code (one compile, one cache
    entry, one load per process) and give the same bits."""
    m = bk.model("microfacet", distribution="beckmann", fresnel="schlick", alpha=0.37)
    rng = np.random.default_rng(5)
    wi, wo = random_unit_vectors(n, rng), random_unit_vectors(n, rng)
    frozen_i, frozen_o = wi.copy(), wo.copy()
    frozen_i.setflags(write=False)
    frozen_o.setflags(write=False)
    seen = []
    real = driver._compile_key

    def spy(drive, pt, *arrays):
        seen.append(tuple(a.flags.writeable for a in arrays))
        return real(drive, pt, *arrays)

    driver._compile_key = spy
    try:
        a = m.eval(wi, wo)
        b = m.eval(frozen_i, wo)
        c = m.eval(frozen_i, frozen_o)
    finally:
        driver._compile_key = real
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, c)
    assert wi.flags.writeable and wo.flags.writeable  # the caller's arrays are untouched
    assert all(not any(w) for w in seen)
    if n > driver.CHUNK:
        assert len(seen) == 3
        kernel = type(m).kernel
        choices = tuple(int(v) for v in m.kernel_args()[1])
        drive = driver.special_driver_for(kernel, choices, False, False)
        assert len(drive.signatures) == 1, drive.signatures
    else:
        gd = driver.driver_for(type(m).kernel, False)._drive
        assert gd.signatures and all(not any(a.mutable for a in sig[:4]) for sig in gd.signatures), gd.signatures
