"""``m.eval_grad`` (SPEC.md, "Gradients") against Richardson-extrapolated central differences of the reference.

For every registered analytic model, every combination of its choice and bool parameters (microfacet's
``multiscatter=True`` excepted: it has no gradient, tested below), and random numeric parameters over the
declared ranges (log-uniform where the spec says log scale; each end inset by three finite-difference steps
so that the differences stay inside the range), the derivative of every parameter component is compared
with central differences of the float64 **reference engine** (``bk.set_engine("reference")``, the kernel's
own source run uncompiled), the parameter changed through the model's own constructor path
(``_from_valid``, so a parameter's path into the kernel is tested, not only the kernel's ``p``).

The difference quotient ``D(h) = (f(x+h) − f(x−h)) / 2h`` is Richardson-extrapolated,
``R = (4·D(h/2) − D(h)) / 3`` (error O(h⁴)), with ``h = 1e-5`` of the parameter's scale (its value for a
log-scale parameter, else max(|x|, 1 % of the span)): R's truncation and rounding errors are both far
below the 1e-6 relative tolerance where the function is smooth on the scale of ``h``. Where it is not —
a ``min``/``max``/clamp or branch switches between ``x − h`` and ``x + h`` (Phong's ``max(0, cos)``, a
Fresnel total-reflection branch) — ``D(h)`` and ``D(h/2)`` disagree; those entries are skipped (at a kink
``eval_grad`` returns the one-sided derivative of the branch the code takes, docs/api.md), and the test
asserts that at most :data:`MAX_SKIPPED` of the entries were skipped, so it cannot pass by skipping.

Agreement: ``|g − R| ≤ 1e-6·|R| + 1e-9·(largest |R| of that parameter component and channel over the
pairs) + 100·2⁻⁵²·|f|/h``: 1e-6 relative, with an absolute floor a billionth of the derivative's own scale
for entries that are (nearly) zero (off-diagonal RGB entries, values that underflow far from a lobe), and
the resolution of differences of values rounded to 100 ulps of ``f``.

Both engines: the reference engine on every choice combination; the compiled engine (numba) on a covering
subset (every choice value at least once; a cold numba compile of a microfacet twin is tens of seconds)
in float64 to the same tolerance and in float32 to :data:`RTOL32`. HTSG's compiled twin takes minutes to
compile cold, so HTSG is tested on the reference engine only (its compiled twin is the same source).
"""

from __future__ import annotations

import itertools
import math
import zlib

import numpy as np
import pytest

import brdfkit as bk
from brdfkit import engine
from brdfkit.geometry import random_unit_vectors
from test_contract import _grazing

#: relative tolerance of eval_grad against the extrapolated differences (float64)
RTOL = 1e-6
#: ... and the absolute floor, relative to the largest derivative of that parameter component and channel
ATOL_OF_SCALE = 1e-9
#: float32: relative tolerance against the float64 differences at the same float32 directions, on pairs
#: away from the horizon (z >= 0.1) with values in [1e-3, 1e3] (as test_contract's float32 check)
RTOL32 = 2e-3
#: cosine-power exponents: their float32 derivatives are not compared (test_compiled_float32_...)
EXPONENTS = {"shininess", "nu", "nv", "n_1", "n_2", "n_3"}
#: relative step of the differences (of the parameter's scale)
STEP = 1e-5
#: D(h) and D(h/2) farther apart than this (relative) mark a kink within the step: the entry is skipped
KINK = 1e-4
#: at most this fraction of the (nonzero) entries of one case may be skipped as kinks
MAX_SKIPPED = 0.1
#: the reference's rounding, relative to |f| (100 ulps): differences cannot resolve a derivative below
#: ROUNDING·|f|/h (a lobe of 1e-21 beside a diffuse term of 0.2), which is added to the absolute floor
ROUNDING = 100 * 2.0**-52
#: pairs per case
NPAIRS = 16

ANALYTIC = [n for n in bk.models() if getattr(bk.registry.get(n), "kernel", None) is not None]
#: compiled twins too slow to compile cold for the test suite (HTSG: ~3 minutes); tested on the reference engine
REFERENCE_ONLY = {"htsg"}


def _seed(*parts) -> int:
    return zlib.crc32(repr(parts).encode())


def _choice_keys(cls):
    return [p for p in cls.spec if p.kind in ("choice", "bool") and not (cls.name == "microfacet" and p.name == "multiscatter")]


def _choice_grid(cls) -> list[dict]:
    keys = _choice_keys(cls)
    values = [p.choices if p.kind == "choice" else (False, True) for p in keys]
    return [dict(zip([p.name for p in keys], combo)) for combo in itertools.product(*values)]


def _covering(cls) -> list[dict]:
    """A few combinations that take every value of every choice at least once."""
    keys = _choice_keys(cls)
    values = [p.choices if p.kind == "choice" else (False, True) for p in keys]
    k = max((len(v) for v in values), default=1)
    return [{p.name: v[(i + j) % len(v)] for j, (p, v) in enumerate(zip(keys, values))} for i in range(k)]


def _inset_range(p) -> tuple[float, float, bool]:
    """``(lo, hi, log)``: where the test draws ``p``, three difference steps inside the declared range."""
    lo, hi = p.range
    if math.isinf(hi):
        hi = lo + 1e3 * max(1.0, abs(lo))
    log = p.log_scale
    if log:
        lo = max(lo, hi * 1e-6)  # a log-scale range from 0 (exponents): the last six decades
        return lo * (1 + 4 * STEP), hi * (1 - 4 * STEP), True
    span = hi - lo
    inset = 4 * STEP * max(abs(lo), abs(hi), span)
    return lo + inset, hi - inset, False


def _draw(p, rng):
    lo, hi, log = _inset_range(p)
    size = 3 if p.kind == "rgb" else None
    v = np.exp(rng.uniform(math.log(lo), math.log(hi), size)) if log else rng.uniform(lo, hi, size)
    return tuple(float(x) for x in v) if size else float(v)


def _random_params(cls, rng, fixed) -> dict:
    out = dict(fixed)
    for p in cls.spec:
        if p.kind in ("choice", "bool") or p.name in out:
            continue
        if p.kind == "int":
            lo, hi = p.range
            out[p.name] = int(rng.integers(int(lo), int(hi) + 1))
            continue
        if cls.name == "microfacet" and p.name == "alpha":
            continue  # alpha_x / alpha_y drawn (anisotropic); alpha tested on its own below
        out[p.name] = _draw(p, rng)
    if cls.name == "lafortune":  # cx, cy, cz over [-100, 100] mostly give lobes far from every direction
        for i in (1, 2, 3):
            out[f"cx_{i}"] = out[f"cy_{i}"] = -rng.uniform(0.5, 1.2)
            out[f"cz_{i}"] = rng.uniform(0.5, 1.2)
            out[f"n_{i}"] = float(np.exp(rng.uniform(0.0, math.log(200.0))))
    return out


def _pairs(seed: int, n: int = NPAIRS):
    """Upper-hemisphere pairs, half of them near the mirror direction (where the lobes are; offsets of
    0.05, 0.01 and 0.002 for the sharp ones), one below the horizon."""
    rng = np.random.default_rng(seed)
    wi = random_unit_vectors(n, rng)
    wo = random_unit_vectors(n, rng)
    k = n // 2
    near = np.stack([-wo[:k, 0], -wo[:k, 1], wo[:k, 2]], -1)
    near += rng.normal(size=(k, 3)) * np.resize([0.05, 0.01, 0.002], k)[:, None]
    near[:, 2] = np.abs(near[:, 2])
    wi[:k] = near / np.linalg.norm(near, axis=-1, keepdims=True)
    wi[-1, 2] = -wi[-1, 2]  # below the horizon: f = 0 and every derivative 0
    return wi, wo


def _components(m):
    """``[(name, index or None, scale, log)]``: every parameter component eval_grad differentiates."""
    by = {p.name: p for p in m.spec}
    out = []
    for name, _, size in __import__("brdfkit.engine.grad", fromlist=["layout"]).layout(m):
        p = by[name]
        for i in range(size) if size > 1 else [None]:
            x = float(np.ravel(m.params[name])[i or 0])
            lo, hi = p.range
            hi = hi if math.isfinite(hi) else lo + 1e3 * max(1.0, abs(lo))
            scale = abs(x) if p.log_scale else max(abs(x), 0.01 * (hi - lo))
            out.append((name, i, scale))
    return out


def _moved(m, name, i, dx):
    """``m`` with parameter ``name`` (component ``i``) moved by ``dx``, built the way the fitter builds it."""
    prm = dict(m.params)
    if name == "alpha":  # microfacet's isotropic roughness sets both
        prm["alpha_x"] = prm["alpha_y"] = prm["alpha"] = prm["alpha"] + dx
    elif i is None:
        prm[name] = prm[name] + dx
    else:
        v = np.array(prm[name], dtype=np.float64)
        v[i] += dx
        v.flags.writeable = False
        prm[name] = v
    return type(m)._from_valid(prm)


def fd_grads(m, wi, wo):
    """``{(name, i): (R, kink)}``: Richardson-extrapolated central differences of the float64 reference engine
    (``R`` shape (n, 3)) and where the step crosses a kink (D(h) and D(h/2) disagree)."""
    old = engine.engine()
    engine.set_engine("reference")
    try:
        comps = _components(m)
        if m.name == "microfacet" and m.params["alpha"] is not None:
            comps.append(("alpha", None, m.params["alpha"]))
        f = np.abs(m.eval(wi, wo))
        out = {}
        for name, i, scale in comps:
            h = STEP * scale
            d = []
            for s in (h, h / 2):
                d.append((_moved(m, name, i, s).eval(wi, wo) - _moved(m, name, i, -s).eval(wi, wo)) / (2 * s))
            r = (4 * d[1] - d[0]) / 3
            floor = ROUNDING * f / h  # what differences of values rounded to ROUNDING·|f| can resolve
            col = np.max(np.abs(r), axis=0, keepdims=True)
            kink = np.abs(d[0] - d[1]) > KINK * np.abs(d[1]) + ATOL_OF_SCALE * col + floor
            out[(name, i)] = (r, kink, floor)
        return out
    finally:
        engine.set_engine(old)


def _assert_against_fd(m, grads, fd, what, rtol=RTOL, mask=None):
    """Every entry of ``grads`` within tolerance of ``fd`` (kinks skipped, counted)."""
    checked = skipped = 0
    for (name, i), (r, kink, floor) in fd.items():
        g = grads[name] if i is None else grads[name][..., i]
        g = np.asarray(g, dtype=np.float64)
        assert g.shape == r.shape, f"{what}: {name} shape {g.shape} vs {r.shape}"
        assert np.all(np.isfinite(g)), f"{what}: non-finite d/d{name}[{i}]"
        col = np.max(np.abs(r), axis=0, keepdims=True)
        use = ~kink if mask is None else (~kink & mask)
        err = np.abs(g - r)
        bad = use & (err > rtol * np.abs(r) + ATOL_OF_SCALE * col + floor)
        if np.any(bad):
            j, c = np.argwhere(bad)[0]
            raise AssertionError(f"{what}: d f[{c}]/d {name}[{i}] = {g[j, c]!r}, differences {r[j, c]!r} "
                                 f"(rel {err[j, c] / max(abs(r[j, c]), 1e-300):.3g}) at pair {j}; {m!r}")
        nz = r != 0
        checked += int(np.sum(use & nz))
        skipped += int(np.sum(kink & nz))
    assert checked > 0, f"{what}: no nonzero derivative compared"
    assert skipped <= MAX_SKIPPED * (checked + skipped), f"{what}: {skipped} of {checked + skipped} entries at kinks"
    return checked, skipped


def _case(name, fixed, tag):
    cls = bk.registry.get(name)
    rng = np.random.default_rng(_seed(name, tuple(fixed.items()), tag))
    m = bk.model(name, **_random_params(cls, rng, fixed))
    wi, wo = _pairs(_seed(name, tuple(fixed.items()), tag, "pairs"))
    return m, wi, wo


def _ref_cases():
    for name in ANALYTIC:
        for fixed in _choice_grid(bk.registry.get(name)):
            yield pytest.param(name, fixed, id="-".join([name, *map(str, fixed.values())]))


def _compiled_cases():
    for name in ANALYTIC:
        if name in REFERENCE_ONLY:
            continue
        for fixed in _covering(bk.registry.get(name)):
            yield pytest.param(name, fixed, id="-".join([name, *map(str, fixed.values())]))


def _with_engine(name, fn):
    old = engine.engine()
    engine.set_engine(name)
    try:
        return fn()
    finally:
        engine.set_engine(old)


@pytest.mark.parametrize("name,fixed", list(_ref_cases()))
def test_reference_engine_grad_matches_differences(name, fixed):
    m, wi, wo = _case(name, fixed, "ref")
    f, grads = _with_engine("reference", lambda: m.eval_grad(wi, wo))
    np.testing.assert_array_equal(f, _with_engine("reference", lambda: m.eval(wi, wo)))
    _assert_against_fd(m, grads, fd_grads(m, wi, wo), f"reference {name} {fixed}")


@pytest.mark.parametrize("name,fixed", list(_compiled_cases()))
def test_compiled_engine_grad_matches_differences_and_reference(name, fixed):
    m, wi, wo = _case(name, fixed, "compiled")
    f, grads = _with_engine("compiled", lambda: m.eval_grad(wi, wo))
    # f is eval's value: the twin's primal lines are the kernel's own (float64: bit for bit)
    np.testing.assert_array_equal(f, _with_engine("compiled", lambda: m.eval(wi, wo)))
    _assert_against_fd(m, grads, fd_grads(m, wi, wo), f"compiled {name} {fixed}")
    # the compiled twin and the same twin run in Python agree to rounding
    _, gref = _with_engine("reference", lambda: m.eval_grad(wi, wo))
    for k in grads:
        np.testing.assert_allclose(grads[k], gref[k], rtol=1e-10, atol=1e-12 * max(np.abs(gref[k]).max(), 1e-300),
                                   err_msg=f"{name} {fixed} d/d{k}: compiled vs reference")


@pytest.mark.parametrize("name,fixed", list(_compiled_cases()))
def test_compiled_float32_grad_close_to_float64_differences(name, fixed):
    m, wi, wo = _case(name, fixed, "compiled")
    wi32, wo32 = wi.astype(np.float32), wo.astype(np.float32)
    f, grads = _with_engine("compiled", lambda: m.eval_grad(wi32, wo32))
    assert f.dtype == np.float32 and all(g.dtype == np.float32 for g in grads.values())
    np.testing.assert_allclose(f, _with_engine("compiled", lambda: m.eval(wi32, wo32)), rtol=4e-7, atol=0)
    wi64, wo64 = wi32.astype(np.float64), wo32.astype(np.float64)
    f64 = m.eval(wi64, wo64)
    ok = ((wi64[:, 2] >= 0.1) & (wo64[:, 2] >= 0.1))[:, None] & (f64 >= 1e-3) & (f64 <= 1e3)
    if not ok.any():
        pytest.skip("no pair with moderate values in this draw")
    fd = fd_grads(m, wi64, wo64)
    # d/d(exponent) of a cosine power is ln(cos)·f: near the peak ln(cos) of a float32 cosine has a relative
    # error eps/|ln cos|, unbounded (measured 0.9 % on Blinn-Phong); those are compared in float64 only
    fd = {k: v for k, v in fd.items() if k[0] not in EXPONENTS}
    _assert_against_fd(m, grads, fd, f"float32 {name} {fixed}", rtol=RTOL32, mask=ok)


# ---------------------------------------------------------------------------- shapes, special cases


@pytest.mark.parametrize("eng", ["compiled", "reference"])
def test_shapes_follow_the_spec(eng):
    """(..., 3) for a scalar parameter, (..., 3, 3) for an RGB one; directions broadcast like eval's."""
    m = bk.model("phong", kd=(0.2, 0.3, 0.4), ks=(0.5, 0.4, 0.3), shininess=20.0)
    wi = random_unit_vectors(6, np.random.default_rng(1)).reshape(2, 3, 3)
    wo = random_unit_vectors(3, np.random.default_rng(2))
    f, g = _with_engine(eng, lambda: m.eval_grad(wi, wo))
    assert f.shape == (2, 3, 3)
    assert set(g) == {"kd", "ks", "shininess"}
    assert g["kd"].shape == g["ks"].shape == (2, 3, 3, 3) and g["shininess"].shape == (2, 3, 3)
    # one pair: no batch axes
    f1, g1 = _with_engine(eng, lambda: m.eval_grad(wi[0, 0], wo[0]))
    assert f1.shape == (3,) and g1["kd"].shape == (3, 3) and g1["shininess"].shape == (3,)
    np.testing.assert_allclose(g1["kd"], g["kd"][0, 0], rtol=1e-14)
    # Phong's diffuse term kd/π: d f_c / d kd_c' = δ_cc' / π, exactly
    np.testing.assert_allclose(g["kd"], np.broadcast_to(np.eye(3) / np.pi, g["kd"].shape), rtol=1e-15)


def test_microfacet_isotropic_alpha_is_the_sum_of_its_axes():
    m = bk.model("microfacet", alpha=0.3)
    wi, wo = _pairs(5)
    _, g = m.eval_grad(wi, wo)
    np.testing.assert_allclose(g["alpha"], g["alpha_x"] + g["alpha_y"], rtol=1e-15)
    assert "alpha" not in bk.model("microfacet", alpha_x=0.3, alpha_y=0.2).eval_grad(wi, wo)[1]


def test_below_the_horizon_everything_is_zero():
    m = bk.model("ward", alpha_x=0.2, alpha_y=0.4)
    wi = np.array([[0.0, 0.6, -0.8], [0.6, 0.0, 0.8]])
    wo = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    f, g = m.eval_grad(wi, wo)
    assert not f.any() and not any(v.any() for v in g.values())


def test_kink_gives_the_branch_taken():
    """Phong's lobe ``max(0, cos α)^s``: at a pair just outside the lobe the code takes 0, and so does
    the derivative with respect to the shininess (the one-sided derivative documented in docs/api.md)."""
    m = bk.model("phong", kd=0.0, ks=1.0, shininess=10.0)
    wi = np.array([[0.0, 0.0, 1.0]])
    wo = np.array([[1.0, 0.0, 1e-3]]) / np.hypot(1.0, 1e-3)  # reflect(wi) · wo ≈ 1e-3 > 0: inside, barely
    _, g = m.eval_grad(wi, wo)
    assert np.all(g["shininess"] < 0)
    wi2 = np.array([[np.sin(1.2), 0.0, np.cos(1.2)]])
    wo2 = np.array([[np.sin(1.2), 0.0, np.cos(1.2)]])  # same direction: reflect(wi)·wo = cos(2.4) < 0: outside
    f2, g2 = m.eval_grad(wi2, wo2)
    assert not f2.any() and not g2["shininess"].any() and not g2["ks"].any()


# ---------------------------------------------------------------------------- models without a gradient


def _one_line_value_error(fn, match):
    with pytest.raises(ValueError, match=match) as e:
        fn()
    msg = str(e.value)
    assert "\n" not in msg.strip(), msg
    return msg


def test_multiscatter_has_no_gradient():
    m = bk.model("microfacet", multiscatter=True)
    wi, wo = _pairs(3)
    msg = _one_line_value_error(lambda: m.eval_grad(wi, wo), "microfacet: no gradient")
    assert "multiscatter" in msg


def test_model_without_kernel_has_no_gradient(tmp_path):
    """A ``.brdf`` file's model (GLSL, evaluated through numpy or GL) and a measured table have no kernel."""
    from pathlib import Path

    m = bk.model(str(Path(__file__).parent / "data" / "lambert.brdf"))
    wi, wo = _pairs(4)
    _one_line_value_error(lambda: m.eval_grad(wi, wo), "no gradient")


# ---------------------------------------------------------------------------- wrt: a subset of the derivatives


WRT_CASES = [
    ("microfacet", {"distribution": "ggx", "fresnel": "conductor", "alpha": 0.3}, "alpha"),
    ("microfacet", {"distribution": "ggx", "fresnel": "conductor", "alpha": 0.3}, ["eta", "alpha"]),
    ("oren-nayar", {"kd": (0.2, 0.5, 0.7), "sigma": 0.4}, "kd"),
    ("microfacet", {"distribution": "beckmann", "fresnel": "conductor", "alpha": 0.2}, ["eta", "kd"]),
    ("ward", {"alpha_x": 0.2, "alpha_y": 0.4}, ("alpha_y",)),
    ("phong", {"kd": (0.2, 0.3, 0.4), "ks": 0.5, "shininess": 30.0}, ["shininess", "ks"]),
    # a kernel without a float32 twin: float32 arrays run the directional passes in float64, rounded once
    # (HTSG, the other, is REFERENCE_ONLY: its compiled twins take minutes to compile cold)
    ("ashikhmin-shirley", {"nu": 40.0, "nv": 400.0}, ["nu", "rs"]),
]


@pytest.mark.parametrize("eng,dtype", [("compiled", np.float64), ("compiled", np.float32), ("reference", np.float64)])
@pytest.mark.parametrize("name,params,wrt", WRT_CASES)
def test_wrt_gives_the_same_derivatives_as_all(eng, dtype, name, params, wrt, monkeypatch):
    """A few names go through the directional driver (one vectorised pass per derivative, at most
    ``DIRECTIONAL_MAX``; an RGB parameter's three in one pass, column compression), more through a twin
    seeded by just those: either way the values are the full
    gradient's to the last bit (float64; float32, where LLVM may also fuse multiply-adds differently: a few ulps)
    and the derivatives agree to rounding (a direction e_x + e_y sums the two tangents inside the
    computation; float64 1e-12 of the largest magnitude, float32, whose derivatives carry
    cancellations, 1e-5), and only the names asked for come back."""
    from brdfkit.engine import grad

    monkeypatch.setattr(grad, "DIRECTIONAL_MAX", 4)  # these full gradients: the many-tangent driver
    m = bk.model(name, **params)
    wi, wo = (w.astype(dtype) for w in _pairs(7, 300))
    f_all, g_all = _with_engine(eng, lambda: m.eval_grad(wi, wo))
    f, g = _with_engine(eng, lambda: m.eval_grad(wi, wo, wrt=wrt))
    asked = {wrt} if isinstance(wrt, str) else set(wrt)
    assert set(g) == asked
    # the directional loop is vectorised and may call the vector math library where the full gradient's
    # scalar loop calls libm: f to the last bit (float64), a few ulps (float32); Ashikhmin-Shirley's lobe is
    # exp(x), x = e·log(n·h) (−3.9 at the pair that differs most here), so a last-bit difference of the
    # logarithm (vector library against libm) is |x| times larger in f: float64 9 ulps of f there
    f64_tol = 1e-14 if name == "ashikhmin-shirley" else 1e-15
    np.testing.assert_allclose(f, f_all, rtol=f64_tol if dtype == np.float64 else 1e-6, atol=0)
    for k in asked:
        assert g[k].dtype == np.dtype(dtype)
        tol = 1e-12 if dtype == np.float64 else 1e-5
        np.testing.assert_allclose(g[k], g_all[k], rtol=0, atol=tol * np.abs(g_all[k]).max(), err_msg=k)
        assert g[k].shape == g_all[k].shape
    assert any(np.abs(g[k]).max() > 0 for k in asked)  # not a vacuous comparison of zeros


def test_wrt_unknown_name_is_a_one_line_error():
    m = bk.model("microfacet", alpha=0.3)
    wi, wo = _pairs(3)
    msg = _one_line_value_error(lambda: m.eval_grad(wi, wo, wrt=["alpha", "roughness"]), "no gradient with respect to 'roughness'")
    assert "alpha_x" in msg and "eta" in msg  # the names it has
    _one_line_value_error(lambda: m.eval_grad(wi, wo, wrt="distribution"), "no gradient with respect to 'distribution'")
    _one_line_value_error(lambda: m.eval_grad(wi, wo, wrt=[3]), "wrt must be parameter names")


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("n", [5, 5000])
def test_non_unit_directions_are_refused_by_the_gradient_driver(dtype, n):
    """eval's unit-direction rule holds for eval_grad: the compiled driver counts lengths outside a safe
    band in the same pass (one chunk and many), and the exact check raises the SPEC's one-line error."""
    m = bk.model("microfacet", alpha=0.3)
    wi, wo = (w.astype(dtype) for w in _pairs(11, n))
    wo = wo.copy()
    wo[n // 2] *= 1.01
    msg = _one_line_value_error(lambda: m.eval_grad(wi, wo, wrt="alpha"), "wo must be unit vectors")
    assert "1.01" in msg
    wi = wi.copy()
    wi[-1, 0] = np.nan
    _one_line_value_error(lambda: m.eval_grad(wi, wo), "wi must be unit vectors")
    # within the tolerance: accepted
    ok = wo.copy()
    ok[n // 2] /= 1.01
    ok[0] *= 1.0 + 0.5 * (1e-3 if dtype == np.float32 else 1e-4)
    m.eval_grad(wi[:-1], ok[:-1], wrt="alpha")


@pytest.mark.parametrize("wrt", [None, "p"])
@pytest.mark.parametrize("p", [1e-40, 1e-90])
def test_float32_arrays_through_the_float64_kernel_are_rounded_once(wrt, p):
    """Float32 arrays whose parameters float32 cannot hold (schlick's p below float32's smallest normal) run
    the float64 kernel, on both routes (the many-tangent twin, ``wrt=None``; the directional passes,
    ``wrt="p"``), which store into the float32 arrays: f and the derivatives are the float64 results
    rounded once, f at most float32's largest value (p = 1e-90: f = 1/√p at w = 0 is 1e45) with its
    derivatives 0 there, and a derivative beyond float32's range ±inf (p = 1e-40: −f/(2p) ≈ −1e60), never NaN."""
    rng = np.random.default_rng(8)
    wi, wo = random_unit_vectors(300, rng), random_unit_vectors(300, rng)
    wi[:4, 0] = wo[:4, 0] = 0.0  # h in the y-z plane: w = 0
    wi = (wi / np.linalg.norm(wi, axis=1, keepdims=True)).astype(np.float32)
    wo = (wo / np.linalg.norm(wo, axis=1, keepdims=True)).astype(np.float32)
    m = bk.model("schlick", p=p, r=0.05)
    f64, g64 = m.eval_grad(wi.astype(np.float64), wo.astype(np.float64), wrt=wrt)
    f32, g32 = m.eval_grad(wi, wo, wrt=wrt)
    top = float(np.finfo(np.float32).max)
    assert f32.dtype == np.float32 and g32["p"].dtype == np.float32
    np.testing.assert_array_equal(f32, np.minimum(f64, top).astype(np.float32))
    with np.errstate(over="ignore"):
        want = np.where(f64 < top, g64["p"], 0.0).astype(np.float32)
    np.testing.assert_array_equal(g32["p"], want)
    assert not np.isnan(g32["p"]).any()
    lit = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    assert lit[:4].any()
    if p == 1e-40:
        assert (g32["p"][:4][lit[:4]] == -np.inf).all()
        assert np.isfinite(g32["p"][4:]).all() and np.abs(g32["p"][4:]).max() > 0
    else:
        assert (f32[:4][lit[:4]] == np.float32(top)).all() and (g32["p"][:4][lit[:4]] == 0).all()


@pytest.mark.parametrize("dtype,zs", [(np.float64, [1e-20, 1e-300, 1e-310, 5e-324]),
                                       (np.float32, [1e-12, 1e-30, 1e-39, 1e-44])])
@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
@pytest.mark.parametrize("shadowing", ["smith", "smith-correlated"])
def test_subnormal_elevations_give_no_nan_derivative(dtype, zs, distribution, shadowing):
    """Directions whose z is subnormal (and pairs of one with a normal z): Smith's Λ and its derivative
    overflowed there and G's derivative came out NaN (inf·0) for Beckmann and for height-correlated GGX;
    Λ now floors w_z at the smallest normal number (terms.distributions.lambda_floor). Every derivative
    is a number, and f is eval's (float64: bit for bit)."""
    m = bk.model("microfacet", distribution=distribution, shadowing=shadowing, alpha=0.2)
    wi, wo = [], []
    for zi, zo in itertools.product(zs + [0.5], zs + [0.5]):  # 0.5: pairs of one grazing, one not
        for az in (0.0, 10.0, 90.0, 170.0, 180.0):
            wi.append(_grazing(0.0, zi))
            wo.append(_grazing(az, zo))
    wi, wo = np.array(wi, dtype=dtype), np.array(wo, dtype=dtype)
    assert (wi[:, 2] > 0).all() and (wo[:, 2] > 0).all()  # none rounded to the horizon
    f, g = m.eval_grad(wi, wo)
    if dtype == np.float64:  # float32: the twins may fuse multiply-adds differently, ill-conditioned here
        np.testing.assert_array_equal(f, m.eval(wi, wo))
    for k, d in g.items():
        assert not np.isnan(d).any(), k
    assert np.abs(g["alpha"]).max() > 0


def test_isotropic_alpha_is_summed_before_float32_rounding():
    """microfacet's ``alpha`` sets both axes: its derivative is the sum of theirs, added in the working
    precision. Float32 arrays run the float64 kernel here (k = 2.2e-308 does not fit float32); at a grazing
    pair f is ~1e38 and ∂f/∂α_x, ∂f/∂α_y are beyond float32's range with opposite signs: summed after the
    float32 store they gave inf − inf = NaN; now the float64 sum is rounded once."""
    m = bk.model("microfacet", distribution="ggx", shadowing="smith-correlated", fresnel="dielectric",
                 k=2.2250738585072014e-308, alpha=0.2)
    z = 1e-40
    wi = np.array([[math.sqrt(1.0 - z * z), 0.0, z], [0.6, 0.0, 0.8]])
    wo = np.array([[math.sqrt(1.0 - z * z), 0.0, z], [0.0, 0.6, 0.8]])
    w32i, w32o = wi.astype(np.float32), wo.astype(np.float32)
    f64, g64 = m.eval_grad(w32i.astype(np.float64), w32o.astype(np.float64))
    f32, g32 = m.eval_grad(w32i, w32o)
    with np.errstate(over="ignore"):
        assert np.isinf(g64["alpha_x"][0].astype(np.float32)).any()  # the case: the axes overflow float32
        want = np.where(f64 < float(np.finfo(np.float32).max), g64["alpha"], 0.0).astype(np.float32)
    assert not np.isnan(g32["alpha"]).any()
    np.testing.assert_array_equal(g32["alpha"], want)


# ---------------------------------------------------------------------------- the twins' analysis, kept on disk

_MANIFEST_SCRIPT = r"""
import json, sys
import numpy as np
import brdfkit as bk
from brdfkit.engine import forward, grad
from brdfkit.geometry import random_unit_vectors

mode, out = sys.argv[1], sys.argv[2]
m = bk.model("phong", kd=(0.2, 0.3, 0.4), ks=0.5, shininess=30.0)
kernel = type(m).kernel
seeds = tuple(range(sum(s for _, _, s in grad.layout(m))))
stem = forward._stem(kernel.py_func, (forward.EMPTY,) * 6 + (forward.P_ARRAY, forward.EMPTY), frozenset(seeds), None)
path = forward._manifest_path(stem)
if mode == "corrupt":
    path.write_text("{")
if mode == "no-analysis":
    def refuse(self):
        raise AssertionError("the source was analysed again")
    forward._Func.analyse = refuse
rng = np.random.default_rng(3)
wi, wo = random_unit_vectors(64, rng), random_unit_vectors(64, rng)
f, g = m.eval_grad(wi, wo)
json.loads(path.read_text())  # a valid manifest is on disk afterwards
np.save(out, np.concatenate([f.ravel()] + [g[k].ravel() for k in sorted(g)]))
"""


def test_a_new_process_loads_the_twin_without_analysing_its_source(tmp_path):
    """The analysis of a kernel's sources (~0.1 s for microfacet) is kept beside the generated files: a
    new process loads the twins from it (here: with the analysis made to fail), and a damaged manifest
    is analysed again and rewritten, with the same values either way."""
    import subprocess
    import sys

    script = tmp_path / "s.py"
    script.write_text(_MANIFEST_SCRIPT)
    got = {}
    for mode in ("first", "no-analysis", "corrupt", "no-analysis"):
        out = tmp_path / f"{mode}.npy"
        r = subprocess.run([sys.executable, str(script), mode, str(out)], capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr[-2000:]
        got[mode] = np.load(out)
    assert np.abs(got["first"]).max() > 0
    for mode in ("no-analysis", "corrupt"):
        np.testing.assert_array_equal(got[mode], got["first"])


@pytest.mark.parametrize("eng", ["compiled", "reference"])
def test_schlick_tiny_isotropy_has_no_nan_derivative(eng):
    """Schlick's ∂f/∂p for p down to the smallest float: never NaN (it was inf/inf below p ≈ 1e-300, an
    intermediate ``d(hx/√p)/dp`` beyond the float range); equal to relative-step differences where it is
    finite (w ≠ 0: dA/dp ≈ A/(2p)), and at w = 0 (hx = 0, A = 1/√p) the true −f/(2p), which is beyond
    the float range (−inf) once p < 1e-205."""
    rng = np.random.default_rng(4)
    wi, wo = random_unit_vectors(200, rng), random_unit_vectors(200, rng)
    wi[:4, 0] = wo[:4, 0] = 0.0  # h in the y-z plane: w = 0
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    for p in (5e-324, 1e-320, 1e-300, 1e-250, 1e-200, 1e-30):
        m = bk.model("schlick", p=p, r=0.05)
        f, g = _with_engine(eng, lambda: m.eval_grad(wi, wo))
        d = g["p"]
        assert not np.isnan(d).any(), p
        assert np.isfinite(d[4:]).all(), p
        if p >= 1e-200:
            w0 = -f[:4] / (2 * p)  # d(1/√p)/dp · f·√p
            np.testing.assert_allclose(d[:4], w0, rtol=1e-12)
        else:
            assert (d[:4] == -np.inf).all()
        if p >= 1e-300:
            e = 1e-6
            up = _with_engine(eng, lambda: bk.model("schlick", p=p * (1 + e), r=0.05).eval(wi, wo))
            dn = _with_engine(eng, lambda: bk.model("schlick", p=p * (1 - e), r=0.05).eval(wi, wo))
            with np.errstate(over="ignore"):  # w = 0: beyond the float range, compared above
                fd = (up - dn) / (2 * p * e)
            np.testing.assert_allclose(d[4:], fd[4:], rtol=1e-6, atol=1e-9 * np.abs(fd[4:]).max())


def test_passes_share_a_pass_only_between_disjoint_channels():
    """Column compression: derivatives share a directional pass only where the channels they can reach are
    disjoint; one that reaches none is in no pass."""
    from brdfkit.engine.grad import passes

    e = np.eye(6)
    dirs = [("s", None, e[0]), ("c", 0, e[1]), ("c", 1, e[2]), ("c", 2, e[3]), ("d", 0, e[4]), ("z", None, e[5])]
    reach = (frozenset({0, 1, 4}), frozenset({0, 2}), frozenset({0, 3}))  # p[0] everywhere, p[5] nowhere
    groups, touched = passes(dirs, reach)
    assert touched == [frozenset({0, 1, 2}), frozenset({0}), frozenset({1}), frozenset({2}), frozenset({0}), frozenset()]
    assert groups == [[0], [1, 2, 3], [4]]


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("name,params,wrt", [
    ("microfacet", {"distribution": "ggx", "fresnel": "conductor", "alpha": 0.3}, ["eta", "alpha"]),
    ("ward", {"alpha_x": 0.2, "alpha_y": 0.4}, "kd"),
    ("cook-torrance", {}, "ior"),
])
def test_compressed_passes_equal_one_pass_per_derivative(monkeypatch, dtype, name, params, wrt):
    """An RGB parameter's three derivatives from one pass along e_r + e_g + e_b are bit for bit those of
    three passes along e_r, e_g, e_b (each channel's tangent sums terms that are exactly 0 but one), and
    the entries [..., c_out, c_in] with c_out != c_in are exactly 0."""
    from brdfkit.engine import grad

    m = bk.model(name, **params)
    wi, wo = (w.astype(dtype) for w in _pairs(11, 3000))
    f, g = m.eval_grad(wi, wo, wrt=wrt)
    compressed = grad.passes

    def one_each(dirs, reach):
        groups, touched = compressed(dirs, reach)
        assert any(len(gr) > 1 for gr in groups)  # the case compresses
        return [[i] for i in range(len(dirs)) if touched[i]], touched

    monkeypatch.setattr(grad, "passes", one_each)
    f1, g1 = m.eval_grad(wi, wo, wrt=wrt)
    np.testing.assert_array_equal(f, f1)
    for k in g:
        np.testing.assert_array_equal(g[k], g1[k], err_msg=k)
        if g[k].ndim == 3:
            assert not (g[k] * (1 - np.eye(3))).any()
            assert np.abs(g[k]).max() > 0
