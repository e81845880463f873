"""Lafortune et al. 1997: hand-worked points, reciprocity, the Phong special case, an independent evaluation."""

from __future__ import annotations

import math

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.geometry import spherical_to_vector


def _unit(rng, n):
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 1e-3
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def test_hand_worked_points():
    # wi = (0.6, 0, 0.8), wo = (0, 0.6, 0.8): d = Cz·0.64 = 0.5·0.64 = 0.32; 0.32³ = 0.032768
    m = bk.model("lafortune", kd=0.3, ks_1=[1, 2, 3], cx_1=-2.0, cy_1=3.0, cz_1=0.5, n_1=3.0)
    f = m.eval(np.array([0.6, 0.0, 0.8]), np.array([0.0, 0.6, 0.8]))
    np.testing.assert_allclose(f, 0.3 / math.pi + np.array([1, 2, 3]) * 0.032768, rtol=1e-13)
    # wi = (0.48, 0.6, 0.64), wo = (0.6, 0, 0.8): d = −0.288 + 0.512 = 0.224; 0.224² = 0.050176
    m = bk.model("lafortune", kd=0.0, ks_1=1.0, cx_1=-1.0, cy_1=5.0, cz_1=1.0, n_1=2.0)
    f = m.eval(np.array([0.48, 0.6, 0.64]), np.array([0.6, 0.0, 0.8]))
    np.testing.assert_allclose(f, 0.050176, rtol=1e-13)
    # a negative generalized dot product gives no lobe: d = −0.36 + ... with Cz = 0 → 0
    m = bk.model("lafortune", kd=0.0, ks_1=1.0, cx_1=1.0, cy_1=0.0, cz_1=0.0, n_1=2.0)
    assert float(m.eval(np.array([0.6, 0.0, 0.8]), np.array([-0.6, 0.0, 0.8]))[0]) == 0.0


def test_two_and_three_lobes_add_up_and_lobes_switch_them():
    rng = np.random.default_rng(4)
    wi, wo = _unit(rng, 500), _unit(rng, 500)
    lobe = [dict(ks=[0.2, 0.3, 0.4], cx=-1.1, cy=-0.9, cz=1.0, n=30.0),
            dict(ks=[0.05, 0.05, 0.1], cx=0.8, cy=0.8, cz=0.9, n=4.0),
            dict(ks=[0.5, 0.1, 0.1], cx=-2.0, cy=-2.0, cz=1.0, n=2.0)]
    params = {"kd": [0.1, 0.2, 0.3]}
    for k, L in enumerate(lobe, 1):
        params.update({f"{a}_{k}": v for a, v in L.items()})
    f3 = bk.model("lafortune", lobes=3, **params).eval(wi, wo)
    singles = [bk.model("lafortune", kd=0.0, **{f"{a}_1": v for a, v in L.items()}).eval(wi, wo) for L in lobe]
    np.testing.assert_allclose(f3, np.array(params["kd"]) / np.pi + sum(singles), rtol=1e-12)
    f1 = bk.model("lafortune", lobes=1, **params).eval(wi, wo)
    np.testing.assert_allclose(f1, np.array(params["kd"]) / np.pi + singles[0], rtol=1e-12)


def test_against_independent_scalar_evaluation():
    """A plain-Python evaluation of eq. (4)-(6) (math.pow, u^T diag(C) v) at random points."""
    rng = np.random.default_rng(7)
    wi, wo = _unit(rng, 300), _unit(rng, 300)
    P = dict(kd=[0.15, 0.1, 0.05], lobes=2, ks_1=[0.7, 0.5, 0.3], cx_1=-1.2, cy_1=-0.7, cz_1=1.1, n_1=12.5,
             ks_2=[0.02, 0.03, 0.04], cx_2=0.9, cy_2=1.3, cz_2=0.6, n_2=1.5)
    f = bk.model("lafortune", **P).eval(wi, wo)
    for a, b, got in zip(wi, wo, f):
        want = [kd / math.pi for kd in P["kd"]]
        for k in (1, 2):
            C = np.diag([P[f"cx_{k}"], P[f"cy_{k}"], P[f"cz_{k}"]])
            d = float(a @ C @ b)
            lobe = math.pow(d, P[f"n_{k}"]) if d > 0 else 0.0
            want = [w + s * lobe for w, s in zip(want, P[f"ks_{k}"])]
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-300)


@pytest.mark.parametrize("n", [1.0, 10.0, 200.0, 5000.0])
def test_cxy_equal_minus_cz_is_normalised_phong(n):
    """Cx = Cy = −Cz = −C with C^n = (n+2)/(2π): Lewis's normalised Phong lobe, ks·(n+2)/(2π)·(r·v)^n."""
    C = ((n + 2) / (2 * math.pi)) ** (1 / n)
    laf = bk.model("lafortune", kd=[0.1, 0.2, 0.3], ks_1=[0.4, 0.5, 0.6], cx_1=-C, cy_1=-C, cz_1=C, n_1=n)
    pho = bk.model("phong", kd=[0.1, 0.2, 0.3], ks=[0.4, 0.5, 0.6], shininess=n, normalized=True)
    rng = np.random.default_rng(11)
    wi = _unit(rng, 2000)
    # half of the outgoing directions near the mirror direction, where the lobe lives
    r = wi * np.array([-1, -1, 1])
    wo = np.concatenate([_unit(rng, 1000), r[1000:] + rng.normal(0, 0.3 / math.sqrt(n), (1000, 3))])
    wo[:, 2] = np.abs(wo[:, 2]) + 1e-3
    wo /= np.linalg.norm(wo, axis=-1, keepdims=True)
    np.testing.assert_allclose(laf.eval(wi, wo), pho.eval(wi, wo), rtol=1e-9, atol=1e-15)


def test_reciprocal_for_random_parameters():
    rng = np.random.default_rng(3)
    wi, wo = _unit(rng, 4000), _unit(rng, 4000)
    for _ in range(5):
        P = {"kd": rng.random(3), "lobes": 3}
        for k in (1, 2, 3):
            P.update({f"ks_{k}": rng.random(3), f"cx_{k}": rng.uniform(-3, 3), f"cy_{k}": rng.uniform(-3, 3),
                      f"cz_{k}": rng.uniform(-3, 3), f"n_{k}": 10 ** rng.uniform(0, 3)})
        m = bk.model("lafortune", **P)
        a, b = m.eval(wi, wo), m.eval(wo, wi)
        np.testing.assert_allclose(a, b, rtol=1e-12)


def test_always_finite_and_non_negative_even_with_overflowing_lobes():
    m = bk.model("lafortune", kd=1.0, ks_1=1e6, cx_1=100.0, cy_1=100.0, cz_1=100.0, n_1=1e5)
    rng = np.random.default_rng(0)
    wi, wo = _unit(rng, 1000), _unit(rng, 1000)
    for dt in (np.float64, np.float32):
        f = m.eval(wi.astype(dt), wo.astype(dt))
        assert np.isfinite(f).all() and (f >= 0).all() and f.dtype == dt
    # the cap: e^60 per unit weight where the lobe overflows
    f = m.eval(np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, 1.0]))
    np.testing.assert_allclose(f, 1 / math.pi + 1e6 * math.exp(60.0), rtol=1e-12)
    below = m.eval(spherical_to_vector(1.0, 0.0), np.array([0.0, 0.6, -0.8]))
    assert (below == 0).all()


def test_bad_parameters_raise_one_line_errors():
    with pytest.raises(ValueError, match="lobes"):
        bk.model("lafortune", lobes=4)
    with pytest.raises(ValueError, match="n_1"):
        bk.model("lafortune", n_1=-1.0)
    with pytest.raises(ValueError, match="ks_2"):
        bk.model("lafortune", ks_2=[0.1, -0.2, 0.1])


@pytest.mark.parametrize("lobes", [1, 2, 3])
def test_glsl_twin_with_every_lobe_count(lobes):
    """The shader (through real OpenGL) equals numpy with 1, 2 and 3 non-zero lobes."""
    from brdfkit.render import glsl

    P = dict(kd=[0.1, 0.2, 0.3], lobes=lobes, ks_1=[0.5, 0.4, 0.3], cx_1=-1.05, cy_1=-1.05, cz_1=1.0, n_1=40.0,
             ks_2=[0.1, 0.3, 0.2], cx_2=0.7, cy_2=0.9, cz_2=0.8, n_2=3.0,
             ks_3=[2.0, 1.0, 0.5], cx_3=-3.0, cy_3=-2.0, cz_3=1.0, n_3=2.5)
    m = bk.model("lafortune", **P)
    rng = np.random.default_rng(lobes)
    wi, wo = _unit(rng, 3000).astype(np.float32), _unit(rng, 3000).astype(np.float32)
    g = glsl.eval_glsl(m, wi, wo)
    f = m.eval(wi.astype(np.float64), wo.astype(np.float64))
    np.testing.assert_allclose(g, f, rtol=2e-4, atol=1e-7)
    # the lobes switch on as counted: with more lobes the values change
    if lobes > 1:
        less = bk.model("lafortune", **dict(P, lobes=lobes - 1)).eval(wi, wo)
        assert np.abs(less - f).max() > 1e-3
