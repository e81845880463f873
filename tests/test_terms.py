"""Shared microfacet terms: Fresnel, distributions D, Smith Λ / G1, V-groove G.

Every expected value here comes from an independent route: numerical
quadrature of the defining integrals, textbook formulas written out
separately, or closed forms at special points.
"""

import math

import numpy as np
import pytest
from numpy.polynomial.legendre import leggauss

from brdfkit.terms import distributions as dist
from brdfkit.terms import fresnel as fr
from brdfkit.terms import shadowing as sh

# ----------------------------------------------------------------- quadrature


def _gauss(a, b, n):
    x, w = leggauss(n)
    return 0.5 * (b - a) * x + 0.5 * (b + a), 0.5 * (b - a) * w


def _radial_scale(phi, ax, ay):
    """Width of the slope distribution along azimuth phi (1-D scale of D's radial profile)."""
    return 1.0 / np.sqrt(np.cos(phi) ** 2 / ax**2 + np.sin(phi) ** 2 / ay**2)


def hemisphere_integral(f, ax, ay, tmax=None, n_phi=32, n_psi=96, phi_breaks=(), panels=8):
    """∫ f(h) dω_h over the upper hemisphere by tensor Gauss-Legendre quadrature.

    Substitution per azimuth: tan θ = s(φ) tan ψ, ψ ∈ [0, atan(T(φ)/s(φ))] with s the
    radial width of the lobe, so that sharp lobes are resolved with a few hundred nodes.
    ``tmax(phi)`` optionally limits tan θ (inf = whole hemisphere). ``phi_breaks`` splits
    the azimuth range where the integrand has kinks; the azimuth is also cut into
    ``panels`` equal pieces (strong anisotropy makes the integrand peaked in φ).
    """
    edges = sorted({*np.linspace(0.0, 2 * np.pi, panels + 1).tolist(), *phi_breaks})
    total = 0.0
    for a, b in zip(edges[:-1], edges[1:]):
        phi, wphi = _gauss(a, b, n_phi)
        s = _radial_scale(phi, ax, ay)
        T = np.full_like(phi, np.inf) if tmax is None else tmax(phi)
        psi_max = np.arctan2(T, s)  # atan(T/s), pi/2 for T = inf
        x, wx = leggauss(n_psi)
        psi = 0.5 * psi_max[:, None] * (x[None, :] + 1)
        wpsi = 0.5 * psi_max[:, None] * wx[None, :]
        t = s[:, None] * np.tan(psi)
        theta = np.arctan(t)
        dtheta_dpsi = s[:, None] / np.cos(psi) ** 2 / (1 + t * t)
        P = phi[:, None] * np.ones_like(psi)
        h = np.stack([np.sin(theta) * np.cos(P), np.sin(theta) * np.sin(P), np.cos(theta)], axis=-1)
        val = f(h) * np.sin(theta) * dtheta_dpsi
        total += np.sum(val * wpsi * wphi[:, None])
    return total


ALPHAS = [(0.01, 0.01), (0.1, 0.1), (0.5, 0.5), (1.0, 1.0), (0.05, 0.4), (0.6, 0.02), (0.3, 0.9)]


@pytest.mark.parametrize("ax,ay", ALPHAS)
@pytest.mark.parametrize("name", ["beckmann", "ggx"])
def test_distribution_projected_area_is_one(name, ax, ay):
    D = dist.DISTRIBUTIONS[name][0]
    kw = dict(n_phi=4, panels=1) if ax == ay else {}  # isotropic: the integrand is constant in φ
    I = hemisphere_integral(lambda h: D(h, ax, ay) * h[..., 2], ax, ay, **kw)
    assert abs(I - 1.0) < 1e-7, I


@pytest.mark.parametrize("m", [0.005, 0.05, 0.2, 0.6, 1.0])
def test_lecture_beckmann_integrates_to_pi(m):
    kw = dict(n_phi=4, panels=1)
    I = hemisphere_integral(lambda h: dist.beckmann_cook(h[..., 2], m) * h[..., 2], m, m, **kw)
    assert abs(I - np.pi) < 1e-6 * np.pi, I
    I2 = hemisphere_integral(lambda h: dist.beckmann(h, m, normalized=False) * h[..., 2], m, m, **kw)
    assert abs(I2 - np.pi) < 1e-7 * np.pi, I2


def test_distribution_closed_forms_at_special_points():
    # At h = n both are 1/(π α_x α_y); the lecture's Beckmann is 1/m².
    n = np.array([0.0, 0.0, 1.0])
    assert dist.ggx(n, 0.3, 0.2) == pytest.approx(1 / (math.pi * 0.06), rel=1e-14)
    assert dist.beckmann(n, 0.3, 0.2) == pytest.approx(1 / (math.pi * 0.06), rel=1e-14)
    assert dist.beckmann_cook(1.0, 0.25) == pytest.approx(16.0, rel=1e-14)
    # At θ = 45° along +x: tan = 1, cos⁴ = 1/4.
    h = np.array([math.sqrt(0.5), 0.0, math.sqrt(0.5)])
    a = 0.4
    assert dist.beckmann(h, a) == pytest.approx(math.exp(-1 / a**2) / (math.pi * a**2 * 0.25), rel=1e-13)
    assert dist.ggx(h, a) == pytest.approx(a**2 / (math.pi * 0.25 * (a**2 + 1) ** 2), rel=1e-13)
    # anisotropy axis: along +x only alpha_x matters
    assert dist.ggx(h, a, 0.05) * 0.05 == pytest.approx(dist.ggx(h, a) * a, rel=1e-13)
    hy = np.array([0.0, math.sqrt(0.5), math.sqrt(0.5)])
    assert dist.beckmann(hy, 0.05, a) * 0.05 == pytest.approx(dist.beckmann(h, a) * a, rel=1e-13)
    # cosine forms equal the vector forms
    c = np.linspace(0.05, 1, 20)
    hv = np.stack([np.sqrt(1 - c * c), 0 * c, c], -1)
    np.testing.assert_allclose(dist.beckmann_iso(c, a), dist.beckmann(hv, a), rtol=1e-12)
    np.testing.assert_allclose(dist.ggx_iso(c, a), dist.ggx(hv, a), rtol=1e-12)
    np.testing.assert_allclose(dist.beckmann_cook(c, a), np.pi * dist.beckmann(hv, a), rtol=1e-12)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_distributions_never_nan_inf(dtype):
    rng = np.random.default_rng(3)
    z = np.concatenate([[0.0, 1e-45, 1e-30, 1e-20, 1e-12, 1e-6, 1.0, -0.5], rng.random(200)])
    r = np.sqrt(np.maximum(0, 1 - z * z))
    ph = rng.random(z.shape) * 2 * np.pi
    h = np.stack([r * np.cos(ph), r * np.sin(ph), z], -1).astype(dtype)
    for a in [(1e-3, 1e-3), (1e-3, 1.0), (1.0, 1.0)]:
        for D in (dist.beckmann, dist.ggx):
            d = D(h, dtype(a[0]), dtype(a[1]))
            assert d.dtype == dtype
            assert np.all(np.isfinite(d)) and np.all(d >= 0)
        lc = dist.beckmann_cook(z.astype(dtype), dtype(a[0]))
        assert lc.dtype == dtype and np.all(np.isfinite(lc)) and np.all(lc >= 0)
        for L in (dist.beckmann_lambda, dist.ggx_lambda):
            lam = L(h, dtype(a[0]), dtype(a[1]))
            assert lam.dtype == dtype and not np.any(np.isnan(lam)) and np.all(lam >= 0)
            g = sh.g1_from_lambda(lam)
            assert np.all((g >= 0) & (g <= 1))
            assert np.all(g[z <= 0] == 0) and g[6] == 1  # horizon: fully masked; normal: unmasked
    # float32 peak at the smallest alpha does not overflow
    n = np.array([0, 0, 1], dtype=np.float32)
    assert dist.beckmann(n, np.float32(1e-3)) == pytest.approx(1 / (np.pi * 1e-6), rel=1e-5)
    # float32 D at a grazing half vector underflows to 0 cleanly
    hg = np.array([1.0, 0.0, 1e-30], dtype=np.float32)
    assert dist.beckmann(hg, np.float32(1e-3)) == 0 and dist.beckmann_cook(np.float32(1e-30), np.float32(1e-3)) == 0


def test_float32_close_to_float64():
    rng = np.random.default_rng(5)
    z = rng.uniform(0.05, 1, 500)
    r = np.sqrt(1 - z * z)
    ph = rng.random(500) * 2 * np.pi
    h = np.stack([r * np.cos(ph), r * np.sin(ph), z], -1)
    for D in (dist.beckmann, dist.ggx, dist.beckmann_lambda, dist.ggx_lambda):
        d64 = D(h, 0.3, 0.1)
        d32 = D(h.astype(np.float32), np.float32(0.3), np.float32(0.1))
        np.testing.assert_allclose(d32, d64, rtol=2e-4, atol=1e-30)


# ------------------------------------------------------------------ Smith Λ


def _lambda_direct(name, w, ax, ay):
    """Λ from the textbook formulas with math.erf (scalar)."""
    cos_t = w[2]
    sin_t = math.hypot(w[0], w[1])
    if sin_t == 0:
        return 0.0
    cphi, sphi = w[0] / sin_t, w[1] / sin_t
    alpha = math.sqrt(cphi**2 * ax**2 + sphi**2 * ay**2)
    tan_t = sin_t / cos_t
    if name == "ggx":
        return (-1 + math.sqrt(1 + alpha**2 * tan_t**2)) / 2
    a = 1 / (alpha * tan_t)
    return (math.erf(a) - 1) / 2 + math.exp(-a * a) / (2 * a * math.sqrt(math.pi))


@pytest.mark.parametrize("name", ["beckmann", "ggx"])
def test_lambda_matches_textbook_formula(name):
    L = dist.DISTRIBUTIONS[name][1]
    for th in [0.0, 0.1, 0.7, 1.2, 1.5, 1.56]:
        for ph in [0.0, 0.9, 2.0]:
            w = np.array([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])
            for ax, ay in [(0.2, 0.2), (0.05, 0.7)]:
                expect = _lambda_direct(name, w, ax, ay)
                got = float(L(w, ax, ay))
                assert got == pytest.approx(expect, rel=1e-9, abs=1e-15), (th, ph, ax, ay)


def _g1_by_quadrature(name, w, ax, ay):
    """Smith G1(w) = cos θ_w / ∫ max(0, w·h) D(h) dω_h (Heitz 2014, eq. 17/43)."""
    D = dist.DISTRIBUTIONS[name][0]
    st = math.hypot(w[0], w[1])
    cos_w = w[2]
    phi_w = math.atan2(w[1], w[0]) if st > 0 else 0.0

    def tmax(phi):
        # w·h = 0  <=>  tan θ_h = cos θ_w / (−sin θ_w cos(φ − φ_w)) where cos(φ − φ_w) < 0
        c = np.cos(phi - phi_w)
        with np.errstate(divide="ignore"):
            return np.where(c < 0, cos_w / np.maximum(-st * c, 1e-300), np.inf)

    breaks = [(phi_w + math.pi / 2) % (2 * math.pi), (phi_w - math.pi / 2) % (2 * math.pi)] if st > 0 else []
    I = hemisphere_integral(
        lambda h: np.maximum(0.0, h @ w) * D(h, ax, ay), ax, ay, tmax=tmax, n_phi=16, n_psi=64, phi_breaks=breaks
    )
    return cos_w / I


@pytest.mark.parametrize("name", ["beckmann", "ggx"])
@pytest.mark.parametrize("ax,ay", [(0.1, 0.1), (0.5, 0.5), (1.0, 1.0), (0.08, 0.6)])
def test_smith_g1_equals_masking_integral(name, ax, ay):
    for th, ph in [(0.3, 0.0), (0.9, 1.1), (1.3, 2.5), (1.5, 0.4)]:
        w = np.array([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])
        expect = _g1_by_quadrature(name, w, ax, ay)
        got = float(sh.smith_g1(w, ax, ay, distribution=name))
        assert got == pytest.approx(expect, rel=1e-6), (name, th, ph, ax, ay, got, expect)


def test_smith_combinations():
    rng = np.random.default_rng(9)
    z = rng.uniform(0.01, 1, (100, 2))
    ph = rng.uniform(0, 2 * np.pi, (100, 2))
    r = np.sqrt(1 - z * z)
    w = np.stack([r * np.cos(ph), r * np.sin(ph), z], -1)
    wi, wo = w[:, 0], w[:, 1]
    for name in ("beckmann", "ggx"):
        L = dist.DISTRIBUTIONS[name][1]
        li, lo = L(wi, 0.3, 0.1), L(wo, 0.3, 0.1)
        sep = sh.smith_g_separable(wi, wo, 0.3, 0.1, distribution=name)
        cor = sh.smith_g_correlated(wi, wo, 0.3, 0.1, distribution=name)
        np.testing.assert_allclose(sep, 1 / ((1 + li) * (1 + lo)), rtol=1e-14)
        np.testing.assert_allclose(cor, 1 / (1 + li + lo), rtol=1e-14)
        assert np.all(cor >= sep - 1e-15) and np.all(cor <= 1)
        # the one-sidedness factor χ⁺(w·h)
        h_bad = np.broadcast_to(-wi, wi.shape)
        assert np.all(sh.smith_g_separable(wi, wo, 0.3, 0.1, distribution=name, h=h_bad) == 0)
        assert np.all(sh.smith_g_correlated(wi, wo, 0.3, 0.1, distribution=name, h=h_bad) == 0)
    with pytest.raises(ValueError, match="beckmann, ggx"):
        sh.smith_g1(wi, 0.1, distribution="phong")


def test_v_groove_by_hand():
    # l at 30°, v at 80° on the other side of the normal: the grazing viewer is masked
    l = (math.sin(math.radians(30)), 0.0, math.cos(math.radians(30)))
    v = (-math.sin(math.radians(80)), 0.0, math.cos(math.radians(80)))
    hx, hz = l[0] + v[0], l[2] + v[2]
    nrm = math.hypot(hx, hz)
    hx, hz = hx / nrm, hz / nrm
    n_h, n_v, n_l = hz, v[2], l[2]
    v_h = v[0] * hx + v[2] * hz
    l_h = l[0] * hx + l[2] * hz
    gm, gs = 2 * n_h * n_v / v_h, 2 * n_h * n_l / l_h
    expect = min(1.0, gm, gs)
    assert expect < 1  # a configuration where shadowing bites
    assert float(sh.v_groove(n_h, n_v, n_l, v_h, l_h)) == pytest.approx(expect, rel=1e-15)
    assert float(sh.v_groove(1.0, 1.0, 1.0, 1.0, 1.0)) == 1.0
    g = sh.v_groove(np.array([1.0, 0.5]), np.array([0.0, 1e-300]), 0.5, np.array([0.0, 0.0]), 0.7)
    assert np.all(np.isfinite(g)) and np.all((g >= 0) & (g <= 1))


# ------------------------------------------------------------------- Fresnel


def _fresnel_sp(cos_i, n1, n2):
    """Unpolarised Fresnel from the s/p amplitude coefficients with Snell's law (textbook)."""
    sin_i = math.sqrt(max(0.0, 1 - cos_i**2))
    sin_t = n1 / n2 * sin_i
    if sin_t >= 1:
        return 1.0
    cos_t = math.sqrt(1 - sin_t**2)
    rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)
    rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t)
    return 0.5 * (rs * rs + rp * rp)


def _fresnel_conductor_real(c, eta, k):
    """Conductor Fresnel in real arithmetic (the a², b² form, e.g. pbrt-v3 FrConductor)."""
    c2 = c * c
    s2 = 1 - c2
    t0 = eta * eta - k * k - s2
    a2b2 = math.sqrt(t0 * t0 + 4 * eta * eta * k * k)
    a = math.sqrt(0.5 * (a2b2 + t0))
    t1 = a2b2 + c2
    t2 = 2 * c * a
    rs = (t1 - t2) / (t1 + t2)
    t3 = c2 * a2b2 + s2 * s2
    t4 = t2 * s2
    rp = rs * (t3 - t4) / (t3 + t4)
    return 0.5 * (rs + rp)


@pytest.mark.parametrize("n", [1.0, 1.1, 1.5, 2.4, 40.0, 0.7, 0.2])
def test_dielectric_cook_equals_sp_form(n):
    for c in np.linspace(0.0, 1.0, 41):
        if c == 0 and n == 1.0:
            expect = 0.0  # no interface
        elif c == 0:
            expect = 1.0
        else:
            expect = _fresnel_sp(c, 1.0, n)
        assert float(fr.fresnel_dielectric_cook(c, n)) == pytest.approx(expect, abs=1e-13), (c, n)
    assert float(fr.fresnel_dielectric_cook(1.0, n)) == pytest.approx(((n - 1) / (n + 1)) ** 2, abs=1e-15)
    assert float(fr.f0_from_ior(n)) == pytest.approx(((n - 1) / (n + 1)) ** 2, rel=1e-15)


@pytest.mark.parametrize("eta,k", [(0.143, 3.98), (0.2, 0.0), (1.5, 0.0), (2.0, 1.0), (1.0, 0.0), (0.05, 8.0)])
def test_conductor_against_real_form_and_dielectric(eta, k):
    cs = np.linspace(0.0, 1.0, 41)
    got = fr.fresnel_conductor(cs, eta, k)
    for c, g in zip(cs, got):
        expect = 0.0 if (c == 0 and eta == 1 and k == 0) else _fresnel_conductor_real(c, eta, k)
        assert g == pytest.approx(expect, abs=1e-12), (c, eta, k)
    if k == 0:
        np.testing.assert_allclose(got, fr.fresnel_dielectric_cook(cs, eta), atol=1e-13)
    # normal incidence ((η−1)² + k²)/((η+1)² + k²)
    assert float(fr.fresnel_conductor(1.0, eta, k)) == pytest.approx(((eta - 1) ** 2 + k * k) / ((eta + 1) ** 2 + k * k), abs=1e-14)
    # grazing incidence reflects everything (except the no-interface case)
    if not (eta == 1 and k == 0):
        assert float(fr.fresnel_conductor(0.0, eta, k)) == pytest.approx(1.0, abs=1e-12)


def test_fresnel_rgb_broadcast_and_dtype():
    c = np.linspace(0, 1, 7, dtype=np.float32)[:, None]
    eta = np.array([1.2, 1.5, 2.0], dtype=np.float32)
    d = fr.fresnel_dielectric_cook(c, eta)
    assert d.shape == (7, 3) and d.dtype == np.float32 and np.all(np.isfinite(d))
    s = fr.fresnel_schlick(np.array([0.04, 0.5, 1.0]), np.array([[0.0], [1.0], [0.5]]))
    np.testing.assert_allclose(s[0], 1.0)
    np.testing.assert_allclose(s[1], [0.04, 0.5, 1.0])
    np.testing.assert_allclose(s[2], np.array([0.04, 0.5, 1.0]) + (1 - np.array([0.04, 0.5, 1.0])) / 32)
    k = fr.fresnel_conductor(c, eta, np.array([0.0, 1.0, 3.0]))
    assert k.shape == (7, 3) and np.all((k >= 0) & (k <= 1))
    # Schlick is exact at both ends (normal incidence by construction, grazing F = 1)
    cs = np.array([0.0, 1.0])
    err = np.abs(fr.fresnel_schlick(fr.f0_from_ior(1.5), cs) - fr.fresnel_dielectric_cook(cs, 1.5))
    assert err.max() < 1e-15


@pytest.mark.parametrize("eta,k", [(1.0001, 0.0), (1.0001, 1e-3), (0.143, 3.98), (10.0, 20.0), (0.01, 0.01), (1.5, 0.0)])
def test_conductor_accuracy_against_mpmath(eta, k):
    """Near η = 1 the naive 1 − sin²θ/η² form cancels; the implementation must not."""
    mp = pytest.importorskip("mpmath")
    mp.mp.dps = 40
    eta32, k32 = np.float32(eta), np.float32(k)
    cs = np.concatenate([[1e-6, 1e-3, 1.0], np.random.default_rng(4).uniform(0, 1, 60)]).astype(np.float32)

    def exact(c):
        c = mp.mpf(float(c))
        n = mp.mpc(float(eta32), float(k32))
        g = mp.sqrt(n * n - 1 + c * c)
        rs = (c - g) / (c + g)
        rp = (n * n * c - g) / (n * n * c + g)
        return float((abs(rs) ** 2 + abs(rp) ** 2) / 2)

    ref = np.array([exact(c) for c in cs])
    f64 = fr.fresnel_conductor(cs.astype(np.float64), float(eta32), float(k32))
    f32 = fr.fresnel_conductor(cs, eta32, k32)
    assert f32.dtype == np.float32
    np.testing.assert_allclose(f64, ref, rtol=1e-12)
    np.testing.assert_allclose(f32, ref, rtol=2e-5)
    # a (near-)index-1 interface at a tiny cosine stays finite in float32
    tiny = fr.fresnel_conductor(np.float32([1e-12, 1e-30, 0.0]), np.float32(1.0), np.float32(0.0))
    assert np.all(np.isfinite(tiny)) and np.all(tiny == 0)


def test_ggx_smith_separable_from_parts_is_the_product_of_g1():
    """G1(wi)·G1(wo) from GGX's undivided Λ = num/den (one division) equals g1_smith(Λi)·g1_smith(Λo)."""
    from brdfkit.geometry import random_unit_vectors

    rng = np.random.default_rng(4)
    w = random_unit_vectors(4000, rng)
    w[:, 2] = np.abs(w[:, 2])
    w[:10, 2] = [0.0, -0.1, 1e-300, 5e-324, 1e-12, 1.0, 1e-6, 0.5, 1e-200, 0.9]
    for ax, ay in ((0.3, 0.3), (1e-3, 1.0), (0.05, 0.7)):
        for j in range(0, len(w) - 1, 2):
            a, b = w[j], w[j + 1]
            li = dist.lambda_ggx(*a, ax, ay)
            lo = dist.lambda_ggx(*b, ax, ay)
            want = sh.g1_smith(li) * sh.g1_smith(lo)
            got = sh.g_smith_separable_parts(*dist.lambda_ggx_parts(*a, ax, ay), *dist.lambda_ggx_parts(*b, ax, ay))
            assert 0.0 <= got <= 1.0
            assert abs(got - want) <= 1e-15 * max(want, 1e-300) or (want < 1e-290 and got < 1e-290), (a, b, got, want)


def test_dielectric_array_form_is_silent_and_equals_the_scalar_source():
    """The branch-free f_dielectric vectorises with every square root argument >= 0 in every lane:
    no invalid-operation flag, so numpy raises no RuntimeWarning for a broadcast grid (it did when
    a discarded lane took sqrt(n² − 1) for n < 1)."""
    import warnings

    from brdfkit.terms import fresnel as fr

    c = np.linspace(0.0, 1.0, 1001)[:, None]
    n = np.array([0.143119, 0.374957, 0.9999, 1.0, 1.0001, 1.442479, 3.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(all="raise"):
            f = fr.fresnel_dielectric_cook(c, n)
    want = np.array([[fr.f_dielectric.py_func(float(a), float(b)) for b in n] for a in c[:, 0]])
    np.testing.assert_array_equal(f, want)
    assert np.all(f[:, 3][1:] == 0.0)  # n = 1: no interface
    assert np.all(f[:, 0][c[:, 0] < 0.98] == 1.0)  # n = 0.14: total internal reflection below c ≈ 0.99
