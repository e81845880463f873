"""The base class every BRDF model derives from.

A model subclass declares, as class attributes:

``name``       registry name (``"ward"``)
``title``      one-line description
``reference``  the paper
``isotropic``  whether the model depends on the azimuth only through φi − φo
``spec``       tuple of :class:`brdfkit.params.Param`, the single parameter source

and implements ``_eval(wi, wo, p)`` for directions that are already known to
lie strictly above the horizon (``wi.z > 0`` and ``wo.z > 0``). ``p`` holds the
parameters converted to the working dtype (rgb parameters as ``(3,)`` arrays).
:meth:`BRDF.eval` does the rest of the contract: broadcasting, dtype,
the zero below the horizon.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from ..params import Param, to_jsonable, validate


class BRDF:
    """A reflectance model: ``eval(wi, wo)`` returns f_r in 1/sr, RGB, without the cosine."""

    name: ClassVar[str] = ""
    title: ClassVar[str] = ""
    reference: ClassVar[str] = ""
    isotropic: ClassVar[bool] = True
    spec: ClassVar[tuple[Param, ...]] = ()

    def __init__(self, **params: Any) -> None:
        self.params: dict[str, Any] = validate(self.name, self.spec, params)
        self._cache: dict[Any, dict[str, Any]] = {}
        self._setup()

    def _setup(self) -> None:
        """Hook for derived quantities (called after validation)."""

    # -- the contract --------------------------------------------------------
    def eval(self, wi, wo) -> np.ndarray:
        """f_r(wi, wo), shape ``broadcast(wi, wo)``; zero where ``wi.z <= 0`` or ``wo.z <= 0``.

        float32 inputs (both) give a float32 result computed in float32.
        """
        wi = np.asarray(wi)
        wo = np.asarray(wo)
        if wi.shape[-1:] != (3,) or wo.shape[-1:] != (3,):
            raise ValueError(f"{self.name}: directions must have a last axis of length 3, got {wi.shape} and {wo.shape}")
        dtype = np.float32 if (wi.dtype == np.float32 and wo.dtype == np.float32) else np.float64
        wi = wi.astype(dtype, copy=False)
        wo = wo.astype(dtype, copy=False)
        wi, wo = np.broadcast_arrays(wi, wo)
        valid = (wi[..., 2] > 0) & (wo[..., 2] > 0)
        all_valid = bool(valid.all())
        if not all_valid:
            up = np.zeros(3, dtype=dtype)
            up[2] = 1
            wi = np.where(valid[..., None], wi, up)
            wo = np.where(valid[..., None], wo, up)
        p = self._typed_params(dtype)
        with np.errstate(all="ignore"):
            f = self._eval(wi, wo, p)
        f = np.broadcast_to(np.asarray(f, dtype=dtype), wi.shape)
        if not all_valid:
            f = np.where(valid[..., None], f, dtype(0))
        return np.ascontiguousarray(f)

    def _eval(self, wi: np.ndarray, wo: np.ndarray, p: dict[str, Any]) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    def active_params(self) -> dict[str, Any]:
        """The parameters that affect this instance's values (for labels and titles).

        All of them by default; a model whose options switch parameters off
        (``microfacet``'s Fresnel choice, say) leaves those out. ``params`` stays
        the complete, effective set.
        """
        return dict(self.params)

    def delta_reflectance(self, w) -> np.ndarray:
        """Reflectance of the model's ideal-mirror (Dirac) part for light from ``w``, shape ``(..., 3)``.

        That light leaves along ``reflect(w)``; ``eval`` cannot return a delta, so
        albedo and energy checks add this term. Zero for models without one (all
        but ``htsg`` and ``schlick``).
        """
        w = np.asarray(w)
        return np.zeros(w.shape[:-1] + (3,), dtype=np.float32 if w.dtype == np.float32 else np.float64)

    # -- conveniences ------------------------------------------------------------
    def eval_angles(self, theta_i, phi_i, theta_o, phi_o) -> np.ndarray:
        """``eval`` from spherical angles in radians."""
        from ..geometry import spherical_to_vector

        return self.eval(spherical_to_vector(theta_i, phi_i), spherical_to_vector(theta_o, phi_o))

    def with_params(self, **changes: Any) -> "BRDF":
        """A copy with some parameters changed (validated again)."""
        new = dict(self.params)
        new.update(changes)
        return type(self)(**new)

    def params_json(self) -> dict[str, Any]:
        return to_jsonable(self.params)

    def _typed_params(self, dtype) -> dict[str, Any]:
        key = np.dtype(dtype).char
        if key not in self._cache:
            out = {}
            for k, v in self.params.items():
                if isinstance(v, np.ndarray):
                    out[k] = v.astype(dtype)
                elif isinstance(v, float):
                    out[k] = dtype(v)
                else:
                    out[k] = v
            self._cache[key] = out
        return self._cache[key]

    @classmethod
    def info(cls) -> dict[str, Any]:
        return {
            "name": cls.name,
            "title": cls.title,
            "reference": cls.reference,
            "isotropic": cls.isotropic,
            "params": [p.as_row() for p in cls.spec],
        }

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" if not isinstance(v, np.ndarray) else f"{k}={v.tolist()}" for k, v in self.params.items())
        return f"bk.model({self.name!r}, {args})"

    # -- notebook display (the work lives in brdfkit.interchange.notebook) -------------
    def _repr_png_(self) -> bytes:
        from ..interchange.notebook import model_png

        return model_png(self)

    def _repr_html_(self) -> str:
        from ..interchange.notebook import model_html

        return model_html(self)
