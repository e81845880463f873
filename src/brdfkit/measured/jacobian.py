"""The Jacobian of a fit's residuals, cheaper than plain forward differences where the model allows.

Forward differences (the step of ``scipy.optimize.approx_derivative``'s 2-point scheme),
except for the columns of parameters the residuals are affine in with a constant
coefficient (a Lambertian ``kd``), found by probing (:func:`constant_columns`) and reused;
the slots of an rgb parameter whose residuals are those of their own channel only (found
by the same probes, :func:`channel_groups`) take one evaluation for their three columns.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterable, Mapping

import numpy as np

from .packing import ParamPacker


def _value_derivative(residuals, packer: ParamPacker, x: np.ndarray, i: int, r0: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
    """∂r/∂v of slot ``i``'s parameter value v (not its optimiser coordinate) at ``x``, by a forward
    difference of 10⁻³ of its range (exact for a parameter the residuals are affine in), and which
    of the three channels' residuals the step changed at all (``(3,)`` booleans, bit for bit)."""
    s = packer.slots[i]
    v = s.from_x(float(x[i]))
    hv = 1e-3 * (s.hi - s.lo)
    if v + hv > s.hi:
        hv = -hv
    y = x.copy()
    y[i] = s.to_x(v + hv)
    r = residuals(y)
    changed = (r != r0).reshape(-1, 3).any(axis=0) if r.size % 3 == 0 else np.ones(3, bool)
    return (r - r0) / hv, changed


@dataclass
class ColumnProbes:
    """Every slot's :func:`_value_derivative` at a few points (:func:`probe_columns`)."""

    points: int
    derivatives: list[list[np.ndarray]]  # per slot, per point probed
    changed: list[list[np.ndarray]]  # per slot, per point probed: the channels the step changed

    @property
    def evaluations(self) -> int:
        """Residual evaluations the probes took: one per point, one per slot and point probed."""
        return self.points + sum(len(ds) for ds in self.derivatives)


def probe_columns(residuals, packer: ParamPacker, points: Iterable[np.ndarray]) -> ColumnProbes:
    """Each slot's value derivative at each of ``points``, the evidence of :func:`constant_columns`
    and :func:`channel_groups`; a slot with no effect at the first point is not probed further.
    Costs one evaluation per point and one per slot and point probed."""
    pts = [np.asarray(x, dtype=np.float64) for x in points]
    base = [residuals(x) for x in pts]
    probes = ColumnProbes(len(pts), [], [])
    for i in range(len(packer)):
        ds, chs = [], []
        for x, r0 in zip(pts, base):
            d, changed = _value_derivative(residuals, packer, x, i, r0)
            ds.append(d)
            chs.append(changed)
            if not np.any(d):
                break  # no effect here: neither constant nor of one channel
        probes.derivatives.append(ds)
        probes.changed.append(chs)
    return probes


def constant_columns(residuals, packer: ParamPacker, points: Iterable[np.ndarray],
                     probes: ColumnProbes | None = None) -> dict[int, np.ndarray]:
    """The slots whose residuals' derivative with respect to the parameter's value is the same at
    every one of ``points``: parameters the model is affine in with a coefficient no other
    parameter changes (a Lambertian ``kd``: ∂f/∂kd = 1/π). Their Jacobian column is known once
    for all (:func:`jacobian`). Returns ``{slot: ∂r/∂v}``; costs one evaluation per point and
    one per slot and point (none with ``probes``, :func:`probe_columns` at those points)."""
    if probes is None:
        probes = probe_columns(residuals, packer, points)
    out = {}
    for i, ds in enumerate(probes.derivatives):
        ref = ds[0]
        if not np.any(ref):
            continue  # no effect here: not known to be constant
        if all(np.allclose(d, ref, rtol=1e-6, atol=1e-9 * float(np.max(np.abs(ref)))) for d in ds[1:]):
            out[i] = ref
    return out


def channel_groups(residuals, packer: ParamPacker, points: Iterable[np.ndarray],
                   skip: Iterable[int] = (), probes: ColumnProbes | None = None) -> list[list[int]]:
    """Slots whose forward-difference columns one evaluation can give together.

    The residuals are ``(samples, 3)`` values raveled (channel ``c`` is every third entry from
    ``c``). A slot of an rgb parameter that, perturbed at every one of ``points``, changes the
    residuals of its own channel only (bit for bit: every other entry stays the same) has a
    Jacobian column that is zero outside that channel; slots of different channels so have
    structurally orthogonal columns, and one evaluation with all of them perturbed gives each
    column exactly as its own evaluation would (Curtis, Powell & Reid, "On the estimation of
    sparse Jacobian matrices", J. Inst. Maths Applics 13, 1974). A model's R, G and B are
    computed each from their own channel's parameters (an eta, k, ks, f0 per channel), so an rgb
    parameter's three slots take one evaluation, not three. Every other slot (scalars, an rgb
    slot that changes another channel) is a group of its own. ``skip``: slots left out (the
    :func:`constant_columns`). Returns the groups, every slot in ascending order, at most one
    slot per channel in a group; costs what :func:`probe_columns` costs (nothing with ``probes``).
    """
    if probes is None:
        probes = probe_columns(residuals, packer, points)
    skip = set(skip)
    by_channel: dict[int, list[int]] = {0: [], 1: [], 2: []}
    single: list[int] = []
    for i, s in enumerate(packer.slots):
        if i in skip:
            continue
        chs = probes.changed[i]
        if s.channel is not None and len(chs) == probes.points and all(
                bool(ch[s.channel]) and int(ch.sum()) == 1 for ch in chs):
            by_channel[s.channel].append(i)
        else:
            single.append(i)
    groups = [[i] for i in single]
    for k in range(max(len(v) for v in by_channel.values())):
        groups.append(sorted(v[k] for v in by_channel.values() if k < len(v)))
    return sorted(groups)


def _own_channel(r0: np.ndarray, rg: np.ndarray, c: int) -> Callable[[], np.ndarray]:
    """The residuals at a grouped column's own point, built when asked: ``r0`` with channel ``c``
    taken from its group's evaluation ``rg`` (the bits that point's own evaluation gives)."""

    def build() -> np.ndarray:
        r = r0.copy()
        r[c::3] = rg[c::3]
        return r

    return build


def jacobian(fn, packer: ParamPacker, const: Mapping[int, np.ndarray],
             groups: list[list[int]] | None = None):
    """The residuals' Jacobian in the optimiser's coordinates: forward differences (the step of
    ``scipy.optimize.approx_derivative``'s 2-point scheme, away from a bound) except for the
    :func:`constant_columns`, which are their fixed ∂r/∂v times dv/dx (v for a log-scale slot).

    ``fn``: one local run's residuals (``brdfkit.measured.optimise._Start``: ``at``, ``evaluate``,
    ``check``, ``known``). ``groups`` (:func:`channel_groups`): slots of one channel each whose
    differences one evaluation gives; each column is still the quotient of the bits it would
    have by its own evaluation, and the basin-joining test of ``fn`` still sees every column's
    point with its residuals, in the same order. Without ``groups``, one evaluation per column."""
    rel = getattr(packer.cls, "fit_diff_step", None) or float(np.finfo(np.float64).eps) ** 0.5
    n = len(packer.slots)
    if groups is None:
        groups = [[i] for i in range(n) if i not in const]
    channel = {i: packer.slots[i].channel for g in groups if len(g) > 1 for i in g}

    def step(x: np.ndarray, i: int) -> float:
        h = rel * max(1.0, abs(float(x[i]))) * (1.0 if x[i] >= 0 else -1.0)
        if not packer.lb[i] <= x[i] + h <= packer.ub[i]:
            h = -h
        return h

    def jac(x: np.ndarray) -> np.ndarray:
        r0 = fn.at(x)
        Jt = np.empty((len(x), r0.size))  # the columns as contiguous rows (J's transpose), written in place
        for i in const:
            s = packer.slots[i]
            np.multiply(const[i], s.from_x(float(x[i])) if s.log else 1.0, out=Jt[i])
        seen = {}  # slot: the residuals at its own point x + h e_i (from its group's evaluation)
        for g in groups:
            y = x.copy()
            for i in g:
                y[i] += step(x, i)
            r = fn.evaluate(y)
            if len(g) == 1:
                i = g[0]
                h = y[i] - x[i]  # the step as represented
                np.divide(np.subtract(r, r0, out=Jt[i]), h, out=Jt[i])
                seen[i] = (y, r)
                continue
            d = r - r0
            for i in g:
                h = y[i] - x[i]
                c = channel[i]
                Jt[i] = 0.0 / h  # the other channels: (r0 - r0) / h, the sign of zero included
                np.divide(d[c::3], h, out=Jt[i, c::3])
                own = x.copy()
                own[i] = y[i]  # the column's own point x + h e_i
                seen[i] = (own, _own_channel(r0, r, c))
        if fn.known:  # the basin test at every column's own point, in column order
            for i in sorted(seen):
                fn.check(*seen[i])
        # handed over in C order: scipy's LSMR products and column norms would be about 20 % faster
        # on the Fortran-ordered view Jt.T, but round differently, which moves where fits in flat
        # valleys stop (errors change by up to ±4e-5 relative, either way)
        return np.ascontiguousarray(Jt.T)

    return jac


__all__ = ["ColumnProbes", "probe_columns", "constant_columns", "channel_groups", "jacobian"]
