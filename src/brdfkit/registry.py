"""Model registry: registry name -> model class.

Model modules register themselves with :func:`register`. Importing the
package ``brdfkit`` imports :mod:`brdfkit.models`, which imports every
published model, so the registry is full before any of its functions can be
called; this module imports no model (the models import it: no cycle).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from .models.base import BRDF

_REGISTRY: dict[str, type["BRDF"]] = {}


def register(cls: type["BRDF"]) -> type["BRDF"]:
    """Class decorator: add a model class under its ``name``."""
    name = cls.name
    if name in _REGISTRY and _REGISTRY[name] is not cls:
        raise RuntimeError(f"model name {name!r} registered twice")
    _REGISTRY[name] = cls
    return cls


def names() -> list[str]:
    """Registry names, in registration order."""
    return list(_REGISTRY)


def get(name: str) -> type["BRDF"]:
    """The registered model class for ``name``; ``ValueError`` naming the valid choices otherwise.

    Registered names only: files, measured materials and fits are resolved by
    :mod:`brdfkit.sources`.
    """
    if not isinstance(name, str) or name not in _REGISTRY:
        raise ValueError(f"unknown model {name!r}; valid models: {', '.join(_REGISTRY)}")
    return _REGISTRY[name]
