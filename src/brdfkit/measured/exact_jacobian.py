"""The exact Jacobian of a fit's residuals, from the model's own derivatives (``eval_grad``, issue 31).

A model with a gradient (``m.eval_grad``: forward-mode derivatives generated from its scalar
source, :mod:`brdfkit.engine.grad`) gives ``∂f/∂θ`` for every continuous parameter θ in one pass.
The residuals of :func:`~brdfkit.measured.residuals.residual_fn` are, per sample ``j`` and channel
``c``, ``r = s_j · (T(f, cos θi) − T(f_measured, cos θi)) / √(3n)`` (``s_j = √w_j``, the sample's
weight), and the optimiser's free value ``x`` of a slot (:class:`~brdfkit.measured.packing.ParamPacker`)
gives the parameter's value ``v = eˣ`` (a log-scale slot) or ``v = x``. So, by the chain rule,

    ∂r/∂x = s_j / √(3n) · T′(f) · ∂f/∂v · dv/dx,

with, per metric (:mod:`brdfkit.measured.metrics`), ``T′`` = ``cos θi`` (``ngan``), 1 (``l2``),
``cos θi / (1 + f cos θi)`` (``log``) and ``cos θi / (3 (f cos θi)^(2/3))`` (``cbrt``); where
``f cos θi ≤ 0`` the last two clamp (``max(·, 0)``) and their derivative is 0, the one-sided
derivative of the branch the code takes; ``cbrt``'s slope, infinite at ``0⁺``, is taken at
``f cos θi ≥`` :data:`CBRT_FLOOR` (the one place the Jacobian is not the exact one).
``dv/dx`` is ``v`` (log scale) or 1; the packer's clamp of ``v`` to its slot's ``[lo, hi]``
only absorbs the rounding of ``exp(log(lo))`` at a bound the optimiser keeps ``x`` within,
and is not differentiated. A slot of an rgb parameter is the channel-in
column of the model's ``(..., 3, 3)`` derivative; a slot an anisotropic model's pair shares
when fitted to isotropic data (``alpha_x`` and its tie ``alpha_y``) is the sum of both
parameters' derivatives, since it sets both.

:func:`exact_jacobian` returns ``None`` for a model with no gradient (a ``.brdf`` file's GLSL,
``multiscatter=true``, a model without a scalar kernel, or one whose free parameters the
gradient does not cover); the fitter then differentiates by forward differences
(:mod:`brdfkit.measured.jacobian`, with the model's ``fit_diff_step``).
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from .packing import ParamPacker
from .residuals import PreparedEval
from .samples import Samples


#: the ``cbrt`` metric's slope ``cos θi / (3 (f cos θi)^(2/3))`` is infinite at ``f cos θi = 0⁺``;
#: below this value (1/sr, far below any measured value) it is taken at this value, so that a
#: sample whose model value underflows (a narrow lobe's tail) gives a finite column
CBRT_FLOOR = 1e-12


def _metric_slope(metric: str) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """``T′(f, cos θi)``, the derivative of the metric's transform with respect to f
    (the table in the module docstring)."""
    if metric == "ngan":
        return lambda f, c: np.broadcast_to(c, f.shape)
    if metric == "l2":
        return lambda f, c: np.ones_like(f)
    if metric == "log":
        def log_slope(f, c):
            fc = f * c
            return np.where(fc > 0, c / (1.0 + np.maximum(fc, 0.0)), 0.0)
        return log_slope
    if metric == "cbrt":
        def cbrt_slope(f, c):
            fc = f * c
            pos = fc > 0
            return np.where(pos, c / (3.0 * np.cbrt(np.maximum(fc, CBRT_FLOOR)) ** 2), 0.0)
        return cbrt_slope
    raise ValueError(f"unknown metric {metric!r}")


def _columns(packer: ParamPacker, grads: dict[str, np.ndarray]) -> list[tuple[str, int | None, str | None]]:
    """Per slot: ``(parameter, channel, tied parameter)`` whose derivatives give its column;
    ValueError if the gradient lacks a free parameter."""
    out = []
    for s in packer.slots:
        name = s.param.name
        twin = packer.tied.get(name)
        for n in (name, twin):
            if n is not None and n not in grads:
                raise ValueError(f"{packer.cls.name}: no derivative with respect to '{n}'")
        out.append((name, s.channel, twin))
    return out


def exact_jacobian(packer: ParamPacker, data: Samples, metric: str) -> Callable[[np.ndarray], np.ndarray] | None:
    """``x ↦`` the transposed Jacobian ``(slots, 3n)`` of :func:`~brdfkit.measured.residuals.residual_fn`'s
    residuals (same ``packer``, ``data`` and ``metric``) in the optimiser's coordinates, from the
    model's ``eval_grad``: one contiguous row per free value, the layout the solver
    (:mod:`brdfkit.measured.trust_region`) takes and the model's derivatives are built in;
    ``None`` where the model has no gradient covering its free values (tried once, at the
    packer's defaults)."""
    if len(packer) == 0:
        return None
    prepared = PreparedEval(packer, data)
    # only the free parameters' derivatives (and their ties'): a twin seeded by fewer does less work,
    # and the probe below compiles or loads the same twin as every later call
    wrt = sorted({n for s in packer.slots for n in (s.param.name, packer.tied.get(s.param.name)) if n is not None})
    try:
        _, grads = prepared.model(packer.x_of(packer.fixed)).eval_grad(data.wi[:1], data.wo[:1], wrt=wrt)
        columns = _columns(packer, grads)
    except (ValueError, NotImplementedError, AttributeError):
        return None
    c = data.cos_i[:, None]
    n = len(data)
    # the residuals' weights: √w_j / √(3n), as residual_fn folds them
    sw = (np.sqrt(data.w) / math.sqrt(3 * n))[:, None]
    slope = _metric_slope(metric)
    logs = np.array([s.log for s in packer.slots])
    k = len(packer)

    def jac(x: np.ndarray) -> np.ndarray:
        m = prepared.model(x)
        f, grads = m.eval_grad(data.wi, data.wo, wrt=wrt)
        f = np.asarray(f, np.float64)
        # a contiguous row per slot: laying it out as (3n, k) costs a transposing copy (~1 ms at
        # 9000 × 16 in a fit's loop, more than eval_grad's 0.6 ms) that the solver does not need
        Jc = np.empty((k, n, 3))
        for i, (name, ch, twin) in enumerate(columns):
            g = grads[name] if ch is None else grads[name][..., ch]
            if twin is not None:
                g = g + (grads[twin] if ch is None else grads[twin][..., ch])
            Jc[i] = g
        dvdx = np.where(logs, np.exp(np.asarray(x, np.float64)), 1.0)
        Jc *= sw * slope(f, c)
        Jc *= dvdx[:, None, None]
        return Jc.reshape(k, 3 * n)

    return jac


#: samples per block of :func:`normal_equations`: one block's transposed Jacobian (slots × 3 × this,
#: float64) and its gradient pass are all it holds at once (16 slots: 25 MB)
NORMAL_CHUNK = 65536


def normal_equations(packer: ParamPacker, data: Samples, metric: str, chunk: int = NORMAL_CHUNK
                     ) -> Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]] | None:
    """``(x, r) ↦ (JᵀJ, Jᵀr)`` for the residuals of :func:`~brdfkit.measured.residuals.residual_fn` over
    ``data`` (``r``: those residuals at ``x``), from the exact Jacobian block by block of ``chunk``
    samples, so that a table-scale fit (909 696 MERL bins: a 2.7 M × slots Jacobian) never holds
    more than one block's; ``None`` where the model has no gradient (:func:`exact_jacobian`).

    A block's Jacobian weights its residuals by ``1/√(3·block)``; the whole vector's by
    ``1/√(3n)``: each block is rescaled by ``√(block/n)``."""
    blocks = []
    n = len(data)
    for a in range(0, n, chunk):
        b = min(a + chunk, n)
        part = Samples(data.wi[a:b], data.wo[a:b], data.f[a:b], data.w[a:b], data.source, data.isotropic)
        jac_t = exact_jacobian(packer, part, metric)
        if jac_t is None:
            return None
        blocks.append((3 * a, 3 * b, jac_t, math.sqrt((b - a) / n)))
    k = len(packer)

    def normal(x: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        JtJ = np.zeros((k, k))
        Jtr = np.zeros(k)
        for a, b, jac_t, s in blocks:
            Jt = jac_t(x)
            Jt *= s
            JtJ += Jt @ Jt.T
            Jtr += Jt @ np.asarray(r[a:b], np.float64)
        return JtJ, Jtr

    return normal


__all__ = ["exact_jacobian", "normal_equations", "CBRT_FLOOR", "NORMAL_CHUNK"]
