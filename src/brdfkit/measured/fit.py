"""Fitting analytic models to measured BRDFs.

``fit(name, measured, fixed={...}, metric="ngan")`` finds the parameters of the
registered model ``name`` that best reproduce ``measured`` (a MERL file, a
built-in material name, or any isotropic model), generically over the model's
parameter spec: every ``scalar``/``rgb`` parameter with ``fit=True`` is free
(an rgb parameter is three free values) within ``Param.fit_range`` or else
``Param.range``; choices, booleans, integers and ``fixed`` parameters keep their
value. Parameters flagged ``log_scale`` are optimised in log space.

Data. A few thousand (θh, θd, φd) samples, uniform in MERL's index space (the
square-root θh mapping puts many of them in the specular peak), with random
φh; both directions within ``max_theta_deg`` (80°, as Ngan et al. 2005) of the
normal. From a MERL table the samples are bin centres of measured bins and the
values are the table's; from any other model the model is evaluated. Each
sample carries the weight ``sin θh · dθh/du · sin θd cos θd`` (the Jacobian of
the half/difference parameterisation, dωi dωo = 4 cos θd dωh dωd with
dωh = sin θh dθh dφh, dωd = sin θd dθd dφd, over the sampling density; the
constant 4 cancels in the normalisation; θh = u² π/2 so dθh/du = π u), so every
metric below estimates an integral over pairs of directions (ωi, ωo), normalised
by the integral of the weight.

Metrics (``METRICS``), weighted RMS over samples and the three channels of a
transform ``T`` of the measured and the fitted values:

==========  =========================  =============================================
metric      T(f)                       source
==========  =========================  =============================================
``ngan``    f · cos θi                 Ngan, Durand & Matusik, "Experimental analysis
                                       of BRDF models", EGSR 2005 (the default)
``l2``      f                          plain L2 of the BRDF values
``log``     ln(1 + f · cos θi)         log-compressed (tames specular peaks)
``cbrt``    (f · cos θi)^(1/3)         Forés, Ferwerda & Gu, "Toward a perceptually
                                       based metric for BRDF modeling", CIC 2012
==========  =========================  =============================================

Optimiser: ``scipy.optimize.least_squares`` (trust-region reflective, bounds)
from several starts: the parameters' defaults plus the best of a few dozen
random points of the bounded parameter space (multi-start, so a local minimum
does not decide); the best result wins. A start that enters the basin of a
minimum an earlier start converged to (within :data:`JOIN_XTOL` of it in every
free value, :data:`JOIN_RTOL` in cost) stops there; its ``start_errors`` entry is
the error it had then. The Jacobian is by forward differences, except for the
columns of parameters the residuals are affine in with a constant coefficient
(a Lambertian ``kd``), found by probing (:func:`constant_columns`) and reused; the
slots of an rgb parameter whose residuals are those of their own channel only (found
by the same probes, :func:`channel_groups`) take one evaluation for their three columns.
"""

from __future__ import annotations

import math
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Mapping

import numpy as np

from ..geometry import from_rusinkiewicz
from ..models.base import BRDF
from ..params import Param, to_jsonable
from .merl import HALF_PI, MERLBRDF, RES_PHI_D, RES_THETA_D, RES_THETA_H, bin_centres

METRICS = ("ngan", "l2", "log", "cbrt")
METRIC_TITLES = {
    "ngan": "cosine-weighted RMS (Ngan, Durand & Matusik 2005)",
    "l2": "RMS of the BRDF values (plain L2)",
    "log": "RMS of ln(1 + f cos θi)",
    "cbrt": "RMS of the cube root of f cos θi (Forés, Ferwerda & Gu 2012)",
}


# --------------------------------------------------------------------------- data
@dataclass
class Samples:
    """Measured samples: directions, values (N, 3) in 1/sr, weights (N,) with mean 1."""

    wi: np.ndarray
    wo: np.ndarray
    f: np.ndarray
    w: np.ndarray
    source: str = ""

    @property
    def cos_i(self) -> np.ndarray:
        return self.wi[:, 2]

    def __len__(self) -> int:
        return len(self.w)


def resolve_source(measured: Any) -> BRDF:
    """The data to fit: any source :func:`brdfkit.sources.resolve` takes (a measured material, a MERL
    or other file, a fit's JSON, a model name or object)."""
    from ..sources import resolve

    return resolve(measured)


def _source_label(model: BRDF) -> str:
    return getattr(model, "label", None) or getattr(model, "name", "model")


def sample(measured: Any, n: int = 3000, seed: int = 0, max_theta_deg: float = 80.0) -> Samples:
    """``n`` weighted samples of a measured material / model (see the module docstring)."""
    model = resolve_source(measured)
    if not getattr(model, "isotropic", True):
        raise ValueError(f"{_source_label(model)}: fitting needs isotropic measured data")
    if not (0 < max_theta_deg <= 90):
        raise ValueError(f"max_theta_deg must be in (0, 90], got {max_theta_deg}")
    if n < 16:
        raise ValueError(f"need at least 16 samples, got {n}")
    rng = np.random.default_rng(seed)
    cos_max = math.cos(math.radians(max_theta_deg)) if max_theta_deg < 90 else 0.0
    is_table = isinstance(model, MERLBRDF)
    _, centre_td, centre_pd = bin_centres()
    wi_l, wo_l, f_l, w_l = [], [], [], []
    have = 0
    for _round in range(20):
        m = max(4 * n, 4096)
        if is_table:
            i = rng.integers(0, RES_THETA_H, m)
            j = rng.integers(0, RES_THETA_D, m)
            k = rng.integers(0, RES_PHI_D, m)
            u = (i + 0.5) / RES_THETA_H  # θh's bin centre in index space (θh = u² π/2 below)
            td, pd = centre_td[j], centre_pd[k]
        else:
            u = rng.random(m)
            td = rng.random(m) * HALF_PI
            pd = rng.random(m) * np.pi
        th = u * u * HALF_PI
        ph = rng.random(m) * 2 * np.pi
        # reciprocity: half of the samples with wi and wo swapped (φd + π)
        pd = pd + np.pi * (rng.random(m) < 0.5)
        wi, wo = from_rusinkiewicz(th, ph, td, pd)
        ok = (wi[:, 2] > cos_max) & (wo[:, 2] > cos_max)
        if is_table:
            v = np.moveaxis(model.table[:, i, j, k], 0, -1)
            ok &= (v >= 0).all(axis=-1)
        idx = np.flatnonzero(ok)[: n - have]
        if idx.size == 0:
            continue
        if is_table:
            fv = v[idx]
        else:
            fv = np.asarray(model.eval(wi[idx], wo[idx]), dtype=np.float64)
        wts = np.sin(th[idx]) * (np.pi * u[idx]) * np.sin(td[idx]) * np.cos(td[idx])
        wi_l.append(wi[idx])
        wo_l.append(wo[idx])
        f_l.append(fv)
        w_l.append(wts)
        have += idx.size
        if have >= n:
            break
    if have < 16:
        raise ValueError(f"{_source_label(model)}: too few measured samples within {max_theta_deg}° ({have})")
    w = np.concatenate(w_l)
    f = np.concatenate(f_l)
    if not np.isfinite(f).all():
        raise ValueError(f"{_source_label(model)}: measured values are not finite")
    return Samples(np.concatenate(wi_l), np.concatenate(wo_l), f, w / w.mean(), _source_label(model))


def table(measured: Any, max_theta_deg: float = 80.0) -> Samples:
    """Every measured bin as a sample (``samples="table"``): MERL's 90 × 90 × 180 bin centres with
    both directions within ``max_theta_deg`` of the normal, φh = 0 (the data are isotropic),
    weighted as :func:`sample` weights them. From a MERL table the values are the table's (bins
    marked missing are left out); from any other isotropic model (a built-in material) the model
    is evaluated at the bin centres."""
    model = resolve_source(measured)
    if not getattr(model, "isotropic", True):
        raise ValueError(f"{_source_label(model)}: fitting needs isotropic measured data")
    if not (0 < max_theta_deg <= 90):
        raise ValueError(f"max_theta_deg must be in (0, 90], got {max_theta_deg}")
    cos_max = math.cos(math.radians(max_theta_deg)) if max_theta_deg < 90 else 0.0
    th, td, pd = bin_centres()
    I, J, K = np.meshgrid(np.arange(RES_THETA_H), np.arange(RES_THETA_D), np.arange(RES_PHI_D), indexing="ij")
    I, J, K = I.ravel(), J.ravel(), K.ravel()
    wi, wo = from_rusinkiewicz(th[I], np.zeros(I.size), td[J], pd[K])
    ok = (wi[:, 2] > cos_max) & (wo[:, 2] > cos_max)
    if isinstance(model, MERLBRDF):
        v = np.moveaxis(model.table[:, I, J, K], 0, -1)
        ok &= (v >= 0).all(axis=-1)
        idx = np.flatnonzero(ok)
        fv = np.ascontiguousarray(v[idx], dtype=np.float64)
    else:
        idx = np.flatnonzero(ok)
        fv = np.asarray(model.eval(wi[idx], wo[idx]), dtype=np.float64)
    if idx.size < 16:
        raise ValueError(f"{_source_label(model)}: too few measured bins within {max_theta_deg}° ({idx.size})")
    if not np.isfinite(fv).all():
        raise ValueError(f"{_source_label(model)}: measured values are not finite")
    u = (I[idx] + 0.5) / RES_THETA_H
    w = np.sin(th[I[idx]]) * (np.pi * u) * np.sin(td[J[idx]]) * np.cos(td[J[idx]])
    return Samples(np.ascontiguousarray(wi[idx]), np.ascontiguousarray(wo[idx]), fv, w / w.mean(),
                   _source_label(model))


def subsample(data: Samples, n: int, seed: int = 0) -> Samples:
    """A uniformly random subset of ``n`` of ``data``'s samples, weights kept (renormalised to mean 1):
    the same integral estimated from fewer points, for the multi-start search of a table-scale fit."""
    if n >= len(data):
        return data
    rng = np.random.default_rng(seed)
    idx = np.sort(rng.choice(len(data), size=n, replace=False))
    w = data.w[idx]
    return Samples(data.wi[idx], data.wo[idx], data.f[idx], w / w.mean(), data.source)


def _transform(metric: str) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    if metric == "ngan":
        return lambda f, c: f * c
    if metric == "l2":
        return lambda f, c: f
    if metric == "log":
        return lambda f, c: np.log1p(np.maximum(f * c, 0.0))
    if metric == "cbrt":
        return lambda f, c: np.cbrt(np.maximum(f * c, 0.0))
    raise ValueError(f"unknown metric {metric!r}; valid metrics: {', '.join(METRICS)}")


def error(model: BRDF, samples: Samples, metric: str = "ngan") -> float:
    """The metric's weighted RMS error of ``model`` against ``samples``."""
    T = _transform(metric)
    c = samples.cos_i[:, None]
    d = T(np.asarray(model.eval(samples.wi, samples.wo), np.float64), c) - T(samples.f, c)
    return float(np.sqrt(np.mean(samples.w[:, None] * d * d)))


# --------------------------------------------------------------------------- parameters
@dataclass
class _Slot:
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


# Anisotropic models fitted to isotropic data: these pairs share one free value.
_TIES = (("alpha_x", "alpha_y"), ("nu", "nv"), ("n_u", "n_v"), ("alpha_u", "alpha_v"), ("m_x", "m_y"),
         ("cx_1", "cy_1"), ("cx_2", "cy_2"), ("cx_3", "cy_3"))
#: the pairs, also for a second lobe's parameters (``lobes=2``: names with the suffix ``_2``)
ISOTROPIC_TIES = _TIES + tuple((a + "_2", b + "_2") for a, b in _TIES[:5])


class ParamPacker:
    """Maps between a model's parameter dict and the free vector the optimiser sees.

    Free: every ``scalar``/``rgb`` parameter with ``fit=True`` not in ``fixed``
    (rgb: three slots). For an anisotropic model fitted to isotropic data
    (``tie_isotropic``), each pair of :data:`ISOTROPIC_TIES` is one slot. The
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
            for a, b in ISOTROPIC_TIES:
                if a in by_name and b in by_name and a not in fixed and b not in fixed \
                        and by_name[a].fit and by_name[b].fit:
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
        return len(self.slots)

    def params(self, x: np.ndarray) -> dict[str, Any]:
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
        return self.cls(**self.params(x))

    def x_of(self, params: Mapping[str, Any]) -> np.ndarray:
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


# --------------------------------------------------------------------------- two lobes
#: parameters that belong to the diffuse part of a model (a second lobe has none)
DIFFUSE_PARAMS = ("kd", "rd")
_TWO_LOBE: dict[type, type] = {}


def two_lobe(cls: type[BRDF]) -> type[BRDF]:
    """``cls`` plus a second specular lobe of the same form (Ngan et al. 2005's two-lobe fits).

    The class's parameters are ``cls``'s plus a copy ``<name>_2`` of every fitted scalar/rgb
    parameter except the diffuse ones (:data:`DIFFUSE_PARAMS`); options (choices, bools) are
    shared. ``eval`` is ``cls(params) + cls(params_2 with kd = rd = 0)``: the first term keeps
    the diffuse part, the second is one more lobe. (The Lafortune model has lobes of its own:
    ``fit(..., lobes=2)`` sets its ``lobes`` parameter instead.)
    """
    if cls in _TWO_LOBE:
        return _TWO_LOBE[cls]
    from dataclasses import replace

    second = tuple(replace(p, name=p.name + "_2", doc=f"{p.doc} (second lobe)") for p in cls.spec
                   if p.name not in DIFFUSE_PARAMS and p.kind in ("scalar", "rgb") and p.fit)
    base_names = tuple(p.name for p in cls.spec)
    zero_diffuse = {p.name: 0.0 for p in cls.spec if p.name in DIFFUSE_PARAMS}

    class TwoLobe(BRDF):
        name = cls.name + "+lobe2"
        title = f"{cls.name} with a second specular lobe"
        reference = cls.reference
        isotropic = cls.isotropic
        spec = tuple(cls.spec) + second
        base = cls

        def _setup(self) -> None:
            p = self.params
            one = {k: p[k] for k in base_names}
            two = dict(one, **zero_diffuse, **{q.name[:-2]: p[q.name] for q in second})
            self.lobe1, self.lobe2 = cls(**one), cls(**two)

        def _eval(self, wi, wo, p):
            return self.lobe1.eval(wi, wo) + self.lobe2.eval(wi, wo)

    TwoLobe.__name__ = TwoLobe.__qualname__ = cls.__name__ + "TwoLobe"
    _TWO_LOBE[cls] = TwoLobe
    return TwoLobe


# --------------------------------------------------------------------------- the fit
@dataclass
class FitResult:
    """The outcome of :func:`fit`: the fitted model, its parameters and its error."""

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


def _at_bound(packer: "ParamPacker", x: np.ndarray) -> list[str]:
    """The free values that ended on a fitting bound: ``name`` or ``name[channel]``, with ``=lo``/``=hi``."""
    out = []
    span = packer.ub - packer.lb
    for s, xv, lo, hi, sp in zip(packer.slots, x, packer.lb, packer.ub, span):
        side = "lo" if xv - lo <= AT_BOUND_TOL * sp else "hi" if hi - xv <= AT_BOUND_TOL * sp else None
        if side:
            label = s.param.name if s.channel is None else f"{s.param.name}[{s.channel}]"
            out.append(f"{label}={side}")
    return out


def _freeze_unused(packer: ParamPacker, residuals, rng: np.random.Generator) -> None:
    """Freeze slots that change nothing at the defaults nor at a random point (unused options)."""
    if len(packer) == 0:
        return
    pts = [packer.x_of(packer.fixed), packer.random_x(rng, 1)[0]]
    unused = set(range(len(packer)))
    for x in pts:
        r0 = residuals(x)
        for i in list(unused):
            y = x.copy()
            mid = 0.5 * (packer.lb[i] + packer.ub[i])
            y[i] = x[i] + 0.25 * (mid - x[i]) + 0.05 * (packer.ub[i] - packer.lb[i]) * (1 if x[i] <= mid else -1)
            if np.any(residuals(y) != r0):
                unused.discard(i)
    if unused and len(unused) < len(packer):
        packer.freeze(unused)


#: samples of the multi-start search of a ``samples="table"`` fit (the polish runs on every bin)
TABLE_SEARCH_SAMPLES = 3000


class _PreparedEval:
    """``x ↦`` the values ``(n, 3)`` of ``packer.model(x)`` at ``data``'s directions, for the hot loop.

    ``packer.model(x).eval(data.wi, data.wo)`` would, per call, validate every parameter,
    broadcast, flatten and unit-check the same directions and allocate the output (about
    half of a 3000-sample evaluation's time). Here the directions are prepared and
    unit-checked once (:func:`brdfkit.engine.evaluate.prepare`), and a call builds the
    model's parameters, its ``kernel_args()`` (the model's own ``_setup`` and ``_pack``) and
    runs the engine (:func:`brdfkit.engine.evaluate.run_kernel`) into one preallocated
    output: the same kernel on the same arrays and parameters, so the same bits.

    Validation is skipped only for values it would accept unchanged: the packer's defaults
    and fixed values were validated when it was built, and a free value is used only if it
    lies within its slot's ``[lo, hi]``, which :func:`_bounds` keeps inside the spec's range
    (open ends moved inwards); anything else (NaN, say) goes through ``packer.model(x)``,
    which raises the spec's error. A class with its own ``__init__`` is always built by
    ``packer.model(x)``, validated, unless it declares ``from_valid_is_init`` beside it
    (``microfacet``, whose ``__init__`` only resolves the roughness aliases). Models without a
    kernel, or whose ``kernel_args()`` is ``None``, are evaluated by ``BRDF.eval`` as before.
    The returned array is overwritten by the next call."""

    def __init__(self, packer: "ParamPacker", data: Samples) -> None:
        from ..engine.evaluate import check_unit_flat, prepare

        self.packer, self.data = packer, data
        cls = packer.cls
        self.kernel = getattr(cls, "kernel", None)
        # _from_valid equals __init__ only for BRDF's own __init__ or a class that declares it (microfacet)
        self.unvalidated = cls.__init__ is BRDF.__init__ or (
            "__init__" in vars(cls) and vars(cls).get("from_valid_is_init", False))
        self.fi, self.fo, shape, dtype = prepare(cls.name, data.wi, data.wo)
        if self.kernel is not None:
            check_unit_flat(cls.name, self.fi, self.fo, dtype)
        self.out = np.empty(shape, dtype=dtype)
        self.fout = self.out.reshape(-1, 3)

    def model(self, x: np.ndarray) -> BRDF:
        """``packer.model(x)``, without re-validating values known to be valid (see the class)."""
        packer = self.packer
        if not self.unvalidated:
            return packer.model(x)
        for s, xv in zip(packer.slots, x):
            v = s.from_x(float(xv))
            if not s.lo <= v <= s.hi:  # NaN: the spec's own error
                return packer.model(x)
        params = dict(packer.defaults, **packer.params(x))  # the spec's order, as validate() gives
        for k, v in params.items():
            if isinstance(v, np.ndarray) and v.flags.writeable:  # validate() returns read-only rgb
                v.setflags(write=False)
        return packer.cls._from_valid(params)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        from ..engine.evaluate import run_kernel

        m = self.model(x)
        args = m.kernel_args() if self.kernel is not None else None
        if args is None:
            return m.eval(self.data.wi, self.data.wo)
        run_kernel(m, self.kernel, args, self.fi, self.fo, self.fout)
        return self.out


def _residual_fn(packer: "ParamPacker", data: Samples, T, metric: str = "", prepared: bool = True):
    """``x ↦`` the weighted, normalised residual vector of ``data`` (its squared norm is the metric²).

    For the metrics linear in f (``ngan``: f cos θi, ``l2``: f) the weights, cosines and target
    are folded into two arrays once, so a call is one model evaluation and one fused update.
    ``prepared``: evaluate through :class:`_PreparedEval` (False: ``packer.model(x).eval``, the
    same values, kept to test that)."""
    c = data.cos_i[:, None]
    target = T(data.f, c)
    sw = np.sqrt(data.w)[:, None]
    scale = 1.0 / math.sqrt(target.size)
    if prepared:
        values = _PreparedEval(packer, data)
    else:
        def values(x: np.ndarray) -> np.ndarray:
            return packer.model(x).eval(data.wi, data.wo)

    if metric in ("ngan", "l2"):
        gain = np.ascontiguousarray(np.broadcast_to(sw * scale * (c if metric == "ngan" else 1.0), target.shape))
        offset = gain * data.f

        def residuals(x: np.ndarray) -> np.ndarray:
            r = np.multiply(values(x), gain)
            return np.subtract(r, offset, out=r).ravel()

        return residuals

    def residuals(x: np.ndarray) -> np.ndarray:
        f = np.asarray(values(x), np.float64)
        return (sw * (T(f, c) - target)).ravel() * scale

    return residuals


def _value_derivative(residuals, packer: "ParamPacker", x: np.ndarray, i: int, r0: np.ndarray
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


def probe_columns(residuals, packer: "ParamPacker", points: Iterable[np.ndarray]) -> ColumnProbes:
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


def constant_columns(residuals, packer: "ParamPacker", points: Iterable[np.ndarray],
                     probes: ColumnProbes | None = None) -> dict[int, np.ndarray]:
    """The slots whose residuals' derivative with respect to the parameter's value is the same at
    every one of ``points``: parameters the model is affine in with a coefficient no other
    parameter changes (a Lambertian ``kd``: ∂f/∂kd = 1/π). Their Jacobian column is known once
    for all (:func:`_jacobian`). Returns ``{slot: ∂r/∂v}``; costs one evaluation per point and
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


def channel_groups(residuals, packer: "ParamPacker", points: Iterable[np.ndarray],
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


def _jacobian(fn: "_Start", packer: "ParamPacker", const: Mapping[int, np.ndarray],
              groups: list[list[int]] | None = None):
    """The residuals' Jacobian in the optimiser's coordinates: forward differences (the step of
    ``scipy.optimize.approx_derivative``'s 2-point scheme, away from a bound) except for the
    :func:`constant_columns`, which are their fixed ∂r/∂v times dv/dx (v for a log-scale slot).

    ``groups`` (:func:`channel_groups`): slots of one channel each whose differences one
    evaluation gives; each column is still the quotient of the bits it would have by its own
    evaluation, and the basin-joining test of :class:`_Start` still sees every column's point
    with its residuals, in the same order. Without ``groups``, one evaluation per column."""
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


#: a start that reaches a point within this fraction of every free value's (optimiser-space) range
#: of a minimum an earlier start converged to, with a cost within :data:`JOIN_RTOL` of that
#: minimum's, is in the same basin: it stops there instead of converging again (the basin-joining
#: rule of clustering multi-start methods, Rinnooy Kan & Timmer, Math. Programming 39, 1987)
JOIN_XTOL = 1e-2
JOIN_RTOL = 1e-3


class _Joined(Exception):
    """Raised inside a start's residuals when it has entered a known minimum's basin."""

    def __init__(self, x: np.ndarray, cost: float) -> None:
        super().__init__()
        self.x, self.cost = x, cost


class _Start:
    """One local optimisation's residuals: counts evaluations, remembers the last one (the
    Jacobian is taken where the residuals were just evaluated) and stops in a known basin."""

    def __init__(self, residuals, packer: "ParamPacker", known: list[tuple[np.ndarray, float]]) -> None:
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


def _local(residuals, x0, packer, max_nfev, tol, known=(), const=None, groups=None):
    """A bounded least-squares run from ``x0``: ``(x, cost = Σ r², evaluations, joined)``.

    ``known``: ``(x, cost)`` of minima found by earlier starts; a run that enters one's
    basin (:data:`JOIN_XTOL`, :data:`JOIN_RTOL`) stops there. ``const``: the
    :func:`constant_columns` of the Jacobian; ``groups``: its :func:`channel_groups`."""
    from scipy.optimize import least_squares

    x0 = np.clip(x0, packer.lb, packer.ub)
    # least_squares needs x0 strictly inside the bounds
    eps = 1e-9 * np.maximum(1.0, packer.ub - packer.lb)
    x0 = np.minimum(np.maximum(x0, packer.lb + eps), packer.ub - eps)
    # a model evaluated in float32 (a .brdf file's GLSL) declares a finite-difference step its
    # values can resolve; scipy's default (~1e-8 relative) would see no change at all
    diff_step = getattr(packer.cls, "fit_diff_step", None)
    fn = _Start(residuals, packer, list(known))
    grouped = groups is not None and any(len(g) > 1 for g in groups)
    jac = _jacobian(fn, packer, const or {}, groups if grouped else None) if const or grouped else "2-point"
    try:
        res = least_squares(
            fn, x0, jac=jac, bounds=(packer.lb, packer.ub), method="trf", x_scale="jac", tr_solver="lsmr",
            max_nfev=max_nfev, xtol=tol, ftol=tol, gtol=tol, diff_step=diff_step,
        )
    except _Joined as j:
        return j.x, j.cost, fn.nfev, True
    return res.x, float(2 * res.cost), fn.nfev, False


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


#: Levenberg-Marquardt iterations of the table-scale polish
POLISH_ITERATIONS = 4


def _polish(residuals, x, packer: "ParamPacker", iterations: int = POLISH_ITERATIONS) -> tuple[np.ndarray, int]:
    """A few bounded Levenberg-Marquardt steps on a large residual vector (every table bin).

    ``least_squares`` would hold the whole (residuals × parameters) Jacobian and run LSMR
    on it (2.7 M × 10 for a table: seconds per iteration); here the forward-difference
    columns are reduced at once to the normal equations JᵀJ (n × n) and Jᵀr, and a step is
    kept only if it lowers the cost, so the result is never worse than the start.
    Returns ``(x, evaluations)``."""
    n = len(x)
    r = residuals(x)
    cost = float(r @ r)
    used, lam = 1, 1e-3
    for _ in range(iterations):
        J = np.empty((n, r.size), np.float32)  # forward-difference columns, as rows
        for i in range(n):
            h = 1e-6 * max(1.0, abs(float(x[i])))
            if x[i] + h > packer.ub[i]:
                h = -h
            y = x.copy()
            y[i] += h
            J[i] = (residuals(y) - r) / h
            used += 1
        JtJ = (J @ J.T).astype(np.float64)
        Jtr = (J @ r.astype(np.float32)).astype(np.float64)
        del J
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
    and the best of ``candidates`` random points). ``data``: precomputed :func:`sample` or
    :func:`table` output (then ``measured`` only names the source).
    Returns a :class:`FitResult` (``params`` holds every parameter of the model;
    ``at_bound`` lists the free values that ended on a fitting bound).
    """
    from .. import registry

    t0 = time.perf_counter()
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
    cls = name if isinstance(name, type) and issubclass(name, BRDF) else registry.get(name)
    fixed = dict(fixed or {})
    if lobes == 2:
        if any(p.name == "lobes" for p in cls.spec):
            fixed.setdefault("lobes", 2)
        else:
            cls = two_lobe(cls)
    packer = ParamPacker(cls, fixed)
    if data is None:
        data = table(measured, max_theta_deg) if is_table else sample(measured, n=samples, seed=seed,
                                                                      max_theta_deg=max_theta_deg)
    search = subsample(data, TABLE_SEARCH_SAMPLES, seed) if is_table else data
    T = _transform(metric)
    residuals = _residual_fn(packer, search, T, metric)

    def cost(x: np.ndarray) -> float:
        r = residuals(x)
        return float(r @ r)

    nfev = 0
    if len(packer) == 0:  # nothing free: just evaluate
        model = packer.model(np.zeros(0))
        err = error(model, data, metric)
        return FitResult(model, dict(model.params), err, metric, data.source, len(data), 0, 1,
                         time.perf_counter() - t0, sorted(packer.fixed_names), [], [err], lobes=lobes,
                         search_samples=len(search))
    # from here on the model is built from the free values
    rng = np.random.default_rng(seed + 1)
    nfev += 2 * (len(packer) + 1)  # _freeze_unused: at most 2 points × (base + one probe per slot)
    with _engine_threads(len(search)):
        _freeze_unused(packer, residuals, rng)
        x_default = packer.x_of(packer.fixed)
        cand = [x_default]
        if candidates > 0:
            cand += list(packer.random_x(rng, candidates))
        costs = np.array([cost(x) for x in cand])
        # Jacobian columns known once for all (a float32-evaluated model's differences are too noisy)
        const, groups = {}, None
        if not getattr(cls, "fit_diff_step", None):
            probes = probe_columns(residuals, packer, cand[:2])
            nfev += probes.evaluations
            const = constant_columns(residuals, packer, cand[:2], probes)
            groups = channel_groups(residuals, packer, cand[:2], const, probes)
    nfev += len(cand)
    order = [0] + [int(i) for i in np.argsort(costs) if i != 0]
    chosen = order[:starts]

    total = len(chosen) + (1 if search is not data else 0)
    bar_ctx = None
    callback = progress if callable(progress) else None
    if progress is True:
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

        bar_ctx = Progress(
            TextColumn(f"fit {cls.name} ← {data.source}"), BarColumn(), TextColumn("{task.completed}/{task.total} starts"),
            TimeElapsedColumn(), transient=True,
        )
        bar_ctx.start()
        task = bar_ctx.add_task("fit", total=total)
    best_x, best_cost = None, math.inf
    start_errors = []
    known: list[tuple[np.ndarray, float]] = []  # the minima the starts converged to
    try:
        for n_done, ci in enumerate(chosen, 1):
            with _engine_threads(len(search)):
                x, cst, used, joined = _local(residuals, cand[ci], packer, max_nfev or 100, tol, known, const, groups)
            nfev += used
            start_errors.append(math.sqrt(cst))
            if not joined:
                known.append((x, cst))
            if cst < best_cost:
                best_cost, best_x = cst, x
            if bar_ctx is not None:
                bar_ctx.update(task, advance=1)
            if callback is not None:
                callback(n_done, total)
        if search is not data:  # polish the best start on every bin
            best_x, used = _polish(_residual_fn(packer, data, T, metric), best_x, packer)
            nfev += used
            if bar_ctx is not None:
                bar_ctx.update(task, advance=1)
            if callback is not None:
                callback(total, total)
    finally:
        if bar_ctx is not None:
            bar_ctx.stop()
    model = packer.model(best_x)
    err = error(model, data, metric)
    return FitResult(
        model, dict(model.params), err, metric, data.source, len(data), len(chosen), nfev,
        time.perf_counter() - t0, sorted(packer.fixed_names), list(packer.frozen), start_errors,
        len(packer), _at_bound(packer, best_x), lobes, len(search),
    )


def fit_batch(
    names: Iterable[str],
    sources: Iterable[str],
    metric: str = "ngan",
    fixed: Mapping[str, Mapping[str, Any]] | None = None,
    progress: bool = True,
    **kw: Any,
) -> list[FitResult]:
    """Fit every model in ``names`` to every source; the samples of a source are shared by the models."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    names = list(names)
    sources = list(sources)
    fixed = fixed or {}
    out: list[FitResult] = []
    samp_kw = {k: kw.pop(k) for k in ("samples", "seed", "max_theta_deg") if k in kw}
    n_samp = samp_kw.pop("samples", 3000)
    import sys

    log_lines = progress and not sys.stderr.isatty()  # a log file: one plain line per material
    t0 = time.perf_counter()
    with Progress(
        TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
        TimeRemainingColumn(), disable=not progress or log_lines,
    ) as bar:
        task = bar.add_task("fitting", total=len(names) * len(sources))
        for n_src, src in enumerate(sources, 1):
            if log_lines:
                print(f"[{n_src}/{len(sources)}] {src} ({time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)
            data = (table(src, samp_kw.get("max_theta_deg", 80.0)) if n_samp == "table"
                    else sample(src, n=n_samp, **samp_kw))
            for nm in names:
                bar.update(task, description=f"{nm:>18} ← {data.source}")
                out.append(fit(nm, src, fixed=fixed.get(nm), metric=metric, data=data, samples=n_samp,
                               seed=samp_kw.get("seed", 0), **kw))
                bar.update(task, advance=1)
    return out


__all__ = ["fit", "fit_batch", "FitResult", "Samples", "sample", "table", "subsample", "two_lobe", "error", "METRICS", "METRIC_TITLES", "ParamPacker"]
