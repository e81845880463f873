"""Tests of the `schlick` model (Schlick 1994): the formulas by hand, the slab types, anisotropy, reciprocity."""

from __future__ import annotations

import math

import numpy as np
import pytest

import brdfkit as bk
from _classic_helpers import albedo, assert_finite_at_all_pairs, random_upper, rotate_z, special_directions, vec


def _slab_by_hand(wi, wo, C, r, p):
    """S(u)·[a/π + b·G(v)G(v')Z(t)A(w)/(4π v v')] for one pair and one channel (Schlick 1994 §5)."""
    h = [wi[k] + wo[k] for k in range(3)]
    ln = math.sqrt(sum(c * c for c in h))
    h = [c / ln for c in h]
    t = h[2]
    u = sum(h[k] * wi[k] for k in range(3))
    v, v2 = wi[2], wo[2]
    w = h[0] / math.hypot(h[0], h[1])
    S = C + (1 - C) * (1 - u) ** 5
    Z = r / (1 + r * t * t - t * t) ** 2
    A = math.sqrt(p / (p * p - p * p * w * w + w * w))
    G = lambda x: x / (r - r * x + x)  # noqa: E731
    b = 4 * r * (1 - r)
    a = 0.0 if r < 0.5 else 1 - b
    return S * (a / math.pi + b * G(v) * G(v2) * Z * A / (4 * math.pi * v * v2)), S


PAIRS = [(vec(30, 10), vec(45, 200)), (vec(60, 80), vec(20, 300)), (vec(5, 0), vec(70, 135))]


@pytest.mark.parametrize("pair", PAIRS)
@pytest.mark.parametrize("r,p", [(0.2, 0.4), (0.5, 1.0), (0.7, 0.9), (0.05, 0.05)])
def test_single_slab_by_hand(pair, r, p):
    wi, wo = pair
    C = np.array([0.9, 0.5, 0.1])
    m = bk.model("schlick", layers="single", color=C, r=r, p=p)
    expect = [_slab_by_hand(wi, wo, c, r, p)[0] for c in C]
    np.testing.assert_allclose(m.eval(wi, wo), expect, rtol=1e-11)


@pytest.mark.parametrize("pair", PAIRS)
def test_double_slab_by_hand(pair):
    wi, wo = pair
    top, S = _slab_by_hand(wi, wo, 0.04, 0.1, 1.0)
    bottom, S2 = _slab_by_hand(wi, wo, 0.6, 0.8, 0.5)
    m = bk.model("schlick", layers="double", color=0.04, r=0.1, p=1.0, color2=0.6, r2=0.8, p2=0.5)
    np.testing.assert_allclose(m.eval(wi, wo), [top + (1 - S) * bottom] * 3, rtol=1e-11)


def test_double_slab_is_top_plus_transmitted_bottom():
    wi, wo = random_upper(300, 51), random_upper(300, 52)
    kw_top = dict(color=[0.05, 0.04, 0.03], r=0.15, p=0.7)
    kw_bot = dict(color=[0.8, 0.3, 0.1], r=0.9, p=1.0)
    top = bk.model("schlick", **kw_top).eval(wi, wo)
    bot = bk.model("schlick", **kw_bot).eval(wi, wo)
    h = wi + wo
    u = np.sum(wi * h, axis=1) / np.linalg.norm(h, axis=1)
    S = np.array(kw_top["color"]) + (1 - np.array(kw_top["color"])) * ((1 - u) ** 5)[:, None]
    d = bk.model(
        "schlick", layers="double", **kw_top, color2=kw_bot["color"], r2=kw_bot["r"], p2=kw_bot["p"]
    ).eval(wi, wo)
    np.testing.assert_allclose(d, top + (1 - S) * bot, rtol=1e-11)


def test_r_one_with_white_colour_is_lambert():
    wi, wo = random_upper(500, 53), random_upper(500, 54)
    m = bk.model("schlick", color=1.0, r=1.0, p=0.3)
    np.testing.assert_allclose(m.eval(wi, wo), bk.model("lambert", kd=1.0).eval(wi, wo), rtol=1e-15)


@pytest.mark.parametrize("layers", ["single", "double"])
def test_reciprocal(layers):
    wi, wo = random_upper(2000, 55), random_upper(2000, 56)
    m = bk.model("schlick", layers=layers, color=[0.1, 0.5, 0.9], r=0.25, p=0.3, color2=0.7, r2=0.6, p2=0.5)
    np.testing.assert_allclose(m.eval(wi, wo), m.eval(wo, wi), rtol=1e-12)


def test_isotropic_when_p_is_one():
    wi, wo = random_upper(300, 57), random_upper(300, 58)
    m = bk.model("schlick", r=0.2, p=1.0)
    np.testing.assert_allclose(m.eval(rotate_z(wi, 37), rotate_z(wo, 37)), m.eval(wi, wo), rtol=1e-11)


def test_isotropy_p_stretches_the_highlight_along_y():
    # same tilt of h toward +x and toward +y: A(w=1) = sqrt(p), A(w=0) = 1/sqrt(p), ratio 1/p
    m = bk.model("schlick", color=0.5, r=0.2, p=0.2)
    n = np.array([0.0, 0.0, 1.0])
    fx = m.eval(vec(20, 0), n)[0]
    fy = m.eval(vec(20, 90), n)[0]
    assert math.isclose(fy / fx, 1 / 0.2, rel_tol=1e-10)
    wi, wo = random_upper(300, 59), random_upper(300, 60)
    f = m.eval(wi, wo)
    fr = m.eval(rotate_z(wi, 90), rotate_z(wo, 90))
    assert np.max(np.abs(fr - f) / f) > 0.5


def test_mirror_reflectance():
    n = np.array([0.0, 0.0, 1.0])
    m = bk.model("schlick", color=0.5, r=0.3)
    c = 1 - 4 * 0.3 * 0.7
    np.testing.assert_allclose(m.mirror_reflectance(n), [0.5 * c] * 3, rtol=1e-14)
    np.testing.assert_allclose(m.mirror_reflectance(vec(60, 0)), [c * (0.5 + 0.5 * 0.5**5)] * 3, rtol=1e-12)
    assert np.all(bk.model("schlick", r=0.5).mirror_reflectance(n) == 0)
    assert np.all(bk.model("schlick", r=0.9).mirror_reflectance(n) == 0)
    assert np.all(m.mirror_reflectance(np.array([0.0, 0.0, -1.0])) == 0)
    d = bk.model("schlick", layers="double", color=0.04, r=0.1, color2=0.6, r2=0.2)
    c1, c2 = 1 - 4 * 0.1 * 0.9, 1 - 4 * 0.2 * 0.8
    np.testing.assert_allclose(d.mirror_reflectance(n), [0.04 * c1 + 0.96 * 0.6 * c2] * 3, rtol=1e-13)


@pytest.mark.parametrize("r", [0.05, 0.3, 0.5, 0.8])
@pytest.mark.parametrize("p", [1.0, 0.3])
def test_albedo_including_mirror_part_at_most_one_up_to_60_degrees(r, p):
    m = bk.model("schlick", color=1.0, r=r, p=p)
    for theta in (0, 30, 60):
        wi = vec(theta, 0)
        a = albedo(m, wi, n_mu=150, n_phi=300)[0] + m.mirror_reflectance(wi)[0]
        assert 0.1 < a <= 1.0 + 1e-3, (theta, a)


def test_albedo_overshoots_at_grazing_for_small_roughness():
    # what is true: with r = 0.05 (81 % mirror part) the glossy part's albedo rises toward
    # grazing incidence (Schlick's G approximation) and the total exceeds 1
    m = bk.model("schlick", color=1.0, r=0.05, p=1.0)
    wi = vec(89, 0)
    a = albedo(m, wi, n_mu=300, n_phi=600)[0] + m.mirror_reflectance(wi)[0]
    assert 1.05 < a < 1.2


@pytest.mark.parametrize("layers", ["single", "double"])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_special_directions_are_finite_and_non_negative(layers, dtype):
    D = special_directions(dtype)
    for r, p in ((1e-6, 1e-6), (1.0, 1.0), (0.5, 1e-6), (1e-6, 1.0)):
        m = bk.model("schlick", layers=layers, color=1.0, r=r, p=p, color2=1.0, r2=r, p2=p)
        assert_finite_at_all_pairs(m, D)


# --- formula audit: S, Z, G and the glossy product pinned at a hand-worked point ---------------
# S, Z, A, G and G G' Z A/(4π v v') checked against LuxCoreRender, RISE and a digest of the paper;
# the a/b/c split is NOT verified against the paper (see the module docstring).


@pytest.mark.parametrize(
    "r,D_times_pi",
    [
        (0.25, 0.75 / (0.25 * 1.25**2)),  # b = 0.75, a = 0: 1.92
        (0.5, 1.0 / (0.5 * 1.5**2)),  # b = 1, a = 0: 8/9
        (0.75, 0.25 + 0.75 / (0.75 * 1.75**2)),  # b = 0.75, a = 0.25
    ],
)
def test_audit_single_slab_with_the_half_vector_on_the_normal(r, D_times_pi):
    # wi = (60°, 0°), wo = (60°, 180°): h = n, so t = 1, u = v = v' = 1/2, Z(1) = r/r² = 1/r,
    # G(1/2) = (1/2)/(r − r/2 + 1/2) = 1/(1 + r), A = 1 (p = 1), S(1/2) = C + (1 − C)/32, and
    # D = a/π + b·G²·Z/(4π·1/4) = (a + b/(r (1 + r)²))/π
    C = 0.3
    m = bk.model("schlick", color=C, r=r, p=1.0)
    expect = (C + (1 - C) / 32) * D_times_pi / math.pi
    assert math.isclose(m.eval(vec(60, 0), vec(60, 180))[0], expect, rel_tol=1e-12)


def test_audit_double_slab_with_the_half_vector_on_the_normal():
    # same geometry: f = S·D + (1 − S)·S'·D' with the top slab (0.04, r = 0.25) and the bottom (0.6, r' = 0.5)
    S, S2 = 0.04 + 0.96 / 32, 0.6 + 0.4 / 32
    D, D2 = 1.92 / math.pi, (8 / 9) / math.pi
    m = bk.model("schlick", layers="double", color=0.04, r=0.25, p=1.0, color2=0.6, r2=0.5, p2=1.0)
    assert math.isclose(m.eval(vec(60, 0), vec(60, 180))[0], S * D + (1 - S) * S2 * D2, rel_tol=1e-12)


# --- issue 14: Z and A guarded down to the smallest positive float --------------------------------
TINY64 = float(np.finfo(np.float64).smallest_subnormal)
TINY32 = float(np.finfo(np.float32).smallest_subnormal)


@pytest.mark.parametrize("r", [1e-170, 1e-300, TINY64])
def test_tiny_roughness_at_the_normal_half_vector_is_the_formula_limit(r):
    """At h = n: b·Z·G G'/(4π v v') = 4r(1 − r)·(1/r)/(4π (r + (1 − r)v)(r + (1 − r)v')) — finite
    for every r > 0 (r = 1e-170 gave Inf before the guard)."""
    wi, wo = np.array([0.5, 0.0, math.sqrt(0.75)]), np.array([-0.5, 0.0, math.sqrt(0.75)])  # h == n exactly
    m = bk.model("schlick", r=r, color=0.8)
    v = wi[2]
    d = r + (1 - r) * v
    S = 0.8 + 0.2 * (1 - v) ** 5  # u = h·wi = v at h = n
    expect = S * (1 - r) / (math.pi * d * d)
    np.testing.assert_allclose(m.eval(wi, wo), [expect] * 3, rtol=1e-12)


@pytest.mark.parametrize("r", [1e-19, 1e-30, TINY32])
def test_tiny_roughness_float32(r):
    wi = np.array([0.5, 0.0, math.sqrt(0.75)], dtype=np.float32)
    wo = np.array([-0.5, 0.0, math.sqrt(0.75)], dtype=np.float32)
    m = bk.model("schlick", r=r, color=0.8)
    f = m.eval(wi, wo)
    assert f.dtype == np.float32
    v = float(wi[2])
    S = 0.8 + 0.2 * (1 - v) ** 5
    np.testing.assert_allclose(f, [S / (math.pi * v * v)] * 3, rtol=1e-5)


def test_double_slab_tiny_lower_roughness_is_finite():
    """The issue's case: layers=double, color=1, r2=1e-170 gave NaN."""
    m = bk.model("schlick", layers="double", color=1.0, r2=1e-170)
    wi, wo = np.array([0.5, 0.0, math.sqrt(0.75)]), np.array([-0.5, 0.0, math.sqrt(0.75)])
    f = m.eval(wi, wo)
    assert np.isfinite(f).all() and (f >= 0).all()
    top = bk.model("schlick", color=1.0).eval(wi, wo)
    np.testing.assert_allclose(f, top, rtol=1e-12)  # (1 − S) = 0 at color = 1


@pytest.mark.parametrize("p", [1e-30, 1e-200, TINY64])
def test_tiny_isotropy_gives_one_over_sqrt_p_across_the_scratches(p):
    """With h in the y-z plane (w = 0), A = sqrt(p/p²) = 1/sqrt(p): finite even where p² underflows."""
    wi = np.array([0.0, math.sin(0.3), math.cos(0.3)])  # exactly in the y-z plane: w = 0
    wo = np.array([0.0, math.sin(0.9), math.cos(0.9)])
    ref = bk.model("schlick", r=0.3, p=1.0).eval(wi, wo)
    f = bk.model("schlick", r=0.3, p=p).eval(wi, wo)
    assert np.isfinite(f).all()
    np.testing.assert_allclose(f, ref / math.sqrt(p), rtol=1e-12)


# --- reinjection -----------------------------------------------------------------------------------
@pytest.mark.parametrize("pair", PAIRS)
@pytest.mark.parametrize("r,p", [(0.2, 0.4), (0.5, 1.0), (0.7, 0.9)])
def test_reinjection_by_hand(pair, r, p):
    """S·[a/π + b·(G G' Z A + 1 − G G')/(4π v v')], the reconstructed re-injection term."""
    wi, wo = pair
    C = np.array([0.9, 0.5, 0.1])
    v, v2 = wi[2], wo[2]
    G = lambda x: x / (r - r * x + x)  # noqa: E731
    b = 4 * r * (1 - r)
    extra = b * (1 - G(v) * G(v2)) / (4 * math.pi * v * v2)
    expect = []
    for c in C:
        base, S = _slab_by_hand(wi, wo, c, r, p)
        expect.append(base + S * extra)
    m = bk.model("schlick", color=C, r=r, p=p, reinjection=True)
    np.testing.assert_allclose(m.eval(wi, wo), expect, rtol=1e-11)


def test_reinjection_off_by_default_and_zero_at_r_one():
    wi, wo = random_upper(300, 61), random_upper(300, 62)
    assert bk.model("schlick").params["reinjection"] is False
    m1 = bk.model("schlick", r=1.0, color=0.4, reinjection=True)
    np.testing.assert_allclose(m1.eval(wi, wo), bk.model("schlick", r=1.0, color=0.4).eval(wi, wo), rtol=1e-15)


@pytest.mark.parametrize("layers", ["single", "double"])
def test_reinjection_reciprocal(layers):
    wi, wo = random_upper(2000, 63), random_upper(2000, 64)
    m = bk.model("schlick", layers=layers, r=0.25, p=0.3, r2=0.6, reinjection=True)
    np.testing.assert_allclose(m.eval(wi, wo), m.eval(wo, wi), rtol=1e-12)


def test_reinjection_albedo_exceeds_one_at_grazing():
    """Documented: the re-injected light alone grows like 1/(2v); with color = 1 the albedo passes 1."""
    m = bk.model("schlick", color=1.0, r=0.5, reinjection=True)
    a_normal = albedo(m, vec(0, 0))
    a_grazing = albedo(m, vec(85, 0))
    assert a_normal.max() < 1.0
    assert a_grazing.min() > 2.0
