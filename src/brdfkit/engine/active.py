"""Which evaluation engine runs ``m.eval``: ``"compiled"`` (default) or ``"reference"`` (SPEC.md, "Evaluation engine").

The choice is process-wide state, read by the engine's modules (:mod:`.evaluate`, :mod:`.vectorize`)
from here rather than from the ``brdfkit.engine`` package, which imports them: no import cycle.
``BRDFKIT_ENGINE`` is read once, at import; :func:`set_engine` changes the choice afterwards.
"""

from __future__ import annotations

import os

ENGINES = ("compiled", "reference")
ENV_VAR = "BRDFKIT_ENGINE"


def _from_env() -> str:
    v = os.environ.get(ENV_VAR, "").strip().lower()
    if v == "":
        return "compiled"
    if v not in ENGINES:
        raise ValueError(f"{ENV_VAR}={v!r} is not a valid engine; valid: {', '.join(ENGINES)}")
    return v


_current = _from_env()


def set_engine(name: str) -> None:
    """Select the evaluation engine: ``"compiled"`` (default) or ``"reference"``."""
    global _current
    if not isinstance(name, str) or name.strip().lower() not in ENGINES:
        raise ValueError(f"unknown engine {name!r}; valid: {', '.join(ENGINES)}")
    _current = name.strip().lower()


def engine() -> str:
    """The active evaluation engine's name."""
    return _current


__all__ = ["ENGINES", "ENV_VAR", "set_engine", "engine"]
