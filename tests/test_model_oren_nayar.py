"""Tests of the `oren-nayar` model: both variants by hand, the Lambert limit, reciprocity, robustness."""

from __future__ import annotations

import math

import numpy as np
import pytest

import brdfkit as bk
from _classic_helpers import assert_finite_at_all_pairs, random_upper, rotate_z, special_directions, vec

PI = math.pi


def _qualitative(kd, sigma, ti, to, dphi):
    """The lecture's formula divided by E0 cos θi (angles in degrees)."""
    s2 = sigma * sigma
    A = 1 - 0.5 * s2 / (s2 + 0.33)
    B = 0.45 * s2 / (s2 + 0.09)
    a, b = math.radians(max(ti, to)), math.radians(min(ti, to))
    return kd / PI * (A + B * max(0.0, math.cos(math.radians(dphi))) * math.sin(a) * math.tan(b))


def _full(kd, sigma, ti, to, dphi):
    """Oren & Nayar 1994, L1 + L2 divided by E0 cos θi (angles in degrees)."""
    s2 = sigma * sigma
    a, b = math.radians(max(ti, to)), math.radians(min(ti, to))
    c = math.cos(math.radians(dphi))
    C1 = 1 - 0.5 * s2 / (s2 + 0.33)
    if c >= 0:
        C2 = 0.45 * s2 / (s2 + 0.09) * math.sin(a)
    else:
        C2 = 0.45 * s2 / (s2 + 0.09) * (math.sin(a) - (2 * b / PI) ** 3)
    C3 = 0.125 * s2 / (s2 + 0.09) * (4 * a * b / PI**2) ** 2
    L1 = kd / PI * (C1 + c * C2 * math.tan(b) + (1 - abs(c)) * C3 * math.tan((a + b) / 2))
    L2 = 0.17 * kd * kd / PI * s2 / (s2 + 0.13) * (1 - c * (2 * b / PI) ** 2)
    return L1 + L2


CONFIGS = [  # (θi, φi, θo, φo) in degrees
    (30, 0, 60, 45),
    (60, 10, 30, 200),  # cos Δφ < 0: the other branch of C2
    (45, 0, 45, 90),  # cos Δφ = 0
    (20, 120, 70, 120),  # same azimuth
    (75, 0, 40, 180),  # opposite azimuths
]


@pytest.mark.parametrize("cfg", CONFIGS)
@pytest.mark.parametrize("sigma", [0.2, 0.5, 1.0])
def test_qualitative_by_hand(cfg, sigma):
    ti, pi_, to, po = cfg
    m = bk.model("oren-nayar", kd=0.7, sigma=sigma, variant="qualitative")
    expect = _qualitative(0.7, sigma, ti, to, po - pi_)
    np.testing.assert_allclose(m.eval(vec(ti, pi_), vec(to, po)), [expect] * 3, rtol=1e-12)


@pytest.mark.parametrize("cfg", CONFIGS)
@pytest.mark.parametrize("sigma", [0.2, 0.5, 1.0])
def test_full_by_hand(cfg, sigma):
    ti, pi_, to, po = cfg
    kd = np.array([0.2, 0.5, 0.9])
    m = bk.model("oren-nayar", kd=kd, sigma=sigma, variant="full")
    expect = [_full(k, sigma, ti, to, po - pi_) for k in kd]
    np.testing.assert_allclose(m.eval(vec(ti, pi_), vec(to, po)), expect, rtol=1e-12)


def test_full_interreflection_is_quadratic_in_kd():
    # f = kd·g1 + kd²·g2: the ratio f(kd=1)/f(kd=0.5) is 2·(g1+g2)/(g1+g2/2) — not 2
    wi, wo = vec(40, 0), vec(50, 30)
    f1 = bk.model("oren-nayar", kd=1.0, sigma=0.8, variant="full").eval(wi, wo)[0]
    f5 = bk.model("oren-nayar", kd=0.5, sigma=0.8, variant="full").eval(wi, wo)[0]
    assert f1 / f5 > 2.0 + 1e-3


@pytest.mark.parametrize("variant", ["qualitative", "full"])
def test_sigma_zero_is_lambert(variant):
    wi, wo = random_upper(2000, 21), random_upper(2000, 22)
    m = bk.model("oren-nayar", kd=[0.1, 0.5, 1.0], sigma=0.0, variant=variant)
    np.testing.assert_allclose(m.eval(wi, wo), bk.model("lambert", kd=[0.1, 0.5, 1.0]).eval(wi, wo), rtol=1e-15)


@pytest.mark.parametrize("variant", ["qualitative", "full"])
def test_reciprocal(variant):
    wi, wo = random_upper(2000, 23), random_upper(2000, 24)
    m = bk.model("oren-nayar", kd=0.8, sigma=0.7, variant=variant)
    np.testing.assert_allclose(m.eval(wi, wo), m.eval(wo, wi), rtol=1e-12)


@pytest.mark.parametrize("variant", ["qualitative", "full"])
def test_isotropic_under_rotation(variant):
    wi, wo = random_upper(500, 25), random_upper(500, 26)
    m = bk.model("oren-nayar", kd=0.8, sigma=0.7, variant=variant)
    np.testing.assert_allclose(m.eval(rotate_z(wi, 73), rotate_z(wo, 73)), m.eval(wi, wo), rtol=1e-11)


def test_normal_incidence_does_not_depend_on_the_undefined_azimuth():
    n = np.array([0.0, 0.0, 1.0])
    s2 = 0.6**2
    for variant in ("qualitative", "full"):
        m = bk.model("oren-nayar", kd=0.5, sigma=0.6, variant=variant)
        vals = np.array([m.eval(n, vec(50, phi))[0] for phi in (0, 45, 90, 180, 270)])
        vals_rev = np.array([m.eval(vec(50, phi), n)[0] for phi in (0, 45, 90, 180, 270)])
        C1 = 1 - 0.5 * s2 / (s2 + 0.33)
        expect = 0.5 / PI * C1
        if variant == "full":
            expect += 0.17 * 0.25 / PI * s2 / (s2 + 0.13)
        np.testing.assert_allclose(vals, expect, rtol=1e-13)
        np.testing.assert_allclose(vals_rev, expect, rtol=1e-13)


def test_full_negative_bracket_is_clamped_to_zero():
    # σ = 1.5, θ = 80° and 89°, Δφ = π: C1 + cos Δφ C2 tan β < 0 in the formula
    s2 = 1.5**2
    a, b = math.radians(89), math.radians(80)
    C1 = 1 - 0.5 * s2 / (s2 + 0.33)
    C2 = 0.45 * s2 / (s2 + 0.09) * (math.sin(a) - (2 * b / PI) ** 3)
    assert C1 - C2 * math.tan(b) < 0  # the raw bracket really is negative here
    m = bk.model("oren-nayar", kd=0.3, sigma=1.5, variant="full")
    f = m.eval(vec(80, 0), vec(89, 180))[0]
    L2 = 0.17 * 0.09 / PI * s2 / (s2 + 0.13) * (1 + (2 * b / PI) ** 2)
    assert math.isclose(f, L2, rel_tol=1e-12)


@pytest.mark.parametrize("variant", ["qualitative", "full"])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_special_directions_are_finite_and_non_negative(variant, dtype):
    D = special_directions(dtype)
    for sigma in (0.0, 0.5, 1.5707):
        m = bk.model("oren-nayar", kd=1.0, sigma=sigma, variant=variant)
        assert_finite_at_all_pairs(m, D)


def test_sigma_range():
    bk.model("oren-nayar", sigma=1.57)
    with pytest.raises(ValueError, match="sigma"):
        bk.model("oren-nayar", sigma=math.pi / 2)
    with pytest.raises(ValueError, match="variant"):
        bk.model("oren-nayar", variant="nope")


# --- formula audit: the paper's constants pinned at hand-worked points -------------------------
# Checked against the restatement in the appendix "Oren-Nayar Diffuse Reflectance Model" and
# Mitsuba 0.5's roughdiffuse.cpp (see the module docstring). σ = 0.5 (σ² = 0.25), θi = 60°,
# θo = 30°: α = π/3, β = π/6, sin α = √3/2, tan β = 1/√3, 2β/π = 1/3, 4αβ/π² = 2/9.
_S2 = 0.25
_C1 = 1 - 0.5 * _S2 / (_S2 + 0.33)  # 1 − 0.125/0.58
_K2 = 0.45 * _S2 / (_S2 + 0.09)  # 0.1125/0.34, C2 without its angular factor
_K3 = 0.125 * _S2 / (_S2 + 0.09)  # 0.03125/0.34, C3 without (4αβ/π²)²
_K4 = 0.17 * _S2 / (_S2 + 0.13)  # 0.0425/0.38, the interreflection coefficient


def test_audit_hand_constants():
    assert math.isclose(_C1, 0.7844827586206897, rel_tol=1e-15)
    assert math.isclose(_K2, 0.33088235294117646, rel_tol=1e-15)
    assert math.isclose(_K3, 0.09191176470588235, rel_tol=1e-15)
    assert math.isclose(_K4, 0.11184210526315788, rel_tol=1e-15)


@pytest.mark.parametrize(
    "dphi,full_bracket,l2_bracket,qual_bracket",
    [
        # cos Δφ = 0: only C1 and C3 tan((α+β)/2) = C3 tan 45° = C3 survive; L2 bracket 1
        (90, _C1 + _K3 * (2 / 9) ** 2, 1.0, _C1),
        # cos Δφ = 1: C2 = K2 sin α, C2 tan β = K2/2; C3 is multiplied by 1 − |cos| = 0; L2: 1 − 1/9
        (0, _C1 + _K2 / 2, 8 / 9, _C1 + _K2 / 2),
        # cos Δφ = −1: C2 = K2 (sin α − (1/3)³), minus C2 tan β = K2 (1/2 − 1/(27√3)); L2: 1 + 1/9
        (180, _C1 - _K2 * (0.5 - 1 / (27 * math.sqrt(3))), 10 / 9, _C1),
    ],
)
def test_audit_paper_formula_at_hand_worked_points(dphi, full_bracket, l2_bracket, qual_bracket):
    rho = 0.6
    wi, wo = vec(60, 0), vec(30, dphi)
    full = bk.model("oren-nayar", kd=rho, sigma=0.5, variant="full").eval(wi, wo)[0]
    assert math.isclose(full, rho / PI * full_bracket + rho * rho / PI * _K4 * l2_bracket, rel_tol=1e-12)
    qual = bk.model("oren-nayar", kd=rho, sigma=0.5, variant="qualitative").eval(wi, wo)[0]
    assert math.isclose(qual, rho / PI * qual_bracket, rel_tol=1e-12)
