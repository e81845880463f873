"""The fitter's bounded least-squares solver (brdfkit.measured.trust_region) against scipy's: the same
trust-region reflective rules, so from the same start the same iterates, evaluations and stop, on
classic bounded test problems and on a fit's own residuals; its minima of bounded linear problems
are scipy.optimize.lsq_linear's; bad starts and non-finite trial points are handled as scipy does."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import least_squares, lsq_linear

from brdfkit.measured import trust_region as TR

TOL = dict(ftol=1e-10, xtol=1e-10, gtol=1e-10)


def _scipy(fun, jac, x0, lb, ub, **kw):
    return least_squares(fun, x0, jac=jac, bounds=(lb, ub), method="trf", x_scale="jac", tr_solver="exact", **kw)


def _ours(fun, jac, x0, lb, ub, **kw):
    return TR.solve(fun, lambda x: jac(x).T, x0, lb, ub, **kw)


def _rosenbrock():
    # scipy's documented bounded example: the unconstrained minimum (1, 1) is cut off by x1 ≥ 1.5
    fun = lambda x: np.array([10 * (x[1] - x[0] ** 2), 1 - x[0]])
    jac = lambda x: np.array([[-20 * x[0], 10.0], [-1.0, 0.0]])
    return fun, jac, np.array([2.0, 2.0]), np.array([-np.inf, 1.5]), np.array([np.inf, np.inf])


# Kowalik & Osborne's enzyme problem (Moré, Garbow & Hillstrom 1981, problem 15), bounded so that
# bounds active at the solution (its unbounded minimum is near (0.193, 0.191, 0.123, 0.136))
_KO_Y = np.array([0.1957, 0.1947, 0.1735, 0.1600, 0.0844, 0.0627, 0.0456, 0.0342, 0.0323, 0.0235, 0.0246])
_KO_U = np.array([4.0, 2.0, 1.0, 0.5, 0.25, 0.167, 0.125, 0.1, 0.0833, 0.0714, 0.0625])


def _kowalik_osborne():
    u, y = _KO_U, _KO_Y

    def fun(x):
        return x[0] * (u * u + u * x[1]) / (u * u + u * x[2] + x[3]) - y

    def jac(x):
        num = u * u + u * x[1]
        den = u * u + u * x[2] + x[3]
        return np.stack([num / den, x[0] * u / den, -x[0] * num * u / den ** 2, -x[0] * num / den ** 2], axis=1)

    return fun, jac, np.array([0.15, 0.39, 0.415, 0.39]), np.array([0.0, 0.0, 0.2, 0.15]), np.array([0.18, 1.0, 1.0, 1.0])


def _exponentials():
    # a two-term decay with a floor, fitted to noisy data; the offset's bound (c ≥ 0.5) is active
    t = np.linspace(0, 4, 60)
    rng = np.random.default_rng(3)
    y = 2.0 * np.exp(-1.3 * t) + 0.7 * np.exp(-0.2 * t) + 0.2 + 0.01 * rng.standard_normal(t.size)

    def fun(x):
        return x[0] * np.exp(-x[1] * t) + x[2] * np.exp(-x[3] * t) + x[4] - y

    def jac(x):
        e1, e2 = np.exp(-x[1] * t), np.exp(-x[3] * t)
        return np.stack([e1, -x[0] * t * e1, e2, -x[2] * t * e2, np.ones_like(t)], axis=1)

    lb = np.array([0.0, 0.0, 0.0, 0.0, 0.5])
    ub = np.array([10.0, 10.0, 10.0, 10.0, 5.0])
    return fun, jac, np.array([1.0, 1.0, 1.0, 0.1, 1.0]), lb, ub


def _rank_deficient():
    # the residuals see only x0 + x1: a whole line of minima, a singular normal matrix
    s = np.linspace(-1, 1, 20)
    fun = lambda x: np.tanh((x[0] + x[1]) * s) - 0.5 * s
    jac = lambda x: np.repeat((s / np.cosh((x[0] + x[1]) * s) ** 2)[:, None], 2, axis=1)
    return fun, jac, np.array([1.0, 0.5]), np.array([-2.0, -2.0]), np.array([2.0, 2.0])


PROBLEMS = {"rosenbrock": _rosenbrock, "kowalik-osborne": _kowalik_osborne, "exponentials": _exponentials,
            "rank-deficient": _rank_deficient}


@pytest.mark.parametrize("name", PROBLEMS)
def test_same_iterates_as_scipy_trf(name):
    fun, jac, x0, lb, ub = PROBLEMS[name]()
    ref = _scipy(fun, jac, x0, lb, ub, **TOL)
    got = _ours(fun, jac, x0, lb, ub, **TOL)
    assert got.status == ref.status and got.status > 0
    assert (got.nfev, got.njev) == (ref.nfev, ref.njev)
    assert got.cost == pytest.approx(ref.cost, rel=1e-9, abs=1e-15)
    span = np.where(np.isfinite(ub - lb), ub - lb, 1.0)
    assert np.max(np.abs(got.x - ref.x) / span) < 1e-7
    assert np.all((got.x >= lb) & (got.x <= ub))
    np.testing.assert_array_equal(got.fun, fun(got.x))


def test_active_bounds_are_the_expected_ones():
    fun, jac, x0, lb, ub = _rosenbrock()
    got = _ours(fun, jac, x0, lb, ub, **TOL)
    # on x1 = 1.5 the residuals are minimised at x0 = 1.2231 (10(1.5 - x0²)·(-20 x0) - (1 - x0) = 0)
    assert got.x[1] == pytest.approx(1.5, abs=1e-9)
    g = jac(got.x).T @ got.fun
    assert abs(g[0]) < 1e-8 and g[1] > 0  # stationary in x0; the gradient pushes x1 into its bound
    fun, jac, x0, lb, ub = _exponentials()
    got = _ours(fun, jac, x0, lb, ub, **TOL)
    assert got.x[4] == pytest.approx(0.5, abs=1e-9)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(3, 40), n=st.integers(1, 6))
def test_bounded_linear_problems_reach_lsq_linear(seed, m, n):
    """A linear residual A x − b over a box: the minimum is unique where A has full column rank;
    the solver's cost is lsq_linear's (an independent method, bounded-variable least squares)."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((m, n)) * 10.0 ** rng.uniform(-2, 2, n)  # columns of very different scales
    b = rng.standard_normal(m) * 3
    lb = -rng.uniform(0.1, 2, n)
    ub = rng.uniform(0.1, 2, n)
    ref = lsq_linear(A, b, bounds=(lb, ub), method="bvls", tol=1e-14)
    got = TR.solve(lambda x: A @ x - b, lambda x: A.T, np.zeros(n), lb, ub, ftol=1e-14, xtol=1e-14, gtol=1e-14,
                   max_nfev=2000)
    assert np.all((got.x >= lb) & (got.x <= ub))
    assert np.all(np.isfinite(got.fun)) and got.cost >= 0
    assert got.cost <= ref.cost * (1 + 1e-7) + 1e-12


def test_max_nfev_stops_with_status_0():
    fun, jac, x0, lb, ub = _kowalik_osborne()
    got = _ours(fun, jac, x0, lb, ub, max_nfev=3, **TOL)
    assert got.status == 0 and got.nfev == 3
    ref = _scipy(fun, jac, x0, lb, ub, max_nfev=3, **TOL)
    assert got.cost == pytest.approx(ref.cost, rel=1e-12)


def test_non_finite_start_and_empty_box_are_value_errors():
    with pytest.raises(ValueError, match="not finite at the initial point"):
        TR.solve(lambda x: np.array([np.nan, x[0]]), lambda x: np.ones((1, 2)), np.array([0.5]),
                 np.array([0.0]), np.array([1.0]))
    with pytest.raises(ValueError, match="lower bound must be below"):
        TR.solve(lambda x: x, lambda x: np.eye(1), np.array([0.5]), np.array([1.0]), np.array([1.0]))


def test_non_finite_trial_point_shrinks_the_radius():
    # the residuals are NaN beyond x = 2.5, the minimum (x = 3) beyond that: every step into the
    # NaN region is refused and the solver ends at a finite point below 2.5, as scipy's does
    def fun(x):
        return np.array([np.nan if x[0] > 2.5 else x[0] - 3.0, 0.1 * (x[0] - 3.0)])

    jac = lambda x: np.array([[1.0], [0.1]])
    x0, lb, ub = np.array([0.0]), np.array([-10.0]), np.array([10.0])
    got = _ours(fun, jac, x0, lb, ub, max_nfev=60, **TOL)
    ref = _scipy(fun, jac, x0, lb, ub, max_nfev=60, **TOL)
    assert np.isfinite(got.cost) and got.x[0] <= 2.5
    assert got.x[0] == pytest.approx(ref.x[0], rel=1e-12) and got.nfev == ref.nfev


def test_start_on_a_bound_is_moved_inside():
    fun, jac, _, lb, ub = _exponentials()
    x0 = lb.copy()
    got = _ours(fun, jac, x0, lb, ub, **TOL)
    assert np.all((got.x >= lb) & (got.x <= ub)) and got.status > 0
    ref = _ours(fun, jac, _exponentials()[2], lb, ub, **TOL)
    assert got.cost == pytest.approx(ref.cost, rel=1e-6)


def test_a_fit_start_takes_scipys_path():
    """One start of a real fit (GGX, Schlick, on a MERL material's samples, with the exact Jacobian):
    the same evaluations and minimum as scipy's least_squares with the exact trust-region solver."""
    from brdfkit.measured import fit as F
    from brdfkit.measured.exact_jacobian import exact_jacobian
    from brdfkit.measured.metrics import transform
    from brdfkit.measured.packing import ParamPacker
    from brdfkit.measured.residuals import freeze_unused, residual_fn
    from brdfkit.sources import model_class

    data = F.sample("merl/dark-blue-paint", n=500, seed=2)
    packer = ParamPacker(model_class("microfacet"), {"distribution": "ggx", "fresnel": "schlick"},
                         tie_isotropic=data.isotropic)
    res = residual_fn(packer, data, transform("ngan"), "ngan")
    freeze_unused(packer, res, np.random.default_rng(0))  # as the fitter does: Schlick's model has no eta, k
    jac_t = exact_jacobian(packer, data, "ngan")
    x0 = np.clip(packer.x_of(packer.fixed), packer.lb + 1e-6, packer.ub - 1e-6)
    kw = dict(ftol=1e-8, xtol=1e-8, gtol=1e-8, max_nfev=100)
    got = TR.solve(res, jac_t, x0, packer.lb, packer.ub, **kw)
    ref = _scipy(res, lambda x: jac_t(x).T, x0, packer.lb, packer.ub, **kw)
    # the eigenvalues of JᵀJ and the SVD of J round differently: near the end the gradient test
    # may pass one iteration apart
    assert got.status == ref.status and abs(got.nfev - ref.nfev) <= 2
    assert got.cost == pytest.approx(ref.cost, rel=1e-9)
    span = packer.ub - packer.lb
    assert np.max(np.abs(got.x - ref.x) / span) < 1e-4
