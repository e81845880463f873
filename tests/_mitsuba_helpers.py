"""Shared helper for the tests that compare with Mitsuba 3 (test_microfacet.py, test_measured_rgl.py).

The ``mi`` fixture of conftest.py gives the mitsuba module in its ``scalar_rgb`` variant.
"""

from __future__ import annotations

import numpy as np


def mitsuba_f_r(mi, bsdf_dict: dict, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """Mitsuba's f_r of the BSDF ``bsdf_dict`` at each pair, ``(N, 3)``, in brdfkit's naming.

    Mitsuba's si.wi is brdfkit's wo and it evaluates towards brdfkit's wi, including that
    direction's cosine, which is divided out here.
    """
    bsdf = mi.load_dict(bsdf_dict)
    ctx = mi.BSDFContext()
    out = np.empty((len(wi), 3))
    for j, (a, b) in enumerate(zip(wi, wo)):
        si = mi.SurfaceInteraction3f()
        si.sh_frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))
        si.wi = mi.Vector3f(*map(float, b))
        v = bsdf.eval(ctx, si, mi.Vector3f(*map(float, a)))
        out[j] = [v[0] / a[2], v[1] / a[2], v[2] / a[2]]
    return out
