"""The cross-model contract of SPEC.md, checked for EVERY registered model.

Parametrised over ``bk.models()`` at collection time, so a model is covered as
soon as it is registered. For each model:

* property tests (hypothesis): random parameters drawn from the model's own
  ``Param`` spec (ranges with their bounds, log-uniform for log-scale or
  unbounded parameters, choices, bools) and random unit directions in both
  hemispheres, plus fixed special configurations (exact horizon z = 0, grazing
  z = 1e-12, wi == wo, wi == reflect(wo), wi == -wo, normal incidence), in
  float64 and float32: the value is finite, non-negative, exactly zero below
  the horizon, float32 in gives float32 out;
* every parameter at each end of its range (deterministic);
* float32 close to float64 at moderate values;
* a model listed as isotropic gives the same value after a common rotation
  of wi and wo about the normal;
* shapes and broadcasting: (3,) with (N,3), (N,1,3) with (M,3), equal to
  pair-by-pair evaluation;
* bad parameters (unknown name, just outside each bound, NaN, Inf, wrong
  choice, not a bool): a one-line ValueError naming the parameter.

The helper :func:`check_values` is itself tested on deliberately broken toy
models at the end of the file, so these tests can fail.

Set ``BRDFKIT_FUZZ=1`` for randomised (non-reproducible) runs with more examples.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, reject, settings
from hypothesis import strategies as st

import brdfkit as bk
from brdfkit.models.base import BRDF
from brdfkit.params import Param

MODELS = bk.models()

_FUZZ = os.environ.get("BRDFKIT_FUZZ", "") not in ("", "0")
SETTINGS = settings(
    max_examples=400 if _FUZZ else 60,
    deadline=None,
    derandomize=not _FUZZ,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

# ---------------------------------------------------------------------------
# Parameter values from the spec
# ---------------------------------------------------------------------------

_OPEN_INSET = 1e-6  # an open bound is tested this fraction of the span inside it
_UNBOUNDED_SPAN = 1e3  # an infinite upper bound is tested up to max(fit_range hi, lo + this * max(1, |lo|))


def numeric_bounds(p: Param) -> tuple[float, float]:
    """The smallest and largest values of ``p`` that the tests use (both valid)."""
    lo, hi = p.range if p.range is not None else (-1e3, 1e3)
    if math.isinf(hi):
        cap = lo + _UNBOUNDED_SPAN * max(1.0, abs(lo))
        if p.fit_range is not None and math.isfinite(p.fit_range[1]):
            cap = max(cap, p.fit_range[1])
        hi_eff = cap
    else:
        hi_eff = hi
    span = hi_eff - lo
    lo_eff = lo + _OPEN_INSET * span if p.open_lo else lo
    if p.open_hi and not math.isinf(hi):
        hi_eff = hi - _OPEN_INSET * span
    if p.kind == "int":
        lo_eff, hi_eff = math.ceil(lo_eff), math.floor(min(hi_eff, lo_eff + 1000))
    return float(lo_eff), float(hi_eff)


def _log_like(p: Param) -> bool:
    lo, hi = numeric_bounds(p)
    return hi > 0 and (p.log_scale or (p.range is not None and math.isinf(p.range[1])) or (lo > 0 and hi / lo > 1e3))


def _number_strategy(p: Param) -> st.SearchStrategy:
    lo, hi = numeric_bounds(p)
    if p.kind == "int":
        return st.integers(int(lo), int(hi))
    ends = st.sampled_from([lo, hi])
    if _log_like(p):
        pos_lo = lo if lo > 0 else max(hi * 1e-6, np.finfo(float).tiny)
        body = st.floats(math.log(pos_lo), math.log(hi)).map(lambda t: float(min(hi, max(lo, math.exp(t)))))
        return st.one_of(ends, body, st.floats(lo, hi))
    return st.one_of(ends, st.floats(lo, hi))


def param_strategy(p: Param) -> st.SearchStrategy:
    """Valid values of one parameter, drawn from its spec."""
    if p.kind == "bool":
        return st.booleans()
    if p.kind == "choice":
        return st.sampled_from(list(p.choices))
    num = _number_strategy(p)
    if p.kind == "rgb":
        return st.one_of(num, st.lists(num, min_size=3, max_size=3))
    return num


def params_strategy(spec) -> st.SearchStrategy:
    """Dicts giving a random subset of the parameters (the rest keep their defaults)."""
    return st.fixed_dictionaries({}, optional={p.name: param_strategy(p) for p in spec})


def _bound_values(p: Param) -> list:
    if p.kind == "bool":
        return [False, True]
    if p.kind == "choice":
        return list(p.choices)
    lo, hi = numeric_bounds(p)
    return [int(lo), int(hi)] if p.kind == "int" else [lo, hi]


# ---------------------------------------------------------------------------
# Directions
# ---------------------------------------------------------------------------


def _sph(theta_deg: float, phi_deg: float) -> np.ndarray:
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def _grazing(phi_deg: float, z: float = 1e-12) -> np.ndarray:
    r = math.sqrt(1.0 - z * z)
    p = math.radians(phi_deg)
    return np.array([r * math.cos(p), r * math.sin(p), z])


def _reflect(w: np.ndarray) -> np.ndarray:
    return w * np.array([-1.0, -1.0, 1.0])


_BASE = [
    np.array([0.0, 0.0, 1.0]),  # normal incidence
    np.array([1.0, 0.0, 0.0]),  # exactly at the horizon, along the tangent
    np.array([0.0, 1.0, 0.0]),  # exactly at the horizon, along the bitangent
    _grazing(0.0),
    _grazing(90.0),
    _grazing(45.0),
    _grazing(200.0, 1e-6),
    _sph(30.0, 0.0),
    _sph(60.0, 120.0),
    _sph(89.9, 300.0),
    _sph(1e-6, 10.0),  # almost normal
    np.array([0.0, 0.0, -1.0]),
    _sph(120.0, 45.0),
    _sph(90.0 + 1e-7, 0.0),  # just below the horizon
]


def special_pairs() -> tuple[np.ndarray, np.ndarray]:
    """Every pair of the base directions, plus wi == wo, wi == reflect(wo), wi == -wo for each."""
    wi, wo = [], []
    for a in _BASE:
        for b in _BASE:
            wi.append(a)
            wo.append(b)
        for b in (a, _reflect(a), -a):
            wi.append(b)
            wo.append(a)
    return np.array(wi), np.array(wo)


def grazing_pairs(z: float = 1e-12) -> tuple[np.ndarray, np.ndarray]:
    """Both directions at elevation ``z`` with azimuths 0-360° apart in 10° steps (issue 31).

    Near-opposite azimuths make the half vector's ``h_z`` ~ z/|wi + wo| a few times ``z``: at
    z = 1e-12 its fourth power is a float32 subnormal (Beckmann D's 0/0 in float32, found at
    wi = (-0.7768, 0.6298, 1e-12), wo = (0.9575, -0.2885, 1e-12)); that pair is included."""
    wi = [_grazing(17.0 * k, z) for k in range(36)]
    wo = [_grazing(17.0 * k + 10.0 * k, z) for k in range(36)]
    a = np.array([-0.7768, 0.6298, 1e-12])
    b = np.array([0.9575, -0.2885, 1e-12])
    wi.append(a / np.linalg.norm(a))
    wo.append(b / np.linalg.norm(b))
    return np.array(wi), np.array(wo)


SPECIAL_WI, SPECIAL_WO = (np.concatenate(x) for x in zip(special_pairs(), grazing_pairs(), grazing_pairs(1e-20)))


def random_pairs(seed: int, n: int = 128) -> tuple[np.ndarray, np.ndarray]:
    """Uniform unit directions over the whole sphere, plus near-specular and near-equal pairs."""
    rng = np.random.default_rng(seed)
    wi = rng.normal(size=(n, 3))
    wo = rng.normal(size=(n, 3))
    wi /= np.linalg.norm(wi, axis=-1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=-1, keepdims=True)
    k = n // 4
    near = _reflect(wo[:k]) + rng.normal(scale=1e-3, size=(k, 3))
    wi[:k] = near / np.linalg.norm(near, axis=-1, keepdims=True)
    wi[k : 2 * k] = wo[k : 2 * k]
    return wi, wo


def drawn_pairs(seed: int, extra=(), grazing=()) -> tuple[np.ndarray, np.ndarray]:
    """The pairs of one hypothesis example: :func:`random_pairs` (64), ``extra`` pairs of spherical angles
    ``(θi, φi, θo, φo)`` in degrees, ``grazing`` pairs ``(φi, φo, e)`` with both directions at elevation
    10^e (issue 31), and the special pairs."""
    wi, wo = random_pairs(seed, 64)
    if len(extra):
        e = np.array(extra)
        wi = np.concatenate([wi, [_sph(a, b) for a, b in e[:, :2]]])
        wo = np.concatenate([wo, [_sph(a, b) for a, b in e[:, 2:]]])
    if len(grazing):
        wi = np.concatenate([wi, [_grazing(a, 10.0 ** e) for a, _, e in grazing]])
        wo = np.concatenate([wo, [_grazing(b, 10.0 ** e) for _, b, e in grazing]])
    return np.concatenate([wi, SPECIAL_WI]), np.concatenate([wo, SPECIAL_WO])


# ---------------------------------------------------------------------------
# The contract on one batch
# ---------------------------------------------------------------------------


def check_values(m: BRDF, wi: np.ndarray, wo: np.ndarray, dtype) -> np.ndarray:
    """Evaluate ``m`` on the pairs in ``dtype`` and assert the SPEC contract; return the values."""
    wi = np.asarray(wi, dtype=dtype)
    wo = np.asarray(wo, dtype=dtype)
    wi_before, wo_before = wi.copy(), wo.copy()
    f = m.eval(wi, wo)
    where = f"{m!r} in {np.dtype(dtype).name}"
    assert isinstance(f, np.ndarray), f"{where}: eval returned {type(f).__name__}"
    assert f.dtype == np.dtype(dtype), f"{where}: returned {f.dtype}"
    assert f.shape == np.broadcast_shapes(wi.shape, wo.shape), f"{where}: shape {f.shape}"
    np.testing.assert_array_equal(wi, wi_before, err_msg=f"{where}: eval modified wi")
    np.testing.assert_array_equal(wo, wo_before, err_msg=f"{where}: eval modified wo")
    bad = ~np.isfinite(f).all(axis=-1)
    if bad.any():
        i = int(np.argmax(bad))
        raise AssertionError(f"{where}: non-finite {f[i]} at wi={wi[i].tolist()}, wo={wo[i].tolist()}")
    neg = (f < 0).any(axis=-1)
    if neg.any():
        i = int(np.argmax(neg))
        raise AssertionError(f"{where}: negative {f[i]} at wi={wi[i].tolist()}, wo={wo[i].tolist()}")
    below = (wi[..., 2] <= 0) | (wo[..., 2] <= 0)
    nz = below & (f != 0).any(axis=-1)
    if nz.any():
        i = int(np.argmax(nz))
        raise AssertionError(f"{where}: {f[i]} != 0 below the horizon at wi={wi[i].tolist()}, wo={wo[i].tolist()}")
    return f


def check_both_dtypes(m: BRDF, wi: np.ndarray, wo: np.ndarray) -> None:
    check_values(m, wi, wo, np.float64)
    check_values(m, wi, wo, np.float32)


def _moderate(wi, wo, f64):
    """Pairs where float32 is expected to agree with float64: away from the horizon, moderate values."""
    ok = (wi[:, 2] >= 0.1) & (wo[:, 2] >= 0.1)
    return ok[:, None] & (f64 >= 1e-3) & (f64 <= 1e3)


def _model_or_reject(name: str, params: dict) -> BRDF:
    """The model, or hypothesis.reject() for a combination the model refuses.

    Each value is valid by itself, but a model may couple parameters (microfacet:
    ``alpha`` and ``alpha_x``/``alpha_y`` must agree when both are given). Such a
    refusal must still be a one-line ValueError naming a parameter; every single
    value alone is checked strictly in test_each_parameter_at_its_bounds.
    """
    try:
        return bk.model(name, **params)
    except ValueError as e:
        msg = str(e)
        assert "\n" not in msg.strip(), f"multi-line message: {msg!r}"
        assert any(k in msg for k in params), f"refusal names no given parameter: {msg!r}"
        reject()


# ---------------------------------------------------------------------------
# Tests over every registered model
# ---------------------------------------------------------------------------


def test_registry_is_not_empty():
    assert "lambert" in MODELS


@pytest.mark.parametrize("name", MODELS)
def test_info_matches_spec(name):
    cls = bk.registry.get(name)
    info = bk.model_info(name)
    assert info["name"] == name == cls.name
    assert info["title"] and info["reference"], "every model needs a title and a reference"
    assert isinstance(info["isotropic"], bool)
    assert [r["name"] for r in info["params"]] == [p.name for p in cls.spec]
    for p, row in zip(cls.spec, info["params"]):
        assert row["kind"] == p.kind
        assert row["doc"], f"{name}.{p.name} has no doc"
        if p.kind in ("scalar", "rgb", "int"):
            assert p.range is not None, f"{name}.{p.name} has no range"
    m = bk.model(name)
    assert list(m.params) == [p.name for p in cls.spec]
    assert list(m.params_json()) == list(m.params)


@pytest.mark.parametrize("name", MODELS)
def test_defaults_special_and_random_directions(name):
    m = bk.model(name)
    check_both_dtypes(m, SPECIAL_WI, SPECIAL_WO)
    wi, wo = random_pairs(0, 512)
    check_both_dtypes(m, wi, wo)


@pytest.mark.parametrize("name", MODELS)
def test_random_parameters_and_directions(name):
    spec = bk.registry.get(name).spec

    @SETTINGS
    @given(params=params_strategy(spec), seed=st.integers(0, 2**32 - 1), extra=st.lists(
        st.tuples(st.floats(0, 180), st.floats(0, 360), st.floats(0, 180), st.floats(0, 360)), max_size=4),
        grazing=st.lists(st.tuples(st.floats(0, 360), st.floats(0, 360), st.floats(-40.0, -1.0)), max_size=4))
    def run(params, seed, extra, grazing):
        m = _model_or_reject(name, params)
        check_both_dtypes(m, *drawn_pairs(seed, extra, grazing))

    run()


def _bound_cases():
    cases = []
    for name in MODELS:
        for p in bk.registry.get(name).spec:
            for v in _bound_values(p):
                cases.append(pytest.param(name, p.name, v, id=f"{name}-{p.name}={v}"))
    return cases


@pytest.mark.parametrize("name,pname,value", _bound_cases())
def test_each_parameter_at_its_bounds(name, pname, value):
    m = bk.model(name, **{pname: value})
    check_both_dtypes(m, SPECIAL_WI, SPECIAL_WO)
    wi, wo = random_pairs(1, 256)
    check_both_dtypes(m, wi, wo)


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("end", [0, 1])
def test_all_parameters_at_one_end(name, end):
    spec = bk.registry.get(name).spec
    params = {p.name: _bound_values(p)[0 if end == 0 else -1] for p in spec}
    m = bk.model(name, **params)
    check_both_dtypes(m, SPECIAL_WI, SPECIAL_WO)
    wi, wo = random_pairs(2, 256)
    check_both_dtypes(m, wi, wo)


@pytest.mark.parametrize("name", MODELS)
def test_float32_close_to_float64_at_defaults(name):
    m = bk.model(name)
    wi, wo = random_pairs(3, 4096)
    wi32, wo32 = wi.astype(np.float32), wo.astype(np.float32)
    f32 = m.eval(wi32, wo32)
    # the reference is float64 evaluated on the same (rounded) directions
    f64 = m.eval(wi32.astype(np.float64), wo32.astype(np.float64))
    sel = _moderate(wi32, wo32, f64)
    assert sel.sum() > 100, "too few moderate values to compare"
    np.testing.assert_allclose(f32[sel], f64[sel], rtol=1e-3, atol=0, err_msg=f"{name}: float32 vs float64")


@pytest.mark.parametrize("name", MODELS)
def test_float32_close_to_float64_random_parameters(name):
    spec = bk.registry.get(name).spec

    @settings(SETTINGS, max_examples=25)
    @given(params=params_strategy(spec), seed=st.integers(0, 2**32 - 1))
    def run(params, seed):
        m = _model_or_reject(name, params)
        wi, wo = random_pairs(seed, 256)
        wi32, wo32 = wi.astype(np.float32), wo.astype(np.float32)
        f32 = m.eval(wi32, wo32)
        f64 = m.eval(wi32.astype(np.float64), wo32.astype(np.float64))
        sel = _moderate(wi32, wo32, f64)
        # loose: random parameters include extremes (high shininess, tiny roughness)
        # where float32 loses digits legitimately; this catches gross float32 failures
        np.testing.assert_allclose(f32[sel], f64[sel], rtol=5e-2, atol=0, err_msg=f"{m!r}")

    run()


def _rotate_z(v: np.ndarray, a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1], v[:, 2]], axis=-1)


@pytest.mark.parametrize("name", [n for n in MODELS if bk.model_info(n)["isotropic"]])
def test_isotropic_models_ignore_a_common_rotation(name):
    """`brdfkit list` calls a model isotropic: then only phi_i - phi_o matters."""
    spec = bk.registry.get(name).spec

    @settings(SETTINGS, max_examples=15)
    @given(params=params_strategy(spec), seed=st.integers(0, 2**32 - 1), angle=st.floats(0.01, 2 * math.pi))
    def run(params, seed, angle):
        m = _model_or_reject(name, params)
        wi, wo = random_pairs(seed, 128)
        f = m.eval(wi, wo)
        g = m.eval(_rotate_z(wi, angle), _rotate_z(wo, angle))
        np.testing.assert_allclose(g, f, rtol=1e-6, atol=1e-12 * max(1.0, float(f.max())), err_msg=f"{m!r}")

    run()


@pytest.mark.parametrize("name", MODELS)
def test_broadcasting_matches_pairwise(name):
    m = bk.model(name)
    rng = np.random.default_rng(4)
    a = bk.geometry.random_unit_vectors(5, rng)
    b = bk.geometry.random_unit_vectors(4, rng)
    single = m.eval(a[0], b[0])
    assert single.shape == (3,)
    one_many = m.eval(a[0], b)
    assert one_many.shape == (4, 3)
    many_one = m.eval(a, b[0])
    assert many_one.shape == (5, 3)
    table = m.eval(a[:, None, :], b)
    assert table.shape == (5, 4, 3)
    table2 = m.eval(a[:, None, :], b[None, :, :])
    for i in range(5):
        for j in range(4):
            ref = m.eval(a[i], b[j])
            np.testing.assert_allclose(table[i, j], ref, rtol=1e-12, atol=1e-300)
            np.testing.assert_allclose(table2[i, j], ref, rtol=1e-12, atol=1e-300)
        np.testing.assert_allclose(many_one[i], m.eval(a[i], b[0]), rtol=1e-12, atol=1e-300)
    for j in range(4):
        np.testing.assert_allclose(one_many[j], m.eval(a[0], b[j]), rtol=1e-12, atol=1e-300)
    # plain lists work and mean float64
    lst = m.eval(a[0].tolist(), b[0].tolist())
    assert lst.dtype == np.float64
    np.testing.assert_allclose(lst, single, rtol=1e-15)
    # float32 broadcasting keeps float32
    t32 = m.eval(a[:, None, :].astype(np.float32), b.astype(np.float32))
    assert t32.dtype == np.float32 and t32.shape == (5, 4, 3)


@pytest.mark.parametrize("name", MODELS)
def test_bad_direction_shape(name):
    m = bk.model(name)
    with pytest.raises(ValueError):
        m.eval(np.zeros((4, 2)), np.zeros((4, 3)))


# ---------------------------------------------------------------------------
# Bad parameters: one-line ValueError naming the parameter
# ---------------------------------------------------------------------------


def _just_outside(x: float, direction: int) -> float:
    step = max(1e-9, 1e-6 * abs(x))
    return x + direction * step


def _bad_cases():
    cases = []
    for name in MODELS:
        cls = bk.registry.get(name)
        cases.append(pytest.param(name, "not_a_parameter", 1.0, id=f"{name}-unknown"))
        for p in cls.spec:
            bad: list = []
            if p.kind in ("scalar", "rgb", "int"):
                bad += [float("nan"), float("inf"), float("-inf")]
                if p.range is not None:
                    lo, hi = p.range
                    bad.append(_just_outside(lo, -1))
                    if p.open_lo:
                        bad.append(lo)
                    if math.isfinite(hi):
                        bad.append(_just_outside(hi, +1))
                        if p.open_hi:
                            bad.append(hi)
                if p.kind == "rgb":
                    bad.append([0.5, 0.5])  # wrong length
                    good = p.validate(name, p.default)
                    if p.range is not None:
                        bad.append([float(good[0]), float(good[1]), _just_outside(p.range[0], -1)])
                    bad.append([float(good[0]), float("nan"), float(good[2])])
                if p.kind == "scalar":
                    bad.append("0.5")  # strings are not numbers in the Python API
                if p.kind == "int":
                    bad.append(1.5 if p.range is None or p.range[0] <= 1.5 <= p.range[1] else p.range[0] + 0.5)
            elif p.kind == "choice":
                bad += ["definitely-not-a-choice", 3]
            elif p.kind == "bool":
                bad += ["maybe", 2]
            for v in bad:
                cases.append(pytest.param(name, p.name, v, id=f"{name}-{p.name}={v!r}"))
    return cases


@pytest.mark.parametrize("name,pname,value", _bad_cases())
def test_bad_parameter_is_one_line_value_error(name, pname, value):
    with pytest.raises(ValueError) as ei:
        bk.model(name, **{pname: value})
    msg = str(ei.value)
    assert "\n" not in msg.strip(), f"multi-line message: {msg!r}"
    assert pname in msg, f"message does not name the parameter {pname!r}: {msg!r}"
    assert name in msg, f"message does not name the model {name!r}: {msg!r}"
    p = {q.name: q for q in bk.registry.get(name).spec}.get(pname)
    if p is not None and p.kind == "choice":
        assert any(c in msg for c in p.choices), f"message does not list the choices: {msg!r}"
    if p is None:  # unknown parameter: the message lists the valid ones
        assert all(q.name in msg for q in bk.registry.get(name).spec), msg


# ---------------------------------------------------------------------------
# The checks themselves can fail: deliberately broken toy models (not registered)
# ---------------------------------------------------------------------------


class _Toy(BRDF):
    name = "toy"
    title = "toy"
    reference = "none"
    spec = (Param("a", "scalar", 1.0, (0.0, 1.0), "", "a number"),)


class _NanAtEqual(_Toy):
    def _eval(self, wi, wo, p):  # 0/0 where wi == wo
        d = np.linalg.norm(wi - wo, axis=-1)
        return np.broadcast_to((d / d)[..., None], wi.shape)


class _NegativeLobe(_Toy):
    def _eval(self, wi, wo, p):
        return np.broadcast_to((wi[..., :1] * p["a"]), wi.shape)  # negative for wi.x < 0


class _InfAtGrazing(_Toy):
    def _eval(self, wi, wo, p):
        with np.errstate(all="ignore"):
            return np.broadcast_to((1.0 / (wi[..., 2:] ** 4)), wi.shape)  # 1e48 overflows float32


class _AlwaysFloat64(_Toy):
    def eval(self, wi, wo):
        return np.ones(np.broadcast_shapes(np.shape(wi), np.shape(wo)))


class _NonZeroBelow(_Toy):
    def eval(self, wi, wo):
        wi = np.asarray(wi)
        return np.ones(np.broadcast_shapes(wi.shape, np.shape(wo)), dtype=wi.dtype)


@pytest.mark.parametrize(
    "cls,dtype,pattern",
    [
        (_NanAtEqual, np.float64, "non-finite"),
        (_NegativeLobe, np.float64, "negative"),
        (_InfAtGrazing, np.float32, "non-finite"),
        (_AlwaysFloat64, np.float32, "returned float64"),
        (_NonZeroBelow, np.float64, "below the horizon"),
    ],
)
def test_contract_checker_catches_broken_models(cls, dtype, pattern):
    with pytest.raises(AssertionError, match=pattern):
        check_values(cls(), SPECIAL_WI, SPECIAL_WO, dtype)


def test_parameter_strategy_stays_in_range_and_reaches_bounds():
    spec = (
        Param("x", "scalar", 1.0, (0.0, 1.0), "", "closed"),
        Param("s", "scalar", 10.0, (0.0, math.inf), "", "unbounded", open_lo=True, log_scale=True),
        Param("c", "rgb", 0.5, (0.0, 1.0), "", "colour"),
        Param("k", "choice", "u", choices=("u", "v"), doc="choice"),
        Param("b", "bool", False, doc="flag"),
    )
    from brdfkit.params import validate

    seen = {"x": set(), "s_min": math.inf, "s_max": 0.0}

    @settings(max_examples=200, deadline=None, derandomize=True, database=None)
    @given(params=params_strategy(spec))
    def run(params):
        validate("toy", spec, params)  # raises if a drawn value were invalid
        if "x" in params:
            seen["x"].add(params["x"])
        if "s" in params:
            seen["s_min"] = min(seen["s_min"], params["s"])
            seen["s_max"] = max(seen["s_max"], params["s"])

    run()
    assert {0.0, 1.0} <= seen["x"]
    assert 0 < seen["s_min"] < 1e-2 and seen["s_max"] >= 1e3


def test_hypothesis_examples_are_reproducible():
    """conftest.py loads a derandomised profile (every run draws the same examples) unless BRDFKIT_FUZZ is set."""
    assert settings.default.derandomize is (not _FUZZ)
    assert settings.default.database is None or _FUZZ
