"""Parameter specifications: the single source of truth for every model parameter.

A model declares its parameters once, as a tuple of :class:`Param`. That tuple
drives

* validation in ``bk.model(name, **params)`` (:func:`validate`),
* ``brdfkit info MODEL`` (:func:`Param.as_row`),
* parsing of ``-p name=value`` on the command line (:func:`parse_value`),
* the web UI's sliders and the fitting bounds (``range``, ``fit``).

Kinds
-----
``scalar``  a finite float within ``range``
``rgb``     a linear-RGB triple (a scalar means grey), each channel within ``range``
``choice``  one of ``choices`` (a string)
``bool``    ``True``/``False``
``int``     an integer within ``range``

``unit`` is empty for dimensionless numbers (albedos, slopes, exponents,
refractive indices); ``info`` shows them as ``1``, SI's notation.

Every error is a one-line :class:`ValueError` naming the model, the parameter
and what is allowed.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

KINDS = ("scalar", "rgb", "choice", "bool", "int")


def to_float(value: Any, what: str, *, finite: bool = True) -> float:
    """The one number parser: ``value`` (a Python/numpy number or numeric text) as a float.

    Every failure is a one-line ``ValueError`` naming ``what``: text that is not
    a number, booleans, containers, integers too large for a float
    (``10**400``, which ``float()`` answers with ``OverflowError``), text that
    overflows (``"1e400"``, which ``float()`` silently turns into ``inf``) and,
    with ``finite`` (the default), NaN and infinities.
    """
    if isinstance(value, (bool, np.bool_)) or value is None:
        raise ValueError(f"{what} must be a number, got {value!r}")
    if isinstance(value, bytes):
        raise ValueError(f"{what} must be a number, got {value!r}")
    if isinstance(value, str):
        text = value.strip()
        if len(text) > 400:
            raise ValueError(f"{what} must be a number, got a {len(text)}-character text")
        try:
            f = float(text)
        except ValueError:
            raise ValueError(f"{what} must be a number, got {value!r}") from None
        if finite and not math.isfinite(f):
            low = text.lower().lstrip("+-")
            if low in ("inf", "infinity", "nan"):
                raise ValueError(f"{what} must be finite, got {value!r}")
            raise ValueError(f"{what} = {value!r} overflows a float (largest {sys.float_info.max:.4g})")
        return f
    if isinstance(value, (list, tuple, dict, set, frozenset)) or (isinstance(value, np.ndarray) and value.ndim != 0):
        raise ValueError(f"{what} must be a single number, got {_short(value)}")
    try:
        f = float(value)
    except OverflowError:
        raise ValueError(f"{what} = {_short(value)} overflows a float (largest {sys.float_info.max:.4g})") from None
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be a number, got {_short(value)}") from None
    if finite and not math.isfinite(f):
        raise ValueError(f"{what} must be finite, got {_short(value)}")
    return f


def _short(value: Any) -> str:
    """``repr(value)``, cut to 60 characters (a 400-digit integer must not fill the screen)."""
    r = repr(value)
    return r if len(r) <= 60 else f"{r[:40]}... ({len(r)} characters)"


@dataclass(frozen=True)
class Param:
    """One parameter of a model.

    ``range`` is ``(lo, hi)`` (inclusive unless ``open_lo``/``open_hi``) for
    ``scalar``, ``rgb`` and ``int``; ``math.inf`` is allowed as ``hi``.
    ``fit_range`` optionally narrows the range used as fitting bounds (e.g. an
    exponent that may be 0 but is fitted within [1, 1e5]).
    ``fit`` says whether the fitter may vary it (choices and bools never are).
    ``tie`` names this parameter's isotropic twin: when the (anisotropic) model is fitted
    to isotropic data, this parameter takes the twin's value instead of a free value of its
    own (``alpha_y`` with ``tie="alpha_x"``: one roughness). Only a ``scalar`` may be tied,
    to another ``scalar`` of the same spec that is not tied itself (:func:`isotropic_ties`).
    """

    name: str
    kind: str
    default: Any
    range: tuple[float, float] | None = None
    unit: str = ""
    doc: str = ""
    choices: tuple[str, ...] = ()
    open_lo: bool = False
    open_hi: bool = False
    fit: bool = True
    fit_range: tuple[float, float] | None = None
    log_scale: bool = False  # UI / fitting hint: the parameter spans decades
    tie: str = ""  # fitting to isotropic data: the parameter whose value this one shares

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise TypeError(f"unknown parameter kind {self.kind!r}")
        if self.tie and (self.kind != "scalar" or self.tie == self.name):
            raise TypeError(f"parameter {self.name}: tie={self.tie!r} needs a scalar tied to another parameter")
        if self.kind == "choice" and self.default not in self.choices:
            raise TypeError(f"default {self.default!r} of {self.name} not among {self.choices}")

    # -- description -----------------------------------------------------
    def range_text(self) -> str:
        if self.kind == "choice":
            return " | ".join(self.choices)
        if self.kind == "bool":
            return "true | false"
        if self.range is None:
            return "any finite"
        lo, hi = self.range
        lb = "(" if self.open_lo else "["
        rb = ")" if (self.open_hi or math.isinf(hi)) else "]"
        return f"{lb}{_fmt(lo)}, {_fmt(hi)}{rb}"

    def unit_text(self) -> str:
        """The unit as shown: ``"1"`` for a dimensionless number (SI's notation), ``""`` for choices and bools."""
        if self.kind in ("choice", "bool"):
            return ""
        return self.unit or "1"

    def default_json(self) -> Any:
        d = self.default
        if isinstance(d, np.ndarray):
            return d.tolist()
        if isinstance(d, tuple):
            return list(d)
        return d

    def as_row(self) -> dict[str, Any]:
        """The row ``model_info`` and ``brdfkit info`` show."""
        return {
            "name": self.name,
            "kind": self.kind,
            "default": self.default_json(),
            "range": self.range_text(),
            "min": None if self.range is None or self.kind in ("choice", "bool") else self.range[0],
            "max": None
            if self.range is None or self.kind in ("choice", "bool") or math.isinf(self.range[1])
            else self.range[1],
            "choices": list(self.choices) if self.kind == "choice" else None,
            "unit": self.unit_text(),
            "doc": self.doc,
        }

    # -- validation --------------------------------------------------------
    def _check_number(self, model: str, x: float, what: str) -> None:
        if not math.isfinite(x):
            raise ValueError(
                f"{model}: parameter '{self.name}'{what} must be finite, got {x!r}; allowed {self.range_text()}"
            )
        if self.range is not None:
            lo, hi = self.range
            bad_lo = x <= lo if self.open_lo else x < lo
            bad_hi = x >= hi if self.open_hi else x > hi
            if bad_lo or bad_hi:
                raise ValueError(
                    f"{model}: parameter '{self.name}'{what} = {_fmt(x)} is out of range; allowed {self.range_text()}"
                )

    def validate(self, model: str, value: Any) -> Any:
        """Return the canonical value (float, (3,) float64 array, str, bool, int)."""
        k = self.kind
        if k == "bool":
            if isinstance(value, (bool, np.bool_)):
                return bool(value)
            if isinstance(value, str) and value.lower() in ("true", "false", "1", "0", "yes", "no", "on", "off"):
                return value.lower() in ("true", "1", "yes", "on")
            if isinstance(value, (int, np.integer)) and value in (0, 1):
                return bool(value)
            raise ValueError(f"{model}: parameter '{self.name}' must be true or false, got {value!r}")
        if k == "choice":
            if isinstance(value, str) and value in self.choices:
                return value
            raise ValueError(
                f"{model}: parameter '{self.name}' must be one of {', '.join(self.choices)}; got {value!r}"
            )
        if k == "int":
            f = to_float(value, f"{model}: parameter '{self.name}'", finite=False)
            if not math.isfinite(f) or f != int(f):
                raise ValueError(f"{model}: parameter '{self.name}' must be an integer, got {_short(value)}")
            self._check_number(model, f, "")
            return int(f)
        if k == "scalar":
            if isinstance(value, (str, bytes)) or isinstance(value, bool):
                raise ValueError(f"{model}: parameter '{self.name}' must be a number, got {value!r}")
            arr = np.asarray(value, dtype=object)
            if arr.ndim != 0:
                raise ValueError(f"{model}: parameter '{self.name}' must be a single number, got {value!r}")
            f = to_float(value, f"{model}: parameter '{self.name}'", finite=False)
            self._check_number(model, f, "")
            return f
        # rgb
        if isinstance(value, (str, bytes)) or isinstance(value, bool):
            raise ValueError(f"{model}: parameter '{self.name}' must be a number or an RGB triple, got {value!r}")
        what = f"{model}: parameter '{self.name}'"
        if isinstance(value, (int, float, np.number)):
            arr = np.asarray(to_float(value, what, finite=False))
        else:
            try:
                obj = np.asarray(value, dtype=object)
            except (TypeError, ValueError):
                obj = np.asarray(None, dtype=object)
            if obj.shape != (3,) and obj.ndim != 0:
                raise ValueError(
                    f"{model}: parameter '{self.name}' must be a number or an RGB triple, got shape {obj.shape}"
                )
            if obj.ndim == 0 and not isinstance(obj.item(), (int, float, np.number)):
                raise ValueError(
                    f"{model}: parameter '{self.name}' must be a number or an RGB triple, got {_short(value)}"
                )
            vals = [to_float(v, what if obj.ndim == 0 else f"{what}[{'rgb'[i]}]", finite=False)
                    for i, v in enumerate(obj.reshape(-1))]
            arr = np.asarray(vals[0]) if obj.ndim == 0 else np.array(vals, dtype=np.float64)
        if arr.ndim == 0:
            arr = np.full(3, float(arr))
        elif arr.shape != (3,):
            raise ValueError(
                f"{model}: parameter '{self.name}' must be a number or an RGB triple, got shape {arr.shape}"
            )
        for i, c in enumerate(arr):
            self._check_number(model, float(c), f"[{'rgb'[i]}]")
        arr = arr.copy()
        arr.setflags(write=False)
        return arr


def _fmt(x: float) -> str:
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return f"{x:g}"


ParamSpec = Sequence[Param]


def spec_names(spec: ParamSpec) -> list[str]:
    return [p.name for p in spec]


def validate(model: str, spec: ParamSpec, given: Mapping[str, Any]) -> dict[str, Any]:
    """Validate ``given`` against ``spec``; fill defaults; return the effective parameters.

    Raises a one-line ``ValueError`` for an unknown name, a wrong kind, a value
    out of range or not finite.
    """
    by_name = {p.name: p for p in spec}
    for name in given:
        if name not in by_name:
            valid = ", ".join(by_name) or "(none)"
            raise ValueError(f"{model}: unknown parameter '{name}'; valid parameters: {valid}")
    out: dict[str, Any] = {}
    for p in spec:
        out[p.name] = p.validate(model, given[p.name] if p.name in given else p.default)
    return out


def isotropic_ties(model: str, spec: ParamSpec) -> dict[str, str]:
    """The spec's declared ties (:attr:`Param.tie`) as ``{twin: tied parameter}``: the pairs that
    share one free value when the model is fitted to isotropic data (``{"alpha_x": "alpha_y"}``).

    Raises a one-line ``ValueError`` naming the model when a tie names no parameter of the spec,
    a parameter of another kind, a parameter that is tied itself, or a twin tied twice.
    """
    by_name = {p.name: p for p in spec}
    out: dict[str, str] = {}
    for p in spec:
        if not p.tie:
            continue
        twin = by_name.get(p.tie)
        if twin is None:
            raise ValueError(f"{model}: parameter '{p.name}' is tied to '{p.tie}', "
                             "which is not a parameter of the model")
        if twin.kind != p.kind:
            raise ValueError(f"{model}: parameter '{p.name}' ({p.kind}) is tied to '{twin.name}' ({twin.kind}); "
                             "a tie needs two parameters of the same kind")
        if twin.tie:
            raise ValueError(f"{model}: parameter '{p.name}' is tied to '{twin.name}', which is tied itself")
        if twin.name in out:
            raise ValueError(f"{model}: parameters '{out[twin.name]}' and '{p.name}' are both tied to '{twin.name}'")
        out[twin.name] = p.name
    return out


def parse_value(model: str, param: Param, text: str) -> Any:
    """Parse the text of ``-p name=value`` for ``param`` (numbers, ``r,g,b``, true/false, choices)."""
    text = text.strip()
    if param.kind in ("choice", "bool"):
        return param.validate(model, text)
    if param.kind == "rgb":
        parts = [t for t in text.split(",")]
        try:
            nums = [to_float(t, f"{model}: parameter '{param.name}'") for t in parts]
        except ValueError as e:
            if "overflows" in str(e) or "finite" in str(e):
                raise
            raise ValueError(
                f"{model}: parameter '{param.name}' expects a number or r,g,b; got {_short(text)}"
            ) from None
        if len(nums) == 1:
            return param.validate(model, nums[0])
        if len(nums) != 3:
            raise ValueError(f"{model}: parameter '{param.name}' expects 1 or 3 numbers, got {len(nums)}")
        return param.validate(model, nums)
    try:
        num = to_float(text, f"{model}: parameter '{param.name}'")
    except ValueError as e:
        if "overflows" in str(e) or "finite" in str(e):
            raise
        raise ValueError(f"{model}: parameter '{param.name}' expects a number; got {_short(text)}") from None
    return param.validate(model, num)


def parse_assignments(model: str, spec: ParamSpec, items: Iterable[str]) -> dict[str, Any]:
    """Parse repeated ``name=value`` strings into a validated-value dict (not yet defaults-filled)."""
    by_name = {p.name: p for p in spec}
    out: dict[str, Any] = {}
    for item in items:
        if "=" not in item:
            raise ValueError(f"{model}: parameter assignment {item!r} must look like name=value")
        name, _, text = item.partition("=")
        name = name.strip()
        if name not in by_name:
            valid = ", ".join(by_name) or "(none)"
            raise ValueError(f"{model}: unknown parameter '{name}'; valid parameters: {valid}")
        if name in out:
            raise ValueError(f"{model}: parameter '{name}' given twice (-p {name}=...); give it once")
        out[name] = parse_value(model, by_name[name], text)
    return out


def to_jsonable(params: Mapping[str, Any]) -> dict[str, Any]:
    """Parameters as plain JSON values (arrays -> lists)."""
    out = {}
    for k, v in params.items():
        if isinstance(v, np.ndarray):
            out[k] = [float(x) for x in v]
        elif isinstance(v, (np.floating,)):
            out[k] = float(v)
        else:
            out[k] = v
    return out


# Frequently used parameter definitions (shared so that kd means the same everywhere).
def kd_param(default: Any = 0.5, doc: str = "diffuse albedo (the diffuse term is kd/π)") -> Param:
    return Param("kd", "rgb", default, (0.0, 1.0), "", doc)


def ks_param(default: Any = 0.5, doc: str = "specular weight", hi: float = 1.0) -> Param:
    return Param("ks", "rgb", default, (0.0, hi), "", doc)


def exponent_param(name: str, default: float, doc: str, tie: str = "") -> Param:
    """A cosine-power exponent (Phong shininess, Ashikhmin-Shirley n_u/n_v): [0, 1e5], fitted in all of [1, 1e5].
    ``tie``: its isotropic twin (:attr:`Param.tie`), e.g. n_v's n_u."""
    return Param(name, "scalar", default, (0.0, 1e5), "", doc, fit_range=(1.0, 1e5), log_scale=True, tie=tie)


__all__ = [
    "to_float",
    "Param",
    "ParamSpec",
    "validate",
    "parse_value",
    "parse_assignments",
    "to_jsonable",
    "spec_names",
    "isotropic_ties",
    "kd_param",
    "ks_param",
    "exponent_param",
]
