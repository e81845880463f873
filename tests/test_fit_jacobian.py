"""The fitter's exact Jacobian (issue 31): the model's eval_grad through the packer's log scales and
ties and the metric's weighting equals a finite-difference Jacobian of the same residuals, and a fit
with it ends at least as low as the finite-difference fit."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize._numdiff import approx_derivative

from brdfkit import registry
from brdfkit.measured import fit as F
from brdfkit.measured import optimise
from brdfkit.measured.exact_jacobian import exact_jacobian, normal_equations

MATERIAL = "merl/gold-metallic-paint"

CASES = [
    ("microfacet", {"distribution": "ggx", "fresnel": "schlick"}, "ngan"),
    ("microfacet", {"distribution": "beckmann", "fresnel": "conductor"}, "log"),
    ("ward", {}, "ngan"),
    ("lafortune", {"lobes": 2}, "l2"),
    ("cook-torrance", {}, "cbrt"),
    ("blinn-phong", {}, "log"),
    ("ashikhmin-shirley", {}, "ngan"),
]


@pytest.fixture(scope="module")
def data():
    return F.sample(MATERIAL, n=400, seed=5)


def _columns_agree(J, ref, rtol):
    """Every column of ``J`` within ``rtol`` of the reference column's largest entry, or of the
    whole Jacobian's largest entry × 1e-9 (a parameter the chosen options leave unused has a zero
    exact column, and differences of one unit in the last place of its residuals)."""
    scale = np.abs(ref).max(axis=0)
    err = np.abs(J - ref).max(axis=0)
    return err <= rtol * scale + 1e-9 * np.abs(ref).max()


def _points(packer, rng, n=3):
    """Points about the defaults, 5 % of each range away, inside the bounds: where the model's
    values are of the measured ones' order, so that differences of the residuals resolve every
    column (at a random point of Lafortune's 1e-6..1e6 ks the values reach 1e30, and the
    differences see no kd; at a bound a kd = 0 puts the cube root's cusp inside the difference)."""
    x0 = packer.x_of(packer.fixed)
    span = packer.ub - packer.lb
    for _ in range(n):
        x = x0 + 0.05 * span * rng.standard_normal(len(x0))
        yield np.clip(x, packer.lb + 0.01 * span, packer.ub - 0.01 * span)


@pytest.mark.parametrize("name, fixed, metric", CASES, ids=lambda v: v if isinstance(v, str) else None)
def test_exact_jacobian_is_the_central_difference_one(name, fixed, metric, data):
    packer = F.ParamPacker(registry.get(name), fixed, tie_isotropic=True)
    res = F.residual_fn(packer, data, F.transform(metric), metric)
    jac = exact_jacobian(packer, data, metric)
    assert jac is not None
    rng = np.random.default_rng(11)
    for x in _points(packer, rng):
        J = jac(x).T  # exact_jacobian gives one row per slot
        ref = approx_derivative(res, x, method="3-point", bounds=(packer.lb, packer.ub))
        assert J.shape == ref.shape == (3 * len(data), len(packer))
        ok = _columns_agree(J, ref, 1e-5)
        bad = [f"{packer.slots[i].param.name}[{packer.slots[i].channel}]" for i in np.flatnonzero(~ok)]
        assert not bad, (name, fixed, metric, bad)


def test_tied_slot_is_the_sum_of_both_derivatives(data):
    # an anisotropic ward fitted to isotropic data: alpha_x's slot sets alpha_y too
    packer = F.ParamPacker(registry.get("ward"), {}, tie_isotropic=True)
    assert packer.tied == {"alpha_x": "alpha_y"}
    i = [s.param.name for s in packer.slots].index("alpha_x")
    x = packer.x_of(packer.fixed)
    m = packer.model(x)
    _, g = m.eval_grad(data.wi, data.wo)
    col = exact_jacobian(packer, data, "l2")(x)[i]
    w = (np.sqrt(data.w) / np.sqrt(3 * len(data)))[:, None]
    v = packer.slots[i].from_x(float(x[i]))  # a log-scale slot: dv/dx = v
    np.testing.assert_allclose(col, (w * (g["alpha_x"] + g["alpha_y"]) * v).ravel(), rtol=1e-12)


def test_no_gradient_keeps_finite_differences(data):
    # multiscatter has no gradient (its table is precomputed outside the kernel's source)
    packer = F.ParamPacker(registry.get("microfacet"), {"multiscatter": True}, tie_isotropic=True)
    assert exact_jacobian(packer, data, "ngan") is None


def test_exact_fit_ends_no_higher_than_the_difference_fit(monkeypatch):
    data = F.sample(MATERIAL, n=1500, seed=1)
    kw = dict(fixed={"distribution": "ggx", "fresnel": "schlick"}, data=data, seed=1)
    monkeypatch.setattr(optimise, "EXACT_JACOBIAN", True)
    exact = F.fit("microfacet", MATERIAL, **kw)
    assert exact.nfev < 700  # the exact run: no difference probes (the FD run takes ~900 here)
    monkeypatch.setattr(optimise, "EXACT_JACOBIAN", False)
    fd = F.fit("microfacet", MATERIAL, **kw)
    assert exact.error <= fd.error * (1 + 1e-6), (exact.error, fd.error)
    # the value it reports is the metric of the parameters it reports
    assert exact.error == pytest.approx(F.error(exact.model, data, "ngan"), rel=1e-9)


@pytest.mark.parametrize("metric", ["ngan", "log"])
def test_normal_equations_are_the_sum_over_blocks(metric):
    """JᵀJ and Jᵀr built block by block (blocks of 700 samples, the last one shorter) equal those of
    the whole exact Jacobian: each block's 1/√(3·block) weighting rescaled to the whole vector's."""
    data = F.sample(MATERIAL, n=2500, seed=3)
    packer = F.ParamPacker(registry.get("microfacet"), {"distribution": "ggx", "fresnel": "schlick"},
                           tie_isotropic=True)
    res = F.residual_fn(packer, data, F.transform(metric), metric)
    normal = normal_equations(packer, data, metric, chunk=700)
    x = next(_points(packer, np.random.default_rng(4), 1))
    r = res(x)
    JtJ, Jtr = normal(x, r)
    Jt = exact_jacobian(packer, data, metric)(x)
    np.testing.assert_allclose(JtJ, Jt @ Jt.T, rtol=1e-10, atol=1e-12 * np.abs(JtJ).max())
    np.testing.assert_allclose(Jtr, Jt @ r, rtol=1e-10, atol=1e-12 * np.abs(Jtr).max())
    assert normal_equations(F.ParamPacker(registry.get("microfacet"), {"multiscatter": True}, tie_isotropic=True),
                            data, metric) is None


def test_table_scale_fit_polishes_with_the_exact_jacobian(monkeypatch):
    """A samples="table" fit polishes on every bin with the normal equations of the exact Jacobian
    (one gradient evaluation per step instead of a difference per free value), and ends where the
    difference polish ends."""
    data = F.table(MATERIAL, 30)
    calls = []

    def counted(*a, **k):
        calls.append(1)
        return normal_equations(*a, **k)

    monkeypatch.setattr(optimise, "normal_equations", counted)
    exact = F.fit("ward", MATERIAL, samples="table", data=data, max_theta_deg=30)
    assert calls
    monkeypatch.setattr(optimise, "EXACT_JACOBIAN", False)
    diff = F.fit("ward", MATERIAL, samples="table", data=data, max_theta_deg=30)
    assert len(calls) == 1  # the difference fit does not build them
    assert exact.error <= diff.error * (1 + 1e-7)
    assert exact.nfev < diff.nfev
