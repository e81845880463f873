"""The outcome of a fit (:class:`FitResult`) and what is reported of it.

A fitted value is reported as the optimiser left it, except that a subnormal float (a
value like 4.94e-324 that a free value pressed against a bound of 0 can end on) is reported
as 0.0 (:func:`flush_subnormal`): it is 0 to every printed digit, and ``4.94e-324`` in a
table of parameters only puzzles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..models.base import BRDF
from ..params import to_jsonable
from .metrics import METRIC_TITLES
from .packing import ParamPacker

#: the smallest positive normal float64; a nonzero float of smaller magnitude is subnormal
_TINY = float(np.finfo(np.float64).tiny)


def _flush_float(v: float) -> float:
    return 0.0 if v != 0.0 and abs(v) < _TINY else v


def flush_subnormal(value: Any) -> Any:
    """``value`` with every subnormal float replaced by 0.0: a float, a float array (copied,
    read-only like the spec's rgb values, only if it has one), or a dict or list of them;
    anything else (and a value without subnormals) is returned as it is."""
    if isinstance(value, dict):
        return {k: flush_subnormal(v) for k, v in value.items()}
    if isinstance(value, list):
        return [flush_subnormal(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return type(value)(_flush_float(float(value))) if math.isfinite(value) else value
    if isinstance(value, np.ndarray) and value.dtype.kind == "f":
        tiny = (value != 0) & (np.abs(value) < _TINY)
        if not tiny.any():
            return value
        out = np.where(tiny, 0.0, value).astype(value.dtype)
        out.setflags(write=value.flags.writeable)
        return out
    return value


@dataclass
class FitResult:
    """The outcome of :func:`~brdfkit.measured.optimise.fit`: the fitted model, its parameters and its error."""

    model: BRDF
    params: dict[str, Any]
    error: float
    metric: str
    source: str
    samples: int
    starts: int
    nfev: int
    seconds: float
    fixed: list[str] = field(default_factory=list)
    unused: list[str] = field(default_factory=list)
    start_errors: list[float] = field(default_factory=list)
    n_free: int = 0
    at_bound: list[str] = field(default_factory=list)
    lobes: int = 1
    search_samples: int = 0

    def __post_init__(self) -> None:
        # results and their output show a subnormal float as 0 (the module docstring)
        self.params = flush_subnormal(self.params)
        self.error = flush_subnormal(self.error)
        self.start_errors = flush_subnormal(list(self.start_errors))

    def to_json(self) -> dict[str, Any]:
        return {
            "model": self.model.name,
            "source": self.source,
            "params": to_jsonable(self.params),
            "error": self.error,
            "metric": self.metric,
            "metric_title": METRIC_TITLES[self.metric],
            "fixed": self.fixed,
            "unused": self.unused,
            "free_values": self.n_free,
            "samples": self.samples,
            "search_samples": self.search_samples or self.samples,
            "lobes": self.lobes,
            "starts": self.starts,
            "start_errors": [float(e) for e in self.start_errors],
            "at_bound": self.at_bound,
            "nfev": self.nfev,
            "seconds": round(self.seconds, 3),
        }

    def __repr__(self) -> str:
        return f"FitResult({self.model!r}, error={self.error:.6g}, metric={self.metric!r})"

    def _repr_html_(self) -> str:  # Jupyter: the fit's report (brdfkit.interchange.notebook)
        from ..interchange.notebook import fit_html

        return fit_html(self)


#: a fitted value within this fraction of its (optimiser-space) range of a bound counts as "at the bound"
AT_BOUND_TOL = 1e-4


def slots_at_bound(packer: ParamPacker, x: np.ndarray) -> list[str]:
    """The free values that ended on a fitting bound: ``name`` or ``name[channel]``, with ``=lo``/``=hi``."""
    out = []
    span = packer.ub - packer.lb
    for s, xv, lo, hi, sp in zip(packer.slots, x, packer.lb, packer.ub, span):
        side = "lo" if xv - lo <= AT_BOUND_TOL * sp else "hi" if hi - xv <= AT_BOUND_TOL * sp else None
        if side:
            label = s.param.name if s.channel is None else f"{s.param.name}[{s.channel}]"
            out.append(f"{label}={side}")
    return out


__all__ = ["FitResult", "AT_BOUND_TOL", "slots_at_bound", "flush_subnormal"]
