"""Bounded nonlinear least squares for a fit's small dense problems: trust-region reflective.

``solve(fun, jac_t, x0, lb, ub, ...)`` minimises ½‖f(x)‖² subject to ``lb ≤ x ≤ ub`` for a
residual vector ``f`` of m values (a fit: 3 × 3000) and n free values (at most a few dozen), given
the exact Jacobian's transpose ``jac_t(x)`` (n × m, a row per free value: the layout in which a
model's derivatives come, :mod:`brdfkit.measured.exact_jacobian`).

The method is the trust-region reflective algorithm of

* M. A. Branch, T. F. Coleman, Y. Li, "A Subspace, Interior, and Conjugate Gradient Method for
  Large-Scale Bound-Constrained Minimization Problems", SIAM J. Sci. Comput. 21(1), 1999: the
  Coleman-Li scaling v(x) (the distance to the bound the gradient points to), the augmented
  quadratic model ½ pᵀ(Ĵᵀ Ĵ + diag(g·v'))p + ĝᵀp in the scaled variables x = D x̂, and the choice of
  each step among the (shortened) trust-region step, its reflection at the first bound it meets
  and the scaled anti-gradient, each kept strictly inside the bounds (θ = max(0.995, 1 − ‖v g‖∞));
* J. J. Moré, "The Levenberg-Marquardt algorithm: implementation and theory", Numerical Analysis,
  Lecture Notes in Mathematics 630, 1978: the trust-region subproblem solved exactly, by Newton's
  iteration on 1/‖p(α)‖ for the Levenberg parameter α with Moré's safeguards, and the radius
  updated by the ratio of actual to predicted reduction (< ¼: shrink to ¼ of the step; > ¾ with
  the step on the boundary: double).

These are the rules of ``scipy.optimize.least_squares(method="trf", x_scale="jac",
tr_solver="exact")``, with its termination tests (``ftol``, ``xtol``, ``gtol``; status 1–4, 0 when
``max_nfev`` ran out) and column scaling (the running maximum of the Jacobian's column norms).
What differs is the linear algebra. scipy factors the (m + n) × n augmented Jacobian by an SVD at
every iteration, or, with ``tr_solver="lsmr"`` (the fitter's solver before this module), runs LSMR
through Python-level linear operators; at a fit's 9000 × 16 that costs 2-4 ms per iteration, more
than the model's exact Jacobian itself. Every quantity the method needs is a function of the n × n
normal matrix A = Ĵᵀ Ĵ + diag(g·v'·s) and the scaled gradient ĝ = Ĵᵀ f: the subproblem's
p(α) = −V (Vᵀ ĝ)/(λ + α) from A's eigendecomposition A = V diag(λ) Vᵀ, and every quadratic-model
value along a direction. JᵀJ is formed once per Jacobian (0.15 ms at 9000 × 16); an iteration's
own work is then on n × n matrices. The normal matrix squares the condition number: a direction
whose singular value lies below √ε of the largest is resolved no better than ε·λ_max, so such a
problem is treated as rank-deficient (the step is the regularised one, α > 0), where the SVD would
still take a Gauss-Newton step. tests/test_trust_region.py checks the solver against scipy's on
bounded test problems and fits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

EPS = float(np.finfo(np.float64).eps)

#: Moré's iteration for α stops when ‖p(α)‖ is within this fraction of the radius, or after
#: :data:`ALPHA_ITERATIONS` steps
ALPHA_RTOL = 0.01
ALPHA_ITERATIONS = 10


@dataclass
class Result:
    """``x``: the solution; ``cost``: ½‖f(x)‖²; ``status``: 1 gtol, 2 ftol, 3 xtol, 4 ftol and xtol,
    0 ``max_nfev`` reached (scipy's codes); ``nfev``/``njev``: residual and Jacobian evaluations."""

    x: np.ndarray
    fun: np.ndarray
    cost: float
    status: int
    nfev: int
    njev: int


def solve(
    fun: Callable[[np.ndarray], np.ndarray],
    jac_t: Callable[[np.ndarray], np.ndarray],
    x0: np.ndarray,
    lb: np.ndarray,
    ub: np.ndarray,
    *,
    ftol: float = 1e-8,
    xtol: float = 1e-8,
    gtol: float = 1e-8,
    max_nfev: int | None = None,
) -> Result:
    """Minimise ½‖fun(x)‖² over ``lb ≤ x ≤ ub`` from ``x0`` (inside the bounds; it is moved off
    any bound it lies on). ``jac_t(x)``: the transposed Jacobian (n, m) of ``fun`` at ``x``. ``max_nfev``:
    residual evaluations allowed (default 100 n). ValueError if ``fun(x0)`` is not finite."""
    lb = np.asarray(lb, np.float64)
    ub = np.asarray(ub, np.float64)
    if not np.all(lb < ub):
        raise ValueError("each lower bound must be below its upper bound")
    x = _strictly_feasible(np.array(x0, np.float64), lb, ub)
    n = x.size
    max_nfev = 100 * n if max_nfev is None else max_nfev
    f = np.asarray(fun(x), np.float64)
    if not np.all(np.isfinite(f)):
        raise ValueError("the residuals are not finite at the initial point")
    nfev, njev = 1, 1
    Jt = np.asarray(jac_t(x), np.float64)
    cost = 0.5 * float(f @ f)
    G, g = Jt @ Jt.T, Jt @ f
    scale_inv = np.sqrt(np.diag(G)).copy()
    scale_inv[scale_inv == 0] = 1.0
    v, dv = _coleman_li(x, g, lb, ub)
    delta = float(np.linalg.norm(x * scale_inv / np.sqrt(_scaled(v, dv, scale_inv)))) or 1.0
    alpha = 0.0
    status = None
    while True:
        v, dv = _coleman_li(x, g, lb, ub)
        # the first-order optimality measure, in the unscaled variables
        g_norm = float(np.max(np.abs(g * v))) if n else 0.0
        if g_norm < gtol:
            status = 1
        if status is not None or nfev == max_nfev:
            break
        scale = 1.0 / scale_inv
        d = np.sqrt(_scaled(v, dv, scale_inv)) * scale  # x = d · x̂
        diag_h = g * dv * scale
        g_h = d * g
        A = G * np.outer(d, d)
        A[np.diag_indices(n)] += diag_h
        lam, V = np.linalg.eigh(A)
        lam = np.maximum(lam, 0.0)
        w = V.T @ g_h
        theta = max(0.995, 1.0 - g_norm)
        actual = -1.0
        while actual <= 0 and nfev < max_nfev:
            p_h, alpha = _subproblem(lam, V, w, delta, alpha)
            step, step_h, predicted = _select_step(x, A, g_h, d * p_h, p_h, d, delta, lb, ub, theta)
            x_new = _strictly_feasible(x + step, lb, ub)
            f_new = np.asarray(fun(x_new), np.float64)
            nfev += 1
            step_h_norm = float(np.linalg.norm(step_h))
            if not np.all(np.isfinite(f_new)):
                delta = 0.25 * step_h_norm
                continue
            cost_new = 0.5 * float(f_new @ f_new)
            actual = cost - cost_new
            delta_new, ratio = _radius(delta, actual, predicted, step_h_norm, step_h_norm > 0.95 * delta)
            status = _termination(actual, cost, float(np.linalg.norm(step)), float(np.linalg.norm(x)), ratio,
                                  ftol, xtol)
            if status is not None:
                break
            if delta_new > 0:  # 0 only after a zero step, which the xtol test has already stopped
                alpha *= delta / delta_new
            delta = delta_new
        if actual > 0:
            x, f, cost = x_new, f_new, cost_new
            Jt = np.asarray(jac_t(x), np.float64)
            njev += 1
            G, g = Jt @ Jt.T, Jt @ f
            scale_inv = np.maximum(scale_inv, np.sqrt(np.diag(G)))
    return Result(x, f, cost, 0 if status is None else status, nfev, njev)


def _coleman_li(x, g, lb, ub) -> tuple[np.ndarray, np.ndarray]:
    """Coleman-Li's scaling ``v`` (distance to the bound the descent direction −g heads for, 1 if
    none) and its derivative ``dv`` (±1, 0)."""
    v = np.ones_like(x)
    dv = np.zeros_like(x)
    up = (g < 0) & np.isfinite(ub)
    v[up] = ub[up] - x[up]
    dv[up] = -1.0
    down = (g > 0) & np.isfinite(lb)
    v[down] = x[down] - lb[down]
    dv[down] = 1.0
    return v, dv


def _scaled(v, dv, scale_inv) -> np.ndarray:
    """Coleman-Li's distances ``v`` measured in the column-scaled variables (× ``scale_inv``; a
    variable with no bound ahead keeps 1)."""
    return np.where(dv != 0, v * scale_inv, v)


def _subproblem(lam, V, w, delta: float, alpha: float) -> tuple[np.ndarray, float]:
    """min ½ p̂ᵀAp̂ + ĝᵀp̂ over ‖p̂‖ ≤ Δ for A = V diag(λ) Vᵀ, w = Vᵀĝ: the Gauss-Newton step if it
    fits (A resolvably positive definite), else p(α) = −V w/(λ + α) with ‖p(α)‖ ≈ Δ (Moré 1978,
    ``alpha``: the last call's α as the first guess). Returns ``(p̂, α)``."""
    w_norm = float(np.linalg.norm(w))
    if w_norm == 0.0 or delta <= 0.0:
        return np.zeros_like(w), alpha
    # λ_min resolvable in a normal matrix whose entries carry ε·λ_max of rounding
    full_rank = lam[0] > EPS * lam.size * lam[-1]
    if full_rank:
        p = -V @ (w / lam)
        if np.linalg.norm(p) <= delta:
            return p, 0.0
    hi = w_norm / delta
    if full_rank:
        phi, dphi = _phi(0.0, lam, w, delta)
        lo = -phi / dphi
    else:
        lo = 0.0
    if alpha == 0.0 and not full_rank:
        alpha = max(1e-3 * hi, math.sqrt(lo * hi))
    for _ in range(ALPHA_ITERATIONS):
        if not lo <= alpha <= hi:
            alpha = max(1e-3 * hi, math.sqrt(lo * hi))
        phi, dphi = _phi(alpha, lam, w, delta)
        if phi < 0:
            hi = alpha
        ratio = phi / dphi
        lo = max(lo, alpha - ratio)
        alpha -= (phi + delta) * ratio / delta
        if abs(phi) < ALPHA_RTOL * delta:
            break
    p = -V @ (w / (lam + alpha))
    p *= delta / np.linalg.norm(p)
    return p, alpha


def _phi(alpha: float, lam, w, delta: float) -> tuple[float, float]:
    """φ(α) = ‖p(α)‖ − Δ and φ'(α)."""
    den = lam + alpha
    q = w / den
    pn = float(np.linalg.norm(q))
    return pn - delta, -float(np.sum(q * q / den)) / pn


def _model(A, g_h, s) -> float:
    """The quadratic model's change ½ sᵀAs + ĝᵀs along the scaled step ``s``."""
    return 0.5 * float(s @ A @ s) + float(g_h @ s)


def _line_model(A, g_h, s, s0=None) -> tuple[float, float, float]:
    """``(a, b, c)`` of the model along s0 + t·s: a t² + b t + c."""
    As = A @ s
    a = 0.5 * float(s @ As)
    b = float(g_h @ s)
    c = 0.0
    if s0 is not None:
        b += float(s0 @ As)
        c = _model(A, g_h, s0)
    return a, b, c


def _line_min(a: float, b: float, lo: float, hi: float, c: float = 0.0) -> tuple[float, float]:
    """The minimiser over [lo, hi] of a t² + b t + c, and its value."""
    ts = [lo, hi]
    if a != 0:
        t = -0.5 * b / a
        if lo < t < hi:
            ts.append(t)
    vals = [t * (a * t + b) + c for t in ts]
    i = int(np.argmin(vals))
    return ts[i], vals[i]


def _to_bound(x, s, lb, ub) -> tuple[float, np.ndarray]:
    """The step length t ≥ 0 at which x + t s first meets a bound, and ±1 for the variables that
    meet it then (the sign of their step), 0 for the others."""
    steps = np.full_like(x, np.inf)
    nz = s != 0
    with np.errstate(over="ignore"):
        steps[nz] = np.maximum((lb - x)[nz] / s[nz], (ub - x)[nz] / s[nz])
    t = float(np.min(steps)) if steps.size else math.inf
    return t, np.equal(steps, t) * np.sign(s)


def _sphere(x, s, delta: float) -> tuple[float, float]:
    """Both t with ‖x + t s‖ = Δ (‖x‖ < Δ), the smaller first."""
    a = float(s @ s)
    b = float(x @ s)
    c = float(x @ x) - delta * delta
    q = -(b + math.copysign(math.sqrt(max(b * b - a * c, 0.0)), b))
    t1, t2 = q / a, c / q
    return (t1, t2) if t1 < t2 else (t2, t1)


def _select_step(x, A, g_h, p, p_h, d, delta, lb, ub, theta):
    """Branch, Coleman & Li's choice: the trust-region step if it stays within the bounds, else the
    best (by the model) of that step cut short at θ of the way to the first bound, its reflection
    there, and the scaled anti-gradient (each at most θ of the way to a bound). Returns
    ``(step, scaled step, predicted reduction)``."""
    if np.all((x + p >= lb) & (x + p <= ub)):
        return p, p_h, -_model(A, g_h, p_h)
    p_stride, hits = _to_bound(x, p, lb, ub)
    r_h = p_h.copy()
    r_h[hits != 0] *= -1.0
    r = d * r_h
    p = p * p_stride
    p_h = p_h * p_stride
    to_tr = _sphere(p_h, r_h, delta)[1]
    to_bound, _ = _to_bound(x + p, r, lb, ub)
    r_stride = min(to_bound, to_tr)
    if r_stride > 0:
        r_lo = (1 - theta) * p_stride / r_stride
        r_hi = theta * to_bound if r_stride == to_bound else to_tr
    else:
        r_lo, r_hi = 0.0, -1.0
    r_value = math.inf
    if r_lo <= r_hi:
        a, b, c = _line_model(A, g_h, r_h, s0=p_h)
        t, r_value = _line_min(a, b, r_lo, r_hi, c)
        r_h = p_h + t * r_h
        r = d * r_h
    p = p * theta
    p_h = p_h * theta
    p_value = _model(A, g_h, p_h)
    ag_h = -g_h
    ag = d * ag_h
    to_tr = delta / float(np.linalg.norm(ag_h))
    to_bound, _ = _to_bound(x, ag, lb, ub)
    ag_stride = theta * to_bound if to_bound < to_tr else to_tr
    a, b, _ = _line_model(A, g_h, ag_h)
    t, ag_value = _line_min(a, b, 0.0, ag_stride)
    if p_value < r_value and p_value < ag_value:
        return p, p_h, -p_value
    if r_value < p_value and r_value < ag_value:
        return r, r_h, -r_value
    return t * ag, t * ag_h, -ag_value


def _strictly_feasible(x, lb, ub) -> np.ndarray:
    """``x`` with every value on or beyond a bound moved to the next float inside it."""
    x = np.clip(x, lb, ub)
    low = x <= lb
    x[low] = np.nextafter(lb[low], ub[low])
    high = x >= ub
    x[high] = np.nextafter(ub[high], lb[high])
    tight = (x < lb) | (x > ub)
    x[tight] = 0.5 * (lb[tight] + ub[tight])
    return x


def _radius(delta: float, actual: float, predicted: float, step_norm: float, on_boundary: bool
            ) -> tuple[float, float]:
    """The next trust radius and the ratio of actual to predicted reduction."""
    if predicted > 0:
        ratio = actual / predicted
    elif predicted == actual == 0:
        ratio = 1.0
    else:
        ratio = 0.0
    if ratio < 0.25:
        delta = 0.25 * step_norm
    elif ratio > 0.75 and on_boundary:
        delta *= 2.0
    return delta, ratio


def _termination(d_cost: float, cost: float, step_norm: float, x_norm: float, ratio: float,
                 ftol: float, xtol: float) -> int | None:
    """2: the cost fell by less than ``ftol`` of itself (on a step the model predicted well);
    3: the step was below ``xtol`` of ‖x‖; 4: both; None: neither."""
    f_ok = d_cost < ftol * cost and ratio > 0.25
    x_ok = step_norm < xtol * (xtol + x_norm)
    if f_ok and x_ok:
        return 4
    if f_ok:
        return 2
    if x_ok:
        return 3
    return None


__all__ = ["solve", "Result"]
