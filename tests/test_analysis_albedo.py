"""Directional albedo by quadrature: checked against closed forms derived independently.

Closed forms used (derivations in docs/physics.md):

* Lambert: a = kd at every angle.
* Solid angle / cosine: ∫ dω = 2π, ∫ cos θ dω = π over the hemisphere.
* A normalised cosine lobe around the mirror direction, (s+2)/(2π) (r·wo)^s: a(0) = 1.
* A normalised half-vector lobe, f = D(h) (n·h) / (4 (wo·h) cos θi): the substitution
  dωi = 4 (wo·h) dωh gives a(wo) = ∫ D(h) (n·h) dωh over the h that keep wi above the
  horizon; at θo = 0 these are θh ≤ 45°, so a(0) = 1 − exp(−1/α²) (Beckmann) and
  1/(1 + α²) (GGX); for α ≤ 0.01 and θo ≤ 80° the clipped tail is < 1e-30 (Beckmann).
* Unnormalised Phong, ks (r·v)^s / cos θi: a(0) = ks 2π/(s+1).
* Unnormalised Blinn-Phong, ks (n·h)^s / cos θi: a(0) = ks 8π (1 − 2^(−(s+2)/2)) / (s+2).
* Normalised Blinn-Phong, (s+8)/(8π) (n·h)^s: a(0) = (s+8)(s + 2^(−s/2)) / ((s+2)(s+4)).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.analysis import albedo, albedo_result, brute_force_albedo
from brdfkit.analysis.albedo import half_vector_rule, mirror_rule, polar_rule
from brdfkit.models.base import BRDF
from brdfkit.params import Param

ANGLES = np.radians([0.0, 10.0, 30.0, 45.0, 60.0, 75.0, 85.0, 89.0, 89.9])


class _MirrorLobe(BRDF):
    """Test-only: (s+2)/(2π) max(0, r·wo)^s, not registered."""

    name = "test-mirror-lobe"
    spec = (Param("s", "scalar", 10.0, (0.0, 1e6)),)

    def _eval(self, wi, wo, p):
        rv = wi[..., 2] * wo[..., 2] - wi[..., 0] * wo[..., 0] - wi[..., 1] * wo[..., 1]
        s = p["s"]
        v = np.where(rv > 0, np.power(np.maximum(rv, 0), s), 0) * (s + 2) / (2 * np.pi)
        return np.repeat(v[..., None], 3, -1)


class _HalfLobe(BRDF):
    """Test-only: D(h) (n·h) / (4 (wo·h) cos θi) with a Beckmann or GGX D."""

    name = "test-half-lobe"
    isotropic = True
    spec = (
        Param("alpha", "scalar", 0.1, (1e-4, 2.0)),
        Param("dist", "choice", "beckmann", choices=("beckmann", "ggx")),
    )

    def _eval(self, wi, wo, p):
        h = wi + wo
        h = h / np.linalg.norm(h, axis=-1, keepdims=True)
        c = h[..., 2]
        a2 = p["alpha"] ** 2
        t2 = (1 - c * c) / (c * c)
        if p["dist"] == "beckmann":
            D = np.exp(-t2 / a2) / (np.pi * a2 * c**4)
        else:
            D = a2 / (np.pi * (c * c * (a2 - 1) + 1) ** 2)
        oh = np.sum(wo * h, -1)
        v = D * c / (4 * oh * wi[..., 2])
        return np.repeat(v[..., None], 3, -1)


@pytest.mark.parametrize("rule", [half_vector_rule, mirror_rule, polar_rule])
@pytest.mark.parametrize("theta", [0.0, 0.4, 1.0, 1.4, math.radians(89.0), math.radians(89.9)])
def test_rules_integrate_solid_angle_and_cosine(rule, theta):
    wi, w = rule(theta, 0.7, 10, 80)
    assert np.all(wi[:, 2] >= -1e-12)
    np.testing.assert_allclose(np.linalg.norm(wi, axis=-1), 1.0, atol=1e-12)
    assert abs(float(np.sum(w * wi[:, 2])) - math.pi) < 1e-6
    if rule is not half_vector_rule:  # H clips the solid angle near grazing; the cosine integral is exact
        assert abs(float(np.sum(w)) - 2 * math.pi) < 1e-6


@pytest.mark.parametrize("phi", [0.0, 1.1])
def test_lambert_albedo_is_kd(phi):
    kd = np.array([0.2, 0.5, 0.9])
    a, err = albedo(bk.model("lambert", kd=kd), ANGLES, phi, return_error=True)
    assert a.shape == (len(ANGLES), 3)
    np.testing.assert_allclose(a, np.broadcast_to(kd, a.shape), atol=1e-6, rtol=0)
    assert np.all(err < 1e-6)


@pytest.mark.parametrize("s", [1.0, 50.0, 1e4])
def test_mirror_lobe_normal_incidence_is_one(s):
    a, err = albedo(_MirrorLobe(s=s), 0.0, return_error=True)
    assert abs(a[0] - 1.0) < 1e-6
    assert err < 1e-5


@pytest.mark.parametrize("alpha", [0.001, 0.01, 0.3])
def test_half_vector_lobe_beckmann_exact(alpha):
    m = _HalfLobe(alpha=alpha, dist="beckmann")
    a, err = albedo(m, 0.0, return_error=True)
    assert abs(a[0] - (1 - math.exp(-1 / alpha**2))) < 1e-6
    if alpha <= 0.01:
        a = albedo(m, np.radians([20.0, 50.0, 80.0]))
        np.testing.assert_allclose(a[:, 0], 1.0, atol=1e-6)


@pytest.mark.parametrize("alpha", [0.001, 0.05, 0.5])
def test_half_vector_lobe_ggx_exact(alpha):
    a, err = albedo(_HalfLobe(alpha=alpha, dist="ggx"), 0.0, return_error=True)
    assert abs(a[0] - 1 / (1 + alpha**2)) < 1e-5


def test_sharp_lobes_at_grazing_agree_between_levels():
    """Shininess 1e4 / alpha 1e-3 near grazing: the two quadrature levels agree to their error."""
    for m in (_MirrorLobe(s=1e4), _HalfLobe(alpha=0.001, dist="ggx")):
        th = np.radians([70.0, 85.0, 89.0])
        r1 = albedo_result(m, th, level="normal")
        r2 = albedo_result(m, th, level="fine")
        assert np.all(np.abs(r1.value - r2.value).max(-1) <= np.maximum(5 * r1.error, 1e-7))
        assert np.all(r1.value <= 1 + 1e-6)


def test_swapped_integral_differs_for_non_reciprocal():
    m = bk.model("phong", kd=0.0, ks=1.0, shininess=1.0, normalized=False)
    view = albedo(m, np.radians([0.0, 80.0]), over="wi")
    light = albedo(m, np.radians([0.0, 80.0]), over="wo")
    # at θ = 0: ∫ cos^s θi dωi = 2π/(s+1) viewed, ∫ cos^s θo cos θo dωo = 2π/(s+2) lit
    assert abs(view[0, 0] - math.pi) < 1e-6
    assert abs(light[0, 0] - 2 * math.pi / 3) < 1e-6
    # at 80° the light-side integral carries 1/cos θi: larger
    assert light[1, 0] > 1.5 * view[1, 0]


@pytest.mark.parametrize("s", [1.0, 10.0, 100.0])
def test_unnormalized_phong_closed_form(s):
    a = albedo(bk.model("phong", kd=0.0, ks=1.0, shininess=s, normalized=False), 0.0)
    assert abs(a[0] - 2 * math.pi / (s + 1)) < 1e-5


@pytest.mark.parametrize("s", [1.0, 10.0, 100.0])
def test_unnormalized_blinn_phong_closed_form(s):
    a = albedo(bk.model("blinn-phong", kd=0.0, ks=1.0, shininess=s, normalized=False), 0.0)
    exact = 8 * math.pi * (1 - 2 ** (-(s + 2) / 2)) / (s + 2)
    assert abs(a[0] - exact) < 1e-5


@pytest.mark.parametrize("s", [4.0, 12.0, 1e4])
def test_normalized_blinn_phong_closed_form(s):
    a = albedo(bk.model("blinn-phong", kd=0.0, ks=1.0, shininess=s, normalized=True), 0.0)
    exact = (s + 8) * (s + 2 ** (-s / 2)) / ((s + 2) * (s + 4))
    assert abs(a[0] - exact) < 1e-6


@pytest.mark.parametrize("theta_deg", [0.0, 40.0, 75.0])
def test_ggx_smith_albedo_matches_brute_force(theta_deg):
    m = bk.model("microfacet", distribution="ggx", alpha=0.4, shadowing="smith", fresnel="none", kd=0.0, ks=1.0)
    a = albedo(m, math.radians(theta_deg))
    ref = brute_force_albedo(m, math.radians(theta_deg), n=1000)
    np.testing.assert_allclose(a, ref, atol=1e-3)
    assert np.all(a <= 1.0)


def test_bad_angles_rejected():
    with pytest.raises(ValueError, match="theta_o"):
        albedo(bk.model("lambert"), math.pi / 2)
    with pytest.raises(ValueError, match="theta_o"):
        albedo(bk.model("lambert"), float("nan"))
    with pytest.raises(ValueError, match="over"):
        albedo(bk.model("lambert"), 0.1, over="x")


def test_albedo_adds_the_mirror_delta_of_htsg_and_schlick():
    """eval cannot return a Dirac delta: the albedo adds delta_reflectance(w) exactly once."""
    import brdfkit as bk
    from brdfkit.analysis import albedo

    th = np.radians([0.0, 40.0, 80.0])
    w = np.stack([np.sin(th), np.zeros_like(th), np.cos(th)], axis=-1)
    htsg = bk.model("htsg", sigma0=0.05)  # smooth enough for a strong coherent part
    schlick = bk.model("schlick", color=1.0, r=0.3)
    for m, delta in ((htsg, htsg.specular_reflectance(w)), (schlick, schlick.mirror_reflectance(w))):
        with_delta = albedo(m, th, level="fast")
        without = albedo(m, th, level="fast", include_delta=False)
        assert np.max(delta) > 0.05
        np.testing.assert_allclose(with_delta - without, delta, rtol=1e-12, atol=1e-15)
    lam = bk.model("lambert", kd=0.7)
    np.testing.assert_array_equal(albedo(lam, th, level="fast"), albedo(lam, th, level="fast", include_delta=False))
