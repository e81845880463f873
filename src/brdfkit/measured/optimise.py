"""The optimiser of a fit: multi-start bounded least squares, and :func:`fit`, which runs it.

``fit(name, measured, fixed={...}, metric="ngan")`` finds the parameters of the registered
model ``name`` that best reproduce ``measured`` (a MERL file, a built-in material name, or
any isotropic model): its free values (:mod:`brdfkit.measured.packing`) minimise the metric
(:mod:`brdfkit.measured.metrics`) over weighted measured samples
(:mod:`brdfkit.measured.samples`).

Optimiser: bounded trust-region reflective least squares (Branch, Coleman & Li 1999) from several
starts: the parameters' defaults plus the best of a few dozen random points of the bounded parameter
space (multi-start, so a local minimum does not decide); the best result wins. Where those starts end
in minima more than :data:`SPREAD` apart in cost, up to :data:`EXTRA_STARTS` more run, from the next
best candidates. Then, for every value optimised in log space, one run from the best minimum so far
with that value at the other end of its range (:data:`HOPS`). A start that enters the basin of a
minimum an earlier start converged to (within :data:`JOIN_XTOL` of it in every free value,
:data:`JOIN_RTOL` in cost) stops there; its ``start_errors`` entry is the error it had then. The
Jacobian is the model's exact one, from its ``eval_grad`` (:mod:`brdfkit.measured.exact_jacobian`), and
the solver :mod:`brdfkit.measured.trust_region` (scipy's ``trf`` rules with the exact subproblem, on
the n × n normal matrix; the last run from the best minimum to a gradient tolerance relative to the
fit's scale of cost, as ftol and xtol are); for a model with no gradient (a ``.brdf`` file's GLSL,
``multiscatter``) the Jacobian is by forward differences, cheaper where the model allows
(:mod:`brdfkit.measured.jacobian`), and the solver ``scipy.optimize.least_squares`` (``trf``, LSMR). A
``samples="table"`` fit searches on :data:`TABLE_SEARCH_SAMPLES` of the bins and polishes the best
start on all of them (:func:`_polish`).
"""

from __future__ import annotations

import math
import os
import time
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Callable, Mapping

import numpy as np

from ..models.base import BRDF
from . import trust_region
from .exact_jacobian import exact_jacobian, normal_equations
from .jacobian import channel_groups, constant_columns, jacobian, probe_columns
from .lobes import two_lobe
from .metrics import METRICS, error, transform
from .packing import ParamPacker
from .progress import fit_progress
from .residuals import freeze_unused, residual_fn
from .result import FitResult, flush_subnormal, slots_at_bound
from .samples import Samples, sample, subsample, table

#: a start that reaches a point within this fraction of every free value's (optimiser-space) range
#: of a minimum an earlier start converged to, with a cost within :data:`JOIN_RTOL` of that
#: minimum's, is in the same basin: it stops there instead of converging again (the basin-joining
#: rule of clustering multi-start methods, Rinnooy Kan & Timmer, Math. Programming 39, 1987)
JOIN_XTOL = 1e-2
JOIN_RTOL = 1e-3

#: use the model's exact Jacobian (its ``eval_grad`` for the free parameters only,
#: :mod:`brdfkit.measured.exact_jacobian`) where it has one; False: forward differences for every
#: model, as before issue 31. Measured (benchmarks/bench_fit.py --jacobian, docs/speed.md; 6 MERL
#: materials × 5 models, warm): the same losses to 3e-8, 30-65 % fewer evaluations, wall time 0.78-1.23×
#: the differences' (median 1.07×: a gradient pass costs several value passes per pair). The variable
#: ``BRDFKIT_FIT_JACOBIAN=differences`` sets it False in every process (a batch's workers included).
EXACT_JACOBIAN = os.environ.get("BRDFKIT_FIT_JACOBIAN", "exact") != "differences"


class _Joined(Exception):
    """Raised inside a start's residuals when it has entered a known minimum's basin."""

    def __init__(self, x: np.ndarray, cost: float) -> None:
        super().__init__()
        self.x, self.cost = x, cost


class _Start:
    """One local optimisation's residuals: counts evaluations, remembers the last one (the
    Jacobian is taken where the residuals were just evaluated) and stops in a known basin."""

    def __init__(self, residuals, packer: ParamPacker, known: list[tuple[np.ndarray, float]]) -> None:
        self.residuals, self.known, self.nfev = residuals, known, 0
        self.span = np.maximum(packer.ub - packer.lb, 1e-300)
        self._last: tuple[np.ndarray, np.ndarray] | None = None

    def __call__(self, x: np.ndarray) -> np.ndarray:
        r = self.evaluate(x)
        self.check(x, r)
        return r

    def evaluate(self, x: np.ndarray) -> np.ndarray:
        """The residuals at ``x``, counted and remembered, without the basin test."""
        r = self.residuals(x)
        self.nfev += 1
        self._last = (np.array(x, dtype=np.float64), r)
        return r

    def check(self, x: np.ndarray, r: np.ndarray | Callable[[], np.ndarray]) -> None:
        """Raise :class:`_Joined` if ``x`` with residuals ``r`` (or ``r()``, called only if needed)
        lies in a known minimum's basin."""
        c = None
        for xk, ck in self.known:
            if float(np.max(np.abs(x - xk) / self.span)) <= JOIN_XTOL:
                if c is None:
                    rv = r() if callable(r) else r
                    c = float(rv @ rv)
                if c <= ck * (1 + JOIN_RTOL):
                    raise _Joined(np.array(x, dtype=np.float64), c)

    def at(self, x: np.ndarray) -> np.ndarray:
        """The residuals at ``x``, reusing the last evaluation if it was there."""
        if self._last is not None and np.array_equal(self._last[0], x):
            return self._last[1]
        return self(x)


def _local(residuals, x0, packer, max_nfev, tol, known=(), const=None, groups=None, exact=None, cost_scale=1.0):
    """A bounded least-squares run from ``x0``: ``(x, cost = Σ r², evaluations, joined, converged)``
    (``converged``: a tolerance stopped it, not ``max_nfev``).

    ``known``: ``(x, cost)`` of minima found by earlier starts; a run that enters one's
    basin (:data:`JOIN_XTOL`, :data:`JOIN_RTOL`) stops there. ``const``: the
    :func:`constant_columns` of the Jacobian; ``groups``: its :func:`channel_groups`.
    ``exact``: the model's exact Jacobian (:func:`exact_jacobian`), used instead of differences;
    each of its calls counts as one evaluation; its runs stop on a gradient below ``tol × cost_scale``
    (:attr:`_StartPlan.cost_scale`)."""
    x0 = np.clip(x0, packer.lb, packer.ub)
    # both solvers need x0 strictly inside the bounds
    eps = 1e-9 * np.maximum(1.0, packer.ub - packer.lb)
    x0 = np.minimum(np.maximum(x0, packer.lb + eps), packer.ub - eps)
    # a model evaluated in float32 (a .brdf file's GLSL) declares a finite-difference step its
    # values can resolve; scipy's default (~1e-8 relative) would see no change at all
    diff_step = getattr(packer.cls, "fit_diff_step", None)
    fn = _Start(residuals, packer, list(known))
    grouped = groups is not None and any(len(g) > 1 for g in groups)
    try:
        if exact is not None:
            # the exact Jacobian: the same trust-region reflective rules as scipy's, on the n × n
            # normal matrix (brdfkit.measured.trust_region), 2x faster per fit than scipy's SVD
            res = trust_region.solve(fn, _counted(exact, fn), x0, packer.lb, packer.ub, max_nfev=max_nfev,
                                     xtol=tol, ftol=tol, gtol=tol * cost_scale)
        else:
            from scipy.optimize import least_squares

            jac = jacobian(fn, packer, const or {}, groups if grouped else None) if const or grouped else "2-point"
            res = least_squares(
                fn, x0, jac=jac, bounds=(packer.lb, packer.ub), method="trf", x_scale="jac", tr_solver="lsmr",
                max_nfev=max_nfev, xtol=tol, ftol=tol, gtol=tol, diff_step=diff_step,
            )
    except _Joined as j:
        return j.x, j.cost, fn.nfev, True, True
    return res.x, float(2 * res.cost), fn.nfev, False, res.status > 0


def _counted(exact, fn: _Start):
    """``exact``, each call counted in ``fn.nfev`` (a gradient evaluation is one evaluation)."""

    def jac(x: np.ndarray) -> np.ndarray:
        fn.nfev += 1
        return exact(x)

    return jac


#: a residual vector of at most this many samples is evaluated on one thread: the engine's
#: parallel driver splits a call into chunks of 2048 pairs, and at a few thousand pairs a second
#: thread per call saves nothing (3000 GGX pairs: 0.196 ms per call on two threads, 0.181 ms on
#: one, measured on the shared 2-core machine) and a batch already runs one fit per core
SERIAL_SAMPLES = 65536


@contextmanager
def _engine_threads(n_samples: int):
    """Evaluate on one numba thread while fitting ``n_samples`` samples, if that is few."""
    import numba

    if n_samples > SERIAL_SAMPLES:
        yield
        return
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(before)


#: when the first ``starts`` local runs of a fit end in minima whose costs differ by more than this
#: fraction, the landscape has basins of materially different depth, and up to :data:`EXTRA_STARTS`
#: more runs start from the next best candidates, to the rougher tolerance :data:`EXTRA_TOL`; one that
#: ends below the best minimum so far converges on from there to the fit's own tolerance, and the best
#: result wins. On the 159 × 9 table (docs/measured.md) 207 of 1431 fits searched on (155 of them
#: He's) and He on rgl/chm_mint_rgb went from 2.380 to 2.085, its published loss; the whole table took
#: 168 s (206 s in a run without them: this machine's noise exceeds their cost there), but
#: gold-metallic-paint's conductor fit, whose starts end in two basins 7 % apart, takes 0.33 s
#: against 0.22 s (0.58 s with the extra runs at the full tolerance)
SPREAD = 1e-2
EXTRA_STARTS = 8
#: ``ftol``, ``xtol`` and ``gtol`` of the extra runs (relative, as the fit's own ``tol``, 1e-8)
EXTRA_TOL = 1e-4

#: after the starts, one more run for every free value optimised in log space, in turn from the best
#: minimum so far (``Param.log_scale``: an exponent, a roughness, an index of refraction, spanning
#: decades), with that one value moved to the other end of its range (:func:`decade_hop`), to the extra
#: runs' tolerance (so a hop that found a deeper basin is where the next starts); as there, one that ends
#: below the best converges on. A local run rarely crosses decades, and such a value can have a basin in
#: each: Cook-Torrance's index of refraction of one channel fits merl/blue-metallic-paint2 both at 5.7 and
#: at 49 (the Fresnel curve's grazing rise against its flat metal-like form; 1.1 % lower in cost there,
#: behind a ridge at 8-12). On the 159 × 9 table (docs/measured.md) they brought the two fits that had
#: stayed worse than commit bbf75cd's published table (by 0.53 % and 0.17 %) down to it and 9 more lower
#: by over 0.1 % (6 Cook-Torrance, 3 Blinn-Phong; up to 1.95 %); the whole table took 142-202 s over five
#: runs with them, 168 s without (this machine's noise exceeds their cost). A hop is basin hopping
#: (Wales & Doye, J. Phys. Chem. A 101, 5111, 1997: perturb, minimise locally, keep the lower minimum)
#: with the perturbation along one coordinate, across its decades
HOPS = True
#: where a hop puts the value: this fraction (dimensionless, in (0, ½)) of its range in the optimiser's
#: log coordinate, measured from the end farther from it
HOP_FRACTION = 0.2

#: Levenberg-Marquardt iterations of the table-scale polish
POLISH_ITERATIONS = 4


def _polish(residuals, x, packer: ParamPacker, iterations: int = POLISH_ITERATIONS, normal=None
            ) -> tuple[np.ndarray, int]:
    """A few bounded Levenberg-Marquardt steps on a large residual vector (every table bin).

    A solver that holds the whole (residuals × parameters) Jacobian would need 2.7 M × 10 values
    for a table (and scipy's LSMR seconds per iteration); here the Jacobian is reduced at once to the
    normal equations JᵀJ (n × n) and Jᵀr: ``normal(x, r)`` gives them from the model's exact Jacobian
    block by block (:func:`~brdfkit.measured.exact_jacobian.normal_equations`, one evaluation),
    else they come from forward-difference columns (n evaluations). A step is kept only if it
    lowers the cost, so the result is never worse than the start. Returns ``(x, evaluations)``."""
    n = len(x)
    r = residuals(x)
    cost = float(r @ r)
    used, lam = 1, 1e-3
    for _ in range(iterations):
        if normal is not None:
            JtJ, Jtr = normal(x, r)
            used += 1
        else:
            JtJ, Jtr = _difference_normal(residuals, x, r, packer)
            used += n
        improved = False
        for _try in range(6):
            A = JtJ + lam * np.diag(np.maximum(np.diag(JtJ), 1e-30))
            try:
                step = -np.linalg.solve(A, Jtr)
            except np.linalg.LinAlgError:
                lam *= 10
                continue
            y = np.clip(x + step, packer.lb, packer.ub)
            ry = residuals(y)
            used += 1
            cy = float(ry @ ry)
            if cy < cost:
                x, r, cost, lam, improved = y, ry, cy, max(lam / 10, 1e-9), True
                break
            lam *= 10
        if not improved:
            break
    return x, used


def _difference_normal(residuals, x, r, packer: ParamPacker) -> tuple[np.ndarray, np.ndarray]:
    """JᵀJ and Jᵀr from forward-difference columns (float32 rows: 2.7 M × n for a table)."""
    J = np.empty((len(x), r.size), np.float32)
    for i in range(len(x)):
        h = 1e-6 * max(1.0, abs(float(x[i])))
        if x[i] + h > packer.ub[i]:
            h = -h
        y = x.copy()
        y[i] += h
        J[i] = (residuals(y) - r) / h
    return (J @ J.T).astype(np.float64), (J @ r.astype(np.float32)).astype(np.float64)


#: samples of the multi-start search of a ``samples="table"`` fit (the polish runs on every bin)
TABLE_SEARCH_SAMPLES = 3000


def fit(
    name: str | type[BRDF],
    measured: Any,
    fixed: Mapping[str, Any] | None = None,
    metric: str = "ngan",
    *,
    starts: int = 4,
    candidates: int = 48,
    samples: int | str = 3000,
    lobes: int = 1,
    seed: int = 0,
    max_theta_deg: float = 80.0,
    max_nfev: int | None = None,
    tol: float = 1e-8,
    progress: bool | Callable[[int, int], None] = False,
    data: Samples | None = None,
) -> FitResult:
    """Fit the registered analytic model ``name`` (or a :class:`BRDF` subclass) to ``measured``.

    ``measured``: a MERL file path, a built-in material name (``"merl/chrome"``) or a
    model (e.g. :func:`brdfkit.load_merl`'s). ``fixed``: parameters held at the given
    values. ``metric``: one of :data:`METRICS`. ``samples``: the number of weighted
    samples (:func:`sample`), or ``"table"``: every measured bin (:func:`table`); then the
    multi-start search runs on :data:`TABLE_SEARCH_SAMPLES` of them and the best start is
    polished on all. ``lobes``: 1, or 2 for a second specular lobe (:func:`two_lobe`;
    Lafortune: its own ``lobes``). ``starts``: local optimisations run (from the defaults
    and the best of ``candidates`` random points); where their minima differ in cost by more
    than :data:`SPREAD`, up to :data:`EXTRA_STARTS` more; then one from the best minimum per
    log-scale value, in turn (:func:`decade_hop`) (``FitResult.starts``: how many ran).
    ``data``: precomputed :func:`sample` or :func:`table` output (then ``measured`` only names
    the source).
    Returns a :class:`FitResult` (``params`` holds every parameter of the model;
    ``at_bound`` lists the free values that ended on a fitting bound).
    """
    t0 = time.perf_counter()
    is_table = _check_options(metric, starts, samples, lobes)
    cls, fixed = _model_class(name, lobes, fixed)
    if data is None:
        data = table(measured, max_theta_deg) if is_table else sample(measured, n=samples, seed=seed,
                                                                      max_theta_deg=max_theta_deg)
    # x/y pairs (alpha_x/alpha_y, …) share one value only when the data are isotropic
    packer = ParamPacker(cls, fixed, tie_isotropic=data.isotropic)
    search = subsample(data, TABLE_SEARCH_SAMPLES, seed) if is_table else data
    T = transform(metric)
    residuals = residual_fn(packer, search, T, metric)
    if len(packer) == 0:  # nothing free: just evaluate
        model = packer.model(np.zeros(0))
        err = error(model, data, metric)
        return FitResult(model, dict(model.params), err, metric, data.source, len(data), 0, 1,
                         time.perf_counter() - t0, sorted(packer.fixed_names), [], [err], lobes=lobes,
                         search_samples=len(search))
    # from here on the model is built from the free values
    plan = _plan_starts(packer, residuals, len(search), seed, candidates, starts + EXTRA_STARTS, search, metric)
    nfev = plan.evaluations
    first, more = plan.chosen[:starts], plan.chosen[starts:]
    polish = 1 if search is not data else 0
    total = len(first) + polish
    best_x, best_cost, best_done = None, math.inf, True
    start_errors: list[float] = []
    known: list[tuple[np.ndarray, float]] = []  # the minima the starts converged to
    with fit_progress(progress, f"fit {cls.name} ← {data.source}", total) as step:
        def local(x0: np.ndarray, tol_run: float, known_minima=(), cost_scale: float = 1.0):
            """One local run from ``x0`` (:func:`_local`), its evaluations counted in ``nfev``."""
            nonlocal nfev
            with _engine_threads(len(search)):
                out = _local(residuals, x0, packer, max_nfev or 100, tol_run, known_minima, plan.const,
                             plan.groups, plan.exact, cost_scale)
            nfev += out[2]
            return out

        def run(x0: np.ndarray, tol_run: float = tol) -> None:
            nonlocal best_x, best_cost, best_done
            x, cst, _, joined, done = local(x0, tol_run, known)
            if tol_run > tol and cst < best_cost:  # a rough run found a deeper basin: converge in it
                x, cst, _, joined, done = local(x, tol)
            start_errors.append(math.sqrt(cst))
            if not joined:
                known.append((x, cst))
            if cst < best_cost:
                best_cost, best_x, best_done = cst, x, done
            step(len(start_errors))

        for x0 in first:
            run(x0)
        if more and max(start_errors) ** 2 > (1 + SPREAD) * min(start_errors) ** 2:
            # basins of materially different depth: search on, from the next best candidates
            total = len(first) + len(more) + polish
            step.total(total)
            for x0 in more:
                run(x0, max(tol, EXTRA_TOL))
        hops = [i for i, slot in enumerate(packer.slots) if slot.log] if HOPS else []
        if hops:  # each log-scale value to the other end of its range, from the best minimum so far
            total += len(hops)
            step.total(total)
            for i in hops:
                run(decade_hop(packer, best_x, i), max(tol, EXTRA_TOL))
        if max_nfev is None and (not best_done or plan.exact is not None):
            # one more run from the best minimum: where it ran out of evaluations in a flat valley
            # (gold-metallic-paint's microfacet fit stopped 2.8e-6 above the minimum, in cost, that
            # other starts reached, and later starts that joined its basin stopped there), and, with
            # the exact Jacobian, to a gradient tolerance relative to the fit's cost (cost_scale)
            x, cst, _, _, _ = local(best_x, tol, cost_scale=plan.cost_scale)
            if cst < best_cost:
                best_cost, best_x = cst, x
        if search is not data:  # polish the best start on every bin
            normal = normal_equations(packer, data, metric) if plan.exact is not None else None
            best_x, used = _polish(residual_fn(packer, data, T, metric), best_x, packer, normal=normal)
            nfev += used
            step(total)
    # the model of the reported parameters: a subnormal value (kd pressed to 0) as 0 (brdfkit.measured.result)
    model = packer.cls(**flush_subnormal(packer.params(best_x)))
    err = error(model, data, metric)
    return FitResult(
        model, dict(model.params), err, metric, data.source, len(data), len(start_errors), nfev,
        time.perf_counter() - t0, sorted(packer.fixed_names), list(packer.frozen), start_errors,
        len(packer), slots_at_bound(packer, best_x), lobes, len(search),
    )


def decade_hop(packer: ParamPacker, x: np.ndarray, i: int) -> np.ndarray:
    """``x`` with its ``i``-th free value (one optimised in log space) moved to :data:`HOP_FRACTION` of
    its range from the end farther from it: where a hop (:data:`HOPS`) starts."""
    lo, hi = packer.lb[i], packer.ub[i]
    x0 = x.copy()
    x0[i] = lo + (1 - HOP_FRACTION) * (hi - lo) if x[i] < 0.5 * (lo + hi) else lo + HOP_FRACTION * (hi - lo)
    return x0


def _check_options(metric: str, starts: int, samples: int | str, lobes: int) -> bool:
    """One-line ``ValueError`` for a bad option of :func:`fit`; whether ``samples`` is ``"table"``."""
    if metric not in METRICS:
        raise ValueError(f"unknown metric {metric!r}; valid metrics: {', '.join(METRICS)}")
    if starts < 1:
        raise ValueError(f"starts must be at least 1, got {starts}")
    is_table = isinstance(samples, str)
    if is_table and samples != "table":
        raise ValueError(f"samples must be a number of samples or 'table', got {samples!r}")
    if not is_table and (isinstance(samples, bool) or not isinstance(samples, (int, np.integer))):
        raise ValueError(f"samples must be a number of samples or 'table', got {samples!r}")
    if isinstance(lobes, bool) or lobes not in (1, 2):
        raise ValueError(f"lobes must be 1 or 2, got {lobes!r}")
    return is_table


def _model_class(name: str | type[BRDF], lobes: int, fixed: Mapping[str, Any] | None
                 ) -> tuple[type[BRDF], dict[str, Any]]:
    """The class :func:`fit` fits and its fixed values: with ``lobes=2`` a model's own ``lobes``
    parameter set to 2 (Lafortune), else the :func:`~brdfkit.measured.lobes.two_lobe` class."""
    from ..sources import model_class

    cls = name if isinstance(name, type) and issubclass(name, BRDF) else model_class(name)
    fixed = dict(fixed or {})
    if lobes == 2:
        if any(p.name == "lobes" for p in cls.spec):
            fixed.setdefault("lobes", 2)
        else:
            cls = two_lobe(cls)
    return cls, fixed


@dataclass
class _StartPlan:
    """Where the local runs of a fit start, and what they know of the Jacobian beforehand."""

    chosen: list[np.ndarray]  # the starting points, the defaults first
    const: dict[int, np.ndarray]  # constant_columns
    groups: list[list[int]] | None  # channel_groups
    exact: Callable[[np.ndarray], np.ndarray] | None  # exact_jacobian, None where the model has no gradient
    evaluations: int  # residual evaluations spent choosing (counted as before: an upper bound)
    #: the best candidate's cost Σ r²: the last run from the best minimum (with the exact Jacobian) stops
    #: on a gradient below ``tol`` times this, as its ftol and xtol are relative. scipy's gtol, absolute,
    #: had stopped the fits of dark materials (costs of 10⁻⁶) up to 5.7·10⁻⁵ short of the minimum in a
    #: flat valley; on the 159 × 9 table 3 fits then stayed above bbf75cd's published losses, by at most
    #: 2.3·10⁻⁷ (55 before, by up to 5.7·10⁻⁵), for 1.6 % more evaluations. Every run at this tolerance
    #: instead: 9 % more, and gold-metallic-paint's conductor fit 0.36 → 0.52 s
    cost_scale: float = 1.0


def _plan_starts(packer: ParamPacker, residuals, n_samples: int, seed: int, candidates: int, starts: int,
                 data: Samples | None = None, metric: str = "ngan") -> _StartPlan:
    """Freeze the unused slots, then take the defaults and the best ``starts - 1`` of ``candidates``
    random points (by cost); the model's exact Jacobian on ``data`` (the residuals' samples) where
    it has one (and :data:`EXACT_JACOBIAN`), else probe the Jacobian's columns at the first two
    of the points for the differences' shortcuts."""
    rng = np.random.default_rng(seed + 1)
    nfev = 2 * (len(packer) + 1)  # freeze_unused: at most 2 points × (base + one probe per slot)
    with _engine_threads(n_samples):
        freeze_unused(packer, residuals, rng)
        cand = [packer.x_of(packer.fixed)]
        if candidates > 0:
            cand += list(packer.random_x(rng, candidates))
        costs = np.array([float(r @ r) for r in map(residuals, cand)])
        # Jacobian columns known once for all (a float32-evaluated model's differences are too noisy)
        const, groups = {}, None
        exact = exact_jacobian(packer, data, metric) if EXACT_JACOBIAN and data is not None else None
        if exact is None and not getattr(packer.cls, "fit_diff_step", None):
            probes = probe_columns(residuals, packer, cand[:2])
            nfev += probes.evaluations
            const = constant_columns(residuals, packer, cand[:2], probes)
            groups = channel_groups(residuals, packer, cand[:2], const, probes)
    nfev += len(cand)
    order = [0] + [int(i) for i in np.argsort(costs) if i != 0]
    return _StartPlan([cand[i] for i in order[:starts]], const, groups, exact, nfev,
                      max(float(costs.min()), np.finfo(np.float64).tiny))

__all__ = ["fit", "EXACT_JACOBIAN", "JOIN_XTOL", "JOIN_RTOL", "SPREAD", "EXTRA_STARTS", "EXTRA_TOL", "HOPS", "HOP_FRACTION", "decade_hop", "TABLE_SEARCH_SAMPLES", "SERIAL_SAMPLES", "POLISH_ITERATIONS"]
