"""Fitting analytic models to measured BRDFs: the public names, gathered from the modules that define them.

``fit(name, measured, fixed={...}, metric="ngan")`` finds the parameters of the registered
model ``name`` that best reproduce ``measured`` (a MERL file, a built-in material name, or
any isotropic model), generically over the model's parameter spec. One purpose per module:

=====================================  ======================================================
:mod:`brdfkit.measured.samples`        weighted measured samples (:func:`sample`, :func:`table`)
:mod:`brdfkit.measured.metrics`        the error metrics (:data:`METRICS`, :func:`error`)
:mod:`brdfkit.measured.packing`        parameters ↔ the optimiser's free vector (:class:`ParamPacker`)
:mod:`brdfkit.measured.lobes`          a second specular lobe (:func:`two_lobe`)
:mod:`brdfkit.measured.residuals`      the residual vector and its hot-loop evaluation
:mod:`brdfkit.measured.jacobian`       the Jacobian: constant columns, channel groups
:mod:`brdfkit.measured.optimise`       multi-start least squares and :func:`fit`
:mod:`brdfkit.measured.result`         :class:`FitResult`
:mod:`brdfkit.measured.progress`       the progress bar of a fit
:mod:`brdfkit.measured.batch`          batches of fits (:func:`fit_batch`, ``run_batch``)
=====================================  ======================================================

This module only re-exports (``from brdfkit.measured.fit import fit`` keeps working). The
optimiser's tunables (``JOIN_XTOL``, ...) are read in :mod:`brdfkit.measured.optimise`: set
them there.
"""

from __future__ import annotations

from ..geometry import from_rusinkiewicz
from .batch import fit_batch
from .jacobian import ColumnProbes, channel_groups, constant_columns, jacobian, probe_columns
from .lobes import DIFFUSE_PARAMS, two_lobe
from .merl import bin_centres
from .metrics import METRIC_TITLES, METRICS, error, transform
from .optimise import JOIN_RTOL, JOIN_XTOL, POLISH_ITERATIONS, SERIAL_SAMPLES, TABLE_SEARCH_SAMPLES, fit
from .optimise import _Joined, _Start  # noqa: F401 - the tests' handles on a local run
from .packing import ParamPacker
from .residuals import PreparedEval, freeze_unused, residual_fn
from .result import AT_BOUND_TOL, FitResult, flush_subnormal
from .samples import Samples, resolve_source, sample, subsample, table

# the names these had when they lived in this module
_transform, _residual_fn, _PreparedEval, _freeze_unused, _jacobian = (
    transform, residual_fn, PreparedEval, freeze_unused, jacobian)

__all__ = [
    "fit", "fit_batch", "FitResult", "Samples", "sample", "table", "subsample", "resolve_source", "two_lobe",
    "DIFFUSE_PARAMS", "error", "transform", "METRICS", "METRIC_TITLES", "ParamPacker", "PreparedEval",
    "residual_fn", "freeze_unused", "ColumnProbes", "probe_columns", "constant_columns", "channel_groups",
    "jacobian", "flush_subnormal", "JOIN_XTOL", "JOIN_RTOL", "TABLE_SEARCH_SAMPLES", "SERIAL_SAMPLES",
    "POLISH_ITERATIONS", "AT_BOUND_TOL", "bin_centres", "from_rusinkiewicz",
]
