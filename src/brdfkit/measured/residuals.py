"""The residual vector a fit minimises, and the evaluation of a model at the samples in the hot loop.

:func:`residual_fn` gives ``x ↦`` the weighted, normalised residuals of a model (its free
values ``x``, :class:`~brdfkit.measured.packing.ParamPacker`) against measured samples: their
squared norm is the square of the metric (:mod:`brdfkit.measured.metrics`).
:func:`freeze_unused` holds the free values that change nothing (parameters of options not
chosen) at their defaults.
"""

from __future__ import annotations

import math

import numpy as np

from ..models.base import BRDF
from .packing import ParamPacker
from .samples import Samples


def freeze_unused(packer: ParamPacker, residuals, rng: np.random.Generator) -> None:
    """Freeze slots that change nothing at the defaults nor at a random point (unused options)."""
    if len(packer) == 0:
        return
    pts = [packer.x_of(packer.fixed), packer.random_x(rng, 1)[0]]
    unused = set(range(len(packer)))
    for x in pts:
        r0 = residuals(x)
        for i in list(unused):
            y = x.copy()
            mid = 0.5 * (packer.lb[i] + packer.ub[i])
            y[i] = x[i] + 0.25 * (mid - x[i]) + 0.05 * (packer.ub[i] - packer.lb[i]) * (1 if x[i] <= mid else -1)
            if np.any(residuals(y) != r0):
                unused.discard(i)
    if unused and len(unused) < len(packer):
        packer.freeze(unused)


class PreparedEval:
    """``x ↦`` the values ``(n, 3)`` of ``packer.model(x)`` at ``data``'s directions, for the hot loop.

    ``packer.model(x).eval(data.wi, data.wo)`` would, per call, validate every parameter,
    broadcast, flatten and unit-check the same directions and allocate the output (about
    half of a 3000-sample evaluation's time). Here the directions are prepared and
    unit-checked once (:func:`brdfkit.engine.evaluate.prepare`), and a call builds the
    model's parameters, its ``kernel_args()`` (the model's own ``_setup`` and ``_pack``) and
    runs the engine (:func:`brdfkit.engine.evaluate.run_kernel`) into one preallocated
    output: the same kernel on the same arrays and parameters, so the same bits.

    Validation is skipped only for values it would accept unchanged: the packer's defaults
    and fixed values were validated when it was built, and a free value is used only if it
    lies within its slot's ``[lo, hi]``, which the packer's bounds keep inside the spec's range
    (open ends moved inwards); anything else (NaN, say) goes through ``packer.model(x)``,
    which raises the spec's error. A class with its own ``__init__`` is always built by
    ``packer.model(x)``, validated, unless it declares ``from_valid_is_init`` beside it
    (``microfacet``, whose ``__init__`` only resolves the roughness aliases). Models without a
    kernel, or whose ``kernel_args()`` is ``None``, are evaluated by ``BRDF.eval`` as before.
    The returned array is overwritten by the next call."""

    def __init__(self, packer: ParamPacker, data: Samples) -> None:
        from ..engine.evaluate import check_unit_flat, prepare

        self.packer, self.data = packer, data
        cls = packer.cls
        self.kernel = getattr(cls, "kernel", None)
        # _from_valid equals __init__ only for BRDF's own __init__ or a class that declares it (microfacet)
        self.unvalidated = cls.__init__ is BRDF.__init__ or (
            "__init__" in vars(cls) and vars(cls).get("from_valid_is_init", False))
        self.fi, self.fo, shape, dtype = prepare(cls.name, data.wi, data.wo)
        if self.kernel is not None:
            check_unit_flat(cls.name, self.fi, self.fo, dtype)
        self.out = np.empty(shape, dtype=dtype)
        self.fout = self.out.reshape(-1, 3)

    def model(self, x: np.ndarray) -> BRDF:
        """``packer.model(x)``, without re-validating values known to be valid (see the class)."""
        packer = self.packer
        if not self.unvalidated:
            return packer.model(x)
        for s, xv in zip(packer.slots, x):
            v = s.from_x(float(xv))
            if not s.lo <= v <= s.hi:  # NaN: the spec's own error
                return packer.model(x)
        params = dict(packer.defaults, **packer.params(x))  # the spec's order, as validate() gives
        for k, v in params.items():
            if isinstance(v, np.ndarray) and v.flags.writeable:  # validate() returns read-only rgb
                v.setflags(write=False)
        return packer.cls._from_valid(params)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        from ..engine.evaluate import run_kernel

        m = self.model(x)
        args = m.kernel_args() if self.kernel is not None else None
        if args is None:
            return m.eval(self.data.wi, self.data.wo)
        run_kernel(m, self.kernel, args, self.fi, self.fo, self.fout)
        return self.out


def residual_fn(packer: ParamPacker, data: Samples, T, metric: str = "", prepared: bool = True):
    """``x ↦`` the weighted, normalised residual vector of ``data`` (its squared norm is the metric²).

    For the metrics linear in f (``ngan``: f cos θi, ``l2``: f) the weights, cosines and target
    are folded into two arrays once, so a call is one model evaluation and one fused update.
    ``prepared``: evaluate through :class:`PreparedEval` (False: ``packer.model(x).eval``, the
    same values, kept to test that)."""
    c = data.cos_i[:, None]
    target = T(data.f, c)
    sw = np.sqrt(data.w)[:, None]
    scale = 1.0 / math.sqrt(target.size)
    if prepared:
        values = PreparedEval(packer, data)
    else:
        def values(x: np.ndarray) -> np.ndarray:
            return packer.model(x).eval(data.wi, data.wo)

    if metric in ("ngan", "l2"):
        gain = np.ascontiguousarray(np.broadcast_to(sw * scale * (c if metric == "ngan" else 1.0), target.shape))
        offset = gain * data.f

        def residuals(x: np.ndarray) -> np.ndarray:
            r = np.multiply(values(x), gain)
            return np.subtract(r, offset, out=r).ravel()

        return residuals

    def residuals(x: np.ndarray) -> np.ndarray:
        f = np.asarray(values(x), np.float64)
        return (sw * (T(f, c) - target)).ravel() * scale

    return residuals


__all__ = ["PreparedEval", "residual_fn", "freeze_unused"]
