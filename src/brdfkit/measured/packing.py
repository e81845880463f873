"""Parameter packing: a model's parameter dict ↔ the free vector the optimiser sees.

Every ``scalar``/``rgb`` parameter with ``fit=True`` that is not held fixed is free (an rgb
parameter is three free values, *slots*) within ``Param.fit_range`` or else ``Param.range``;
choices, booleans, integers and fixed parameters keep their value. Parameters flagged
``log_scale`` are optimised in log space. An anisotropic model fitted to isotropic data
shares one slot between the parameters its spec ties (:attr:`brdfkit.params.Param.tie`,
read by :func:`brdfkit.params.isotropic_ties`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Iterable, Mapping

import numpy as np

from ..models.base import BRDF
from ..params import Param, isotropic_ties


@dataclass
class _Slot:
    """One free value: a scalar parameter, or one channel of an rgb one, with its bounds."""

    param: Param
    channel: int | None  # None for a scalar
    lo: float
    hi: float
    log: bool

    def to_x(self, v: float) -> float:
        v = min(max(v, self.lo), self.hi)
        return math.log(v) if self.log else v

    def from_x(self, x: float) -> float:
        v = math.exp(x) if self.log else x
        return min(max(v, self.lo), self.hi)


def _bounds(p: Param) -> tuple[float, float, bool]:
    """A parameter's fitting bounds ``(lo, hi, log)``, inside its spec range, open ends moved inwards."""
    rng = p.fit_range or p.range
    if rng is None:
        raise ValueError(f"parameter '{p.name}' has no range; it cannot be fitted (fix it with fixed={{...}})")
    lo, hi = float(rng[0]), float(rng[1])
    if p.range is not None:  # never outside the spec's range
        lo, hi = max(lo, float(p.range[0])), min(hi, float(p.range[1]))
    if math.isinf(hi):
        hi = max(1e4, 100 * abs(lo)) if p.log_scale else max(10.0, 10 * abs(lo))
    if math.isinf(lo):
        lo = -hi
    log = bool(p.log_scale)
    if log and lo <= 0:
        lo = hi * 1e-5
    span = hi - lo
    if p.open_lo:
        lo = lo * (1 + 1e-6) if log else lo + max(1e-9, 1e-6 * span)
    if p.open_hi:
        hi = hi - max(1e-9, 1e-6 * span)
    if not lo < hi:
        raise ValueError(f"parameter '{p.name}': empty fitting range [{lo}, {hi}]")
    return lo, hi, log


class ParamPacker:
    """Maps between a model's parameter dict and the free vector the optimiser sees.

    Free: every ``scalar``/``rgb`` parameter with ``fit=True`` not in ``fixed``
    (rgb: three slots). For an anisotropic model fitted to isotropic data
    (``tie_isotropic``), each pair its spec ties (``Param.tie``, both free) is one
    slot, the twin's; the tied parameter takes the twin's value. The
    model is built from ``fixed`` plus the free values only; everything else
    takes the model's own default.
    """

    def __init__(self, cls: type[BRDF], fixed: Mapping[str, Any] | None = None, tie_isotropic: bool = True) -> None:
        fixed = dict(fixed or {})
        by_name = {p.name: p for p in cls.spec}
        for k in fixed:
            if k not in by_name:
                raise ValueError(f"{cls.name}: unknown parameter '{k}'; valid parameters: {', '.join(by_name) or '(none)'}")
        self.cls = cls
        self.given = {k: by_name[k].validate(cls.name, v) for k, v in fixed.items()}
        self.fixed_names = set(fixed)
        self.defaults = {p.name: p.validate(cls.name, p.default) for p in cls.spec}
        self.fixed = dict(self.defaults, **self.given)
        tied: dict[str, str] = {}
        if tie_isotropic and not getattr(cls, "isotropic", True):
            for a, b in isotropic_ties(cls.name, cls.spec).items():
                if a not in fixed and b not in fixed and by_name[a].fit and by_name[b].fit:
                    tied[a] = b
        self.tied = tied
        self.frozen: list[str] = []  # parameters held at their defaults by freeze()
        skip = set(tied.values())
        self.slots: list[_Slot] = []
        for p in cls.spec:
            if p.name in fixed or p.name in skip or not p.fit or p.kind not in ("scalar", "rgb"):
                continue
            lo, hi, log = _bounds(p)
            if p.kind == "scalar":
                self.slots.append(_Slot(p, None, lo, hi, log))
            else:
                for c in range(3):
                    self.slots.append(_Slot(p, c, lo, hi, log))
        self._update_bounds()

    def _update_bounds(self) -> None:
        self.free_names = list(dict.fromkeys(s.param.name for s in self.slots))
        self.lb = np.array([s.to_x(s.lo) for s in self.slots])
        self.ub = np.array([s.to_x(s.hi) for s in self.slots])

    def freeze(self, indices: Iterable[int]) -> None:
        """Hold some slots at their default (e.g. parameters the chosen options do not use)."""
        drop = set(indices)
        names = {self.slots[i].param.name for i in drop}
        # an rgb parameter is frozen only as a whole
        names = {n for n in names if all(i in drop for i, s in enumerate(self.slots) if s.param.name == n)}
        self.slots = [s for s in self.slots if s.param.name not in names]
        self.frozen = sorted(set(self.frozen) | names)
        self._update_bounds()

    def __len__(self) -> int:
        """The number of slots (free values)."""
        return len(self.slots)

    def params(self, x: np.ndarray) -> dict[str, Any]:
        """The given and frozen parameters plus the free values of ``x`` (tied ones copied)."""
        out = dict(self.given)
        for n in self.frozen:
            out[n] = self.defaults[n]
        rgb: dict[str, list[float]] = {}
        for s, xv in zip(self.slots, x):
            v = s.from_x(float(xv))
            if s.channel is None:
                out[s.param.name] = v
                if s.param.name in self.tied:
                    out[self.tied[s.param.name]] = v
            else:
                rgb.setdefault(s.param.name, [0.0, 0.0, 0.0])[s.channel] = v
        for k, v in rgb.items():
            out[k] = np.array(v)
        return out

    def model(self, x: np.ndarray) -> BRDF:
        """The model at ``x``, validated by its spec."""
        return self.cls(**self.params(x))

    def x_of(self, params: Mapping[str, Any]) -> np.ndarray:
        """The free vector of a parameter dict, clipped to the bounds."""
        x = []
        for s in self.slots:
            v = params[s.param.name]
            v = float(np.asarray(v).reshape(-1)[s.channel] if s.channel is not None and np.ndim(v) else v)
            x.append(s.to_x(v))
        return np.clip(np.array(x), self.lb, self.ub)

    def random_x(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """Random points; an rgb parameter gets a random grey level with a little colour."""
        xs = rng.uniform(self.lb, self.ub, size=(n, len(self.slots)))
        names = [s.param.name for s in self.slots]
        for name in dict.fromkeys(names):
            cols = [i for i, nm in enumerate(names) if nm == name]
            if len(cols) == 3:
                base = xs[:, cols[0]][:, None]
                span = (self.ub[cols] - self.lb[cols])[None, :]
                xs[:, cols] = np.clip(base + rng.normal(0, 0.1, (n, 3)) * span, self.lb[cols], self.ub[cols])
        return xs


__all__ = ["ParamPacker"]
