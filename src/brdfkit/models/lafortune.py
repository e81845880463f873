"""Lafortune: a diffuse term plus generalized cosine lobes.

Reference:
  E. P. F. Lafortune, S.-C. Foo, K. E. Torrance, D. P. Greenberg,
  "Non-linear approximation of reflectance functions", SIGGRAPH 1997, eq. (4)-(6).

In the local frame (n = +z, tangent +x) with ``u = wi`` and ``v = wo``, each lobe k
is a cosine power of a *generalized* dot product, a weighted sum of the
componentwise products of the two directions:

    d_k(u, v) = cx_k·u_x·v_x + cy_k·u_y·v_y + cz_k·u_z·v_z

    f_r = kd/π + Σ_{k=1..lobes} ks_k · max(0, d_k)^n_k

(the paper's ρ_s,k is ``ks_k``, an RGB weight; its C_x, C_y, C_z and n are
``cx_k``, ``cy_k``, ``cz_k``, ``n_k``). With ``cx = cy = −cz`` the lobe is a
Phong lobe around the mirror direction: ``d = cz · (r·v)`` with
``r = (−u_x, −u_y, u_z)``, so ``ks·cz^n = ks_phong·(n+2)/(2π)`` gives Lewis's
normalised Phong lobe exactly. ``cx = cy > 0`` makes a retro-reflective lobe,
``|cx| > cz`` an off-specular lobe that grows toward grazing (Fresnel-like),
``cx ≠ cy`` an anisotropic one. Every ``d_k`` is symmetric in u and v, so the
model is reciprocal for every parameter set; it is not energy conserving in
general (``brdfkit check`` measures it).

Numerics: ``max(0, d)^n`` is ``exp(n·ln d)`` for ``d > 0`` and 0 otherwise (also
for n = 0: the lobe is one-sided). ``|C|`` greater than 1 raised to a large n
would overflow, so the exponent ``n·ln d`` is capped at :data:`LOG_CAP` = 60
(a lobe value of e^60 ≈ 1.1e26, some twenty orders of magnitude above any
measured reflectance), and ``ks_k`` ≤ 1e6: every value stays below 4e32, finite
also in float32.

Fitting: for ``cz > 0`` the lobe ``ks·d^n`` depends only on ``ks·cz^n`` and on
the ratios ``cx/cz``, ``cy/cz``; ``cz_k`` is therefore not a fitted parameter
(``fit=False``, held at its value, 1 by default) and ``ks_k`` carries the
magnitude, so it is fitted on a log scale up to 1e6. ``n_k`` stops at 1e5 (as the
Phong exponents do): in float32 one ulp of d moves d^n by n·6e-8, 0.6 % at 1e5.

==========  ======  =========  =============  ===========================================
parameter   kind    default    range          meaning
==========  ======  =========  =============  ===========================================
kd          rgb     0.2        [0, 1]         diffuse albedo (kd/π)
lobes       int     1          [1, 3]         number of lobes used
ks_k        rgb     0.5, 0, 0  [0, 1e6]       lobe k's weight ρ_s (fitted in [1e-6, 1e6])
cx_k        scalar  -1         [-100, 100]    C_x of lobe k (along the tangent)
cy_k        scalar  -1         [-100, 100]    C_y of lobe k (along the bitangent)
cz_k        scalar  1          [-100, 100]    C_z of lobe k (along the normal; not fitted)
n_k         scalar  20         [0, 1e5]       exponent of lobe k (fitted in [1, 1e5])
==========  ======  =========  =============  ===========================================

(k = 1, 2, 3; lobes above ``lobes`` are ignored.)
"""

from __future__ import annotations

import numpy as np

from ..params import Param, kd_param
from ..registry import register
from .base import BRDF

MAX_LOBES = 3
#: cap on n·ln d (keeps |C| > 1 with a large n finite; e^60 ≈ 1.1e26)
LOG_CAP = 60.0


def generalized_dot(wi, wo, cx, cy, cz):
    """Lafortune et al. 1997, eq. (5): ``Cx·u_x·v_x + Cy·u_y·v_y + Cz·u_z·v_z``."""
    return cx * wi[..., 0] * wo[..., 0] + cy * wi[..., 1] * wo[..., 1] + cz * wi[..., 2] * wo[..., 2]


def cosine_lobe(d, n):
    """``max(0, d)^n`` (0 where ``d <= 0``, also for n = 0), as ``exp(min(n·ln d, LOG_CAP))``."""
    dt = d.dtype.type
    pos = d > 0
    t = np.minimum(dt(n) * np.log(np.where(pos, d, dt(1))), dt(LOG_CAP))
    return np.where(pos, np.exp(t), dt(0))


def _lobe_params(k: int, ks_default: float) -> tuple[Param, ...]:
    return (
        Param(f"ks_{k}", "rgb", ks_default, (0.0, 1e6), "", f"weight ρ_s of lobe {k}",
              fit_range=(1e-6, 1e6), log_scale=True),
        Param(f"cx_{k}", "scalar", -1.0, (-100.0, 100.0), "", f"C_x of lobe {k} (tangent)"),
        Param(f"cy_{k}", "scalar", -1.0, (-100.0, 100.0), "", f"C_y of lobe {k} (bitangent)"),
        Param(f"cz_{k}", "scalar", 1.0, (-100.0, 100.0), "", f"C_z of lobe {k} (normal; held fixed in fits)",
              fit=False),
        Param(f"n_{k}", "scalar", 20.0, (0.0, 1e5), "", f"exponent of lobe {k}", fit_range=(1.0, 1e5),
              log_scale=True),
    )


@register
class Lafortune(BRDF):
    name = "lafortune"
    title = "Lafortune: kd/π + Σ ks_k·(Cx·ux·vx + Cy·uy·vy + Cz·uz·vz)^n_k, 1-3 generalized cosine lobes"
    reference = (
        "Lafortune, Foo, Torrance, Greenberg, Non-linear approximation of reflectance functions, SIGGRAPH 1997"
    )
    isotropic = False  # cx_k != cy_k is anisotropic
    spec = (
        kd_param(0.2),
        Param("lobes", "int", 1, (1, MAX_LOBES), "", "number of lobes used", fit=False),
        *_lobe_params(1, 0.5),
        *_lobe_params(2, 0.0),
        *_lobe_params(3, 0.0),
    )

    def _eval(self, wi, wo, p):
        dt = wi.dtype.type
        f = p["kd"] / dt(np.pi) + np.zeros(wi.shape, dt)
        for k in range(1, int(p["lobes"]) + 1):
            d = generalized_dot(wi, wo, p[f"cx_{k}"], p[f"cy_{k}"], p[f"cz_{k}"])
            f = f + p[f"ks_{k}"] * cosine_lobe(d, p[f"n_{k}"])[..., None]
        return f
