"""microfacet: Walter et al. 2007 with Beckmann/GGX, Smith/V-groove, four Fresnel choices."""

import cmath
import itertools
import math

import numpy as np
import pytest
from numpy.polynomial.legendre import leggauss

import brdfkit as bk
from brdfkit.geometry import random_unit_vectors, reflect
from _mitsuba_helpers import mitsuba_f_r
from _numeric_helpers import lifted_pairs

DISTS = ("beckmann", "ggx")
SHADOWS = ("smith", "smith-correlated", "v-groove")
FRESNELS = ("conductor", "dielectric", "schlick", "none")
COMBOS = list(itertools.product(DISTS, SHADOWS, FRESNELS))


# ------------------------------------------------------- scalar reference (math only)


def _ref(wi, wo, dist, ax, ay, shadowing, fresnel, eta, k, f0, kd, ks):
    """f_r for one channel, written from the papers with the math/cmath modules only."""
    hx, hy, hz = wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]
    nrm = math.sqrt(hx * hx + hy * hy + hz * hz)
    hx, hy, hz = hx / nrm, hy / nrm, hz / nrm
    # D: Walter et al. 2007 eqs. 25 and 33, anisotropic as in Heitz 2014 eqs. 71 and 85
    cos2 = hz * hz
    tan2_phi_term = (hx * hx / (ax * ax) + hy * hy / (ay * ay)) / cos2  # tan²θ (cos²φ/ax² + sin²φ/ay²)
    if dist == "beckmann":
        D = math.exp(-tan2_phi_term) / (math.pi * ax * ay * cos2 * cos2)
    else:
        D = 1.0 / (math.pi * ax * ay * cos2 * cos2 * (1 + tan2_phi_term) ** 2)

    def lam(w):
        sin_t = math.hypot(w[0], w[1])
        if sin_t == 0:
            return 0.0
        cp, sp = w[0] / sin_t, w[1] / sin_t
        alpha = math.sqrt(cp * cp * ax * ax + sp * sp * ay * ay)
        tan_t = sin_t / w[2]
        if dist == "ggx":
            return (-1 + math.sqrt(1 + alpha * alpha * tan_t * tan_t)) / 2
        a = 1 / (alpha * tan_t)
        return (math.erf(a) - 1) / 2 + math.exp(-a * a) / (2 * a * math.sqrt(math.pi))

    vh = wo[0] * hx + wo[1] * hy + wo[2] * hz
    lh = wi[0] * hx + wi[1] * hy + wi[2] * hz
    if shadowing == "smith":
        G = 1 / (1 + lam(wi)) / (1 + lam(wo))
    elif shadowing == "smith-correlated":
        G = 1 / (1 + lam(wi) + lam(wo))
    else:
        G = min(1.0, 2 * hz * wo[2] / vh, 2 * hz * wi[2] / lh)
    c = vh
    if fresnel == "conductor" or fresnel == "dielectric":
        n = complex(eta, k if fresnel == "conductor" else 0.0)
        sin_t2 = (1 - c * c) / (n * n)  # Snell with a complex index
        cos_t = cmath.sqrt(1 - sin_t2)
        rs = (c - n * cos_t) / (c + n * cos_t)
        rp = (n * c - cos_t) / (n * c + cos_t)
        F = 0.5 * (abs(rs) ** 2 + abs(rp) ** 2)
    elif fresnel == "schlick":
        F = f0 + (1 - f0) * (1 - c) ** 5
    else:
        F = 1.0
    return kd / math.pi + ks * F * D * G / (4 * wi[2] * wo[2])


def _random_pairs(n, seed, zmin=0.0):
    rng = np.random.default_rng(seed)
    wi = random_unit_vectors(n, rng)
    wo = random_unit_vectors(n, rng)
    keep = (wi[:, 2] > zmin) & (wo[:, 2] > zmin)
    return wi[keep], wo[keep]


PARAMS = dict(eta=(0.2, 1.4, 2.6), k=(3.5, 0.0, 1.2), f0=(0.9, 0.05, 0.5), kd=(0.1, 0.0, 0.3), ks=(1.0, 0.7, 0.4))


@pytest.mark.parametrize("dist,shadowing,fresnel", COMBOS)
def test_matches_scalar_reference(dist, shadowing, fresnel):
    wi, wo = _random_pairs(60, COMBOS.index((dist, shadowing, fresnel)))
    for ax, ay in [(0.3, 0.3), (0.07, 0.6)]:
        m = bk.model("microfacet", distribution=dist, alpha_x=ax, alpha_y=ay, shadowing=shadowing, fresnel=fresnel, **PARAMS)
        got = m.eval(wi, wo)
        expect = np.array(
            [
                [
                    _ref(a, b, dist, ax, ay, shadowing, fresnel, *(PARAMS[p][ch] for p in ("eta", "k", "f0", "kd", "ks")))
                    for ch in range(3)
                ]
                for a, b in zip(wi, wo)
            ]
        )
        np.testing.assert_allclose(got, expect, rtol=1e-10, atol=1e-300)


@pytest.mark.parametrize("dist,shadowing,fresnel", COMBOS)
def test_reciprocity_and_contract(dist, shadowing, fresnel):
    wi, wo = _random_pairs(2000, 7)
    for alpha in (1e-3, 0.25, 1.0):
        m = bk.model("microfacet", distribution=dist, alpha=alpha, shadowing=shadowing, fresnel=fresnel, kd=0.1)
        for dtype in (np.float64, np.float32):
            a = m.eval(wi.astype(dtype), wo.astype(dtype))
            b = m.eval(wo.astype(dtype), wi.astype(dtype))
            assert a.dtype == dtype and a.shape == wi.shape
            np.testing.assert_array_equal(a, b)  # exactly symmetric by construction
            assert np.all(np.isfinite(a)) and np.all(a >= 0)


def _edge_pairs():
    s = math.sqrt(1 - 1e-24)
    dirs = np.array(
        [[0, 0, 1], [1, 0, 0], [s, 0, 1e-12], [-s, 0, 1e-12], [0, -s, 1e-12], [0.6, 0, 0.8], [0, 0, -1],
         [1, 0, 1e-300], [-1, 0, 1e-300], [0.0, 0.6, -0.8]],
        dtype=np.float64,
    )
    wi = np.repeat(dirs, len(dirs), axis=0)
    wo = np.tile(dirs, (len(dirs), 1))
    extra = np.array([[0.6, 0, 0.8], [0.3, 0.4, math.sqrt(0.75)], [0.999, 0.0, math.sqrt(1 - 0.999**2)]])
    wi = np.concatenate([wi, extra, extra, -extra, extra])
    wo = np.concatenate([wo, extra, reflect(extra), extra, -reflect(extra)])  # ==, mirror, opposite, backwards
    return wi, wo


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_edge_directions_never_nan_inf_negative(dtype):
    wi, wo = (v.astype(dtype) for v in _edge_pairs())  # 1e-300 becomes 0 (the horizon) in float32
    below = (wi[:, 2] <= 0) | (wo[:, 2] <= 0)
    for (dist, shadowing, fresnel), (ax, ay) in itertools.product(COMBOS, [(1e-3, 1e-3), (1e-3, 1.0), (1.0, 1.0)]):
        m = bk.model("microfacet", distribution=dist, alpha_x=ax, alpha_y=ay, shadowing=shadowing, fresnel=fresnel,
                     eta=(0.01, 1.0, 10.0), k=(0.0, 0.0, 20.0), f0=(0.0, 0.5, 1.0), kd=1.0, ks=1.0)
        f = m.eval(wi, wo)
        assert f.dtype == dtype
        assert np.all(np.isfinite(f)) and np.all(f >= 0), (dist, shadowing, fresnel, ax, ay)
        assert np.all(f[below] == 0)
        assert np.all(f[~below] >= 1 / np.pi * (1 - 1e-6))  # the kd = 1 floor survives everywhere


def test_mirror_peak_value():
    # wi = reflect(wo): h = n, D = 1/(π α²), F at c = cos θ; Smith G1 from Λ at θ
    th = math.radians(35)
    wo = np.array([math.sin(th), 0, math.cos(th)])
    wi = reflect(wo)
    a = 0.01
    for dtype in (np.float64, np.float32):
        m = bk.model("microfacet", distribution="ggx", alpha=a, fresnel="none", shadowing="smith")
        f = m.eval(wi.astype(dtype), wo.astype(dtype))
        lam = (-1 + math.sqrt(1 + a * a * math.tan(th) ** 2)) / 2
        expect = (1 / (math.pi * a * a)) / (1 + lam) ** 2 / (4 * math.cos(th) ** 2)
        np.testing.assert_allclose(f, [expect] * 3, rtol=1e-12 if dtype == np.float64 else 1e-5)


def test_float32_close_to_float64():
    wi, wo = _random_pairs(3000, 21, zmin=0.05)
    for dist, shadowing, fresnel in COMBOS[::2]:
        m = bk.model("microfacet", distribution=dist, alpha_x=0.1, alpha_y=0.3, shadowing=shadowing, fresnel=fresnel)
        a = m.eval(wi, wo)
        b = m.eval(wi.astype(np.float32), wo.astype(np.float32))
        np.testing.assert_allclose(b, a, rtol=1e-3, atol=1e-6 * a.max())


# ------------------------------------------------------------- energy (quadrature)


def _albedo(m, theta_o, n_t=96, n_p=96):
    """∫ f cos θi dωi, integrated over half vectors: dωi = 4 (wo·h) dωh."""
    wo = np.array([math.sin(theta_o), 0.0, math.cos(theta_o)])
    a = m.params["alpha_x"]
    x, w = leggauss(n_t)
    psi = 0.25 * np.pi * (x + 1)  # tan θh = a tan ψ, ψ in [0, π/2)
    wpsi = 0.25 * np.pi * w
    t = a * np.tan(psi)
    th = np.arctan(t)
    jac = a / np.cos(psi) ** 2 / (1 + t * t)
    xp, wp = leggauss(n_p)
    ph = np.pi * (xp + 1)
    wph = np.pi * wp
    TH, PH = np.meshgrid(th, ph, indexing="ij")
    h = np.stack([np.sin(TH) * np.cos(PH), np.sin(TH) * np.sin(PH), np.cos(TH)], -1)
    vh = h @ wo
    wi = 2 * vh[..., None] * h - wo
    f = m.eval(wi, np.broadcast_to(wo, wi.shape))[..., 0]
    integrand = f * np.maximum(wi[..., 2], 0) * 4 * np.maximum(vh, 0) * np.sin(TH) * jac[:, None]
    return float(np.sum(integrand * wpsi[:, None] * wph[None, :]))


@pytest.mark.parametrize("dist", DISTS)
def test_energy_conservation_without_fresnel(dist):
    for shadowing in ("smith", "smith-correlated"):
        for a in (0.05, 0.5, 1.0):
            m = bk.model("microfacet", distribution=dist, alpha=a, shadowing=shadowing, fresnel="none", kd=0.0)
            alb = [_albedo(m, th) for th in (0.0, 0.6, 1.2, 1.5)]
            assert max(alb) <= 1.0 + 2e-3, (shadowing, a, alb)
            if a == 0.05:
                assert alb[0] > 0.99  # a smooth surface loses (almost) nothing to masking at normal incidence


# ----------------------------------------------------------------- parameters


def test_roughness_rule_and_params():
    m = bk.model("microfacet")
    p = m.params
    for name in ("distribution", "alpha", "alpha_x", "alpha_y", "shadowing", "fresnel", "eta", "k", "f0", "kd", "ks"):
        assert name in p
    assert p["alpha"] == p["alpha_x"] == p["alpha_y"] and m.isotropic

    iso = bk.model("microfacet", alpha=0.3)
    assert iso.params["alpha_x"] == iso.params["alpha_y"] == 0.3
    an = bk.model("microfacet", alpha_x=0.1, alpha_y=0.4)
    assert an.params["alpha"] is None and not an.isotropic
    assert bk.model("microfacet", alpha_x=0.05).params["alpha_y"] == p["alpha_y"]  # the other keeps its default
    # round trips
    assert bk.model("microfacet", **an.params).params["alpha_y"] == 0.4
    assert bk.model("microfacet", **iso.params).params["alpha"] == 0.3
    assert an.with_params(alpha=0.2).params["alpha_x"] == 0.2
    assert iso.with_params(alpha_y=0.6).params["alpha"] is None
    # alpha together with a different alpha_x is refused, naming both
    with pytest.raises(ValueError, match="alpha.*alpha_x"):
        bk.model("microfacet", alpha=0.1, alpha_x=0.2)
    with pytest.raises(ValueError, match="'alpha_y'.*allowed"):
        bk.model("microfacet", alpha_y=0.0)
    with pytest.raises(ValueError, match="beckmann, ggx"):
        bk.model("microfacet", distribution="phong")
    with pytest.raises(ValueError, match="smith-correlated"):
        bk.model("microfacet", shadowing="torrance")
    info = bk.model_info("microfacet")
    assert info["isotropic"] is False and "Walter" in info["reference"]


def test_anisotropy_axis_is_tangent():
    # With alpha_x > alpha_y the lobe is wider along x: a half vector tilted along x sees more D.
    m = bk.model("microfacet", alpha_x=0.4, alpha_y=0.05, fresnel="none")
    wo = np.array([0.0, 0.0, 1.0])
    tilt = math.radians(20)
    wi_x = np.array([math.sin(tilt), 0, math.cos(tilt)])
    wi_y = np.array([0, math.sin(tilt), math.cos(tilt)])
    assert m.eval(wi_x, wo)[0] > 100 * m.eval(wi_y, wo)[0]
    swapped = bk.model("microfacet", alpha_x=0.05, alpha_y=0.4, fresnel="none")
    np.testing.assert_allclose(swapped.eval(wi_y, wo), m.eval(wi_x, wo), rtol=1e-12)


# ---------------------------------------------------------------- Mitsuba 3


def _mitsuba_eval(mi, dist, ax, ay, eta, k, wi, wo):
    """Mitsuba's roughconductor f_r (brdfkit's naming; see _mitsuba_helpers.mitsuba_f_r)."""
    return mitsuba_f_r(mi, {
        "type": "roughconductor", "distribution": dist, "alpha_u": ax, "alpha_v": ay,
        "eta": {"type": "rgb", "value": list(map(float, eta))},
        "k": {"type": "rgb", "value": list(map(float, k))},
    }, wi, wo)


MI_CASES = [(0.3, 0.3), (0.05, 0.05), (0.8, 0.8), (0.1, 0.5), (0.6, 0.15)]  # (alpha_u along +x, alpha_v)


def _mi_setup(seed):
    rng = np.random.default_rng(seed)
    wi, wo = _random_pairs(500, seed, zmin=0.02)
    eta = rng.uniform(0.1, 2.5, 3)
    k = rng.uniform(0.0, 5.0, 3)
    return wi, wo, eta, k


@pytest.mark.parametrize("ax,ay", MI_CASES)
def test_ggx_matches_mitsuba_roughconductor(mi, ax, ay):
    wi, wo, eta, k = _mi_setup(int(ax * 100 + ay * 10))
    ours = bk.model("microfacet", distribution="ggx", alpha_x=ax, alpha_y=ay, shadowing="smith",
                    fresnel="conductor", eta=eta, k=k).eval(wi, wo)
    theirs = _mitsuba_eval(mi, "ggx", ax, ay, eta, k, wi, wo)
    # Mitsuba's scalar_rgb computes in float32; measured max relative difference ~1.5e-5
    np.testing.assert_allclose(ours, theirs, rtol=1e-4, atol=1e-9)


def _beckmann_g1_walter_rational(w, ax, ay):
    """Walter et al. 2007 eq. 27's rational approximation of the Beckmann Smith G1 (what Mitsuba uses)."""
    s = np.sqrt((w[:, 0] * ax) ** 2 + (w[:, 1] * ay) ** 2)
    a = w[:, 2] / s
    return np.where(a >= 1.6, 1.0, (3.535 * a + 2.181 * a * a) / (1 + 2.276 * a + 2.577 * a * a))


@pytest.mark.parametrize("ax,ay", MI_CASES)
def test_beckmann_matches_mitsuba_roughconductor(mi, ax, ay):
    from brdfkit.terms.distributions import beckmann
    from brdfkit.terms.fresnel import fresnel_conductor

    wi, wo, eta, k = _mi_setup(int(ax * 100 + ay * 10) + 1)
    theirs = _mitsuba_eval(mi, "beckmann", ax, ay, eta, k, wi, wo)
    # (a) our D and conductor F with Mitsuba's rational G1 reproduce Mitsuba to float32 precision
    h = wi + wo
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    c = np.sum(wo * h, -1)
    g = _beckmann_g1_walter_rational(wi, ax, ay) * _beckmann_g1_walter_rational(wo, ax, ay)
    approx = fresnel_conductor(c[:, None], eta, k) * (beckmann(h, ax, ay) * g / (4 * wi[:, 2] * wo[:, 2]))[:, None]
    np.testing.assert_allclose(approx, theirs, rtol=1e-4, atol=1e-9)
    # (b) the model (exact erf Λ) differs only by the approximation's error: at most 0.32 % per G1
    # (max over a of |rational/exact − 1|, 0.313 % at a ≈ 1.34), so < 0.7 % for the product
    ours = bk.model("microfacet", distribution="beckmann", alpha_x=ax, alpha_y=ay, shadowing="smith",
                    fresnel="conductor", eta=eta, k=k).eval(wi, wo)
    np.testing.assert_allclose(ours, theirs, rtol=7e-3, atol=1e-9)
    np.testing.assert_allclose(ours, approx, rtol=7e-3, atol=1e-12)


@pytest.mark.parametrize("fresnel", ["conductor", "dielectric", "schlick", "none"])
def test_active_params_leave_out_exactly_what_changes_nothing(fresnel):
    """A parameter missing from active_params() must not change eval; every rgb one kept must."""
    import brdfkit as bk

    wi, wo = lifted_pairs(200, seed=3, lift=0.1)
    m = bk.model("microfacet", fresnel=fresnel, eta=1.7, k=2.0, f0=0.3)
    base = m.eval(wi, wo)
    active = m.active_params()
    assert "alpha" in active and "alpha_x" not in active
    for name, other in (("eta", 2.5), ("k", 0.5), ("f0", 0.8)):
        changed = m.with_params(**{name: other}).eval(wi, wo)
        if name in active:
            assert np.max(np.abs(changed - base)) > 1e-6, name
        else:
            np.testing.assert_array_equal(changed, base)
    aniso = bk.model("microfacet", alpha_x=0.1, alpha_y=0.3)
    assert "alpha" not in aniso.active_params() and "alpha_x" in aniso.active_params()
