"""JSON in and out of the explorer's HTTP API, shared by :mod:`.server` (the HTTP plumbing)
and :mod:`.api` (the extra endpoints), so that neither imports the other's private helpers.

* :class:`BadRequest`: a client error, answered with status 400 and its one-line message;
* :func:`loads`: ``json.loads`` for query values, with a nesting limit
  (:func:`brdfkit.jsonsafe.nesting_exceeds`) and a one-line :class:`BadRequest`;
* :func:`jsonable`: numpy values as plain JSON (non-finite floats as ``null``);
* :func:`one_line`: an exception's first line;
* :func:`ui_model_info`: a model class's ``info()`` with the parameter rows the explorer's UI reads.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from ..jsonsafe import nesting_exceeds

MAX_JSON_DEPTH = 8  # nesting of the JSON in a query

__all__ = ["BadRequest", "MAX_JSON_DEPTH", "jsonable", "loads", "one_line", "ui_model_info"]


class BadRequest(ValueError):
    """A client error: answered with status 400 and the one-line message."""


def loads(text: str, what: str, hint: str = "") -> Any:
    """``json.loads`` for query values: a one-line :class:`BadRequest` for bad or too deeply nested JSON."""
    hint = f"; {hint}" if hint else ""
    if nesting_exceeds(text, MAX_JSON_DEPTH):
        raise BadRequest(f"{what}: JSON nested deeper than {MAX_JSON_DEPTH} levels{hint}")
    try:
        return json.loads(text)
    except (json.JSONDecodeError, RecursionError, ValueError) as e:
        msg = getattr(e, "msg", None) or type(e).__name__
        raise BadRequest(f"{what}: not valid JSON ({msg}){hint}") from None


def one_line(e: BaseException) -> str:
    """The first line of an exception's message (its type's name when empty)."""
    lines = str(e).strip().splitlines()
    return lines[0] if lines else type(e).__name__


def jsonable(obj: Any) -> Any:
    """``obj`` with numpy arrays and scalars as lists and Python numbers, tuples as lists, keys as
    strings, and non-finite floats as ``None`` (JSON has no NaN or infinity)."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, (np.floating,)):
        obj = float(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def ui_model_info(cls, uniform_types: dict[str, str]) -> dict[str, Any]:
    """``cls.info()`` with each parameter row as the explorer's UI reads it.

    Each row gains ``log_scale``, ``open_lo``, ``open_hi`` (from the class's :class:`~brdfkit.params.Param`)
    and ``uniform`` (``u_<name>`` and its GLSL type, ``uniform_types[kind]``: the registry's shaders
    take booleans as ``int``, a ``.brdf`` file declares them ``bool``); an infinite ``min``/``max``
    becomes ``None``. Not yet passed through :func:`jsonable`.
    """
    info = cls.info()
    by_name = {p.name: p for p in cls.spec}
    for row in info["params"]:
        p = by_name[row["name"]]
        row["log_scale"] = bool(p.log_scale)
        row["open_lo"] = bool(p.open_lo)
        row["open_hi"] = bool(p.open_hi)
        row["uniform"] = {"name": f"u_{p.name}", "type": uniform_types[p.kind]}
        for k in ("min", "max"):
            if isinstance(row.get(k), float) and not math.isfinite(row[k]):
                row[k] = None
    return info
