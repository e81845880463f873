"""The shared GLSL terms (shaders/common.glsl) against their numpy twins and exact references.

Each test runs a tiny ``brdf()`` that returns the term(s) under test, fed
through the ``wi``/``wo`` inputs of :func:`brdfkit.render.glsl.eval_glsl`
(six floats per evaluation), through real OpenGL. References: scipy.special
for erf/erfc, numpy float64 for atan/acos/log1p/pow, and the brdfkit.terms
functions in float64 for Fresnel, D, Λ and G.

The bounds are derived, not fitted: a float32 evaluation of a function of a
float32 argument x cannot beat the function's conditioning times the
argument's rounding, e.g. for exp(y) with y = s·ln x, an absolute error of
|y|·2^-23 in y is a relative error of |y|·2^-23 in the result.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import special

import brdfkit as bk
from brdfkit.render import glsl
from brdfkit.terms import distributions as D
from brdfkit.terms import fresnel as F
from brdfkit.terms import shadowing as G

EPS32 = 2.0**-23


def run(body: str, a, b=None) -> np.ndarray:
    """Evaluate ``vec3 brdf(vec3 wi, vec3 wo) { body }`` after common.glsl for inputs a, b: (N, 3)."""
    a = np.asarray(a, dtype=np.float32)
    b = np.zeros_like(a) if b is None else np.asarray(b, dtype=np.float32)
    src = glsl.common_source() + "\nvec3 brdf(vec3 wi, vec3 wo) {\n" + body + "\n}\n"
    return glsl.eval_glsl(bk.model("lambert"), a, b, source=src).astype(np.float64)


def cols(*xs) -> np.ndarray:
    xs = list(np.broadcast_arrays(*[np.asarray(x, dtype=np.float64) for x in xs]))
    while len(xs) < 3:
        xs.append(np.zeros_like(xs[0]))
    return np.stack(xs, axis=-1).astype(np.float32)


def f64(a) -> np.ndarray:
    return np.asarray(a, dtype=np.float32).astype(np.float64)


# ---------------------------------------------------------------------------
# math helpers
# ---------------------------------------------------------------------------
def test_erf_erfc():
    x = np.linspace(-6, 9, 30001)
    g = run("return vec3(bk_erf(wi.x), bk_erfc(wi.x), 0.0);", cols(x))
    x = f64(cols(x)[:, 0])
    # erf: absolute 1.2e-7 (the fit) + float32 rounding of 1 − erfc
    assert np.max(np.abs(g[:, 0] - special.erf(x))) < 4e-7
    # erfc for x >= 0: relative 1.2e-7 (the fit) + rounding of the exponent −x² + p, |x²|·2^-23
    pos = (x >= 0) & (special.erfc(x) > 1e-36)
    rel = np.abs(g[pos, 1] - special.erfc(x[pos])) / special.erfc(x[pos])
    assert np.all(rel < 1e-6 + 2 * (x[pos] ** 2 + 2) * EPS32)
    neg = x < 0
    assert np.max(np.abs(g[neg, 1] - special.erfc(x[neg]))) < 5e-7


def test_atan_acos_atan2():
    x = np.concatenate([np.linspace(-50, 50, 20001), np.geomspace(1e-8, 1e8, 2001)])
    g = run("return vec3(bk_atan(wi.x), 0.0, 0.0);", cols(x))
    ref = np.arctan(f64(cols(x)[:, 0]))
    assert np.all(np.abs(g[:, 0] - ref) <= 4e-7 * np.abs(ref))

    c = np.concatenate([np.linspace(-1, 1, 20001), 1 - np.geomspace(1e-7, 1e-1, 500), -1 + np.geomspace(1e-7, 1e-1, 500)])
    g = run("return vec3(bk_acos(wi.x), 0.0, 0.0);", cols(c))
    ref = np.arccos(f64(cols(c)[:, 0]))
    assert np.max(np.abs(g[:, 0] - ref) / np.maximum(ref, 1e-30)) < 4e-7
    # GL's own acos is far worse on llvmpipe (about 1e-4 absolute): the reason bk_acos exists
    t = np.linspace(0, np.pi / 2, 4001)
    y, x_ = np.sin(t), np.cos(t)
    g = run("return vec3(bk_atan2_pos(wi.x, wi.y), 0.0, 0.0);", cols(y, x_))
    ref = np.arctan2(f64(cols(y)[:, 0]), f64(cols(x_)[:, 0]))
    assert np.max(np.abs(g[1:, 0] - ref[1:]) / ref[1:]) < 4e-7 and g[0, 0] == 0


def test_log1p_log_pow():
    x = np.concatenate([np.linspace(-0.999, 3, 40001), -np.geomspace(1e-9, 0.5, 1000), np.geomspace(1e-9, 0.5, 1000)])
    g = run("return vec3(bk_log1p(wi.x), 0.0, 0.0);", cols(x))
    xx = f64(cols(x)[:, 0])
    ref = np.log1p(xx)
    # |x| <= 0.5: series, ~2e-7 relative; elsewhere log(1 + x) with 1 + x rounded: 2^-24/|log(1+x)| more
    small = np.abs(xx) <= 0.5
    assert np.max(np.abs(g[small, 0] - ref[small]) / np.abs(ref[small])) < 4e-7
    assert np.all(np.abs(g[~small, 0] - ref[~small]) <= 4e-7 * np.abs(ref[~small]) + 2 * EPS32)

    # pow(x, s) near the peak of a sharp lobe, where GL's pow loses accuracy
    x = 1 - np.geomspace(1e-7, 0.9, 3000)
    for s in (1.0, 37.5, 1e3, 1e5):
        g = run(f"return vec3(bk_pow(wi.x, {s:.1f}), pow(wi.x, {s:.1f}), 0.0);", cols(x))
        xx = f64(cols(x)[:, 0])
        ref = xx**s
        ok = ref > 1e-30
        y = np.abs(s * np.log(xx[ok]))
        rel = np.abs(g[ok, 0] - ref[ok]) / ref[ok]
        assert np.all(rel < 1e-6 + 4 * (y + 1) * EPS32), s
    assert run("return vec3(bk_pow(wi.x, 0.0), bk_pow(wi.x, 2.0), 0.0);", cols([0.0]))[0, :2].tolist() == [1, 0]


# ---------------------------------------------------------------------------
# Fresnel
# ---------------------------------------------------------------------------
C = np.concatenate([[0.0, 1e-6, 1e-3, 1.0], np.linspace(0, 1, 501)])


@pytest.mark.parametrize(
    "eta,k",
    [(0.143, 3.983), (1.49, 7.82), (0.2, 0.0), (0.7, 0.0), (1.5, 0.0), (2.4, 1e-3), (10.0, 20.0), (0.01, 0.01),
     (1.0, 0.0), (1.0001, 0.0)],
)
def test_fresnel(eta, k):
    cc = cols(C)
    f0 = float(np.float32(eta / 11))
    g = run(f"return vec3(fresnel_conductor1(wi.x, {eta!r}, {k!r}), fresnel_dielectric_cook1(wi.x, {eta!r}),"
            f" fresnel_schlick1({f0!r}, wi.x));", cc)
    c = f64(cc[:, 0])
    eta, k = float(np.float32(eta)), float(np.float32(k))  # what the shader's float literals hold
    cond = F.fresnel_conductor(c, eta, k)
    diel = F.fresnel_dielectric_cook(c, eta)
    sch = F.fresnel_schlick(f0, c)
    # 1e-5 relative (a few dozen float32 operations; for |η| << 1 the real part of η·cos θt
    # cancels), 1e-10 absolute (F of an index-1 "interface" is 0, numpy's float64 gives up
    # to 3e-11 there); for a dielectric also the conditioning at the critical angle, where
    # g = sqrt(n² + c² − 1) has an infinite slope: F's change when the float32 sum
    # n² + c² − 1 moves by its rounding, 4·2^-23·(n² + c² + 1)
    delta = 4 * EPS32 * (eta**2 + c**2 + 1)
    cond_d = np.zeros_like(c)
    for sign in (-1, 1):
        c2 = np.sqrt(np.clip(c**2 + sign * delta, 0, 1))
        cond_d = np.maximum(cond_d, np.abs(F.fresnel_dielectric_cook(c2, eta) - diel))
    assert np.all(np.abs(g[:, 0] - cond) <= 1e-5 * cond + 1e-10 + (cond_d if k == 0 else 0)), (eta, k)
    assert np.all(np.abs(g[:, 1] - diel) <= 1e-5 * diel + 1e-10 + cond_d), eta
    np.testing.assert_allclose(g[:, 2], sch, rtol=1e-6, atol=EPS32)


def test_fresnel_rgb_and_f0():
    cc = cols(C)
    g = run("return fresnel_conductor(wi.x, vec3(0.143, 0.375, 1.442), vec3(3.983, 2.386, 1.603));", cc)
    ref = F.fresnel_conductor(f64(cc[:, 0])[:, None], np.float32([0.143, 0.375, 1.442]).astype(float),
                              np.float32([3.983, 2.386, 1.603]).astype(float))
    np.testing.assert_allclose(g, ref, rtol=2e-6)
    g = run("return f0_from_ior(vec3(1.0, 1.5, 37.0));", cols([0.0]))
    np.testing.assert_allclose(g[0], F.f0_from_ior(np.array([1.0, 1.5, 37.0])), rtol=1e-6, atol=1e-12)


# ---------------------------------------------------------------------------
# D, Λ, G
# ---------------------------------------------------------------------------
def _directions(n, seed, zmin=1e-3):
    rng = np.random.default_rng(seed)
    z = np.concatenate([rng.uniform(zmin, 1, n - 6), [1.0, zmin, 0.5, 0.999999, 0.01, 0.9]])
    phi = rng.uniform(0, 2 * np.pi, n)
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1).astype(np.float32)


@pytest.mark.parametrize("ax,ay", [(0.2, 0.2), (0.001, 0.001), (1.0, 1.0), (0.05, 0.5), (0.7, 0.01)])
def test_distributions_and_lambda(ax, ay):
    h = _directions(3000, 1)
    hh = f64(h)
    g = run(f"return vec3(beckmann(wi, {ax!r}, {ay!r}), ggx(wi, {ax!r}, {ay!r}), "
            f"beckmann_unnormalized(wi, {ax!r}, {ay!r}));", h)
    ax32, ay32 = float(np.float32(ax)), float(np.float32(ay))
    db = D.beckmann(hh, ax32, ay32)
    # D = exp(−e − 4 ln h_z): the float32 exponent carries |e|·2^-23, the result that relative error
    e = (hh[:, 0] / ax32) ** 2 / hh[:, 2] ** 2 + (hh[:, 1] / ay32) ** 2 / hh[:, 2] ** 2
    ok = db > 1e-30
    assert np.all(np.abs(g[ok, 0] - db[ok]) / db[ok] < 2e-6 + 4 * (e[ok] + 4) * EPS32)
    np.testing.assert_allclose(g[:, 1], D.ggx(hh, ax32, ay32), rtol=2e-6, atol=1e-30)
    dbu = D.beckmann(hh, ax32, ay32, normalized=False)
    assert np.all(np.abs(g[ok, 2] - dbu[ok]) / dbu[ok] < 2e-6 + 4 * (e[ok] + 4) * EPS32)

    g = run(f"return vec3(beckmann_lambda(wi, {ax!r}, {ay!r}), ggx_lambda(wi, {ax!r}, {ay!r}), "
            f"smith_g1(wi, {ax!r}, {ay!r}, BK_BECKMANN, vec3(0.0, 0.0, 1.0)));", h)
    lb = D.beckmann_lambda(hh, ax32, ay32)
    lg = D.ggx_lambda(hh, ax32, ay32)
    # Λ enters the BRDF only through 1/(1 + Λ): compare on that scale (absolute 1e-6 of 1 + Λ)
    assert np.all(np.abs(g[:, 0] - lb) <= 1e-6 * (1 + lb))
    assert np.all(np.abs(g[:, 1] - lg) <= 1e-6 * (1 + lg))
    np.testing.assert_allclose(g[:, 2], G.smith_g1(hh, ax32, ay32, "beckmann"), rtol=2e-6)


def test_beckmann_cook():
    c = np.concatenate([np.linspace(0, 1, 2001), [1e-3, 0.999999]])
    for m in (0.001, 0.05, 0.2, 1.0):
        g = run(f"return vec3(beckmann_cook(wi.x, {m!r}), 0.0, 0.0);", cols(c))
        m32 = float(np.float32(m))
        cc = f64(cols(c)[:, 0])
        ref = D.beckmann_cook(cc, m32)
        with np.errstate(divide="ignore"):
            t2 = np.where(cc > 0, (1 - cc**2) / np.maximum(cc, 1e-30) ** 2, 0)
        # (1 − c²)/c² in float32: absolute error ~2^-23/c², times 1/m² in the exponent
        bound = 2e-6 + 4 * (t2 / m32**2 + 4 + 2 / np.maximum(cc, 1e-30) ** 2 / m32**2) * EPS32
        ok = ref > 1e-30
        assert np.all(np.abs(g[ok, 0] - ref[ok]) / ref[ok] < bound[ok]), m
        assert np.all(g[~ok, 0] < 1e-29)


@pytest.mark.parametrize("ax,ay", [(0.3, 0.3), (0.02, 0.6)])
def test_shadowing(ax, ay):
    wi = _directions(2000, 2)
    wo = _directions(2000, 3)
    wi64, wo64 = f64(wi), f64(wo)
    h = wi64 + wo64
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    g = run(
        f"vec3 h = normalize(wi + wo);"
        f"return vec3(smith_g_separable(wi, wo, {ax!r}, {ay!r}, BK_GGX, h),"
        f" smith_g_correlated(wi, wo, {ax!r}, {ay!r}, BK_BECKMANN, h),"
        f" v_groove(h.z, wo.z, wi.z, dot(wo, h), dot(wi, h)));",
        wi,
        wo,
    )
    ax32, ay32 = float(np.float32(ax)), float(np.float32(ay))
    np.testing.assert_allclose(g[:, 0], G.smith_g_separable(wi64, wo64, ax32, ay32, "ggx", h), rtol=2e-6, atol=1e-7)
    np.testing.assert_allclose(g[:, 1], G.smith_g_correlated(wi64, wo64, ax32, ay32, "beckmann", h), rtol=2e-6,
                               atol=1e-7)
    vg = G.v_groove(h[:, 2], wo64[:, 2], wi64[:, 2], np.sum(wo64 * h, 1), np.sum(wi64 * h, 1))
    np.testing.assert_allclose(g[:, 2], vg, rtol=2e-6, atol=1e-7)
    # below the horizon, G and G1 are 0
    down = np.array([[0.6, 0.0, -0.8]], np.float32)
    up = np.array([[0.0, 0.6, 0.8]], np.float32)
    z = run("vec3 h = vec3(0.0, 0.0, 1.0); return vec3(smith_g1(wi, 0.3, 0.3, BK_GGX, h),"
            " smith_g_correlated(wi, wo, 0.3, 0.3, BK_BECKMANN, h), smith_g_separable(wo, wi, 0.3, 0.3, BK_GGX, h));",
            down, up)
    assert z.tolist() == [[0.0, 0.0, 0.0]]


# ---------------------------------------------------------------------------
# HTSG's series, Lambert W and constants (shaders/htsg.glsl)
# ---------------------------------------------------------------------------
def run_htsg(body: str, a, b=None) -> np.ndarray:
    """Like :func:`run`, with htsg.glsl's helpers available (its own brdf renamed away)."""
    a = np.asarray(a, dtype=np.float32)
    b = np.zeros_like(a) if b is None else np.asarray(b, dtype=np.float32)
    htsg_src = glsl.shader_path("htsg").read_text().replace("vec3 brdf(vec3 wi, vec3 wo)", "vec3 htsg_unused(vec3 wi, vec3 wo)")
    src = glsl.common_source() + htsg_src + "\nvec3 brdf(vec3 wi, vec3 wo) {\n" + body + "\n}\n"
    return glsl.eval_glsl(bk.model("htsg"), a, b, source=src).astype(np.float64)


def test_htsg_constants_match_numpy():
    import re
    from math import lgamma

    from brdfkit.terms import htsg_series as htsg

    text = glsl.shader_path("htsg").read_text()
    for n in range(1, len(htsg._Q)):
        body = re.search(rf"float htsg_q{n}\(float a\) \{{(.*?)return p;", text, re.S).group(1)
        coeffs = [float(x) for x in re.findall(r"(-?\d+\.\d*(?:e-?\d+)?);", body)]
        np.testing.assert_allclose(coeffs[::-1], htsg._Q[n], rtol=1e-15, err_msg=f"Q_{n}")
    assert len(htsg._Q) - 1 == htsg.ASYMPTOTIC_ORDER == 6
    assert (htsg.ASYMPTOTIC_G, htsg.ASYMPTOTIC_A_SCALE, htsg.ASYMPTOTIC_A_POWER) == (40.0, 0.5, 0.55)
    table = re.search(r"HTSG_LNFACT\[17\] = float\[17\]\((.*?)\);", text).group(1)
    np.testing.assert_allclose([float(x) for x in table.split(",")], [lgamma(m + 1) for m in range(17)], rtol=1e-15)


def test_htsg_lambertw():
    from brdfkit.terms import special

    lz = np.concatenate([np.linspace(-40, 80, 2401), [-29.9, -30.1, 0.0, 1.0]])
    g = run_htsg("return vec3(htsg_lambertw_from_log(wi.x), 0.0, 0.0);", cols(lz))
    ref = special.lambertw_from_log(f64(cols(lz)[:, 0]))
    # W'(z) z / W = 1/(1 + W): a float32 lz (rounding |lz|·2^-24) moves W by at most that, relatively
    assert np.all(np.abs(g[:, 0] - ref) <= (4e-7 + np.abs(lz) * EPS32) * ref)


@pytest.mark.parametrize("g_val", [1e-6, 0.01, 0.5, 3.0, 12.0, 39.0, 41.0, 150.0, 1500.0, 15000.0])
def test_htsg_series(g_val):
    """ln(Σ/g) in float32 against the float64 numpy series, both branches, T over many decades."""
    from brdfkit.terms import htsg_series as htsg

    T = np.concatenate([[0.0], np.geomspace(1e-6, 1e6, 400)])
    gg = np.full_like(T, g_val)
    cc = cols(gg, T)
    out = run_htsg("return vec3(htsg_log_series_ratio(wi.x, wi.y), 0.0, 0.0);", cc)
    g32, T32 = f64(cc[:, 0]), f64(cc[:, 1])
    ref = htsg.htsg_log_series_ratio(g32, T32)
    # only where Σ/g is a normal float32 number matters; there the log must be good to
    # 1e-5 absolute, plus the conditioning of a float32 exponent of size |ref| (|ref|·2^-22)
    ok = ref > -80
    assert ok.sum() > 20
    err = np.abs(out[ok, 0] - ref[ok])
    assert np.all(err <= 1e-5 + 4 * np.abs(ref[ok]) * EPS32), (g_val, err.max())
