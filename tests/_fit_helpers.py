"""Shared helpers for the fitting tests (test_measured_fit*.py)."""

from __future__ import annotations

import numpy as np

from brdfkit.models.base import BRDF


class Bright(BRDF):
    """A constant f_r = 1.6/π: brighter than any allowed lambert (kd = 1.6 is outside [0, 1])."""

    name = "bright"
    spec = ()

    def _eval(self, wi, wo, p):
        return np.full(wi.shape, 1.6 / np.pi)
