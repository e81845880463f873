"""Helpers shared by every ``brdfkit`` command module.

Every helper raises a one-line ``ValueError`` on bad input, which
:func:`brdfkit.cli.main` prints as ``brdfkit: error: ...`` with a non-zero
exit status (never a traceback).

``model_from_cli(name, items)``  a model from any source (:mod:`brdfkit.sources`) and ``-p name=value`` strings
``parse_floats(text, n, what)``   ``"a,b,c"`` -> tuple of ``n`` finite floats
``parse_pair(text, what)``        ``"a,b"`` -> ``(a, b)``
``direction_from_degrees(text, what)``  ``"THETA,PHI"`` (degrees) -> unit vector
``direction_from_vector(text, what)``   ``"x,y,z"`` -> unit vector (zero vector rejected)
``to_json(obj)`` / ``print_json(obj)``  JSON text with numpy arrays/scalars converted
"""

from __future__ import annotations

import json
import math
from typing import Any, Iterable

import numpy as np
import typer

from .geometry import spherical_to_vector


def model_from_cli(name: str, items: Iterable[str] | None = None):
    """The model ``name`` names (:func:`brdfkit.sources.from_cli`), ``items`` being ``-p name=value`` strings.

    Values are parsed against the source's parameter spec by
    :func:`brdfkit.params.parse_assignments` (numbers, ``r,g,b``, true/false,
    choices by name); unknown names, out-of-range or non-finite values, and
    ``-p`` given to measured data, raise a one-line ``ValueError``.
    """
    from .sources import from_cli

    return from_cli(name, items)


def parse_floats(text: str, n: int, what: str) -> tuple[float, ...]:
    """Parse ``n`` comma-separated finite numbers; ``what`` names the option in errors."""
    if text is None:
        raise ValueError(f"{what}: missing value")
    parts = [t.strip() for t in str(text).split(",")]
    shape = ",".join(["x"] * n) if n != 2 else "a,b"
    if len(parts) != n:
        raise ValueError(f"{what}: expected {n} comma-separated numbers ({shape}), got {text!r}")
    try:
        vals = tuple(float(t) for t in parts)
    except ValueError:
        raise ValueError(f"{what}: expected {n} comma-separated numbers ({shape}), got {text!r}") from None
    if not all(math.isfinite(v) for v in vals):
        raise ValueError(f"{what}: numbers must be finite, got {text!r}")
    return vals


def parse_pair(text: str, what: str) -> tuple[float, float]:
    """Parse ``"a,b"`` into two finite floats."""
    a, b = parse_floats(text, 2, what)
    return a, b


def direction_from_degrees(text: str, what: str) -> np.ndarray:
    """``"THETA,PHI"`` in degrees (theta from +z in [0, 180], phi from +x toward +y) -> unit vector."""
    theta, phi = parse_pair(text, what)
    if not 0.0 <= theta <= 180.0:
        raise ValueError(f"{what}: theta must lie in [0, 180] degrees, got {theta:g}")
    v = spherical_to_vector(math.radians(theta), math.radians(phi))
    # exact zeros at the axes and the horizon (cos(90°) is 6e-17 in floating point)
    v[np.abs(v) < 1e-15] = 0.0
    return v / np.linalg.norm(v)


def direction_from_vector(text: str, what: str) -> np.ndarray:
    """``"x,y,z"`` -> the unit vector along it; a zero vector is an error."""
    v = np.array(parse_floats(text, 3, what), dtype=np.float64)
    n = float(np.linalg.norm(v))
    if not n > 0.0 or not math.isfinite(n):
        raise ValueError(f"{what}: the vector must be non-zero and finite, got {text!r}")
    return v / n


def _default(o: Any) -> Any:
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, (set, frozenset, tuple)):
        return list(o)
    raise TypeError(f"cannot write {type(o).__name__} as JSON")


def _plain(obj: Any) -> Any:
    """``obj`` with numpy arrays/scalars and tuples turned into plain JSON values."""
    if isinstance(obj, dict):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set, frozenset, np.ndarray)):
        return [_plain(v) for v in (obj.tolist() if isinstance(obj, np.ndarray) else obj)]
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def _dump(obj: Any, indent: int, level: int) -> str:
    pad, inner = " " * (indent * level), " " * (indent * (level + 1))
    if isinstance(obj, dict):
        if not obj:
            return "{}"
        items = [f"{inner}{json.dumps(k, ensure_ascii=False)}: {_dump(v, indent, level + 1)}" for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(obj, list):
        if all(not isinstance(v, (dict, list)) for v in obj):  # a row of scalars: one line
            return "[" + ", ".join(_dump(v, indent, level + 1) for v in obj) + "]"
        return "[\n" + ",\n".join(inner + _dump(v, indent, level + 1) for v in obj) + "\n" + pad + "]"
    return json.dumps(obj, default=_default, allow_nan=False, ensure_ascii=False)


def to_json(obj: Any, indent: int | None = 2) -> str:
    """JSON text; numpy arrays and scalars become lists and numbers; NaN/Inf are refused.

    With ``indent`` (the default), objects and lists of objects are indented and
    lists of plain values (RGB triples, vectors) stay on one line.
    """
    plain = _plain(obj)
    if indent is None:
        return json.dumps(plain, default=_default, allow_nan=False, ensure_ascii=False)
    return _dump(plain, indent, 0)


def print_json(obj: Any) -> None:
    """Print ``obj`` as JSON on stdout (plain text, no colour: safe to pipe)."""
    typer.echo(to_json(obj))


__all__ = [
    "model_from_cli",
    "parse_floats",
    "parse_pair",
    "direction_from_degrees",
    "direction_from_vector",
    "to_json",
    "print_json",
]
