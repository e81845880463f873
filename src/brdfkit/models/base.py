"""The base class every BRDF model derives from, and the hooks a model may define.

A model subclass declares, as class attributes:

``name``       registry name (``"ward"``)
``title``      one-line description
``reference``  the paper
``isotropic``  whether the model depends on the azimuth only through φi − φo
``spec``       tuple of :class:`brdfkit.params.Param`, the single parameter source

and implements EITHER a compiled scalar kernel (``kernel`` and
``kernel_args()``, the protocol of :mod:`brdfkit.engine`, which every built-in
analytic model uses) OR, the fallback, ``_eval(wi, wo, p)`` in numpy for
directions that are already known to lie strictly above the horizon
(``wi.z > 0`` and ``wo.z > 0``); ``p`` holds the parameters converted to the
working dtype (rgb parameters as ``(3,)`` arrays). :meth:`BRDF.eval` does the
rest of the contract: broadcasting, dtype, the unit-direction check, the zero
below the horizon.

Every other hook is declared on :class:`BRDF` with its default, and documented there
(who reads it, and when): ``kernel_float32``, ``kernel_span``, ``from_valid_is_init``,
``fit_diff_step``, ``glsl_source``, ``source_path``, ``label``, ``source``, and the methods
``kernel_args``, ``_setup``, ``active_params``, ``delta_reflectance``. A model overrides only
what it needs; the readers find the default on the base class. ``docs/adding-a-model.md``
walks through adding a model.

Jupyter display (``_repr_png_``, ``_repr_html_``) is not defined here: models do not import
:mod:`brdfkit.interchange`. Importing :mod:`brdfkit` attaches both to :class:`BRDF`; the work
lives in :mod:`brdfkit.interchange.notebook`.
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
    # -- hooks: declared here with their defaults; a model overrides what it needs ---------
    #: The compiled scalar kernel (protocol: :mod:`brdfkit.engine`), as ``staticmethod(fn)``.
    #: Read by :func:`brdfkit.engine.evaluate.evaluate` on every ``eval`` (None: ``_eval`` runs),
    #: by the fitter's prepared evaluation (:mod:`brdfkit.measured.fit`) and the engine tests.
    kernel: ClassVar[Any] = None
    #: Whether float32 input runs the kernel's float32 twin (:mod:`brdfkit.engine.precision`).
    #: Read by the engine on every float32 ``eval``; False: the kernel computes in float64 and the
    #: result is rounded (measured tables, HTSG, Ashikhmin-Shirley).
    kernel_float32: ClassVar[bool] = True
    #: The same kernel over a span of pairs, ``staticmethod(fn)``, for a kernel whose inner loop
    #: the compiled driver should run in the model's own order (HTSG's series). Read by
    #: :func:`brdfkit.engine.evaluate.evaluate` and passed to the driver; None: pair by pair.
    kernel_span: ClassVar[Any] = None
    #: True when ``_from_valid`` may build the model although the class defines its own
    #: ``__init__`` (that ``__init__`` only prepares the values for validation; ``_init_valid``
    #: derives the rest). Read by the fitter's prepared evaluation (:mod:`brdfkit.measured.fit`)
    #: when it builds one model per step; it looks at the class's own ``vars``, so declare it
    #: beside that ``__init__`` (microfacet does).
    from_valid_is_init: ClassVar[bool] = False
    #: Relative finite-difference step the fitter uses for this model's Jacobian, or None for
    #: scipy's default (sqrt of machine epsilon). Read by :func:`brdfkit.measured.fit.fit` when it
    #: sets up least squares. A model whose values move in float32 steps (a ``.brdf`` shader
    #: evaluated through GL uniforms) needs a larger one (1e-3).
    fit_diff_step: ClassVar[float | None] = None
    #: GLSL source the model carries itself (defines ``vec3 brdf(vec3 wi, vec3 wo)``), instead of
    #: ``render/shaders/<module>.glsl``. Read by :mod:`brdfkit.render.glsl` (shader_path,
    #: has_shader, shader_source) whenever the model is rendered or its shader compiled; "" for
    #: the built-in models (their shader file is found from the module name).
    glsl_source: ClassVar[str] = ""
    #: Where a carried ``glsl_source`` came from (a ``.brdf`` file's path); read by
    #: :func:`brdfkit.render.glsl.shader_path` to name the shader in messages and caches.
    source_path: ClassVar[str] = ""
    #: A display name that replaces ``name`` in reports, plots, fits and exports (measured data:
    #: ``"merl/gold-metallic-paint"``, a MERL file's stem). Usually set per instance; read by
    #: ``brdfkit eval``/``info``, :mod:`brdfkit.analysis` (plot labels, check reports), the fitter
    #: and :func:`brdfkit.export`. None: ``name`` is shown.
    label: ClassVar[str | None] = None
    #: Where the model's data came from (a MERL file's path), set per instance by loaders; read by
    #: ``brdfkit info``. "" for analytic models.
    source: ClassVar[str] = ""

    def __init__(self, **params: Any) -> None:
        self._init_valid(validate(self.name, self.spec, params))

    @classmethod
    def _from_valid(cls, params: dict[str, Any]) -> "BRDF":
        """The model of ``params`` already in the form ``validate`` returns (every value checked, in
        the spec's order, rgb values read-only arrays), without checking them again: for a hot loop
        that keeps its values inside the spec (the fitter's prepared evaluation). A class whose
        ``__init__`` does more than validate must not be built this way, unless it declares
        ``from_valid_is_init = True`` beside that ``__init__`` (its ``__init__`` only prepares the
        values for validation and its ``_init_valid`` derives the rest: microfacet)."""
        m = object.__new__(cls)
        m._init_valid(params)
        return m

    def _init_valid(self, params: dict[str, Any]) -> None:
        self.params: dict[str, Any] = params
        self._cache: dict[Any, dict[str, Any]] = {}
        self._setup()

    def _setup(self) -> None:
        """Hook for derived quantities: called by ``_init_valid`` once the parameters are validated
        (construction, ``with_params``, the fitter's ``_from_valid``). Does nothing by default."""

    # -- the contract --------------------------------------------------------
    def eval(self, wi, wo) -> np.ndarray:
        """f_r(wi, wo), shape ``broadcast(wi, wo)``; zero where ``wi.z <= 0`` or ``wo.z <= 0``.

        float32 inputs (both) give a float32 result. ``wi`` and ``wo`` must be unit
        vectors (within 1e-4, float32 1e-3); others raise ``ValueError``. Runs the
        model's compiled kernel, the same kernel uncompiled under
        ``bk.set_engine("reference")``, or ``_eval`` for a model without a kernel
        (see :mod:`brdfkit.engine`). Fortran-ordered ``(n, 3)`` directions (each component
        contiguous) are read in place where the compiled engine can, and give a Fortran-ordered
        result of the same values (:func:`brdfkit.engine.evaluate.evaluate`).
        """
        from ..engine import evaluate

        return evaluate(self, wi, wo)

    def eval_grad(self, wi, wo, wrt=None):
        """``(f, grads)``: ``f`` as :meth:`eval` gives it, ``grads`` a dict from each continuous parameter's
        name to ``∂f/∂param``, shape ``(..., 3)`` for a scalar and ``(..., 3, 3)`` for an RGB parameter
        (``[..., channel_out, channel_in]``). Exact (forward mode over the kernel's own source,
        :mod:`brdfkit.engine.forward`); at a ``min``/``max``/clamp or branch, the derivative of the branch
        taken. ``wrt``: a parameter name or names, to compute only those derivatives (default: all; the
        work grows with their number). ValueError for a model without a kernel, or a name that is not
        one of its continuous parameters (SPEC.md, "Gradients")."""
        from ..engine.grad import eval_grad

        return eval_grad(self, wi, wo, wrt)

    def kernel_args(self):
        """``(p, c)`` for :attr:`kernel`: float64 numeric and int64 choice arrays (see :mod:`brdfkit.engine`).

        Returning ``None`` makes this instance use ``_eval`` instead (for an option
        the kernel does not implement yet). Called by :func:`brdfkit.engine.evaluate.evaluate` on
        every ``eval`` of a model with a ``kernel`` and by the fitter's prepared evaluation; build the
        arrays with :meth:`_pack` (cached per instance).
        """
        raise NotImplementedError(f"{self.name}: a model with a kernel must implement kernel_args()")

    def _pack(self, numeric: tuple[str, ...], choices: tuple[str, ...] = ()):
        """``(p, c)`` from parameter names: rgb as 3 floats, scalars as 1, choices as their index, bools 0/1.

        Cached per instance (parameters never change after construction).
        """
        key = ("_pack", numeric, choices)
        hit = self._cache.get(key)
        if hit is None:
            by_name = {q.name: q for q in self.spec}
            vals = []
            for n in numeric:
                vals.extend(np.ravel(np.asarray(self.params[n], dtype=np.float64)).tolist())
            ints = []
            for n in choices:
                v = self.params[n]
                q = by_name[n]
                ints.append(q.choices.index(v) if q.choices else int(bool(v)))
            p = np.ascontiguousarray(vals, dtype=np.float64)
            c = np.ascontiguousarray(ints if ints else [0], dtype=np.int64)
            hit = self._cache[key] = (p, c)
        self._cache["_pack_numeric"] = numeric  # the layout of p, for eval_grad (brdfkit.engine.grad)
        return hit

    def _eval(self, wi: np.ndarray, wo: np.ndarray, p: dict[str, Any]) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    def active_params(self) -> dict[str, Any]:
        """The parameters that affect this instance's values (for labels and titles).

        All of them by default; a model whose options switch parameters off
        (``microfacet``'s Fresnel choice, say) leaves those out. ``params`` stays
        the complete, effective set. Called by :func:`brdfkit.analysis.plots.label` (legends,
        titles) when a model is plotted or rendered with a caption.
        """
        return dict(self.params)

    def delta_reflectance(self, w) -> np.ndarray:
        """Reflectance of the model's ideal-mirror (Dirac) part for light from ``w``, shape ``(..., 3)``.

        That light leaves along ``reflect(w)``; ``eval`` cannot return a delta, so
        albedo and energy checks add this term. Zero for models without one (all
        but ``htsg`` and ``schlick``). Called by :func:`brdfkit.analysis.albedo.albedo_result`
        (``brdfkit check``, the energy tests) for every albedo it computes.
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
