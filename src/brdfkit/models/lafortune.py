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

import math

import numpy as np

from ..engine import jit, vectorize
from ..params import Param, kd_param
from ..registry import register
from .base import BRDF

MAX_LOBES = 3
#: cap on n·ln d (keeps |C| > 1 with a large n finite; e^60 ≈ 1.1e26)
LOG_CAP = 60.0
#: parameters per lobe in the kernel's ``p``: ks (3), cx, cy, cz, n
LOBE_STRIDE = 7


# ------------------------------------------------------------ scalar sources
@jit
def generalized_dot_c(ux, uy, uz, vx, vy, vz, cx, cy, cz):
    """Lafortune et al. 1997, eq. (5): ``Cx·u_x·v_x + Cy·u_y·v_y + Cz·u_z·v_z``."""
    return cx * ux * vx + cy * uy * vy + cz * uz * vz


@jit
def cosine_lobe_c(d, n):
    """``max(0, d)^n`` (eq. 4; 0 where ``d <= 0``, also for n = 0), as ``exp(min(n·ln d, LOG_CAP))``.

    Two cases are written for the derivatives (issue 31: the forward twin differentiates this source),
    with the same values: where ``d^n`` underflows to 0 the result is the constant 0 (derivatives 0,
    not 0·inf = NaN when ``d`` is subnormal and ``∂ ln d = ∂d/d`` overflows); at n = 0, the range's end,
    it is ``1 + n·ln(max(d, 1e-150))`` = 1, so ``∂/∂n = ln d`` (d floored at 1e-150, 1e-19 in the float32
    twin) and the other derivatives 0 (not 0·inf).
    """
    if d <= 0.0:
        return 0.0
    if n == 0.0:
        return 1.0 + n * math.log(max(d, 1e-150))
    v = math.exp(min(n * math.log(d), LOG_CAP))
    return v if v > 0.0 else 0.0


@jit(inline=True)
def lobe_c(wix, wiy, wiz, wox, woy, woz, p, o):
    """The cosine lobe ``max(0, d_k)^n_k`` of the lobe whose parameters start at ``p[o]`` (ks at o..o+2)."""
    d = generalized_dot_c(wix, wiy, wiz, wox, woy, woz, p[o + 3], p[o + 4], p[o + 5])
    return cosine_lobe_c(d, p[o + 6])


@jit
def lafortune_kernel(wix, wiy, wiz, wox, woy, woz, p, c):
    """Lafortune et al. (1997) eq. (6): ``kd/π + Σ_k ks_k · max(0, d_k)^n_k``, per RGB channel.

    ``p = [kd (3), then per lobe k = 1..3: ks_k (3), cx_k, cy_k, cz_k, n_k]``; ``c = [lobes]``.
    """
    r = p[0] / math.pi
    g = p[1] / math.pi
    b = p[2] / math.pi
    if c[0] >= 1:
        L = lobe_c(wix, wiy, wiz, wox, woy, woz, p, 3)
        r += p[3] * L
        g += p[4] * L
        b += p[5] * L
    if c[0] >= 2:
        L = lobe_c(wix, wiy, wiz, wox, woy, woz, p, 10)
        r += p[10] * L
        g += p[11] * L
        b += p[12] * L
    if c[0] >= 3:
        L = lobe_c(wix, wiy, wiz, wox, woy, woz, p, 17)
        r += p[17] * L
        g += p[18] * L
        b += p[19] * L
    return r, g, b


# ------------------------------------------------------ array API (wrappers)
_v_dot = vectorize(generalized_dot_c, 9)
_v_lobe = vectorize(cosine_lobe_c, 2)


def generalized_dot(wi, wo, cx, cy, cz):
    """Lafortune et al. 1997, eq. (5) over direction arrays. Scalar source: :func:`generalized_dot_c`."""
    wi = np.asarray(wi)
    wo = np.asarray(wo)
    return _v_dot(wi[..., 0], wi[..., 1], wi[..., 2], wo[..., 0], wo[..., 1], wo[..., 2], cx, cy, cz)


def cosine_lobe(d, n):
    """``max(0, d)^n`` elementwise (float64). Scalar source: :func:`cosine_lobe_c`."""
    return _v_lobe(d, n)


def _lobe_params(k: int, ks_default: float) -> tuple[Param, ...]:
    return (
        Param(f"ks_{k}", "rgb", ks_default, (0.0, 1e6), "", f"weight ρ_s of lobe {k}",
              fit_range=(1e-6, 1e6), log_scale=True),
        Param(f"cx_{k}", "scalar", -1.0, (-100.0, 100.0), "", f"C_x of lobe {k} (tangent)"),
        Param(f"cy_{k}", "scalar", -1.0, (-100.0, 100.0), "", f"C_y of lobe {k} (bitangent)", tie=f"cx_{k}"),
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

    kernel = staticmethod(lafortune_kernel)

    def kernel_args(self):
        p, _ = self._pack(("kd", "ks_1", "cx_1", "cy_1", "cz_1", "n_1", "ks_2", "cx_2", "cy_2", "cz_2", "n_2",
                           "ks_3", "cx_3", "cy_3", "cz_3", "n_3"))
        key = "lafortune_c"
        c = self._cache.get(key)
        if c is None:  # the lobe count as the kernel's choice (a specialised driver per count)
            c = self._cache[key] = np.array([int(self.params["lobes"])], dtype=np.int64)
        return p, c
