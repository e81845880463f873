"""brdfkit.engine.vecmath: libmvec behind the vectorised exp/log/pow of the compiled drivers.

What is checked: the IR rewrite (names by function, width and type; everything else untouched);
that on this platform (Linux x86-64, glibc >= 2.22) vector math is on and a loop compiled inside
``compiling()`` calls libmvec while one compiled outside does not; libmvec's accuracy against
libm (<= 4 ulp, glibc's documented bound) and its special values, float64 and float32, through
such a compiled loop; that a driver calling libmvec has its own cache file name.
"""

import math
import os
import platform
import re
import subprocess
import sys

import numba
import numpy as np
import pytest

from brdfkit.engine import driver, vecmath

ON_GLIBC_X86 = sys.platform == "linux" and platform.machine() == "x86_64"

IR = """
declare <8 x double> @llvm.exp.v8f64(<8 x double>) #0
declare <16 x float> @llvm.pow.v16f32(<16 x float>, <16 x float>) #0
declare <3 x double> @llvm.exp.v3f64(<3 x double>) #0
declare double @llvm.exp.f64(double) #0
define void @f() {
  %a = call <8 x double> @llvm.exp.v8f64(<8 x double> zeroinitializer)
  %b = call fast <16 x float> @llvm.pow.v16f32(<16 x float> zeroinitializer, <16 x float> zeroinitializer)
  %c = call <3 x double> @llvm.exp.v3f64(<3 x double> zeroinitializer)
  %d = call double @llvm.exp.f64(double 0.0)
  %e = call <8 x double> @llvm.sin.v8f64(<8 x double> zeroinitializer)
  ret void
}
"""


def test_vector_names_follow_the_x86_vector_function_abi():
    assert vecmath.vector_name("exp", 8, "f64") == "_ZGVeN8v_exp"
    assert vecmath.vector_name("pow", 16, "f32") == "_ZGVeN16vv_powf"
    assert vecmath.vector_name("log", 4, "f64") == "_ZGVdN4v_log"
    assert vecmath.vector_name("log", 2, "f64") == "_ZGVbN2v_log"
    assert vecmath.vector_name("exp", 3, "f64") is None  # no such ISA width
    assert vecmath.vector_name("sin", 8, "f64") is None  # not a renamed function


def test_rewrite_renames_only_mapped_vector_intrinsics():
    names = {("exp", 8, "f64"): "_ZGVeN8v_exp", ("pow", 16, "f32"): "_ZGVeN16vv_powf"}
    out = vecmath.rewrite(IR, names)
    assert "declare <8 x double> @_ZGVeN8v_exp(<8 x double>) #0" in out
    assert "call <8 x double> @_ZGVeN8v_exp(" in out
    assert "call fast <16 x float> @_ZGVeN16vv_powf(" in out
    for untouched in ("@llvm.exp.v3f64(", "@llvm.exp.f64(", "@llvm.sin.v8f64("):
        assert untouched in out
    assert "llvm.exp.v8f64" not in out and "llvm.pow.v16f32" not in out
    assert vecmath.rewrite(IR, {}) == IR


SCALAR_IR = """
declare double @erfc(double)
declare double @llvm.pow.f64(double, double) #0
define double @f(double %x) {
  %a = tail call double @erfc(double %x), !noalias !4
  %b = call double @llvm.pow.f64(double %a, double %x) #0
  %c = call double @llvm.sin.f64(double %b)
  ret double %c
}
"""


def test_annotate_names_the_vector_variants_of_scalar_calls():
    variants = {"erfc": [(8, "_ZGVeN8v_erfc")], "llvm.pow.f64": [(4, "_ZGVdN4vv_pow"), (8, "_ZGVeN8vv_pow")]}
    signature = {"erfc": (1, "double"), "llvm.pow.f64": (2, "double")}
    out = vecmath.annotate(SCALAR_IR, variants, signature)
    lines = out.splitlines()
    erfc_call = next(ln for ln in lines if "call double @erfc(" in ln)
    pow_call = next(ln for ln in lines if "call double @llvm.pow.f64(" in ln)
    g_erfc = re.search(r"\) (#\d+), !noalias !4$", erfc_call).group(1)
    g_pow = re.search(r"\) (#\d+) #0$", pow_call).group(1)
    assert f'attributes {g_erfc} = {{ "vector-function-abi-variant"="_ZGV_LLVM_N8v_erfc(_ZGVeN8v_erfc)" }}' in out
    assert (f'attributes {g_pow} = {{ "vector-function-abi-variant"='
            '"_ZGV_LLVM_N4vv_llvm.pow.f64(_ZGVdN4vv_pow),_ZGV_LLVM_N8vv_llvm.pow.f64(_ZGVeN8vv_pow)" }') in out
    assert "declare <8 x double> @_ZGVeN8v_erfc(<8 x double>)" in out
    assert "declare <4 x double> @_ZGVdN4vv_pow(<4 x double>, <4 x double>)" in out
    assert re.search(r"@llvm.compiler.used = appending global \[3 x ptr\] \[ptr @_ZGVeN8v_erfc, ptr @_ZGVdN4vv_pow, "
                     r"ptr @_ZGVeN8vv_pow\]", out)
    assert "call double @llvm.sin.f64(double %b)\n" in out  # not in the table: untouched
    # nothing to annotate, or a compiler.used list already there: unchanged
    assert vecmath.annotate(SCALAR_IR, {}, {}) == SCALAR_IR
    kept = SCALAR_IR + '@llvm.compiler.used = appending global [0 x ptr] [], section "llvm.metadata"\n'
    assert vecmath.annotate(kept, variants, signature) == kept


def test_annotated_module_parses_and_a_scalar_erfc_loop_vectorises():
    if not vecmath.available():  # pragma: no cover
        pytest.skip("no libmvec on this platform")

    @numba.njit(error_model="numpy")
    def loop(x, s, out):
        for i in range(x.size):
            out[i] = math.erfc(x[i]) + x[i] ** s + math.atan2(x[i], 0.5)

    x = np.linspace(-3, 3, 4096)
    out = np.empty_like(x)
    with vecmath.compiling("all"):
        loop(x, 2.5, out)
    asm = loop.inspect_asm(loop.signatures[0])
    assert re.search(r"_ZGV[bde]N\d+v_erfc", asm) and re.search(r"_ZGV[bde]N\d+vv_pow", asm)
    want = np.array([math.erfc(v) + (v ** 2.5 if v >= 0 else math.nan) + math.atan2(v, 0.5) for v in x])
    ok = np.isfinite(want)
    np.testing.assert_allclose(out[ok], want[ok], rtol=4e-15)
    assert np.all(np.isnan(out[~ok]))


def test_rewrite_keeps_one_declaration_where_annotate_declared_the_function_already():
    ir = (IR.replace("define void @f() {", "declare <8 x double> @_ZGVeN8v_exp(<8 x double>)\ndefine void @f() {"))
    out = vecmath.rewrite(ir, {("exp", 8, "f64"): "_ZGVeN8v_exp"})
    assert len(re.findall(r"declare <8 x double> @_ZGVeN8v_exp\(", out)) == 1
    assert "call <8 x double> @_ZGVeN8v_exp(" in out


def _loop():
    @numba.njit(error_model="numpy")
    def loop(x, y, out):
        for i in range(x.size):
            out[i] = math.exp(x[i]) + math.log(y[i])

    return loop


def test_compiling_context_turns_libmvec_on_for_that_compile_only():
    if ON_GLIBC_X86:
        assert vecmath.available(), "glibc's libmvec should be found on Linux x86-64"
    if not vecmath.available():  # pragma: no cover - another platform: nothing to rename
        pytest.skip("no libmvec on this platform")
    x = np.linspace(-5, 5, 64)
    plain, vm = _loop(), _loop()
    plain(x, x + 6, np.empty_like(x))
    with vecmath.compiling("all"):
        vm(x, x + 6, np.empty_like(x))
    asm_plain = plain.inspect_asm(plain.signatures[0])
    asm_vm = vm.inspect_asm(vm.signatures[0])
    assert not re.search(r"_ZGV", asm_plain)
    assert re.search(r"_ZGV[bde]N\d+v_exp", asm_vm) and re.search(r"_ZGV[bde]N\d+v_log", asm_vm)
    # the flag is reset after the context
    assert not getattr(vecmath._state, "on", False)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_libmvec_accuracy_and_special_values_through_a_compiled_loop(dtype):
    if not vecmath.available():  # pragma: no cover
        pytest.skip("no libmvec on this platform")
    rng = np.random.default_rng(3)
    lim = 700.0 if dtype == np.float64 else 87.0
    xe = np.concatenate([rng.uniform(-lim - 50, lim + 10, 20000),
                         [0.0, -0.0, 1e-300, -1e-300, np.inf, -np.inf, np.nan, -745.2, 709.8, -103.0, 89.0]]).astype(dtype)
    tiny = float(np.finfo(dtype).smallest_subnormal)
    xl = np.concatenate([10.0 ** rng.uniform(-300 if dtype == np.float64 else -40, 300 if dtype == np.float64 else 38, 20000),
                         [0.0, tiny, 1.0, np.inf, -1.0, np.nan, 2.0]]).astype(dtype)
    xp = np.abs(rng.normal(size=xe.size)).astype(dtype) + dtype(0.01)
    yp = rng.uniform(-30, 30, xe.size).astype(dtype)

    @numba.njit(error_model="numpy")
    def run(a, b, c, d, oe, ol, op):
        for i in range(a.size):
            oe[i] = math.exp(a[i])
        for i in range(b.size):
            ol[i] = math.log(b[i])
        for i in range(c.size):
            op[i] = c[i] ** d[i]

    oe, ol, op = np.empty_like(xe), np.empty_like(xl), np.empty_like(xp)
    with vecmath.compiling("all"):
        run(xe, xl, xp, yp, oe, ol, op)
    assert "_ZGV" in run.inspect_asm(run.signatures[0])
    wide = np.float64 if dtype == np.float32 else np.longdouble
    with np.errstate(all="ignore"):  # the reference's own overflow, log(-1), inf casts
        _compare(dtype, wide, xe, xl, xp, yp, oe, ol, op)


def _compare(dtype, wide, xe, xl, xp, yp, oe, ol, op):
    for got, want in ((oe, np.exp(xe.astype(wide))), (ol, np.log(xl.astype(wide))), (op, np.power(xp.astype(wide), yp.astype(wide)))):
        want_r = want.astype(dtype)
        same_special = ~np.isfinite(want_r) | (want_r == 0)
        np.testing.assert_array_equal(got[same_special], want_r[same_special])
        fin = ~same_special & (np.abs(want_r) >= np.finfo(dtype).tiny)  # normal results: ulp error
        ulp = np.spacing(np.abs(want_r[fin]).astype(dtype)).astype(wide)
        err = np.abs(got[fin].astype(wide) - want[fin]) / ulp
        assert err.max() <= 4.0, err.max()


def test_drivers_scope_edits_the_drivers_modules_only(tmp_path):
    """In the engine's scope a driver calls libmvec, the terms compiled meanwhile do not (their
    cache is shared with processes that have vector math off); an ad-hoc loop is left alone."""
    if not vecmath.available():  # pragma: no cover
        pytest.skip("no libmvec on this platform")
    code = (
        "import re, numpy as np, brdfkit as bk\n"
        "from brdfkit.engine import driver\n"
        "from brdfkit.terms import distributions\n"
        "from brdfkit.geometry import random_unit_vectors\n"
        "rng = np.random.default_rng(0)\n"
        "w1, w2 = random_unit_vectors(50000, rng), random_unit_vectors(50000, rng)\n"
        "bk.model('microfacet', distribution='beckmann').eval(w1, w2)\n"
        "d = [d for d in driver._SERIAL.values() if d.signatures][0]\n"
        "print(sorted(set(re.findall(r'call [^@\\n]*@(_ZGV\\w+)', d.inspect_llvm(d.signatures[0])))))\n"
        "f = distributions.lambda_beckmann\n"
        "print('vector-function-abi-variant' in f.inspect_llvm(f.signatures[0]))\n"
    )
    env = dict(os.environ, BRDFKIT_CACHE_DIR=str(tmp_path), NUMBA_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout.split("\n")
    assert re.search(r"_ZGV[bde]N\d+v_erfc", out[0]), out  # Beckmann's Smith Λ: erfc per vector
    assert out[1] == "False"  # the term lambda_beckmann, compiled meanwhile: as numba writes it

    @numba.njit(error_model="numpy")
    def loop(x, out):
        for i in range(x.size):
            out[i] = math.exp(x[i])

    x = np.linspace(-3, 3, 256)
    with vecmath.compiling():  # the drivers' scope: not a driver, not edited
        loop(x, np.empty_like(x))
    assert "_ZGV" not in loop.inspect_asm(loop.signatures[0])
    with pytest.raises(ValueError, match="scope"):
        vecmath.compiling("everything")


def test_a_driver_calling_libmvec_has_its_own_cache_file():
    from brdfkit.models.ward import ward_kernel

    stem = driver._stem(ward_kernel.py_func)
    assert stem.endswith("__vm") == vecmath.available()
