"""Physical plausibility of any BRDF: reciprocity, energy conservation (albedo), plots.

>>> from brdfkit.analysis import reciprocity_error, albedo, check
>>> reciprocity_error(m)          # largest relative asymmetry f(a,b) vs f(b,a)
>>> albedo(m, theta_o)            # a(wo) = ∫ f cos θi dωi, (..., 3)
>>> check(m)                      # the verdict: reciprocal, energy_conserving, albedo curve ...

Plots live in :mod:`brdfkit.analysis.plots` (imported lazily: matplotlib).
"""

from .albedo import AlbedoResult, albedo, albedo_result, brute_force_albedo
from .reciprocity import RECIPROCITY_TOL, direction_pairs, reciprocity_error, reciprocity_report
from .verdict import DEFAULT_THETA_DEG, STRESS, check, check_all, stress_settings

__all__ = [
    "albedo",
    "albedo_result",
    "AlbedoResult",
    "brute_force_albedo",
    "reciprocity_error",
    "reciprocity_report",
    "direction_pairs",
    "RECIPROCITY_TOL",
    "check",
    "check_all",
    "stress_settings",
    "STRESS",
    "DEFAULT_THETA_DEG",
]
