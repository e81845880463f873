"""GLSL == numpy: every registered model's shader, run through real OpenGL, equals its numpy.

The GLSL (``render/shaders/<module>.glsl``) is evaluated through a headless
moderngl context (Mesa EGL / llvmpipe, transform feedback) at the shared,
deterministic test vectors of :func:`brdfkit.render.glsl.parity_vectors`
(random pairs over the upper hemisphere, pairs near the mirror direction,
normal incidence, ``wi == wo``, exact mirror pairs, near-grazing ``z = 1e-3``
and ``z = 6e-17``, at and below the horizon), plus 20 000 denser random pairs
per model, and compared with ``model.eval`` on the very same
float32 inputs.

Tolerance, per value ``f`` (each channel): the GLSL value must agree with
numpy in float32 (``f32 = model.eval(wi, wo)``) or with numpy in float64 at
the same float32 inputs and with the parameters rounded to float32 as the
uniforms hold them (``f64``, the exact value of the formula)::

    |f_glsl − f32| <= RTOL·|f32| + ATOL + 2·spread   or
    |f_glsl − f64| <= RTOL·|f64| + ATOL + 2·spread

* ``RTOL = 1e-4`` — the contract (issue 5).
* The float64 alternative admits a shader that is *more* accurate than numpy's
  float32 evaluation where a formula is ill-conditioned in float32 (e.g.
  Blinn-Phong at s = 1e5: one ulp of ``n·h`` moves ``(n·h)^s`` by
  1e5·6e-8 = 0.6 %, and the shader computes ``1 − n·h`` without cancellation).
  The shaders are written to be accurate rather than merely similar: GL's
  ``log``/``pow``/``acos``/``atan`` carry absolute errors of 1e-7..1e-4 on
  llvmpipe (and on GPUs), so common.glsl supplies accurate replacements.
* ``ATOL = 1e-12`` 1/sr — the absolute floor for values near 0. GL
  implementations may flush subnormal floats (below 1.2e-38) to zero (the
  GLSL ES 3.00 precision rules allow it; llvmpipe does), and exp() underflows
  at slightly different arguments than numpy's; a later factor of up to ~1e6
  (1/(4 cos θi cos θo) at z = 1e-3) can lift such a difference above 1e-38.
  1e-12 1/sr is ten orders of magnitude below any reflectance a renderer or
  a measurement can resolve.
* ``spread`` — the conditioning of the exact function at that input: the
  largest change of ``f64`` when every input component moves by up to 4
  float32 ulps (4 random perturbations). The first intermediate results of
  any float32 program (``h``, ``c = wo·h``) carry errors of that size, so no
  float32 implementation can pin the value down more closely. It matters only
  where the function is (nearly) singular — the dielectric Fresnel term at the
  critical angle (index < 1), where dF/dc is infinite; elsewhere it is orders
  of magnitude below RTOL·|f| and the test is the plain 1e-4 relative one
  (measured over the parameter sets below: 2·spread exceeds RTOL·|f| for 0.8 %
  of the ~450 000 compared values, and only 2 of them, both next to a
  critical angle, would fail without it).

Parameter sets per model, generated from its ``spec``: defaults; each numeric
parameter alone at the low and the high end of its range (an infinite upper
end is replaced by the fit range's or 1e4); every combination of choice/bool
values (each value alone if there are more than 48 combinations); a few
random sets of the fitted parameters (log-uniform for ``log_scale`` ones,
within the fit range, RGB channels differing, so ``alpha_x != alpha_y``
anisotropy arises naturally); plus hand-written
sets in ``EXTRA``. A combination the model itself rejects (ValueError) is
skipped.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.render import glsl
from _numeric_helpers import float32_spread

RTOL = 1e-4
ATOL = 1e-12

# Models that have no GLSL twin, with the reason. Kept honest by
# test_every_model_has_glsl: an entry here that has a shader file fails.
NO_GLSL: dict[str, str] = {}

# Hand-picked parameter sets on top of the generated ones.
EXTRA: dict[str, list[dict]] = {
    "ward": [dict(alpha_x=0.05, alpha_y=0.4), dict(alpha_x=0.5, alpha_y=0.02)],
    "ashikhmin-shirley": [dict(nu=10.0, nv=1000.0), dict(nu=2000.0, nv=5.0)],
    "microfacet": [
        dict(alpha_x=0.05, alpha_y=0.5, distribution="beckmann", shadowing="smith"),
        dict(alpha_x=0.6, alpha_y=0.1, distribution="beckmann", shadowing="smith-correlated", fresnel="schlick"),
        dict(alpha_x=0.01, alpha_y=0.3, distribution="ggx", shadowing="smith-correlated", fresnel="dielectric",
             eta=[1.2, 1.5, 2.4], kd=0.2, ks=0.7),
        dict(alpha_x=0.002, alpha_y=0.002, distribution="beckmann", shadowing="v-groove", fresnel="conductor"),
        dict(alpha=0.5, fresnel="conductor", eta=[1.0001, 0.3, 0.01], k=[0.0, 0.0, 0.01]),
        dict(alpha=0.5, fresnel="dielectric", eta=[1.0001, 0.3, 1.0]),
    ],
    "cook-torrance": [dict(m=0.01, ior=[1.05, 2.0, 37.0]), dict(m=0.6, ior=200.0, kd=0.0)],
    "oren-nayar": [dict(sigma=1.5, variant="full"), dict(sigma=1.0, variant="qualitative", kd=[0.2, 0.5, 0.9])],
    "htsg": [
        dict(sigma0=2.0, tau=0.05, wavelengths=200.0),
        dict(sigma0=2.0, tau=100.0, wavelengths=[200.0, 1000.0, 2000.0]),
        dict(sigma0=0.01, tau=1.0),
        dict(sigma0=0.5, tau=2.0, eta=1.5, k=0.0, kd=0.3),
        dict(sigma0=1.0, tau=10.0, wavelengths=[300.0, 450.0, 700.0]),
    ],
    "schlick": [
        dict(layers="double", r=0.05, p=0.2, r2=0.7, p2=0.5, color=[0.9, 0.6, 0.3]),
        dict(layers="single", r=0.5, p=0.01),
    ],
    "phong": [dict(shininess=0.0), dict(shininess=1.0, normalized=False)],
    "blinn-phong": [dict(shininess=0.0), dict(shininess=1.0, normalized=False)],
}


def _safe_model(name: str, params: dict):
    try:
        return bk.model(name, **params)
    except ValueError:
        return None


def _hi(p):
    lo, hi = p.range
    if math.isinf(hi):
        hi = p.fit_range[1] if p.fit_range else max(1e4, lo + 1e4)
    return hi


def _extremes(p):
    if p.range is None:
        return []
    lo, hi = p.range[0], _hi(p)
    span = hi - lo
    lo_v = lo + (max(1e-6 * span, 1e-6 * abs(lo), 1e-7) if p.open_lo else 0.0)
    hi_v = hi - (1e-6 * span if (p.open_hi and not math.isinf(p.range[1])) else 0.0)
    if p.kind == "int":
        lo_v, hi_v = math.ceil(lo_v), math.floor(hi_v)
    return [lo_v, hi_v]


def _random_value(p, rng):
    lo, hi = p.range[0], _hi(p)
    if p.fit_range is not None:
        lo, hi = max(lo, p.fit_range[0]), min(hi, p.fit_range[1])
    if p.open_lo and lo == p.range[0]:
        lo = lo + max(1e-3 * (hi - lo), 1e-6)
    n = 3 if p.kind == "rgb" else 1
    if p.log_scale and lo > 0:
        v = np.exp(rng.uniform(np.log(lo), np.log(hi), n))
    else:
        v = rng.uniform(lo, hi, n)
    if p.kind == "int":
        return int(round(float(v[0])))
    return [float(x) for x in v] if p.kind == "rgb" else float(v[0])


def param_sets(name: str) -> list[tuple[str, dict]]:
    """``(id, params)`` pairs for one model, see the module docstring."""
    cls = bk.registry.get(name)
    spec = cls.spec
    out: list[tuple[str, dict]] = [("defaults", {})]
    for p in spec:
        if p.kind in ("scalar", "rgb", "int"):
            for tag, v in zip(("min", "max"), _extremes(p)):
                out.append((f"{p.name}={tag}", {p.name: v}))
    discrete = [p for p in spec if p.kind in ("choice", "bool")]
    values = [list(p.choices) if p.kind == "choice" else [False, True] for p in discrete]
    if discrete:
        combos = list(itertools.product(*values))
        if len(combos) <= 48:
            for combo in combos:
                d = {p.name: v for p, v in zip(discrete, combo)}
                out.append((",".join(f"{k}={v}" for k, v in d.items()), d))
        else:
            for p, vals in zip(discrete, values):
                for v in vals:
                    out.append((f"{p.name}={v}", {p.name: v}))
    rng = np.random.default_rng(sum(map(ord, name)))
    # shorthand parameters that the fitter never varies (microfacet's alpha, which would
    # contradict random alpha_x/alpha_y) keep their defaults in the random sets
    numeric = [p for p in spec if p.kind in ("scalar", "rgb", "int") and p.range is not None and p.fit]
    for i in range(3):
        d = {p.name: _random_value(p, rng) for p in numeric}
        for p, vals in zip(discrete, values):
            d[p.name] = vals[int(rng.integers(len(vals)))]
        out.append((f"random{i}", d))
    for i, d in enumerate(EXTRA.get(name, [])):
        out.append((f"extra{i}", d))
    return out


MODELS = bk.models()
WITH_GLSL = [n for n in MODELS if n not in NO_GLSL]
CASES = [pytest.param(n, pid, d, id=f"{n}[{pid}]") for n in WITH_GLSL for pid, d in param_sets(n)]


@pytest.fixture(scope="module")
def vectors():
    return glsl.parity_vectors()


def _float32_params(model):
    """A copy of the model whose numeric parameters are rounded to float32, as the uniforms hold them.

    Set directly (not re-validated): float32(0.01) = 0.0099999998 lies just outside a range
    that starts at 0.01, yet it is the value the shader computes with.
    """
    m = model.with_params()
    for p in type(model).spec:
        v = m.params[p.name]
        if v is not None and p.kind == "scalar":
            m.params[p.name] = float(np.float32(v))
        elif v is not None and p.kind == "rgb":
            a = np.asarray(v, dtype=np.float32).astype(np.float64)
            a.setflags(write=False)
            m.params[p.name] = a
    m._cache.clear()
    m._setup()
    return m


def assert_parity(model, wi, wo, kinds, version="330 core", source=None):
    g = glsl.eval_glsl(model, wi, wo, version=version, source=source)
    n = model.eval(wi, wo)
    assert n.dtype == np.float32 and g.dtype == np.float32
    assert np.all(np.isfinite(g)), f"GLSL returned NaN/Inf for {model!r}"
    assert np.all(g >= 0), f"GLSL returned a negative value for {model!r}"
    below = (wi[:, 2] <= 0) | (wo[:, 2] <= 0)
    assert np.all(g[below] == 0), "GLSL must return exactly 0 at and below the horizon"
    n32 = n.astype(np.float64)
    model64 = _float32_params(model)
    n64 = model64.eval(wi.astype(np.float64), wo.astype(np.float64))
    g64 = g.astype(np.float64)
    slack = ATOL + 2.0 * float32_spread(model64, wi.astype(np.float64), wo.astype(np.float64), seed=7)
    err32, err64 = np.abs(g64 - n32), np.abs(g64 - n64)
    tol32, tol64 = RTOL * np.abs(n32) + slack, RTOL * np.abs(n64) + slack
    bad = (err32 > tol32) & (err64 > tol64)
    if bad.any():
        score = np.where(bad, np.minimum(err32 / tol32, err64 / tol64), 0)
        i, c = np.unravel_index(np.argmax(score), score.shape)
        raise AssertionError(
            f"{model!r} ({version}): {int(bad.any(axis=1).sum())} of {len(wi)} pairs differ; worst "
            f"[{kinds[i]}] wi={wi[i].tolist()} wo={wo[i].tolist()} channel {c}: "
            f"glsl={g[i, c]:.9g} numpy32={n32[i, c]:.9g} numpy64={n64[i, c]:.9g} "
            f"rel={err32[i, c] / max(abs(n32[i, c]), 1e-38):.3g} tol={tol32[i, c]:.3g}"
        )


# ---------------------------------------------------------------------------
# coverage
# ---------------------------------------------------------------------------
def test_every_model_has_glsl():
    for name in MODELS:
        has = glsl.has_shader(name)
        if name in NO_GLSL:
            assert not has, f"{name} has {glsl.shader_path(name).name}: remove it from NO_GLSL"
        else:
            assert has, f"{name} has no GLSL ({glsl.shader_path(name)}): write it or list it in NO_GLSL"
    assert set(NO_GLSL) <= set(MODELS), "NO_GLSL names a model that is not registered"


@pytest.mark.parametrize("name", WITH_GLSL)
def test_uniforms_match_spec(name):
    """The model file declares exactly one uniform per parameter, of the kind's type."""
    cls = bk.registry.get(name)
    declared = glsl.declared_uniforms(glsl.shader_path(name).read_text())
    expected = glsl.declared_uniforms(glsl.uniform_declarations(name))
    assert declared == expected
    assert set(glsl.uniform_values(cls())) == set(expected)


# ---------------------------------------------------------------------------
# parity
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("name,pid,params", CASES)
def test_glsl_equals_numpy(name, pid, params, vectors):
    model = _safe_model(name, params)
    if model is None:
        pytest.skip(f"{name} rejects {params}")
    assert_parity(model, vectors["wi"], vectors["wo"], vectors["kind"])


@pytest.mark.parametrize("name", WITH_GLSL)
def test_glsl_es_equals_numpy(name, vectors):
    """The same source compiled as GLSL ES 3.00 (the browser's dialect) agrees too."""
    for pid, params in param_sets(name)[:1] + [s for s in param_sets(name) if s[0].startswith("random")][:1]:
        model = _safe_model(name, params)
        if model is not None:
            assert_parity(model, vectors["wi"], vectors["wo"], vectors["kind"], version="300 es")


@pytest.mark.parametrize("name", WITH_GLSL)
def test_glsl_equals_numpy_dense(name):
    """20 000 more random pairs per model (defaults and one random set), half of them within 3° of
    the horizon, where float32 cancellations hide."""
    rng = np.random.default_rng(11)
    n = 10_000

    def dirs(zmax):
        z = rng.uniform(0, 1, n) ** 3 * zmax
        phi = rng.uniform(0, 2 * np.pi, n)
        r = np.sqrt(1 - z * z)
        return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)

    wi = np.concatenate([dirs(1.0), dirs(0.05)]).astype(np.float32)
    wo = np.concatenate([dirs(1.0), dirs(0.05)])[rng.permutation(2 * n)].astype(np.float32)
    kinds = np.array(["dense"] * (2 * n))
    sets = param_sets(name)
    for pid, params in [sets[0]] + [s for s in sets if s[0] == "random0"]:
        model = _safe_model(name, params)
        if model is not None:
            assert_parity(model, wi, wo, kinds)


def test_parity_vectors_are_deterministic_and_cover_special_cases():
    a = glsl.parity_vectors()
    b = glsl._parity_vectors.__wrapped__(512)
    np.testing.assert_array_equal(a["wi"], b[0])
    np.testing.assert_array_equal(a["wo"], b[1])
    wi, wo, kind = a["wi"], a["wo"], a["kind"]
    assert wi.dtype == np.float32 and wi.shape == wo.shape and wi.shape[1] == 3
    for k in ("random", "near-mirror", "normal", "wi==wo", "mirror", "grazing-wi", "grazing-wo", "grazing-both",
              "grazing-6e-17", "horizon", "below"):
        assert np.any(kind == k), k
    np.testing.assert_allclose(np.linalg.norm(wi, axis=1), 1, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(wo, axis=1), 1, atol=1e-6)
    up = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    assert up.sum() >= 800
    assert np.isclose(wi[kind == "normal"][0], [0, 0, 1]).all()
    m = kind == "mirror"
    np.testing.assert_allclose(wi[m][:, :2], -wo[m][:, :2], atol=1e-7)
    np.testing.assert_allclose(wi[m][:, 2], wo[m][:, 2], atol=1e-7)
    assert np.isclose(wi[kind == "grazing-wi"][:, 2], 1e-3).all()
    hz = kind == "horizon"
    assert np.all((wi[hz, 2] == 0) | (wo[hz, 2] == 0))
    assert np.all((wi[kind == "below", 2] < 0) | (wo[kind == "below", 2] < 0))


# ---------------------------------------------------------------------------
# the harness can fail
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("name", WITH_GLSL)
def test_parity_detects_a_wrong_shader(name, vectors):
    """Every model's shader scaled by 1.0005 fails the parity check (the check is not vacuous)."""
    model = bk.model(name)
    src = glsl.shader_source(model)
    head = "vec3 brdf(vec3 wi, vec3 wo) {"
    assert src.count(head) == 1
    wrong = src.replace(head, "vec3 bk_brdf_right(vec3 wi, vec3 wo) {") + (
        "\nvec3 brdf(vec3 wi, vec3 wo) { return bk_brdf_right(wi, wo) * 1.0005; }\n"
    )
    assert_parity(model, vectors["wi"], vectors["wo"], vectors["kind"])
    with pytest.raises(AssertionError, match="differ"):
        assert_parity(model, vectors["wi"], vectors["wo"], vectors["kind"], source=wrong)


def test_eval_glsl_large_batches_and_broadcasting():
    m = bk.model("lambert", kd=[0.1, 0.2, 0.3])
    rng = np.random.default_rng(3)
    n = glsl._CHUNK * 2 + 12345  # several transform-feedback draws
    # unit directions (m.eval rejects others, SPEC), in both hemispheres
    wi = bk.geometry.normalize(rng.normal(size=(n, 3))).astype(np.float32)
    wo = bk.geometry.normalize(rng.normal(size=(n, 3))).astype(np.float32)
    g = glsl.eval_glsl(m, wi, wo)
    np.testing.assert_array_equal(g, m.eval(wi, wo))
    # broadcasting (..., 3) like model.eval
    g2 = glsl.eval_glsl(m, wi[:6].reshape(2, 3, 3), np.array([0.0, 0.0, 1.0], np.float32))
    assert g2.shape == (2, 3, 3)
    np.testing.assert_array_equal(g2.reshape(6, 3), g[:6] * 0 + m.eval(wi[:6], np.array([0, 0, 1], np.float32)))
    assert glsl.eval_glsl(m, np.zeros((0, 3)), np.zeros((0, 3))).shape == (0, 3)
    with pytest.raises(ValueError, match="last axis"):
        glsl.eval_glsl(m, np.zeros((4, 2)), np.zeros((4, 3)))


def test_uniform_values_kinds():
    m = bk.model("lambert", kd=0.25)
    assert glsl.uniform_values(m) == {"u_kd": (0.25, 0.25, 0.25)}
    for name in MODELS:
        cls = bk.registry.get(name)
        vals = glsl.uniform_values(cls())
        for p in cls.spec:
            v = vals[f"u_{p.name}"]
            if p.kind == "choice":
                assert v == p.choices.index(p.default)
            elif p.kind == "bool":
                assert v == int(p.default)
            elif p.kind == "rgb":
                assert isinstance(v, tuple) and len(v) == 3
            elif p.kind == "scalar":
                assert isinstance(v, float)


def test_shader_source_errors():
    with pytest.raises(ValueError, match="unknown model"):
        glsl.shader_source("no-such-model")
    src = glsl.shader_source("lambert")
    assert not any(line.lstrip().startswith("#version") for line in src.splitlines())
    assert "vec3 brdf(vec3 wi, vec3 wo)" in src


def test_eval_glsl_leaves_other_contexts_alone():
    """Another moderngl context in the process (the renderer's) stays current and intact."""
    import moderngl

    other = moderngl.create_standalone_context(backend="egl")
    try:
        buf = other.buffer(b"brdfkit!" * 4)
        fbo = other.simple_framebuffer((2, 2))
        fbo.use()
        m = bk.model("lambert", kd=0.3)
        w = np.array([[0.0, 0.0, 1.0]], np.float32)
        np.testing.assert_allclose(glsl.eval_glsl(m, w, w), 0.3 / np.pi, rtol=1e-6)
        glsl.compile_check("lambert")
        # `other` is still the current context: its objects work without re-entering it
        assert buf.read() == b"brdfkit!" * 4
        fbo.clear(0.0, 1.0, 0.0, 1.0)
        assert np.frombuffer(fbo.read(components=4), np.uint8)[:4].tolist() == [0, 255, 0, 255]
        np.testing.assert_allclose(glsl.eval_glsl(m, w, w), 0.3 / np.pi, rtol=1e-6)
    finally:
        other.release()
