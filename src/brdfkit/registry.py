"""Model registry: registry name -> model class.

Model modules register themselves with :func:`register`; importing
:mod:`brdfkit.models` imports every published model.
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


def _ensure_loaded() -> None:
    from . import models  # noqa: F401  (imports every model module)


def names() -> list[str]:
    """Registry names, in registration order."""
    _ensure_loaded()
    return list(_REGISTRY)


def get(name: str) -> type["BRDF"]:
    """The model class for ``name``; ``ValueError`` naming the valid choices otherwise."""
    _ensure_loaded()
    if isinstance(name, str) and name.endswith(".brdf") and name not in _REGISTRY:
        # a BRDF Explorer file works wherever a model name does (brdfkit.interchange)
        from .interchange.brdf_explorer import load_brdf_class

        return load_brdf_class(name)
    if not isinstance(name, str) or name not in _REGISTRY:
        raise ValueError(f"unknown model {name!r}; valid models: {', '.join(_REGISTRY)}")
    return _REGISTRY[name]
