"""Tests of the `ashikhmin-shirley` model: the paper's formula by hand, anisotropy, reciprocity, robustness."""

from __future__ import annotations

import math

import numpy as np
import pytest

import brdfkit as bk
from _classic_helpers import albedo, assert_finite_at_all_pairs, random_upper, rotate_z, special_directions, vec


def _lobe_by_hand(wi, wo, nu, nv):
    """The anisotropic Phong lobe sqrt((nu+1)(nv+1))/(8π)·(n·h)^e/((h·k) max(n·wi, n·wo)) without
    its Fresnel factor, for one pair, in spherical angles of h; and h·k."""
    h = [wi[k] + wo[k] for k in range(3)]
    ln = math.sqrt(sum(c * c for c in h))
    h = [c / ln for c in h]
    phi_h = math.atan2(h[1], h[0])
    expo = nu * math.cos(phi_h) ** 2 + nv * math.sin(phi_h) ** 2
    hk = sum(h[k] * wi[k] for k in range(3))
    return math.sqrt((nu + 1) * (nv + 1)) / (8 * math.pi) * h[2] ** expo / (hk * max(wi[2], wo[2])), hk


def _by_hand(wi, wo, rd, rs, nu, nv):
    """Ashikhmin & Shirley 2000, ρ_s + ρ_d, for one pair and one channel, in spherical angles of h."""
    lobe, hk = _lobe_by_hand(wi, wo, nu, nv)
    F = rs + (1 - rs) * (1 - hk) ** 5
    spec = lobe * F
    diff = 28 * rd / (23 * math.pi) * (1 - rs) * (1 - (1 - wi[2] / 2) ** 5) * (1 - (1 - wo[2] / 2) ** 5)
    return spec + diff


@pytest.mark.parametrize("pair", [((35, 20), (50, 170)), ((10, 0), (15, 100)), ((70, 45), (60, 250))])
def test_value_by_hand(pair):
    (ti, pi_), (to, po) = pair
    wi, wo = vec(ti, pi_), vec(to, po)
    rd, rs = np.array([0.1, 0.5, 0.9]), np.array([0.02, 0.3, 0.9])
    m = bk.model("ashikhmin-shirley", rd=rd, rs=rs, nu=20, nv=300)
    expect = [_by_hand(wi, wo, rd[c], rs[c], 20, 300) for c in range(3)]
    np.testing.assert_allclose(m.eval(wi, wo), expect, rtol=1e-11)


def test_half_vector_on_the_normal():
    # wo = reflect(wi): h = n, (n·h)^e = 1 for any e; h·k = max(n·l, n·v) = cos θ
    wi = vec(40, 30)
    wo = np.array([-wi[0], -wi[1], wi[2]])
    c = wi[2]
    m = bk.model("ashikhmin-shirley", rd=0.0, rs=0.1, nu=50, nv=5000)
    F = 0.1 + 0.9 * (1 - c) ** 5
    expect = math.sqrt(51 * 5001) / (8 * math.pi) / (c * c) * F
    np.testing.assert_allclose(m.eval(wi, wo), [expect] * 3, rtol=1e-12)


def test_reciprocal():
    wi, wo = random_upper(2000, 41), random_upper(2000, 42)
    m = bk.model("ashikhmin-shirley", rd=0.4, rs=0.2, nu=30, nv=700)
    np.testing.assert_allclose(m.eval(wi, wo), m.eval(wo, wi), rtol=1e-12)


def test_nu_runs_along_x():
    # light 20° off the normal in x-z vs y-z, viewer on the normal: smaller nu = wider lobe in x
    m = bk.model("ashikhmin-shirley", rd=0.0, rs=0.5, nu=10, nv=1000)
    n = np.array([0.0, 0.0, 1.0])
    fx = m.eval(vec(20, 0), n)[0]
    fy = m.eval(vec(20, 90), n)[0]
    assert fx > 100 * fy
    c10 = math.cos(math.radians(10))
    assert math.isclose(fx / fy, c10**10 / c10**1000, rel_tol=1e-9)


def test_anisotropic_rotation_by_90_degrees():
    wi, wo = random_upper(500, 43), random_upper(500, 44)
    a = bk.model("ashikhmin-shirley", rd=0.3, rs=0.2, nu=10, nv=400)
    b = bk.model("ashikhmin-shirley", rd=0.3, rs=0.2, nu=400, nv=10)
    fa = a.eval(wi, wo)
    fr = a.eval(rotate_z(wi, 90), rotate_z(wo, 90))
    assert np.max(np.abs(fr - fa) / fa) > 0.5
    np.testing.assert_allclose(fr, b.eval(wi, wo), rtol=1e-10)


def test_diffuse_term_albedo_is_one_minus_the_view_factor():
    # with 28/(23π) the diffuse albedo is rd (1 − rs)(1 − (1 − cos θi/2)^5) exactly;
    # the diffuse part is isolated as f(rd = 1) − f(rd = 0)
    from _classic_helpers import hemisphere_grid

    full = bk.model("ashikhmin-shirley", rd=1.0, rs=0.2, nu=10, nv=10)
    spec = bk.model("ashikhmin-shirley", rd=0.0, rs=0.2, nu=10, nv=10)
    dirs, w = hemisphere_grid(200, 16)
    for theta in (0, 40, 75):
        wi = vec(theta, 0)[None, :]
        fd = full.eval(wi, dirs)[:, 0] - spec.eval(wi, dirs)[:, 0]
        expect = 0.8 * (1 - (1 - math.cos(math.radians(theta)) / 2) ** 5)
        assert math.isclose((w * fd).sum(), expect, rel_tol=1e-9), theta


@pytest.mark.parametrize("n", [1.0, 100.0, 1000.0])
def test_specular_albedo_at_most_one(n):
    m = bk.model("ashikhmin-shirley", rd=0.0, rs=1.0, nu=n, nv=n)
    for theta in (0, 60, 85):
        a = albedo(m, vec(theta, 0), n_mu=200, n_phi=400)[0]
        assert 0.1 < a <= 1.0 + 1e-3, (theta, a)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_special_directions_are_finite_and_non_negative(dtype):
    D = special_directions(dtype)
    for nu, nv in ((0.0, 0.0), (1e5, 1e5), (0.0, 1e5), (10.0, 100.0)):
        m = bk.model("ashikhmin-shirley", rd=1.0, rs=1.0, nu=nu, nv=nv)
        assert_finite_at_all_pairs(m, D)


# --- formula audit: ρ_s and ρ_d pinned at hand-worked points -----------------------------------
# Checked against pbrt-v3's FresnelBlend::f and the CS 184 slides; see the module docstring.


def test_audit_half_vector_on_the_normal_with_round_numbers():
    # wi = (60°, 0°), wo = (60°, 180°): h = n, h·k = 1/2, max(n·k1, n·k2) = 1/2;
    # nu = 3, nv = 15: sqrt(4·16)/(8π) = 1/π, so ρ_s = (1/π)/(1/4)·F(1/2) = 4/π·(Rs + (1 − Rs)/32);
    # ρ_d = 28 Rd/(23π)(1 − Rs)(1 − (3/4)⁵)², 1 − (3/4)⁵ = 781/1024
    rd, rs = 0.5, 0.2
    m = bk.model("ashikhmin-shirley", rd=rd, rs=rs, nu=3, nv=15)
    spec = 4 / math.pi * (rs + (1 - rs) / 32)
    diff = 28 * rd / (23 * math.pi) * (1 - rs) * (781 / 1024) ** 2
    assert math.isclose(m.eval(vec(60, 0), vec(60, 180))[0], spec + diff, rel_tol=1e-12)


@pytest.mark.parametrize("phi,expo", [(0, 10.0), (90, 40.0), (45, 25.0)])
def test_audit_anisotropic_exponent(phi, expo):
    # wo = n, wi tilted by 2·atan(0.1) at azimuth φ: h tilted by θh = atan(0.1), n·h = h·k = 1/sqrt(1.01),
    # max(n·k1, n·k2) = 1; the exponent is nu cos²φ + nv sin²φ: 10, 40, (10 + 40)/2
    rs = 0.05
    m = bk.model("ashikhmin-shirley", rd=0.0, rs=rs, nu=10, nv=40)
    c = 1 / math.sqrt(1.01)
    spec = math.sqrt(11 * 41) / (8 * math.pi) * c**expo / (c * 1.0) * (rs + (1 - rs) * (1 - c) ** 5)
    wi = vec(math.degrees(2 * math.atan(0.1)), phi)
    assert math.isclose(m.eval(wi, np.array([0.0, 0.0, 1.0]))[0], spec, rel_tol=1e-12)


# --- variant "ngan" (Ngan, Durand & Matusik 2005) ----------------------------------------------------
def _ngan_by_hand(wi, wo, kd, ks, f0, nu, nv):
    """kd/π + ks·sqrt((nu+1)(nv+1))/(8π)·(n·h)^e/((h·k) max(n·wi, n·wo))·F_schlick(f0, h·k)."""
    lobe, hk = _lobe_by_hand(wi, wo, nu, nv)
    F = f0 + (1 - f0) * (1 - hk) ** 5
    return kd / math.pi + ks * lobe * F


@pytest.mark.parametrize("pair", [((35, 20), (50, 170)), ((10, 0), (15, 100)), ((70, 45), (60, 250))])
@pytest.mark.parametrize("nu,nv", [(100.0, 100.0), (10.0, 400.0)])
def test_ngan_value_by_hand(pair, nu, nv):
    (ti, pi_), (to, po) = pair
    wi, wo = vec(ti, pi_), vec(to, po)
    kd, ks, f0 = [0.1, 0.4, 0.7], [0.3, 0.6, 2.0], [0.02, 0.5, 0.9]
    m = bk.model("ashikhmin-shirley", variant="ngan", kd=kd, ks=ks, f0=f0, nu=nu, nv=nv)
    expect = [_ngan_by_hand(wi, wo, kd[c], ks[c], f0[c], nu, nv) for c in range(3)]
    np.testing.assert_allclose(m.eval(wi, wo), expect, rtol=1e-12)


def test_ngan_with_no_lobe_is_lambert():
    wi, wo = random_upper(400, 71), random_upper(400, 72)
    m = bk.model("ashikhmin-shirley", variant="ngan", kd=[0.2, 0.5, 0.8], ks=0.0)
    np.testing.assert_allclose(m.eval(wi, wo), bk.model("lambert", kd=[0.2, 0.5, 0.8]).eval(wi, wo), rtol=1e-15)


def test_ngan_lobe_equals_the_paper_lobe_with_its_fresnel():
    """The two variants share the specular lobe: with kd = 0, ks = 1 and f0 = R_s, ngan is the paper less ρ_d."""
    wi, wo = random_upper(400, 73), random_upper(400, 74)
    kw = dict(nu=50.0, nv=300.0)
    paper_spec = bk.model("ashikhmin-shirley", rd=0.0, rs=0.3, **kw).eval(wi, wo)
    ngan = bk.model("ashikhmin-shirley", variant="ngan", kd=0.0, ks=1.0, f0=0.3, **kw).eval(wi, wo)
    np.testing.assert_allclose(ngan, paper_spec, rtol=1e-14)


def test_ngan_reciprocal_and_active_params():
    wi, wo = random_upper(1000, 75), random_upper(1000, 76)
    m = bk.model("ashikhmin-shirley", variant="ngan", kd=0.3, ks=[0.5, 1.0, 2.0], f0=0.1, nu=20.0, nv=800.0)
    np.testing.assert_allclose(m.eval(wi, wo), m.eval(wo, wi), rtol=1e-12)
    assert "rd" not in m.active_params() and "ks" in m.active_params()
    assert "ks" not in bk.model("ashikhmin-shirley").active_params()
