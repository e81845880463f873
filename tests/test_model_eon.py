"""Tests of `oren-nayar` variant="eon" (Portsmouth, Kutz & Hill 2025): the formula by hand, the
published albedo against brdfkit's quadrature, the white furnace, reciprocity, the GLSL twin."""

from __future__ import annotations

import math

import numpy as np
import pytest

import brdfkit as bk
from _classic_helpers import assert_finite_at_all_pairs, random_upper, rotate_z, vec
from brdfkit.analysis.albedo import albedo
from brdfkit.models import eon

PI = math.pi
C1 = 0.5 - 2 / (3 * PI)
C2 = 2 / 3 - 28 / (15 * PI)


def _e_fon(mu, r):
    """The paper's closed-form albedo of its FON lobe, written as the paper prints it (tan form)."""
    th = math.acos(mu)
    si = math.sin(th)
    G = si * (th - si * mu) + 2 / 3 * ((si / mu) * (1 - si**3) - si)
    A = 1 / (1 + C1 * r)
    return A + r * A / PI * G


def _eon_by_hand(kd, r, wi, wo):
    """f_EON from the paper's formulas, directly (r > 0, directions not at the horizon)."""
    mi, mo = wi[2], wo[2]
    s = float(np.dot(wi, wo)) - mi * mo
    t = max(mi, mo) if s > 0 else 1.0
    A = 1 / (1 + C1 * r)
    f_ss = kd / PI * A * (1 + r * s / t)
    Eavg = A * (1 + C2 * r)
    rho_ms = kd * kd * Eavg / (1 - kd * (1 - Eavg))
    f_ms = rho_ms / PI * (1 - _e_fon(mi, r)) * (1 - _e_fon(mo, r)) / (1 - Eavg)
    return f_ss + f_ms


CONFIGS = [(30, 0, 60, 45), (60, 10, 30, 200), (45, 0, 45, 90), (20, 120, 70, 120), (75, 0, 40, 180), (85, 0, 88, 0)]


@pytest.mark.parametrize("cfg", CONFIGS)
@pytest.mark.parametrize("sigma", [0.1, 0.5, 1.0])
def test_eon_by_hand(cfg, sigma):
    ti, pi_, to, po = cfg
    kd = np.array([0.2, 0.6, 1.0])
    m = bk.model("oren-nayar", kd=kd, sigma=sigma, variant="eon")
    wi, wo = vec(ti, pi_), vec(to, po)
    expect = [_eon_by_hand(k, sigma, wi, wo) for k in kd]
    np.testing.assert_allclose(m.eval(wi, wo), expect, rtol=1e-10)


def test_roughness_is_sigma_clamped_at_one():
    wi, wo = random_upper(500, 31), random_upper(500, 32)
    one = bk.model("oren-nayar", kd=0.7, sigma=1.0, variant="eon").eval(wi, wo)
    for s in (1.2, 1.57):
        np.testing.assert_array_equal(bk.model("oren-nayar", kd=0.7, sigma=s, variant="eon").eval(wi, wo), one)
    assert not np.allclose(bk.model("oren-nayar", kd=0.7, sigma=0.9, variant="eon").eval(wi, wo), one)


def test_sigma_zero_is_lambert():
    wi, wo = random_upper(2000, 33), random_upper(2000, 34)
    m = bk.model("oren-nayar", kd=[0.1, 0.5, 1.0], sigma=0.0, variant="eon")
    np.testing.assert_allclose(m.eval(wi, wo), bk.model("lambert", kd=[0.1, 0.5, 1.0]).eval(wi, wo), rtol=1e-15)


def test_reciprocal_and_isotropic():
    wi, wo = random_upper(3000, 35), random_upper(3000, 36)
    m = bk.model("oren-nayar", kd=[0.3, 0.7, 1.0], sigma=0.8, variant="eon")
    f = m.eval(wi, wo)
    np.testing.assert_allclose(m.eval(wo, wi), f, rtol=1e-12)
    np.testing.assert_allclose(m.eval(rotate_z(wi, 41), rotate_z(wo, 41)), f, rtol=1e-11)
    assert np.all(f > 0)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_special_directions_are_finite_and_non_negative(dtype):
    g = 1e-300 if dtype == np.float64 else 1e-38
    D = np.array([[0, 0, 1], [1, 0, g], [-1, 0, g], [0, 1, g], [0.6, 0, 0.8], [1e-20, 0, 1], [0, 0, -1]], dtype=dtype)
    for sigma in (0.0, 0.5, 1.0, 1.5707):
        assert_finite_at_all_pairs(bk.model("oren-nayar", kd=1.0, sigma=sigma, variant="eon"), D)


# --- energy: the white furnace and the published albedo ----------------------------------------
THETAS_DEG = np.array([0.0, 20.0, 40.0, 60.0, 75.0, 85.0, 89.0])
#: |albedo − 1| allowed for kd = 1: the quadrature's own error (measured worst 3.4e-6, at 30°, where the
#: lobe has its kink s = 0 inside the hemisphere); the model itself is exact
FURNACE_TOL = 2e-5


@pytest.mark.parametrize("sigma", [0.1, 0.3, 0.6, 1.0])
def test_white_furnace(sigma):
    """kd = 1: the directional albedo is 1 at every angle up to 89° (EON preserves energy)."""
    m = bk.model("oren-nayar", kd=1.0, sigma=sigma, variant="eon")
    a = albedo(m, np.radians(THETAS_DEG))
    np.testing.assert_allclose(a, 1.0, atol=FURNACE_TOL)


def test_the_qualitative_model_loses_energy_where_eon_does_not():
    th = np.radians([60.0, 89.0])
    q = albedo(bk.model("oren-nayar", kd=1.0, sigma=1.0, variant="qualitative"), th)[:, 0]
    e = albedo(bk.model("oren-nayar", kd=1.0, sigma=1.0, variant="eon"), th)[:, 0]
    assert np.all(q < 0.9)  # the lecture's formula: 0.83 and below
    np.testing.assert_allclose(e, 1.0, atol=FURNACE_TOL)


@pytest.mark.parametrize("r", [0.2, 0.5, 1.0])
def test_published_albedo_matches_quadrature(r):
    """brdfkit's numerical albedo of the model at kd = ρ is the paper's ρ E_FON + ρ_ms (1 − E_FON);
    the FON albedo recovered from it, E = (a − ρ_ms)/(ρ − ρ_ms), equals the paper's closed form and,
    to its stated fit accuracy, the paper's polynomial approximation; the mean Ē = 2∫E μ dμ equals
    A (1 + (2/3 − 28/(15π)) r)."""
    rho = 0.5
    m = bk.model("oren-nayar", kd=rho, sigma=r, variant="eon")
    th = np.radians(THETAS_DEG)
    a = albedo(m, th)[:, 0]
    mu = np.cos(th)
    closed = np.array([eon.eon_albedo(x, r, rho) for x in mu])
    np.testing.assert_allclose(a, closed, atol=1e-5)
    e_avg = (1 + C2 * r) / (1 + C1 * r)
    rho_ms = rho * rho * e_avg / (1 - rho * (1 - e_avg))
    e_num = (a - rho_ms) / (rho - rho_ms)
    np.testing.assert_allclose(e_num, [_e_fon(x, r) for x in mu], atol=5e-5)
    np.testing.assert_allclose(e_num, [eon.fon_albedo(x, r) for x in mu], atol=5e-5)
    # the paper's fast fit (measured against the closed form: worst 4.7e-4 absolute at r = 1)
    np.testing.assert_allclose(e_num, [eon.fon_albedo_approx(x, r) for x in mu], atol=1e-3)
    # Ē by Gauss-Legendre in μ over the closed-form E (checked above against the quadrature)
    x, w = np.polynomial.legendre.leggauss(64)
    mus = 0.5 * (x + 1)
    mean = float(np.sum(0.5 * w * 2 * mus * np.array([eon.fon_albedo(v, r) for v in mus])))
    assert math.isclose(mean, e_avg, rel_tol=1e-6)


def test_eon_albedo_closed_form_is_one_for_white():
    for r in (0.0, 0.3, 1.0):
        for mu in (1.0, 0.5, 0.01):
            assert math.isclose(eon.eon_albedo(mu, r, 1.0), 1.0, rel_tol=1e-14)


# --- the GLSL twin at more parameter sets than the generated parity cases ------------------------
@pytest.mark.parametrize("params", [dict(sigma=0.05, kd=[0.2, 0.5, 0.9]), dict(sigma=0.7, kd=1.0),
                                    dict(sigma=1.3, kd=[1.0, 0.0, 0.4])])
def test_glsl_twin(params):
    pytest.importorskip("moderngl")
    from brdfkit.render import glsl
    from test_glsl_parity import assert_parity

    v = glsl.parity_vectors()
    assert_parity(bk.model("oren-nayar", variant="eon", **params), v["wi"], v["wo"], v["kind"])
