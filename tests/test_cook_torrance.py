"""cook-torrance: the lecture's 1982 formula, worked by hand with the math module."""

import math

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.geometry import random_unit_vectors, reflect


def _vec(theta_deg, phi_deg):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return (math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t))


def cook_torrance_by_hand(l, v, kd, ks, m, n):
    """kd/π + ks (F/π) D G / ((N·L)(N·V)) step by step, scalars only (the lecture's slides)."""
    # half vector H = (L + V)/|L + V|
    sx, sy, sz = l[0] + v[0], l[1] + v[1], l[2] + v[2]
    norm = math.sqrt(sx * sx + sy * sy + sz * sz)
    H = (sx / norm, sy / norm, sz / norm)
    NdotL, NdotV, NdotH = l[2], v[2], H[2]
    VdotH = v[0] * H[0] + v[1] * H[1] + v[2] * H[2]
    LdotH = l[0] * H[0] + l[1] * H[1] + l[2] * H[2]
    # D = exp(−(tan α / m)²) / (m² cos⁴ α), α = angle(N, H)
    alpha = math.acos(min(1.0, NdotH))
    D = math.exp(-((math.tan(alpha) / m) ** 2)) / (m * m * math.cos(alpha) ** 4)
    # F = ½ (g−c)²/(g+c)² (1 + (c(c+g)−1)²/(c(c−g)−1)²), c = V·H, g² = n² + c² − 1
    c = VdotH
    g = math.sqrt(n * n + c * c - 1)
    F = 0.5 * (g - c) ** 2 / (g + c) ** 2 * (1 + (c * (c + g) - 1) ** 2 / (c * (c - g) - 1) ** 2)
    # G = min(1, G_mask, G_shadow)
    G_mask = 2 * NdotH * NdotV / VdotH
    G_shadow = 2 * NdotH * NdotL / LdotH
    G = min(1.0, G_mask, G_shadow)
    return kd / math.pi + ks * (F / math.pi) * D * G / (NdotL * NdotV), (D, F, G)


CASES = [
    # (wi: toward light, wo: toward viewer) as (theta, phi) in degrees
    ((30.0, 0.0), (30.0, 180.0)),  # mirror pair: H = N, D = 1/m²
    ((45.0, 10.0), (20.0, 150.0)),
    ((70.0, 0.0), (80.0, 200.0)),  # grazing viewer: G_mask < 1
    ((10.0, 90.0), (60.0, 30.0)),
    ((50.0, 45.0), (50.0, 45.0)),  # wi == wo: H = L = V, G = 2cos²50° < 1
]


@pytest.mark.parametrize("wi_deg,wo_deg", CASES)
@pytest.mark.parametrize("m,n", [(0.2, 1.5), (0.45, 3.0), (0.08, 37.0)])
def test_equals_lecture_formula_by_hand(wi_deg, wo_deg, m, n):
    l, v = _vec(*wi_deg), _vec(*wo_deg)
    kd, ks = 0.3, 0.7
    expect, _ = cook_torrance_by_hand(l, v, kd, ks, m, n)
    got = bk.model("cook-torrance", kd=kd, ks=ks, m=m, ior=n).eval(np.array(l), np.array(v))
    np.testing.assert_allclose(got, [expect] * 3, rtol=1e-12)


def test_hand_values_at_a_mirror_pair():
    # l = v mirrored: H = N, so D = 1/m², G = min(1, 2 cosθ/cosθ) = 1, c = cos 30°
    l, v = _vec(30, 0), _vec(30, 180)
    val, (D, F, G) = cook_torrance_by_hand(l, v, 0.0, 1.0, 0.2, 1.5)
    assert D == pytest.approx(25.0, rel=1e-12) and G == 1.0
    c = math.cos(math.radians(30))
    # independent Fresnel: s/p amplitudes with Snell's law
    st = math.sin(math.radians(30)) / 1.5
    ct = math.sqrt(1 - st * st)
    rs = (c - 1.5 * ct) / (c + 1.5 * ct)
    rp = (1.5 * c - ct) / (1.5 * c + ct)
    assert F == pytest.approx(0.5 * (rs * rs + rp * rp), rel=1e-12)
    f = bk.model("cook-torrance", kd=0.0, ks=1.0, m=0.2, ior=1.5).eval(np.array(l), np.array(v))
    np.testing.assert_allclose(f, (F / math.pi) * 25.0 / (c * c), rtol=1e-12)


def test_rgb_ior_and_weights():
    l, v = _vec(40, 0), _vec(25, 120)
    ior = (1.3, 2.0, 8.0)
    kd = (0.1, 0.2, 0.3)
    ks = (0.9, 0.5, 0.2)
    got = bk.model("cook-torrance", kd=kd, ks=ks, m=0.3, ior=ior).eval(np.array(l), np.array(v))
    expect = [cook_torrance_by_hand(l, v, kd[i], ks[i], 0.3, ior[i])[0] for i in range(3)]
    np.testing.assert_allclose(got, expect, rtol=1e-12)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_reciprocity_and_finiteness(dtype):
    rng = np.random.default_rng(11)
    wi = random_unit_vectors(4000, rng)
    wo = random_unit_vectors(4000, rng)
    for m, n in [(0.001, 1.5), (0.2, (1.2, 3.0, 1000.0)), (1.0, 1.0)]:
        mdl = bk.model("cook-torrance", kd=0.2, ks=1.0, m=m, ior=n)
        a = mdl.eval(wi.astype(dtype), wo.astype(dtype))
        b = mdl.eval(wo.astype(dtype), wi.astype(dtype))
        assert a.dtype == dtype
        np.testing.assert_array_equal(a, b)  # exactly symmetric by construction
        assert np.all(np.isfinite(a)) and np.all(a >= 0)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_edge_directions(dtype):
    s = math.sqrt(1 - 1e-24)
    dirs = np.array(
        [[0, 0, 1], [1, 0, 0], [s, 0, 1e-12], [-s, 0, 1e-12], [0, s, 1e-12], [0.6, 0, 0.8], [0, 0, -1], [1, 0, 1e-300]],
        dtype=np.float64,
    )
    wi = np.repeat(dirs, len(dirs), axis=0)
    wo = np.tile(dirs, (len(dirs), 1))
    extra_i = np.array([[0.6, 0, 0.8], [0.3, 0.4, math.sqrt(0.75)]])
    wi = np.concatenate([wi, extra_i, extra_i, -extra_i])
    wo = np.concatenate([wo, extra_i, reflect(extra_i), extra_i])  # wi == wo, wi == reflect(wo), wi == -wo
    for m in (0.001, 0.05, 1.0):
        for n in (1.0, 1.5, 1000.0):
            f = bk.model("cook-torrance", kd=0.5, ks=1.0, m=m, ior=n).eval(wi.astype(dtype), wo.astype(dtype))
            assert f.dtype == dtype
            assert np.all(np.isfinite(f)) and np.all(f >= 0), (m, n)
            below = (wi[:, 2] <= 0) | (wo[:, 2] <= 0)
            assert np.all(f[below] == 0)


def test_float32_close_to_float64():
    rng = np.random.default_rng(2)
    wi = random_unit_vectors(3000, rng)
    wo = random_unit_vectors(3000, rng)
    keep = (wi[:, 2] > 0.05) & (wo[:, 2] > 0.05)
    wi, wo = wi[keep], wo[keep]
    mdl = bk.model("cook-torrance", kd=0.1, ks=0.9, m=0.15, ior=(1.5, 2.5, 40.0))
    a = mdl.eval(wi, wo)
    b = mdl.eval(wi.astype(np.float32), wo.astype(np.float32))
    np.testing.assert_allclose(b, a, rtol=1e-3, atol=1e-6 * a.max())


def test_params_and_errors():
    m = bk.model("cook-torrance")
    assert set(m.params) == {"kd", "ks", "m", "ior"}
    info = bk.model_info("cook-torrance")
    assert "Cook" in info["reference"] and info["isotropic"]
    with pytest.raises(ValueError, match="'m'.*allowed"):
        bk.model("cook-torrance", m=0.0)
    with pytest.raises(ValueError, match="'ior'"):
        bk.model("cook-torrance", ior=0.5)
