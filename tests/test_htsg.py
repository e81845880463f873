"""He-Torrance-Sillion-Greenberg (1991): the series, its pieces, and the BRDF's physical properties.

Every reference here is computed independently of the model's code path: the series by a
long log-space sum over every m and by mpmath, W by scipy, the effective roughness by
substituting back into the paper's equation, the shadowing by integrating Smith's slope
integral numerically, the rough limit by the microfacet (Beckmann) formula.
"""

from __future__ import annotations

import importlib

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import integrate
from scipy.special import gammaln, lambertw

import brdfkit as bk
from brdfkit.geometry import spherical_to_vector
from brdfkit.terms.fresnel import fresnel_conductor
from _htsg_reference import mp_series

H = importlib.import_module("brdfkit.models.htsg")
K = importlib.import_module("brdfkit.terms.htsg_series")  # the series Σ(g, T)
S = importlib.import_module("brdfkit.terms.special")  # Lambert W, ln m!, Stirling, Loader's deviance


# ---------------------------------------------------------------------------- series
def _long_sum_log_ratio(g: float, T: float) -> float:
    """ln(Σ/g) summing every term m = 1..M in log space (no window, no asymptotics)."""
    M = int(g + 60 * np.sqrt(g + 1) + 300 + 3 * np.sqrt(T))
    m = np.arange(1, M + 1, dtype=np.float64)
    ll = (m - 1) * np.log(g) - g - gammaln(m + 1) - np.log(m) - T / m
    mx = ll.max()
    return float(mx + np.log(np.sum(np.exp(ll - mx))))


def test_series_matches_long_sum_over_documented_range():
    rng = np.random.default_rng(20260522)
    gs, Ts = [], []
    for _ in range(400):
        g = 10 ** rng.uniform(-4, 5)
        if rng.random() < 0.15:
            T = 0.0
        elif rng.random() < 0.6:
            T = g * 10 ** rng.uniform(-4, 2.5)  # around and beyond the lobe (a = T/g)
        else:
            T = 10 ** rng.uniform(-3, 6)
        gs.append(g)
        Ts.append(T)
    gs, Ts = np.array(gs), np.array(Ts)
    got = H.htsg_log_series_ratio(gs, Ts)
    ref = np.array([_long_sum_log_ratio(g, T) for g, T in zip(gs, Ts)])
    ok = ref > -700  # values that are normal doubles
    assert ok.sum() > 300
    rel = np.abs(np.expm1(got[ok] - ref[ok]))
    assert rel.max() < 1e-6, (gs[ok][rel.argmax()], Ts[ok][rel.argmax()], rel.max())


def test_thinned_direct_sum_matches_long_sum():
    # the direct tier alone where it takes every h-th term (h > 1: wide peaks), and near the
    # thinning's switch (the m = 1 term about e^-30 of the peak, g ≈ 30-45): Poisson summation's
    # bound is ~2e-13; without the m = 1 condition the error is ~4e-5 at g ≈ 14
    rng = np.random.default_rng(7)
    g = np.concatenate([10 ** rng.uniform(1, 4.3, 300), rng.uniform(10, 50, 300)])
    T = np.where(rng.random(600) < 0.2, 0.0, g * 10 ** rng.uniform(-4, 1.5, 600))
    lw = np.where(T > 0, S.lambertw_from_log(np.log(np.maximum(2 * T, 1e-300)) - 2 * np.log(g)), 0.0)
    mstar = np.maximum(g * np.exp(0.5 * lw), 1.0)
    var = 1 / (1 / mstar + 2 * T / mstar**3)
    steps = np.array([K.thinning_step(v, -40.0) for v in var])
    assert (steps > 1).mean() > 0.5 and steps.max() > 20  # the test exercises the thinning
    got = K._direct_log_ratio(g, T)
    ref = np.array([_long_sum_log_ratio(a, b) for a, b in zip(g, T)])
    rel = np.abs(np.expm1(got - ref))
    assert rel.max() < 1e-8, (g[rel.argmax()], T[rel.argmax()], rel.max())


@pytest.mark.parametrize(
    "g,T",
    [(1e-3, 0.0), (0.3, 2.0), (1.0, 0.0), (4.2, 17.0), (12.0, 300.0), (25.0, 1.0), (39.0, 80.0),
     (41.0, 10.0), (60.0, 150.0), (150.0, 30.0), (300.0, 9000.0), (2.0, 1500.0)],
)
def test_series_matches_mpmath(g, T):
    got = float(H.htsg_series(np.array([g]), np.array([T]))[0])
    ref = mp_series(g, T)
    assert abs(got / float(ref) - 1) < 1e-7


def test_both_tiers_agree_where_asymptotic_form_is_used():
    g = np.repeat([40.0, 55.0, 120.0, 800.0, 5e3, 5e4], 12)
    amax = K.ASYMPTOTIC_A_SCALE * g**K.ASYMPTOTIC_A_POWER
    a = amax * np.tile(np.linspace(0, 1, 12), 6)
    asym = K._asymptotic_log_ratio(g, a * g)
    direct = K._direct_log_ratio(g, a * g)
    assert np.max(np.abs(np.expm1(asym - direct))) < 1e-6


def test_asymptotic_first_order_coefficient():
    # order 1/g: ∫ e^-s (s²/2) J0(2√(as)) ds = L_2(a) e^-a, L_2(a) = (a² − 4a + 2)/2
    Q = K.asymptotic_coefficients(3)
    assert [float(c) for c in Q[1]] == [1.0, -2.0, 0.5]
    assert all(float(c) == 0 for c in Q[0])
    assert len(Q[3]) == 5  # Q_n has degree n + 1


def test_series_small_g_limit_and_zero():
    # Σ/g → e^-T as g → 0 (only m = 1 survives); Σ itself → 0: no directional diffuse at σ = 0
    T = np.array([0.0, 1.0, 5.0])  # (the m = 2 term, g e^(-T/2)/4, is negligible here)
    np.testing.assert_allclose(np.exp(H.htsg_log_series_ratio(1e-12, T)), np.exp(-T), rtol=1e-9)
    assert np.all(H.htsg_series(0.0, T) == 0)


def test_lambertw_matches_scipy():
    lz = np.concatenate([np.linspace(-720, 700, 50001), [-np.inf]])
    ref = np.where(np.isfinite(lz), lambertw(np.exp(lz)).real, 0.0)
    got = S.lambertw_from_log(lz)
    assert np.all(np.abs(got - ref) <= 1e-13 * np.maximum(ref, 1e-300))
    # huge arguments, where exp(lz) overflows: w + ln w = lz
    lz = np.array([1e3, 1e6, 1e300])
    w = S.lambertw_from_log(lz)
    np.testing.assert_allclose(w + np.log(w), lz, rtol=1e-14)


# ---------------------------------------------------------------------------- pieces
@pytest.mark.parametrize("sigma0,tau", [(0.18, 3.0), (0.8, 3.0), (0.05, 0.3), (1.5, 1.0)])
def test_effective_roughness_solves_the_papers_equation(sigma0, tau):
    th = np.radians(np.array([0.0, 10, 45, 70, 85, 89.5, 89.99]))
    ci, cr = np.meshgrid(np.cos(th), np.cos(th))
    sigma = H.effective_roughness(ci, cr, sigma0, tau)
    z0 = sigma0 * np.sqrt(H.z0_ratio_squared(ci, cr, sigma0, tau))
    np.testing.assert_allclose(sigma, sigma0 / np.sqrt(1 + (z0 / sigma0) ** 2), rtol=1e-15)

    def K(c):
        t = np.sqrt(1 - c * c) / c
        return t * np.array([float(mpmath.erfc(tau / (2 * sigma0 * x))) if x > 0 else 0.0 for x in t.ravel()]).reshape(t.shape)

    lhs = np.sqrt(np.pi / 2) * z0
    rhs = sigma0 / 4 * (K(ci) + K(cr)) * np.exp(-(z0**2) / (2 * sigma0**2))
    np.testing.assert_allclose(lhs, rhs, rtol=1e-10, atol=1e-300)
    assert np.all((sigma > 0) & (sigma <= sigma0))
    assert sigma[0, 0] == pytest.approx(sigma0, rel=1e-12)  # no shadowing at normal incidence


@pytest.mark.parametrize("sigma0,tau", [(0.18, 3.0), (0.8, 3.0), (1.0, 1.0)])
def test_shadowing_is_smiths_function(sigma0, tau):
    # Smith 1967: S = (1 − ½ erfc(μ/(√2 s))) / (1 + Λ), Λ = (1/μ) ∫_μ^∞ (q − μ) p(q) dq,
    # p = N(0, s²) slopes along the plane of incidence, s² = 2 σ0²/τ² for a Gaussian correlation
    s = np.sqrt(2) * sigma0 / tau
    for deg in [20.0, 50.0, 70.0, 85.0, 89.0]:
        mu = 1 / np.tan(np.radians(deg))
        p = lambda q: np.exp(-q * q / (2 * s * s)) / (np.sqrt(2 * np.pi) * s)  # noqa: E731
        lam = integrate.quad(lambda q: (q - mu) * p(q), mu, np.inf, epsabs=0, epsrel=1e-12)[0] / mu
        ref = (1 - 0.5 * float(mpmath.erfc(mu / (np.sqrt(2) * s)))) / (1 + lam)
        got = float(H.shadowing(np.cos(np.radians(deg)), sigma0, tau))
        assert got == pytest.approx(ref, rel=1e-9)


# ---------------------------------------------------------------------------- the BRDF
unit = st.tuples(st.floats(0, 1), st.floats(0, 2 * np.pi))


def _dir(u, phi):
    z = u
    r = np.sqrt(max(0.0, 1 - z * z))
    return np.array([r * np.cos(phi), r * np.sin(phi), z])


params = st.fixed_dictionaries(
    {
        "sigma0": st.one_of(st.just(0.0), st.floats(1e-6, 2.0)),
        "tau": st.floats(0.05, 100.0),
        "eta": st.floats(0.01, 10.0),
        "k": st.one_of(st.just(0.0), st.floats(0.0, 20.0)),
        "wavelengths": st.tuples(st.floats(200, 2000), st.floats(200, 2000), st.floats(200, 2000)),
        "kd": st.floats(0, 1),
    }
)


@settings(max_examples=60, deadline=None)
@given(params, st.lists(st.tuples(unit, unit), min_size=1, max_size=6))
def test_finite_nonnegative_and_reciprocal(p, pairs):
    m = bk.model("htsg", **p)
    wi = np.array([_dir(*a) for a, _ in pairs])
    wo = np.array([_dir(*b) for _, b in pairs])
    # add the special configurations: grazing, wi == wo, mirror, wi == -wo, normal
    g = np.array([1.0, 0.0, 1e-300])
    g /= np.linalg.norm(g)
    extra_i = np.array([g, [0.6, 0.0, 0.8], [0.6, 0.0, 0.8], [0.0, 0.0, 1.0], g, [0.6, 0, 0.8]])
    extra_o = np.array([g, [0.6, 0.0, 0.8], [-0.6, 0.0, 0.8], [0.0, 0.0, 1.0], [-g[0], 0, g[2]], [-0.6, 0, -0.8]])
    wi = np.concatenate([wi, extra_i])
    wo = np.concatenate([wo, extra_o])
    f = m.eval(wi, wo)
    r = m.eval(wo, wi)
    assert np.all(np.isfinite(f)) and np.all(f >= 0)
    assert np.all(np.abs(f - r) <= 1e-6 * np.maximum(np.abs(f), 1e-300) + 1e-300)
    below = (wi[:, 2] <= 0) | (wo[:, 2] <= 0)
    assert np.all(f[below] == 0)
    sp = m.specular_reflectance(wi)
    assert np.all(np.isfinite(sp)) and np.all((sp >= 0) & (sp <= 1))


def _albedo(model, theta, n=160, nphi=360):
    """∫ f_r cos θo dωo by Gauss-Legendre in cos θo × midpoint in φ, plus the delta part."""
    wi = spherical_to_vector(theta, 0.0)
    x, w = np.polynomial.legendre.leggauss(n)
    ct, wct = 0.5 * (x + 1), 0.5 * w
    phi = (np.arange(nphi) + 0.5) * 2 * np.pi / nphi
    stt = np.sqrt(1 - ct**2)
    wo = np.stack(
        [stt[:, None] * np.cos(phi), stt[:, None] * np.sin(phi), np.broadcast_to(ct[:, None], (n, nphi))], -1
    )
    dd = np.einsum("ijc,i->c", model.eval(wi, wo), ct * wct) * 2 * np.pi / nphi
    return dd, model.specular_reflectance(wi)


@pytest.mark.parametrize("material", [{}, {"eta": 1.5, "k": 0.0}], ids=["aluminium", "dielectric"])
@pytest.mark.parametrize("sigma0", [0.18, 0.38, 0.8])
def test_directional_albedo_at_most_one(material, sigma0):
    m = bk.model("htsg", sigma0=sigma0, tau=3.0, **material)
    for deg in [0.0, 45.0, 75.0, 85.0]:
        dd, sp = _albedo(m, np.radians(deg))
        assert np.all(dd + sp <= 1.0), (deg, dd, sp)
        assert np.all(dd + sp > 0)


def test_kirchhoff_energy_consistency_for_gentle_slopes():
    # for small slopes the Kirchhoff model conserves the Fresnel reflectance: coherent + incoherent
    # = F(θi). This checks the normalisation π²τ²/(4λ²) and the wave-vector units of v_xy.
    m = bk.model("htsg", sigma0=0.05, tau=2.0)
    for deg in [0.0, 30.0]:
        dd, sp = _albedo(m, np.radians(deg), n=200, nphi=720)
        F = fresnel_conductor(np.cos(np.radians(deg)), m.params["eta"], m.params["k"])
        assert np.all(sp > 0.1) and np.all(dd > 0.3)  # both parts matter here
        np.testing.assert_allclose(dd + sp, F, rtol=2e-3)


def test_sigma0_to_zero_gives_fresnel_mirror():
    wi = spherical_to_vector(np.radians([0.0, 40.0, 80.0]), 0.0)
    F = fresnel_conductor(wi[:, 2:3], np.array(H._AL_ETA), np.array(H._AL_K))
    m0 = bk.model("htsg", sigma0=0.0)
    np.testing.assert_allclose(m0.specular_reflectance(wi), F, rtol=1e-12)
    wo = spherical_to_vector(np.radians([0.0, 40.0, 80.0]), np.pi)
    assert np.all(m0.eval(wi, wo) == 0)
    prev = None
    for s in [1e-2, 1e-3, 1e-4]:
        np.testing.assert_allclose(bk.model("htsg", sigma0=s).specular_reflectance(wi), F, rtol=40 * s)
    # directional diffuse albedo: O(σ0²) → 0, and it carries what the coherent part lost, F − ρ_sp
    # (for g ≪ 1 only the m = 1 term is left, whose lobe e^(-T) has a width set by λ/τ alone, so one
    # quadrature resolves it at every σ0; τ ≫ λ is the regime where Kirchhoff conserves energy)
    theta = np.radians(40.0)
    for s in [0.02, 0.01, 0.005]:
        m = bk.model("htsg", sigma0=s, tau=2.0)
        dd, sp = _albedo(m, theta, n=128, nphi=360)
        F40 = fresnel_conductor(np.cos(theta), np.array(H._AL_ETA), np.array(H._AL_K))
        np.testing.assert_allclose(dd, F40 - sp, rtol=0.02)
        if prev is not None:
            assert np.all((dd > prev / 4.5) & (dd < prev / 3.5))  # halving σ0 quarters it
        prev = dd
    assert np.all(prev < 0.02)


def test_rough_limit_is_beckmann_microfacet():
    # g ≫ 1 (here g ≈ 300–1500): Σ → e^-a/g and ρ_dd → F·D_Beckmann·S/(4 cos θi cos θr), RMS slope 2σ/τ
    sigma0, tau = 1.5, 10.0
    m = bk.model("htsg", sigma0=sigma0, tau=tau)
    wi = spherical_to_vector(np.radians(30.0), 0.0)
    th = np.radians(np.linspace(-70, 20, 10))  # around the lobe (far tails: higher orders in 1/g)
    wo = spherical_to_vector(np.abs(th), np.where(th < 0, np.pi, 0.0))
    f = m.eval(wi, wo)
    h = wi + wo
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    ci, co = wi[2], wo[:, 2]
    slope = 2 * H.effective_roughness(ci, co, sigma0, tau) / tau
    tan2 = (1 - h[:, 2] ** 2) / h[:, 2] ** 2
    D = np.exp(-tan2 / slope**2) / (np.pi * slope**2 * h[:, 2] ** 4)
    F = fresnel_conductor((h @ wi)[:, None], m.params["eta"], m.params["k"])
    S = H.shadowing(ci, sigma0, tau) * H.shadowing(co, sigma0, tau)
    np.testing.assert_allclose(f, F * (D * S / (4 * ci * co))[:, None], rtol=1.5e-2)


def _in_plane_peak_deg(m, theta_i_deg):
    wi = spherical_to_vector(np.radians(theta_i_deg), np.pi)
    th = np.radians(np.linspace(0, 89.95, 4000))
    f = m.eval(wi, spherical_to_vector(th, 0.0))[:, 1]
    return float(np.degrees(th[np.argmax(f)]))


def test_off_specular_peaks():
    # near-normal incidence: the directional-diffuse lobe peaks at the mirror direction;
    # oblique/grazing incidence: the peak leaves the mirror direction (Torrance-Sparrow's
    # off-specular peak toward grazing for the rougher surface; at grazing incidence on the
    # paper's aluminium, where g is small, the lobe is pulled back toward the normal)
    al = bk.model("htsg", sigma0=0.18, tau=3.0)
    rough = bk.model("htsg", sigma0=0.38, tau=3.0)
    assert abs(_in_plane_peak_deg(al, 10.0) - 10.0) < 1.0
    assert abs(_in_plane_peak_deg(rough, 10.0) - 10.0) < 2.0
    assert _in_plane_peak_deg(rough, 60.0) > 65.0
    assert abs(_in_plane_peak_deg(al, 85.0) - 85.0) > 5.0


def test_contract_dtype_zero_below_and_parts():
    m = bk.model("htsg", kd=0.2)
    wi = bk.geometry.normalize(np.array([[0.3, 0.1, 0.9], [0.3, 0.1, -0.2]])).astype(np.float32)
    wo = bk.geometry.normalize(np.array([[-0.5, 0.0, 0.8], [0.0, 0.0, 1.0]])).astype(np.float32)
    f = m.eval(wi, wo)
    assert f.dtype == np.float32 and f.shape == (2, 3)
    assert np.all(f[1] == 0) and np.all(f[0] > 0.2 / np.pi)
    f64 = m.eval(wi.astype(np.float64), wo.astype(np.float64))
    np.testing.assert_allclose(f, f64, rtol=1e-6)
    np.testing.assert_allclose(f64[0] - 0.2 / np.pi, m.directional_diffuse(wi[0], wo[0]).astype(np.float64), rtol=1e-12)
    sp = m.specular_reflectance(wi)
    assert sp.dtype == np.float32 and sp.shape == (2, 3) and np.all(sp[1] == 0)
    np.testing.assert_array_equal(m.specular_direction(np.array([0.3, 0.1, 0.9])), [-0.3, -0.1, 0.9])


def test_registry_and_parameters():
    assert "htsg" in bk.models()
    names = [r["name"] for r in bk.model_info("htsg")["params"]]
    for p in ("sigma0", "tau", "eta", "k", "wavelengths", "kd"):
        assert p in names
    with pytest.raises(ValueError, match="tau"):
        bk.model("htsg", tau=0.0)
    with pytest.raises(ValueError, match="wavelengths"):
        bk.model("htsg", wavelengths=[650, 550, 50])
    with pytest.raises(ValueError, match="sigma0"):
        bk.model("htsg", sigma0=-1)


def test_ks_scales_the_surface_reflection_not_the_uniform_diffuse():
    """ks (a fitting parameter, 1 = the 1991 model) multiplies ρ_dd and the coherent specular part."""
    rng = np.random.default_rng(91)
    wi = bk.geometry.random_unit_vectors(300, rng)
    wo = bk.geometry.random_unit_vectors(300, rng)
    base = bk.model("htsg", sigma0=0.3, tau=2.0, kd=0.2)
    scaled = bk.model("htsg", sigma0=0.3, tau=2.0, kd=0.2, ks=[0.5, 2.0, 0.0])
    ks = np.array([0.5, 2.0, 0.0])
    dd = base.eval(wi, wo) - 0.2 / np.pi
    np.testing.assert_allclose(scaled.eval(wi, wo), ks * dd + 0.2 / np.pi, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(scaled.specular_reflectance(wi), ks * base.specular_reflectance(wi), rtol=1e-13)


def test_fit_ranges_lie_inside_the_ranges():
    spec = {p.name: p for p in bk.registry.get("htsg").spec}
    for name in ("sigma0", "tau", "ks"):
        lo, hi = spec[name].fit_range
        assert spec[name].range[0] <= lo < hi <= spec[name].range[1]
    assert spec["sigma0"].fit_range[0] > 0  # σ0 = 0 is a mirror: nothing left to fit


# ---------------------------------------------------------------------------- the compiled span
def test_series_windows_fit_the_table_and_the_span_cap_over_the_parameter_range():
    """Over the whole parameter range (g ≤ (4π·2 µm/200 nm)² ≈ 1.6e4, T ≤ 4(π·100 µm/200 nm)² ≈ 1e7, scanned
    wider) the direct sum's window holds at most 86 terms, far below the span's WINDOW_CAP, and its last
    term lies inside the ln(m!·m) table (no Stirling series in range)."""
    most, last = 0.0, 0.0
    for g in np.concatenate([np.geomspace(1e-4, 40, 120), np.geomspace(40, 2e4, 120)]):
        for T in np.concatenate([[0.0], np.geomspace(1e-4, 1e8, 120)]):
            if K.asymptotic_tier(g, T):
                continue
            mc, h, jlo, jhi, peak = K.direct_window(g, T, np.log(g))
            most = max(most, jhi - jlo + 1)
            last = max(last, mc + jhi * h)
    assert 60 <= most <= 86 < K.WINDOW_CAP
    assert last < S.LN_TABLE_SIZE


def test_stirling_series_continues_the_table():
    m = np.array([S.LN_TABLE_SIZE - 2.0, S.LN_TABLE_SIZE - 1.0, 1e5, 1e7])
    want = gammaln(m + 1) + np.log(m)
    got = np.array([S.stirling_ln_fact_times_m(x) for x in m])
    np.testing.assert_allclose(got, want, rtol=1e-15)
    assert S.ln_fact_times_m(S.LN_TABLE_SIZE - 1.0) == S.LN_FACT_TIMES_M[-1]
    assert S.ln_fact_times_m(1e5) == S.stirling_ln_fact_times_m(1e5)


def _mp_log_term(m, g, T):
    """ln of the m-th term of Σ/g, (m−1) ln g − g − ln(m!·m) − T/m, in 50-digit arithmetic."""
    with mpmath.workdps(50):
        m, g, T = mpmath.mpf(m), mpmath.mpf(g), mpmath.mpf(T)
        return (m - 1) * mpmath.log(g) - g - mpmath.loggamma(m + 1) - mpmath.log(m) - T / m


def test_poisson_deviance_matches_mpmath_on_both_sides_of_its_switch():
    rng = np.random.default_rng(11)
    g = 10 ** rng.uniform(-4, 4.3, 3000)
    v = np.concatenate([rng.uniform(-0.6, 0.6, 2000), rng.uniform(-0.26, 0.26, 1000)])  # v = (m − g)/(m + g)
    m = np.maximum(np.round(g * (1 + v) / (1 - v)), 1.0)
    worst = 0.0
    with mpmath.workdps(50):
        for mi, gi in zip(m, g):
            want = mpmath.mpf(mi) * mpmath.log(mpmath.mpf(mi) / mpmath.mpf(gi)) + mpmath.mpf(gi) - mpmath.mpf(mi)
            got = S.poisson_deviance(mi, gi)
            worst = max(worst, abs(got - float(want)) / max(float(want), 1e-300))
    vv = (m - g) / (m + g)
    assert (np.abs(vv) < S.DEVIANCE_SERIES).sum() > 500 and (np.abs(vv) >= S.DEVIANCE_SERIES).sum() > 500
    assert worst < 5e-14


def test_stirling_remainder_matches_mpmath_below_and_above_the_table():
    for m in list(range(1, 40)) + [100, 1000, 32767, 1e5, 1e7]:
        with mpmath.workdps(50):
            mm = mpmath.mpf(m)
            want = mpmath.loggamma(mm + 1) - (mm + mpmath.mpf(0.5)) * mpmath.log(mm) + mm - mpmath.log(2 * mpmath.pi) / 2
        assert abs(S.stirling_remainder(float(m)) - float(want)) <= 2e-16 * max(float(want), 1e-3), m


def test_peak_term_has_no_cancellation_and_does_not_amplify_an_error_in_ln_g():
    """The peak's log term against 50-digit arithmetic where it is a difference of numbers of ~m ln m (m up to
    ~3e4): within 2e-14 plus 2e-15 of the value (bd0's plain form, |v| ≥ 0.25, cancels up to a factor ~5; the
    first form, ``(m−1) ln g − g − ln(m!·m) − T/m`` in doubles, is off by up to m ln m times the rounding,
    ~5e-11, also where the value is small); and an error of 4 ulp in ln g moves it by 4 ulp of ln g, not m
    times."""
    rng = np.random.default_rng(12)
    worst = 0.0
    for _ in range(300):
        g = 10 ** rng.uniform(-2, 4.5)
        T = g * 10 ** rng.uniform(-3, 2) if rng.random() < 0.8 else 0.0
        m = max(round(g * 10 ** rng.uniform(-0.05, 0.3)), 1)
        lg = np.log(g)
        got = K.log_term(float(m), lg, g, T)
        want = float(_mp_log_term(m, g, T))
        worst = max(worst, abs(got - want) / (1.0 + abs(want) / 10.0))  # + 2e-15 of the value itself
        moved = K.log_term(float(m), lg * (1 + 4 * 2.0**-52), g, T) - got
        assert abs(moved) <= 4 * 2.0**-52 * abs(lg) + 4 * 2.0**-52 * max(abs(lg), abs(got), 1.0)  # + the roundings
    assert worst < 2e-14


def test_span_terms_sum_each_window_whatever_the_order_of_the_pairs():
    """span_terms sorts the pairs by their counts (to 127; longer windows in any order) and stops the loop over
    pairs where the windows have ended: each pair's sum is its own window's, in any order and with counts past
    the sort's bins."""
    rng = np.random.default_rng(13)
    nb = H.SPAN_BLOCK
    for m in (nb, 37, 1):
        g = 10 ** rng.uniform(-1, 3, nb)
        T = g * 10 ** rng.uniform(-2, 1, nb)
        LG, TT, BASE, Hs, CNT, MC, LFC = (np.zeros(nb) for _ in range(7))
        for i in range(nb):
            mc, h, jlo, jhi, peak = K.direct_window(g[i], T[i], np.log(g[i]))
            LG[i], TT[i], BASE[i], Hs[i], MC[i] = np.log(g[i]), T[i], mc + jlo * h, h, mc
            CNT[i], LFC[i] = jhi - jlo + 1, S.ln_fact_times_m(mc)
        CNT[:3] = [200.0, 150.0, 0.0]  # past SORT_BINS, and an empty window
        BASE[:2] = np.maximum(MC[:2] - 20 * Hs[:2], 1.0)
        ACC = np.zeros(nb)
        K.span_terms(LG, TT, BASE, Hs, CNT, MC, LFC, ACC, m, np.empty((8, nb)), np.empty(nb, np.int64),
                     np.empty(K.SORT_BINS, np.int64))
        for i in range(nb):
            mm = BASE[i] + Hs[i] * np.arange(CNT[i] if i < m else 0)
            lf = np.array([S.ln_fact_times_m(x) for x in mm])
            want = np.exp((mm - MC[i]) * (LG[i] + TT[i] / (mm * MC[i])) - (lf - LFC[i])).sum()
            assert ACC[i] == pytest.approx(want, rel=1e-13, abs=0.0)


def test_compiled_span_keeps_parity_where_the_tail_is_ill_conditioned():
    """Far in the tail (rough, short wavelength) the terms have m up to ~1e4: the compiled span (the vector math
    library's functions, 4 ulp) agrees with the reference engine (glibc's scalar ones) to 1e-12 there, as the
    peak's term is computed without cancellation (:func:`log_term`); with ``(m−1) ln g − g − ln(m!·m)`` and
    the vector library's ln g, they differed by 1.4e-11 here."""
    from brdfkit import engine
    from brdfkit.geometry import random_unit_vectors

    m = bk.model("htsg", sigma0=1.7255399073135693, tau=32.688899503880755,
                 wavelengths=(628.6245769527334, 671.7300963791487, 210.39891750906855))
    rng = np.random.default_rng(6)
    wi, wo = random_unit_vectors(1500, rng), random_unit_vectors(1500, rng)
    old = engine.engine()
    try:
        engine.set_engine("compiled")
        c = m.eval(wi, wo)
        engine.set_engine("reference")
        r = m.eval(wi, wo)
    finally:
        engine.set_engine(old)
    nz = r > 1e-300
    assert nz.sum() > 1000 and np.all(c[~nz] <= 1e-290)
    assert np.max(np.abs(c[nz] - r[nz]) / r[nz]) < 1e-12


def test_eval_runs_the_span_driver():
    from brdfkit.engine import driver
    from brdfkit.geometry import random_unit_vectors

    m = bk.model("htsg")
    rng = np.random.default_rng(1)
    m.eval(random_unit_vectors(50, rng), random_unit_vectors(50, rng))
    assert driver._span_key(H.htsg_span) in driver._DRIVERS


def test_small_calls_run_the_per_pair_kernel_with_the_spans_values():
    """At most SPAN_MIN_PAIRS pairs run the per-pair kernel (it starts ~25 µs sooner); the values agree with the
    span's to the vector math library's rounding."""
    from brdfkit.engine import driver
    from brdfkit.geometry import random_unit_vectors

    m = bk.model("htsg", sigma0=0.6, tau=2.0)
    rng = np.random.default_rng(14)
    wi, wo = random_unit_vectors(400, rng), random_unit_vectors(400, rng)
    big = m.eval(wi, wo)
    k = driver.SPAN_MIN_PAIRS
    small = np.concatenate([m.eval(wi[i:i + k], wo[i:i + k]) for i in range(0, 400, k)])
    one = m.eval(wi[7], wo[7])
    nz = big > 1e-300
    assert nz.sum() > 500
    np.testing.assert_allclose(small[nz], big[nz], rtol=1e-12, atol=0)
    np.testing.assert_allclose(one, big[7], rtol=1e-12, atol=0)


def test_model_module_keeps_the_series_names():
    """The series and its special functions live in brdfkit.terms; the model module still offers its
    public names (the same objects, not copies), and the kernels it composes are theirs."""
    for name in ("htsg_series", "htsg_log_series_ratio", "asymptotic_coefficients", "ASYMPTOTIC_G",
                 "ASYMPTOTIC_ORDER", "ASYMPTOTIC_A_SCALE", "ASYMPTOTIC_A_POWER"):
        assert getattr(H, name) is getattr(K, name), name
    assert H.lambertw_from_log is S.lambertw_from_log
    assert H.log_series_ratio is K.log_series_ratio and H.span_terms is K.span_terms
    assert K.ln_fact_times_m is S.ln_fact_times_m and K.LN_FACT_TIMES_M is S.LN_FACT_TIMES_M
    assert set(H.__all__) <= set(dir(H))
