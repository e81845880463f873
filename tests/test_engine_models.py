"""Compiled kernel vs the same kernel run uncompiled (the reference engine), for every model and choice.

For every registered model that has a kernel, every combination of its choice and
bool parameters, and a few random draws of its numeric parameters (log-uniform
where the spec says log scale), the compiled float64 result equals the reference
to 1e-12 relative over random direction pairs (both hemispheres, grazing and
special configurations included); float32 in gives the float64 reference rounded
once — for HTSG, whose kernel computes in float64 also for float32 input — or, for
every other model, the kernel's float32 twin (``brdfkit.engine.precision``: the
same source computed in float32), which agrees with the float64 reference of the
same float32 directions to :func:`float32_tolerance`: the rounding of the inputs'
products (2^-24 each) amplified by the formula's own condition number, which is
large only where the float64 result is itself that sensitive to its inputs — a
cosine power x^s (relative error s·δx/x), the Beckmann exponential exp(−e)
(e·δ), the dielectric Fresnel term near its critical angle, Oren-Nayar's tan β at
grazing angles. Where the sensitivity is extreme (the dielectric Fresnel term of
index 0.14 moves 1.2 % per float32 ulp of v·h just past its critical angle, so the
few ulps that v·h loses in float32 cost a few per cent), the tolerance adds the
float64 reference's own spread under a perturbation of the input directions
(:func:`_sensitivity`).

The random draws are seeded from the test's id (CRC-32, not ``hash``, which Python
salts per process): every run tests the same numbers, and a failure reproduces.
"""

from __future__ import annotations

import itertools
import math
import zlib

import numpy as np
import pytest

import brdfkit as bk
from brdfkit import engine
from brdfkit.geometry import random_unit_vectors, spherical_to_vector

#: models converted to the kernel protocol by the engine work (every built-in analytic model is meant to be)
CONVERTED_HERE = ["lambert", "phong", "blinn-phong", "cook-torrance", "microfacet", "oren-nayar", "ward", "lafortune"]

#: float32 twin vs float64 reference, relative (measured worst over the draws below: 3.0e-4, oren-nayar "full"
#: at 89.99°; 1.1e-4 the dielectric Fresnel term of index 0.14 near its critical angle; 3e-5 Beckmann)
RTOL32 = 1e-3
#: ... plus this much per unit of a cosine-power exponent (Phong, Blinn-Phong, Lafortune; measured 3.6e-8·s)
RTOL32_PER_EXPONENT = 2.0**-22
#: ... and absolute: values this small lose digits to float32's subnormal range inside the formula
ATOL32 = 1e-30
#: ... and twice the float64 reference's largest change when one component of wi or wo moves by this
#: much (then renormalised), about 16 float32 ulps: the error that the ulps lost by a cosine computed in
#: float32 cause where the formula is that sensitive (measured over 1e6 random pairs, dielectric index
#: 0.143: worst 2.5e-2 plain, 2.3e-4 beyond twice this spread; 2^-21: 1.1e-3, 2^-22: 2.9e-3)
PERTURB32 = 2.0**-20


def float32_tolerance(m) -> float:
    """Relative tolerance of the float32 twin of ``m``'s kernel against the float64 reference."""
    prm = m.params
    exponent = float(prm.get("shininess", 0.0))
    if m.name == "lafortune":
        exponent = max(float(prm[f"n_{k}"]) for k in range(1, int(prm["lobes"]) + 1))
    return RTOL32 + RTOL32_PER_EXPONENT * exponent


def _sensitivity(m, wi, wo, b):
    """The largest change of ``m.eval`` (float64) from ``b`` when one component of wi or wo moves by ±PERTURB32."""
    out = np.zeros_like(b)
    for which in (0, 1):
        for j in range(3):
            for sign in (-1.0, 1.0):
                d = [wi.copy(), wo.copy()]
                d[which][..., j] += sign * PERTURB32
                d[which] /= np.linalg.norm(d[which], axis=-1, keepdims=True)
                out = np.maximum(out, np.abs(m.eval(d[0], d[1]) - b))
    return out


def _assert_f32(c32, wi32, wo32, m, what):
    """``c32`` (the float32 twin's values for ``wi32``, ``wo32``) within :func:`float32_tolerance` of the float64
    reference of the same float32 directions, plus twice the reference's own spread (:func:`_sensitivity`)."""
    wi, wo = wi32.astype(np.float64), wo32.astype(np.float64)
    a = np.asarray(c32, dtype=np.float64)
    b = np.asarray(m.eval(wi, wo), dtype=np.float64)
    assert np.all(np.isfinite(a)) and np.all(a >= 0), what
    rtol = float32_tolerance(m)
    err = np.abs(a - b)
    bad = err > rtol * np.abs(b) + ATOL32
    if np.any(bad):  # only there: the spread costs twelve more evaluations
        bad &= err > rtol * np.abs(b) + ATOL32 + 2.0 * _sensitivity(m, wi, wo, b)
    if np.any(bad):
        i = np.argwhere(bad)[0]
        raise AssertionError(f"{what}: float32 {a[tuple(i)]!r} vs float64 reference {b[tuple(i)]!r} "
                             f"(rel {err[tuple(i)] / abs(b[tuple(i)]):.3g} > {rtol:.3g})")

def test_float32_tolerance_follows_the_formulas_sensitivity():
    """The sensitivity term admits the float32 twin's few per cent where the float64 reference itself moves that
    much within a few ulps (the dielectric Fresnel term of index 0.143 at v·h = its critical cosine + 6e-9), and
    nowhere else: an error of 2e-3 at a well-conditioned pair, or at that pair in a channel whose index has no
    critical angle, still fails."""
    m = bk.model("microfacet", distribution="ggx", shadowing="smith", fresnel="dielectric")  # eta 0.143, 0.375, 1.44
    wi = np.array([[-0.5044227838516235, -0.2566543221473694, 0.8244308829307556]], dtype=np.float32)
    wo = np.array([[-0.3086482286453247, -0.4654083549976349, 0.8295367956161499]], dtype=np.float32)
    c32 = m.eval(wi, wo)
    ref = m.eval(wi.astype(np.float64), wo.astype(np.float64))
    assert abs(c32[0, 0] / ref[0, 0] - 1.0) > 1e-2  # float32 loses that much here: the pair is ill-conditioned
    _assert_f32(c32, wi, wo, m, "critical angle")
    wrong = c32.copy()
    wrong[0, 2] *= np.float32(1.002)  # eta 1.44: the same pair is well conditioned in this channel
    with pytest.raises(AssertionError, match="float32"):
        _assert_f32(wrong, wi, wo, m, "critical angle, blue")
    wi2 = spherical_to_vector(np.radians(30), 0.0)[None].astype(np.float32)
    wo2 = spherical_to_vector(np.radians(40), 2.0)[None].astype(np.float32)
    c = m.eval(wi2, wo2)
    _assert_f32(c, wi2, wo2, m, "generic pair")
    with pytest.raises(AssertionError, match="float32"):
        _assert_f32(c * np.float32(1.002), wi2, wo2, m, "generic pair")


KERNEL_MODELS = [n for n in bk.models() if getattr(bk.registry.get(n), "kernel", None) is not None]


def test_converted_models_have_kernels():
    missing = [n for n in CONVERTED_HERE if n not in KERNEL_MODELS]
    assert not missing, f"no kernel: {missing}"


def _choice_grid(cls):
    keys = [p for p in cls.spec if p.kind in ("choice", "bool")]
    values = [p.choices if p.kind == "choice" else (False, True) for p in keys]
    return [dict(zip([p.name for p in keys], combo)) for combo in itertools.product(*values)]


def _draw(p, rng):
    lo, hi = p.range if p.range is not None else (-10.0, 10.0)
    if math.isinf(hi):
        hi = lo + 1e3 * max(1.0, abs(lo))
    if p.open_lo:
        lo = lo + 1e-6 * (hi - lo)
    if p.open_hi:
        hi = hi - 1e-6 * (hi - lo)
    size = 3 if p.kind == "rgb" else None
    if p.kind == "int":
        return int(rng.integers(math.ceil(lo), math.floor(min(hi, lo + 100)) + 1))
    if p.log_scale and lo > 0:
        v = np.exp(rng.uniform(np.log(lo), np.log(hi), size))
    else:
        v = rng.uniform(lo, hi, size)
    v = np.clip(v, lo, hi)
    return tuple(float(x) for x in v) if size else float(v)


def _random_params(cls, rng, fixed):
    out = dict(fixed)
    for p in cls.spec:
        if p.kind in ("choice", "bool") or p.name in out:
            continue
        if cls.name == "microfacet" and p.name == "alpha":
            continue  # alpha_x / alpha_y drawn instead (anisotropic)
        out[p.name] = _draw(p, rng)
    return out


def _directions(n, seed):
    rng = np.random.default_rng(seed)
    wi = random_unit_vectors(n, rng, hemisphere=False)
    wo = random_unit_vectors(n, rng, hemisphere=False)
    up = random_unit_vectors(n, rng)
    wi[: n // 2, 2] = np.abs(wi[: n // 2, 2])  # most pairs above the horizon
    wo[: n // 2] = up[: n // 2]
    # special configurations: normal, grazing, wi == wo, mirror, wi == -wo(x,y), exactly horizon
    sp = [
        (spherical_to_vector(0.0, 0.0), spherical_to_vector(0.0, 0.0)),
        (spherical_to_vector(np.radians(89.99), 0.3), spherical_to_vector(np.radians(89.99), 0.3 + np.pi)),
        (spherical_to_vector(np.radians(45), 1.0), spherical_to_vector(np.radians(45), 1.0)),
        (spherical_to_vector(np.radians(60), 2.0), spherical_to_vector(np.radians(60), 2.0 + np.pi)),
        (spherical_to_vector(np.radians(89.9999), 0.0), spherical_to_vector(np.radians(1e-3), 0.5)),
        (np.array([1.0, 0.0, 0.0]), spherical_to_vector(np.radians(30), 0.0)),
    ]
    wi = np.concatenate([wi, np.array([a for a, _ in sp])])
    wo = np.concatenate([wo, np.array([b for _, b in sp])])
    return wi, wo


def _assert_rel(a, b, rtol, what):
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    assert np.all(np.isfinite(a)) and np.all(np.isfinite(b)), what
    err = np.abs(a - b)
    bad = err > rtol * np.maximum(np.abs(b), 1e-300)
    if np.any(bad):
        i = np.argwhere(bad)[0]
        raise AssertionError(f"{what}: compiled {a[tuple(i)]!r} vs reference {b[tuple(i)]!r} (rel {err[tuple(i)] / abs(b[tuple(i)]):.3g})")


def _cases():
    for name in KERNEL_MODELS:
        cls = bk.registry.get(name)
        for fixed in _choice_grid(cls):
            yield pytest.param(name, fixed, id=name + "-" + "-".join(str(v) for v in fixed.values()) if fixed else name)


@pytest.mark.parametrize("name,fixed", list(_cases()))
def test_compiled_equals_reference(name, fixed):
    cls = bk.registry.get(name)
    rng = np.random.default_rng(zlib.crc32(repr((name, sorted(fixed.items()))).encode()))
    wi, wo = _directions(160, seed=int(rng.integers(1 << 30)))
    wi32, wo32 = wi.astype(np.float32), wo.astype(np.float32)
    draws = [dict(fixed)] + [_random_params(cls, rng, fixed) for _ in range(3)]  # defaults, then random
    old = engine.engine()
    try:
        for params in draws:
            m = cls(**params)
            engine.set_engine("compiled")
            c64 = m.eval(wi, wo)
            c32 = m.eval(wi32, wo32)
            engine.set_engine("reference")
            r64 = m.eval(wi, wo)
            r32 = m.eval(wi32, wo32)
            what = f"{name} {m.params_json()}"
            assert c64.dtype == r64.dtype == np.float64 and c32.dtype == r32.dtype == np.float32
            _assert_rel(c64, r64, 1e-12, what + " float64")
            if cls.kernel_float32:  # the float32 twin against the float64 reference of the same directions
                _assert_f32(c32, wi32, wo32, m, what + " float32")
            else:  # float64 computation: both round the float64 result of the same float32 directions once
                _assert_rel(c32, r32, 2.0**-23, what + " float32")
            below = (wi[:, 2] <= 0) | (wo[:, 2] <= 0)
            assert np.all(c64[below] == 0) and np.all(r64[below] == 0)
            assert np.all(c64 >= 0)
    finally:
        engine.set_engine(old)


@pytest.mark.parametrize("name", KERNEL_MODELS)
def test_array_wrappers_match_the_engine_under_the_reference(name):
    """The same numbers through ``bk.set_engine`` both ways for a table call (broadcast shapes)."""
    m = bk.model(name)
    wi, wo = _directions(20, seed=3)
    old = engine.engine()
    try:
        engine.set_engine("compiled")
        a = m.eval(wi[:, None, :], wo[None, :, :])
        engine.set_engine("reference")
        b = m.eval(wi[:, None, :], wo[None, :, :])
    finally:
        engine.set_engine(old)
    assert a.shape == b.shape == (len(wi), len(wo), 3)
    _assert_rel(a, b, 1e-12, name)


@pytest.mark.parametrize("name,fixed", [
    ("microfacet", {}),
    ("microfacet", {"distribution": "beckmann", "shadowing": "smith-correlated", "fresnel": "dielectric", "multiscatter": True}),
    ("microfacet", {"shadowing": "v-groove", "fresnel": "schlick"}),
    ("ward", {}),
    ("lambert", {}),
    ("lafortune", {"lobes": 3, "ks_2": 0.2, "cx_2": 0.5, "cy_2": 0.7, "n_2": 3.0, "ks_3": 0.1, "n_3": 200.0}),
    ("phong", {"shininess": 5000.0}),
    ("htsg", {}),
])
def test_specialised_driver_equals_reference(name, fixed):
    """Calls of more than one chunk run the driver specialised per choice combination: same results."""
    from brdfkit.engine import driver

    n = driver.CHUNK + 300
    wi, wo = _directions(n, seed=7)
    m = bk.registry.get(name)(**fixed)
    old = engine.engine()
    try:
        for dt in (np.float64, np.float32):
            engine.set_engine("compiled")
            c = m.eval(wi.astype(dt), wo.astype(dt))
            engine.set_engine("reference")
            r = m.eval(wi.astype(dt), wo.astype(dt))
            assert c.dtype == r.dtype == dt
            what = f"{name} {fixed} {np.dtype(dt).name}"
            if dt == np.float64:
                _assert_rel(c, r, 1e-12, what)
            elif type(m).kernel_float32:
                _assert_f32(c, wi.astype(dt), wo.astype(dt), m, what)
            else:
                _assert_rel(c, r, 2.0**-23, what)
        engine.set_engine("compiled")
        bad = wi.copy()
        bad[n - 5] *= 1.01
        with pytest.raises(ValueError, match="wi must be unit"):
            m.eval(bad, wo)
    finally:
        engine.set_engine(old)


@pytest.mark.parametrize("name", [n for n in KERNEL_MODELS if bk.registry.get(n).kernel_float32])
def test_float32_twin_computes_in_float32(name):
    """numba infers no float64 variable in the float32 twin of the kernel (callees included)."""
    from brdfkit.engine.precision import float64_variables

    leaks = float64_variables(bk.registry.get(name).kernel)
    assert leaks == [], leaks[:10]


def test_float32_twin_maps_constants_by_role():
    from brdfkit.engine.precision import F32_CAP, F32_FLOOR, f32_constant

    assert f32_constant(0.5) == np.float32(0.5) and f32_constant(0.5).dtype == np.float32
    assert f32_constant(1e-150) == F32_FLOOR and f32_constant(-1e-300) == -F32_FLOOR
    assert f32_constant(1e300) == F32_CAP and np.isinf(f32_constant(math.inf))
    # the smallest normal float64 (geometry.NORMAL_MIN, keeping 1/m finite) becomes the smallest normal float32
    assert f32_constant(float(np.finfo(np.float64).tiny)) == np.finfo(np.float32).tiny
    assert f32_constant(2 * float(np.finfo(np.float64).tiny)) == F32_FLOOR  # other floors keep theirs
    assert 4 * F32_FLOOR * F32_FLOOR >= np.finfo(np.float32).tiny  # a product of two floors stays normal
    assert np.isfinite(F32_CAP * np.float32(3.9))



def test_parameters_outside_float32_are_computed_in_float64():
    """A parameter float32 cannot hold (schlick's p = 5e-324, a weight of 1e-154) runs the float64 kernel."""
    from brdfkit.engine.precision import fits_float32

    assert fits_float32(np.array([0.0, 0.25, -3.0, math.inf, 1e30]))
    assert not fits_float32(np.array([0.25, 5e-324])) and not fits_float32(np.array([1e39]))
    wi, wo = _directions(3000, seed=11)
    wi32, wo32 = wi.astype(np.float32), wo.astype(np.float32)
    for m in (bk.model("schlick", p=5e-324), bk.model("lafortune", lobes=2, ks_2=1e-154, cx_2=-100.0,
                                                       cy_2=-100.0, n_2=1e5)):
        f = m.eval(wi32, wo32)
        ref = m.eval(wi32.astype(np.float64), wo32.astype(np.float64)).astype(np.float32)
        assert np.array_equal(f, ref), m  # the float64 value rounded once, as before the twin


def _soa_cases():
    for name in KERNEL_MODELS:
        cls = bk.registry.get(name)
        grid = list(_choice_grid(cls))
        for fixed in grid[:: max(1, len(grid) // 3)]:  # a few choice combinations per model
            yield pytest.param(name, fixed, id=name + "-" + "-".join(str(v) for v in fixed.values()) if fixed else name)


@pytest.mark.parametrize("name,fixed", list(_soa_cases()))
def test_fortran_ordered_directions_give_the_same_bits(name, fixed):
    """Fortran-ordered (n, 3) directions (each component contiguous) run the structure-of-arrays driver
    where it applies, in place: the values equal those of the same directions in rows (float64 bit for
    bit; float32 to the rounding of its fused multiply-adds, which LLVM may place differently in the two
    loops: 1 ulp on 3 of 13 209 values of one Schlick setting), the result is Fortran-ordered; a non-unit direction is refused the same way; under the
    reference engine, and with one argument in rows, the rows path runs (same values again)."""
    from brdfkit.engine import driver

    n = driver.CHUNK * 2 + 301  # several chunks, the last one partial
    wi, wo = _directions(n, seed=11)
    m = bk.registry.get(name)(**fixed)
    old = engine.engine()
    try:
        engine.set_engine("compiled")
        for dt in (np.float64, np.float32):
            a, b = wi.astype(dt), wo.astype(dt)
            fa, fb = np.asfortranarray(a), np.asfortranarray(b)
            want = m.eval(a, b)
            got = m.eval(fa, fb)
            assert got.dtype == want.dtype == dt and got.shape == want.shape
            if dt == np.float64:
                np.testing.assert_array_equal(got, want)
            else:  # the float32 twins may fuse a·b + c (LLVM's contract): the two loops can fuse differently
                np.testing.assert_allclose(got, want, rtol=1e-6, atol=0)
            assert got.flags.f_contiguous  # in place where driver.runs_soa, else copied back: always
            np.testing.assert_array_equal(m.eval(fa, b), want)  # mixed layouts: copied to rows
            bad = fa.copy(order="F")
            bad[n - 5] *= 1.01
            with pytest.raises(ValueError, match="wi must be unit"):
                m.eval(bad, fb)
            bad = fb.copy(order="F")
            bad[7, 2] = np.nan
            with pytest.raises(ValueError, match="wo must be unit"):
                m.eval(fa, bad)
        engine.set_engine("reference")
        k = 40  # the reference engine is slow: a few pairs, Fortran-ordered, against the same in rows
        fa, fb = np.asfortranarray(wi[-k:]), np.asfortranarray(wo[-k:])
        np.testing.assert_array_equal(m.eval(fa, fb), m.eval(wi[-k:], wo[-k:]))
    finally:
        engine.set_engine(old)


def test_the_soa_template_is_derived_from_the_specialised_one():
    """One loop source: the structure-of-arrays driver differs from the specialised driver only in how it
    addresses the components (and its header line)."""
    from brdfkit.engine import driver

    soa = driver.SOA_TEMPLATE.splitlines()
    spec = driver.SPECIAL_TEMPLATE.splitlines()
    differ = [line for line in spec if line not in soa]
    assert differ and all(("[3 * " in line) or line.startswith("# Generated") for line in differ)
    assert "a0[j]" in driver.SOA_TEMPLATE and "o2[j] =" in driver.SOA_TEMPLATE and "[3 * j" not in driver.SOA_TEMPLATE
    # the structure-of-arrays driver is only for the specialised calls: asked for one chunk, run() says so
    m = bk.model("lambert")
    p, c = m.kernel_args()
    wi = np.asfortranarray(np.tile([0.0, 0.0, 1.0], (driver.CHUNK, 1)))
    assert not driver.runs_soa(driver.CHUNK, p) and driver.runs_soa(driver.CHUNK + 1, p)
    with pytest.raises(ValueError, match="soa=True needs more than 2048 pairs"):
        driver.run(type(m).kernel, wi, wi, p, c, np.empty((driver.CHUNK, 3), order="F"), soa=True)
