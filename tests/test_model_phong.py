"""Tests of the `phong` model: hand-worked values, limits, normalisation, reciprocity, robustness."""

from __future__ import annotations

import math

import numpy as np
import pytest

import brdfkit as bk
from _classic_helpers import albedo, assert_finite_at_all_pairs, assert_reciprocal_only_with_cosines, random_upper, vec

# light at 30° in the x-z plane, viewer at θ = 36.87° on the other side (slightly off the mirror)
WI = np.array([0.5, 0.0, math.sqrt(3) / 2])
WO = np.array([-0.6, 0.0, 0.8])


def _rv():
    # r = reflect(wi) = (-0.5, 0, √3/2); r·wo = 0.3 + 0.8·√3/2
    return 0.3 + 0.8 * math.sqrt(3) / 2


def test_normalized_value_by_hand():
    m = bk.model("phong", kd=[0.2, 0.1, 0.0], ks=0.5, shininess=10, normalized=True)
    spec = 0.5 * 12 / (2 * math.pi) * _rv() ** 10
    expect = np.array([0.2, 0.1, 0.0]) / math.pi + spec
    np.testing.assert_allclose(m.eval(WI, WO), expect, rtol=1e-13)


def test_unnormalized_value_by_hand():
    m = bk.model("phong", kd=0.2, ks=0.5, shininess=10, normalized=False)
    expect = 0.2 / math.pi + 0.5 * _rv() ** 10 / (math.sqrt(3) / 2)
    np.testing.assert_allclose(m.eval(WI, WO), [expect] * 3, rtol=1e-13)


def test_unnormalized_times_cosine_is_the_lighting_equation_term():
    # f·cos θi = ks (r·v)^s for every light above the 1e-4 floor
    m = bk.model("phong", kd=0.0, ks=0.7, shininess=5, normalized=False)
    wi = random_upper(500, 1)
    wo = random_upper(500, 2)
    rv = -wi[:, 0] * wo[:, 0] - wi[:, 1] * wo[:, 1] + wi[:, 2] * wo[:, 2]
    term = 0.7 * np.maximum(rv, 0) ** 5
    np.testing.assert_allclose(m.eval(wi, wo)[:, 0] * wi[:, 2], term, rtol=1e-12, atol=1e-300)


@pytest.mark.parametrize("normalized", [True, False])
def test_ks_zero_is_lambert(normalized):
    wi, wo = random_upper(300, 3), random_upper(300, 4)
    m = bk.model("phong", kd=[0.3, 0.6, 0.9], ks=0.0, shininess=20, normalized=normalized)
    np.testing.assert_allclose(m.eval(wi, wo), bk.model("lambert", kd=[0.3, 0.6, 0.9]).eval(wi, wo), rtol=1e-15)


@pytest.mark.parametrize("s", [0.0, 1.0, 10.0, 100.0, 1000.0])
def test_normalized_lobe_has_unit_albedo_at_normal_incidence(s):
    # ∫ (s+2)/(2π) (r·v)^s cos θo dωo = 1 for wi = n (then r = n and r·v = cos θo)
    m = bk.model("phong", kd=0.0, ks=1.0, shininess=s, normalized=True)
    a = albedo(m, np.array([0.0, 0.0, 1.0]), n_mu=600, n_phi=8)
    np.testing.assert_allclose(a, 1.0, rtol=1e-6)


@pytest.mark.parametrize("s", [1.0, 30.0])
def test_normalized_albedo_is_largest_at_normal_incidence(s):
    m = bk.model("phong", kd=0.0, ks=1.0, shininess=s, normalized=True)
    prev = 1.0 + 1e-9
    for theta in (20, 45, 70, 85):
        a = albedo(m, vec(theta, 0), n_mu=200, n_phi=400)[0]
        assert a < prev, (theta, a)
        prev = a


@pytest.mark.parametrize("s", [1.0, 10.0])
def test_unnormalized_albedo_at_normal_incidence_is_2pi_over_s_plus_2(s):
    # ∫ cos^s θ cos θ dω = 2π/(s+2): above 1 for s < 2π − 2, so not energy conserving
    m = bk.model("phong", kd=0.0, ks=1.0, shininess=s, normalized=False)
    a = albedo(m, np.array([0.0, 0.0, 1.0]), n_mu=300, n_phi=8)[0]
    assert math.isclose(a, 2 * math.pi / (s + 2), rel_tol=1e-6)


def test_unnormalized_albedo_grows_without_bound_toward_grazing():
    m = bk.model("phong", kd=0.0, ks=1.0, shininess=10, normalized=False)
    a80 = albedo(m, vec(80, 0), n_mu=200, n_phi=400)[0]
    a899 = albedo(m, vec(89.9, 0), n_mu=400, n_phi=400)[0]
    assert a899 > 1.0 and a899 > 3 * a80


def test_normalized_is_reciprocal():
    wi, wo = random_upper(1000, 5), random_upper(1000, 6)
    m = bk.model("phong", kd=0.3, ks=0.6, shininess=7.5, normalized=True)
    np.testing.assert_allclose(m.eval(wi, wo), m.eval(wo, wi), rtol=1e-12)


def test_unnormalized_is_not_reciprocal_and_breaks_it_by_the_cosine_ratio():
    m = bk.model("phong", kd=0.0, ks=1.0, shininess=3, normalized=False)
    # f(wi,wo) cos θi = f(wo,wi) cos θo = (r·v)^s
    assert_reciprocal_only_with_cosines(m, WI, WO, gap=0.05)


def test_mirror_direction_is_the_peak_value():
    m = bk.model("phong", kd=0.1, ks=0.4, shininess=1e5, normalized=True)
    wi = vec(50, 30)
    wo = np.array([-wi[0], -wi[1], wi[2]])
    np.testing.assert_allclose(m.eval(wi, wo), 0.1 / math.pi + 0.4 * (1e5 + 2) / (2 * math.pi), rtol=1e-9)


@pytest.mark.parametrize("normalized", [True, False])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_special_directions_are_finite_and_non_negative(normalized, dtype):
    g = 1e-300 if dtype == np.float64 else 1e-38
    dirs = [
        [0, 0, 1],
        [1, 0, g],
        [0.6, 0.0, 0.8],
        [-0.6, 0.0, 0.8],
        [math.sqrt(1 - g * g), 0, g],
        [-1, 0, g],
        [0.0, 1.0, 0.0],
    ]
    D = np.array(dirs, dtype=dtype)
    for s in (0.0, 1.0, 1e5):
        m = bk.model("phong", kd=0.5, ks=1.0, shininess=s, normalized=normalized)
        assert_finite_at_all_pairs(m, D)


def test_shininess_range_reaches_1e5_and_rejects_beyond():
    bk.model("phong", shininess=1e5)
    with pytest.raises(ValueError, match="shininess"):
        bk.model("phong", shininess=2e5)
