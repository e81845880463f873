"""brdfkit: a lab for lighting and materials.

>>> import brdfkit as bk
>>> m = bk.model("ward", kd=0.2, ks=0.05, alpha_x=0.1, alpha_y=0.3)
>>> m.eval(wi, wo)          # (..., 3) -> (..., 3), 1/sr, no cosine
"""

from __future__ import annotations

from typing import Any

from . import geometry, params, registry
from .models.base import BRDF

__version__ = "0.1.0"


def models() -> list[str]:
    """Registry names of every analytic model."""
    return registry.names()


def model_info(name: str) -> dict[str, Any]:
    """Name, title, reference, isotropy and the parameter table of a model."""
    return registry.get(name).info()


def model(name: str, **params: Any) -> BRDF:
    """An instance of model ``name`` with validated parameters (defaults for the rest)."""
    return registry.get(name)(**params)


__all__ = ["BRDF", "models", "model_info", "model", "geometry", "params", "registry", "__version__"]
