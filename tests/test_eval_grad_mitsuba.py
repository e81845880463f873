"""``eval_grad`` of ``microfacet`` (conductor Fresnel, Smith shadowing) against Mitsuba 3's automatic
differentiation of ``roughconductor``: ``dr.forward`` from ``alpha_u``, ``alpha_v``, ``eta`` and ``k``
(variant ``llvm_ad_rgb``, float32; skipped where Mitsuba 3 or its LLVM backend is missing).

brdfkit's ``alpha_x`` is Mitsuba's ``alpha_u`` (along the tangent +x, test_microfacet.py) and Mitsuba's
``si.wi`` is brdfkit's ``wo`` (:mod:`_mitsuba_helpers`); Mitsuba's value includes the cosine of brdfkit's
``wi``, divided out. ``eta``/``k`` are RGB: channel c depends on ``eta_c`` alone, so ``dr.forward`` from the
whole colour gives the diagonal ``∂f_c/∂eta_c``, compared with the sum over brdfkit's input channels
(whose off-diagonal entries are checked to be zero).

GGX: every parameter agrees to 1e-4 relative. Beckmann: Mitsuba's Smith G1 is Walter et al.'s rational
approximation (test_microfacet.py; up to 0.7 % from brdfkit's exact erf form), so the roughness
derivatives differ by more than that approximation's slope; the Fresnel derivatives do not depend on G:
``(∂f/∂eta)/f`` and ``(∂f/∂k)/f`` are compared to 1e-4 relative, with an absolute floor of 1e-5 of their
largest value (a ratio of Mitsuba's float32 results: where ``∂ log F/∂k`` is small it loses digits).
"""

from __future__ import annotations

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.geometry import random_unit_vectors

RTOL = 1e-4


@pytest.fixture(scope="module")
def mi_ad():
    mitsuba = pytest.importorskip("mitsuba")
    dr = pytest.importorskip("drjit")
    try:
        mitsuba.set_variant("llvm_ad_rgb")
    except Exception as e:  # no LLVM library for Dr.Jit's backend
        pytest.skip(f"mitsuba llvm_ad_rgb unavailable: {e}")
    yield mitsuba, dr
    mitsuba.set_variant("scalar_rgb")


def _pairs(seed, n=400):
    rng = np.random.default_rng(seed)
    wi = random_unit_vectors(n, rng)
    wo = random_unit_vectors(n, rng)
    k = n // 2  # half near the mirror direction, where the lobe is
    near = np.stack([-wo[:k, 0], -wo[:k, 1], wo[:k, 2]], -1) + rng.normal(scale=0.1, size=(k, 3))
    wi[:k] = near
    for w in (wi, wo):
        w[:, 2] = np.maximum(np.abs(w[:, 2]), 0.05)  # Mitsuba computes in float32: away from the horizon
        w /= np.linalg.norm(w, axis=-1, keepdims=True)
    return wi, wo


def mitsuba_value_and_grad(mi, dr, dist, ax, ay, eta, k, wi, wo, key):
    """Mitsuba's f_r ``(n, 3)`` and its forward derivative with respect to the parameter ``key``."""
    bsdf = mi.load_dict({"type": "roughconductor", "distribution": dist, "alpha_u": ax, "alpha_v": ay,
                         "eta": {"type": "rgb", "value": list(map(float, eta))},
                         "k": {"type": "rgb", "value": list(map(float, k))}})
    params = mi.traverse(bsdf)
    name = key + ".value"
    dr.enable_grad(params[name])
    params.update()
    n = len(wi)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.sh_frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))
    si.wi = mi.Vector3f(wo[:, 0], wo[:, 1], wo[:, 2])
    v = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(wi[:, 0], wi[:, 1], wi[:, 2]))
    dr.forward(params[name])
    g = dr.grad(v)
    cos = wi[:, 2:3]
    return (np.stack([np.array(v[c]) for c in range(3)], -1) / cos,
            np.stack([np.array(g[c]) for c in range(3)], -1) / cos)


CASES = [(0.3, 0.3), (0.08, 0.08), (0.7, 0.7), (0.1, 0.4), (0.5, 0.15)]


def _setup(seed):
    rng = np.random.default_rng(seed)
    return rng.uniform(0.1, 2.5, 3), rng.uniform(0.0, 5.0, 3)


def _assert_close(ours, theirs, what, atol_of_scale=1e-6):
    scale = np.abs(ours).max()
    err = np.abs(ours - theirs)
    bad = err > RTOL * np.abs(ours) + atol_of_scale * scale
    if bad.any():
        i = np.argwhere(bad)[0]
        raise AssertionError(f"{what}: brdfkit {ours[tuple(i)]!r}, Mitsuba {theirs[tuple(i)]!r} "
                             f"(rel {err[tuple(i)] / abs(ours[tuple(i)]):.3g})")


@pytest.mark.parametrize("ax,ay", CASES)
def test_ggx_grads_match_mitsuba_autodiff(mi_ad, ax, ay):
    mi, dr = mi_ad
    eta, k = _setup(int(ax * 100 + ay * 10))
    wi, wo = _pairs(int(ax * 1000 + ay * 10))
    m = bk.model("microfacet", distribution="ggx", alpha_x=ax, alpha_y=ay, shadowing="smith",
                 fresnel="conductor", eta=eta, k=k)
    f, g = m.eval_grad(wi, wo)
    for key, ours in (("alpha_u", g["alpha_x"]), ("alpha_v", g["alpha_y"]),
                      ("eta", g["eta"].sum(-1)), ("k", g["k"].sum(-1))):
        val, theirs = mitsuba_value_and_grad(mi, dr, "ggx", ax, ay, eta, k, wi, wo, key)
        np.testing.assert_allclose(val, f, rtol=RTOL, atol=1e-9)
        _assert_close(ours, theirs, f"ggx ({ax}, {ay}) d/d{key}")
    for key in ("eta", "k"):  # channel c depends on eta_c / k_c only
        off = g[key] * (1 - np.eye(3))
        assert not off.any(), f"d f_c / d {key}_c' != 0 for c != c'"


@pytest.mark.parametrize("ax,ay", CASES[:3])
def test_beckmann_fresnel_grads_match_mitsuba_autodiff(mi_ad, ax, ay):
    mi, dr = mi_ad
    eta, k = _setup(int(ax * 100 + ay * 10) + 1)
    wi, wo = _pairs(int(ax * 1000 + ay * 10) + 1)
    m = bk.model("microfacet", distribution="beckmann", alpha_x=ax, alpha_y=ay, shadowing="smith",
                 fresnel="conductor", eta=eta, k=k)
    f, g = m.eval_grad(wi, wo)
    ok = f > 1e-6 * f.max()
    for key in ("eta", "k"):
        val, theirs = mitsuba_value_and_grad(mi, dr, "beckmann", ax, ay, eta, k, wi, wo, key)
        ok &= val > 1e-6 * val.max()
        _assert_close(np.where(ok, g[key].sum(-1) / np.where(ok, f, 1.0), 0.0),
                      np.where(ok, theirs / np.where(ok, val, 1.0), 0.0), f"beckmann ({ax}, {ay}) dlog f/d{key}",
                      atol_of_scale=1e-5)  # a ratio of two float32 results: measured worst 8e-7 absolute, 3e-6 of its scale
