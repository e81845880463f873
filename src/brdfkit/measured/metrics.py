"""The error metrics of a fit: weighted RMS over samples and channels of a transform of the values.

Every metric is a weighted RMS over the samples (:class:`~brdfkit.measured.samples.Samples`,
whose weights make it an integral over pairs of directions) and the three channels of a
transform ``T`` of the measured and the fitted values:

==========  =========================  =============================================
metric      T(f)                       source
==========  =========================  =============================================
``ngan``    f · cos θi                 Ngan, Durand & Matusik, "Experimental analysis
                                       of BRDF models", EGSR 2005 (the default)
``l2``      f                          plain L2 of the BRDF values
``log``     ln(1 + f · cos θi)         log-compressed (tames specular peaks)
``cbrt``    (f · cos θi)^(1/3)         Forés, Ferwerda & Gu, "Toward a perceptually
                                       based metric for BRDF modeling", CIC 2012
==========  =========================  =============================================
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..models.base import BRDF
from .samples import Samples

#: the metric names, the default first
METRICS = ("ngan", "l2", "log", "cbrt")
METRIC_TITLES = {
    "ngan": "cosine-weighted RMS (Ngan, Durand & Matusik 2005)",
    "l2": "RMS of the BRDF values (plain L2)",
    "log": "RMS of ln(1 + f cos θi)",
    "cbrt": "RMS of the cube root of f cos θi (Forés, Ferwerda & Gu 2012)",
}


def transform(metric: str) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """``T(f, cos θi)`` of ``metric`` (the table in the module docstring); unknown: one-line ValueError."""
    if metric == "ngan":
        return lambda f, c: f * c
    if metric == "l2":
        return lambda f, c: f
    if metric == "log":
        return lambda f, c: np.log1p(np.maximum(f * c, 0.0))
    if metric == "cbrt":
        return lambda f, c: np.cbrt(np.maximum(f * c, 0.0))
    raise ValueError(f"unknown metric {metric!r}; valid metrics: {', '.join(METRICS)}")


def error(model: BRDF, samples: Samples, metric: str = "ngan") -> float:
    """The metric's weighted RMS error of ``model`` against ``samples``."""
    T = transform(metric)
    c = samples.cos_i[:, None]
    d = T(np.asarray(model.eval(samples.wi, samples.wo), np.float64), c) - T(samples.f, c)
    return float(np.sqrt(np.mean(samples.w[:, None] * d * d)))


__all__ = ["METRICS", "METRIC_TITLES", "transform", "error"]
