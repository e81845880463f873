"""Tests of the `blinn-phong` model: hand-worked values, limits, the (s+8)/(8π) normalisation, reciprocity."""

from __future__ import annotations

import math

import numpy as np
import pytest

import brdfkit as bk
from _classic_helpers import albedo, assert_finite_at_all_pairs, assert_reciprocal_only_with_cosines, random_upper, vec

# light at 36.87° (x-z plane), viewer on the normal: h ∝ (0.6, 0, 1.8)
WI = np.array([0.6, 0.0, 0.8])
WO = np.array([0.0, 0.0, 1.0])
NH = 1.8 / math.sqrt(0.36 + 3.24)


def test_normalized_value_by_hand():
    m = bk.model("blinn-phong", kd=[0.2, 0.4, 0.0], ks=0.5, shininess=20, normalized=True)
    spec = 0.5 * 28 / (8 * math.pi) * NH**20
    np.testing.assert_allclose(m.eval(WI, WO), np.array([0.2, 0.4, 0.0]) / math.pi + spec, rtol=1e-13)


def test_unnormalized_value_by_hand():
    m = bk.model("blinn-phong", kd=0.2, ks=0.5, shininess=20, normalized=False)
    expect = 0.2 / math.pi + 0.5 * NH**20 / 0.8
    np.testing.assert_allclose(m.eval(WI, WO), [expect] * 3, rtol=1e-13)


def test_unnormalized_times_cosine_is_the_opengl_term():
    m = bk.model("blinn-phong", kd=0.0, ks=0.9, shininess=12, normalized=False)
    wi, wo = random_upper(500, 11), random_upper(500, 12)
    h = wi + wo
    nh = h[:, 2] / np.linalg.norm(h, axis=1)
    np.testing.assert_allclose(m.eval(wi, wo)[:, 0] * wi[:, 2], 0.9 * nh**12, rtol=1e-12)


@pytest.mark.parametrize("normalized", [True, False])
def test_ks_zero_is_lambert(normalized):
    wi, wo = random_upper(300, 13), random_upper(300, 14)
    m = bk.model("blinn-phong", kd=[0.3, 0.6, 0.9], ks=0.0, shininess=20, normalized=normalized)
    np.testing.assert_allclose(m.eval(wi, wo), bk.model("lambert", kd=[0.3, 0.6, 0.9]).eval(wi, wo), rtol=1e-15)


def _normal_incidence_albedo(s):
    """Exact albedo of (s+8)/(8π)(n·h)^s at wi = n (n·h = cos(θo/2); substitute x = cos(θo/2))."""
    return (s + 8) * (2 ** (-s / 2) + s) / ((s + 2) * (s + 4))


@pytest.mark.parametrize("s", [0.0, 1.0, 4.0, 8.764, 30.0, 300.0])
def test_normalization_is_the_known_approximation_at_normal_incidence(s):
    m = bk.model("blinn-phong", kd=0.0, ks=1.0, shininess=s, normalized=True)
    a = albedo(m, np.array([0.0, 0.0, 1.0]), n_mu=800, n_phi=8)[0]
    assert math.isclose(a, _normal_incidence_albedo(s), rel_tol=1e-6)
    # what is true of (s+8)/(8π): exact at s = 0, otherwise an overshoot of at most 7.6 %
    assert 1.0 - 1e-9 <= a <= 1.0753
    if s > 0:
        assert a > 1.0


def test_normalized_albedo_falls_away_from_normal_incidence():
    m = bk.model("blinn-phong", kd=0.0, ks=1.0, shininess=30, normalized=True)
    a0 = _normal_incidence_albedo(30)
    for theta in (30, 60, 85):
        assert albedo(m, vec(theta, 0), n_mu=200, n_phi=400)[0] < a0


def test_normalized_is_reciprocal():
    wi, wo = random_upper(1000, 15), random_upper(1000, 16)
    m = bk.model("blinn-phong", kd=0.3, ks=0.6, shininess=55, normalized=True)
    np.testing.assert_allclose(m.eval(wi, wo), m.eval(wo, wi), rtol=1e-12)


def test_unnormalized_is_not_reciprocal():
    m = bk.model("blinn-phong", kd=0.0, ks=1.0, shininess=3, normalized=False)
    assert_reciprocal_only_with_cosines(m, WI, WO, gap=0.1)


@pytest.mark.parametrize("normalized", [True, False])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_special_directions_are_finite_and_non_negative(normalized, dtype):
    g = 1e-300 if dtype == np.float64 else 1e-38
    D = np.array(
        [[0, 0, 1], [1, 0, g], [-1, 0, g], [0.6, 0, 0.8], [-0.6, 0, 0.8], [0, math.sqrt(1 - g * g), g], [0, 0, -1]],
        dtype=dtype,
    )
    for s in (0.0, 2.0, 1e5):
        m = bk.model("blinn-phong", kd=0.5, ks=1.0, shininess=s, normalized=normalized)
        assert_finite_at_all_pairs(m, D)
