"""brdfkit: a lab for lighting and materials.

>>> import brdfkit as bk
>>> m = bk.model("ward", kd=0.2, ks=0.05, alpha_x=0.1, alpha_y=0.3)
>>> m.eval(wi, wo)          # (..., 3) -> (..., 3), 1/sr, no cosine
"""

from __future__ import annotations

from typing import Any

from . import engine, geometry, params, registry, sources
from .engine import set_engine

# ``models`` is the package brdfkit.models, made callable: ``bk.models()`` lists the
# registry names (SPEC) and ``import brdfkit.models.ward`` still works.
from . import models
from .models.base import BRDF

from ._version import __version__


def model_info(name: str) -> dict[str, Any]:
    """Name, title, reference, isotropy and the parameter table of a model (or a ``.brdf`` file)."""
    return sources.model_class(name).info()


def model(name: str, **params: Any) -> BRDF:
    """The model ``name`` names, with validated parameters (defaults for the rest).

    ``name`` is a registry name, a built-in measured material, or a file
    (``.brdf``, MERL ``.binary``, a fit's ``.json``): see :mod:`brdfkit.sources`.
    """
    return sources.model(name, **params)


def load_measured(path) -> BRDF:
    """A measured-data file as a model, its format told by its suffix (see :mod:`brdfkit.sources`)."""
    return sources.load_measured(path)


__all__ = ["BRDF", "models", "model_info", "model", "load_measured", "geometry", "params", "registry", "sources",
           "engine", "set_engine", "__version__"]


# -- measured data and fitting (brdfkit.measured; imported on first use) -------------
def load_merl(path, interpolation: str = "nearest"):
    """Read a MERL ``.binary`` file as a model (see :mod:`brdfkit.measured.merl`)."""
    from .measured.merl import load_merl as _f

    return _f(path, interpolation=interpolation)


def save_merl(model, path) -> None:
    """Tabulate an isotropic model into a MERL ``.binary`` file."""
    from .measured.merl import save_merl as _f

    _f(model, path)


def material(name: str):
    """A built-in measured material as a model, e.g. ``material("merl/gold-metallic-paint")``."""
    from .measured.nbrdf import material as _f

    return _f(name)


def materials() -> list[str]:
    """Names of the 159 built-in measured materials (``merl/…``, ``rgl/…``, ``nielsen/…``)."""
    from .measured.nbrdf import materials as _f

    return list(_f())


def fit(name: str, measured, fixed=None, metric: str = "ngan", **kw):
    """Fit analytic model ``name`` to measured data (see :func:`brdfkit.measured.fit.fit`)."""
    from .measured.fit import fit as _f

    return _f(name, measured, fixed=fixed, metric=metric, **kw)


def tabulate(source, path, format=None, **kw):
    """Write any model as a MERL ``.binary`` or RGL ``.bsdf`` file (``format`` "merl" or "rgl", else
    told by the suffix); returns what was written and its tabulation error.
    See :mod:`brdfkit.measured.tabulation`."""
    from .measured.tabulation import tabulate as _f

    return _f(source, path, format, **kw)


__all__ += ["load_merl", "save_merl", "material", "materials", "fit", "tabulate"]


# -- interchange (brdfkit.interchange; imported on first use) -----------------------
def load_brdf(path, **params):
    """A Disney BRDF Explorer ``.brdf`` file as a model (see :mod:`brdfkit.interchange.brdf_explorer`)."""
    from .interchange.brdf_explorer import load_brdf as _f

    return _f(path, **params)


def export(model, fmt: str, path, **kw):
    """Write ``model`` as a Mitsuba 3 (``"mitsuba"``), MaterialX (``"materialx"``) or glTF (``"gltf"``)
    material; returns an ExportResult whose ``error`` is the approximation error (None where exact).
    See :mod:`brdfkit.interchange.export`."""
    from .interchange.export import export as _f

    return _f(model, fmt, path, **kw)


__all__ += ["load_brdf", "export"]


# -- Jupyter display: attached to BRDF here, so that brdfkit.models never imports interchange;
#    the work (and the import of brdfkit.interchange.notebook) happens on the first display ---
def _attach_notebook_display(cls: type) -> None:
    def _repr_png_(self) -> bytes:
        from .interchange.notebook import model_png

        return model_png(self)

    def _repr_html_(self) -> str:
        from .interchange.notebook import model_html

        return model_html(self)

    cls._repr_png_, cls._repr_html_ = _repr_png_, _repr_html_


_attach_notebook_display(BRDF)
