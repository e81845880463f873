"""Ashikhmin-Shirley: an anisotropic Phong BRDF with a coupled diffuse term.

Reference: M. Ashikhmin and P. Shirley, "An Anisotropic Phong BRDF Model",
Journal of Graphics Tools 5(2), 2000, 25-32 (the specular term ρ_s and the
coupled diffuse term ρ_d; the journal text was not available to us, so their
equation numbers are not cited).

Verification (formula audit): ρ_s (with (h·k)·max(n·k1, n·k2) in the
denominator, the exponent nu cos²φh + nv sin²φh = (nu (h·u)² + nv (h·v)²)/
(1 − (h·n)²) and Schlick's Fresnel of h·k) and ρ_d (28 Rd/(23π) (1 − Rs)
(1 − (1 − n·k1/2)⁵)(1 − (1 − n·k2/2)⁵)) agree term by term with the
UC Berkeley CS 184 lecture slides (2016, "Ashikhmin-Shirley BRDF", both
forms of the exponent; the second has a typo, pu twice), a blog article "Ashikhmin-Shirley Lighting Model"
(both terms written out) and pbrt-v3's `FresnelBlend::f` (the same ρ_d; its
ρ_s is D(h)/(4 (h·k) max(cos θi, cos θo)) F, which with A&S's normal
distribution sqrt((nu+1)(nv+1))/(2π) (n·h)^(…) is the formula here). No
disagreement between these sources and this module was found; nothing was
changed. (Of the University of Utah technical-report version, "An
Anisotropic Phong Light Reflection Model", only the introduction and
parameter list were available to us.)

With k = wi (or wo: h·wi = h·wo), h = normalize(wi + wo) with azimuth φh from
the tangent +x, n = +z:

    f_r = ρ_s + ρ_d

    ρ_s = sqrt((nu+1)(nv+1))/(8π) · (n·h)^(nu cos²φh + nv sin²φh)
          / ((h·k) · max(n·wi, n·wo)) · F(h·k)
    F(c) = Rs + (1 − Rs)(1 − c)⁵                         (Schlick's Fresnel)

    ρ_d = 28 Rd / (23π) · (1 − Rs) · (1 − (1 − n·wi/2)⁵) · (1 − (1 − n·wo/2)⁵)

``nu`` is the exponent along the tangent +x, ``nv`` along +y: with nu < nv the
highlight is wider in x. The exponent is evaluated as
(nu hx² + nv hy²)/(hx² + hy²) (= nu cos²φh + nv sin²φh), and the power as

    (n·h)^e = exp(½ · (nu hx² + nv hy²) · log(1 − s²)/s²),   s² = hx² + hy²

(log(1 − s²)/s² → −1 as s² → 0), so h = n gives exactly 1 instead of 0/0, and
large exponents underflow to 0 instead of overflowing.

Both terms are symmetric in wi and wo: the model is reciprocal. The paper
designs it to conserve energy (the diffuse term is scaled by (1 − Rs) and its
constant 28/23 normalises it); the specular lobe's albedo approaches but does
not in general equal F, so energy conservation holds only approximately —
`brdfkit check` measures it.

Numerics: h·k and max(n·wi, n·wo) are clamped to a floor of 1e-6 in the
denominator (they vanish only when both directions are within 0.00006° of
the horizon), which keeps every value finite.

Variant ``"ngan"`` (Ngan, Durand & Matusik, "Experimental Analysis of BRDF
Models", EGSR 2005, the form their fits to the MERL data use): the diffuse term
is decoupled — a plain Lambert ``kd/π`` — and the specular lobe gets its own RGB
weight ``ks`` and its own Schlick Fresnel reflectance ``f0``::

    f_r = kd/π + ks · sqrt((nu+1)(nv+1))/(8π) · (n·h)^(nu cos²φh + nv sin²φh)
                     / ((h·k) · max(n·wi, n·wo)) · F(h·k),   F(c) = f0 + (1 − f0)(1 − c)⁵

(``rd`` and ``rs`` are not used there; ``kd``, ``ks`` and ``f0`` are not used by
``"paper"``). Both variants share the lobe function below; ``"paper"`` is
``"ngan"`` with ks = 1, f0 = R_s and the coupled ρ_d in place of kd/π.

=========  ======  =======  ============  =============================================
parameter  kind    default  range         meaning
=========  ======  =======  ============  =============================================
variant    choice  paper    paper | ngan  the paper's coupled form, or Ngan et al.'s
rd         rgb     0.5      [0, 1]        diffuse reflectance R_d (paper)
rs         rgb     0.05     [0, 1]        specular reflectance at normal incidence R_s (paper)
nu         scalar  100      [0, 1e5]      Phong exponent along the tangent +x
nv         scalar  100      [0, 1e5]      Phong exponent along the bitangent +y
kd         rgb     0.5      [0, 1]        Lambert diffuse albedo (ngan)
ks         rgb     1        [0, 10]       weight of the specular lobe (ngan)
f0         rgb     0.05     [0, 1]        Schlick reflectance at normal incidence (ngan)
=========  ======  =======  ============  =============================================
"""

from __future__ import annotations

import math

from ..engine import jit
from ..geometry import NORMAL_MIN, dot3, half_vector_c
from ..params import Param, exponent_param
from ..registry import register
from ..terms.fresnel import f_schlick
from .base import BRDF

#: floor on h·k and max(n·wi, n·wo) in the specular denominator
COS_FLOOR = 1e-6


@jit
def anisotropic_cos_power(hx, hy, hz, nu, nv):
    """``(n·h)^((nu hx² + nv hy²)/(hx² + hy²))`` for a unit h, stable at h = n and for huge exponents.

    As ``exp(½ (nu hx² + nv hy²) · log(1 − s²)/s²)``, s² = hx² + hy², with log1p where s² is
    small (no cancellation) and 2 log(hz) otherwise; ``log(1 − s²)/s² → −1`` at h = n.
    """
    s2 = hx * hx + hy * hy
    t = nu * hx * hx + nv * hy * hy
    # both logarithms computed (arguments guarded), one selected: no branch around log1p/log/exp,
    # so a loop over this function vectorises (brdfkit.engine.vecmath)
    small = s2 < 0.5
    lg = math.log1p(-min(s2, 0.5)) if small else 2.0 * math.log(max(hz, NORMAL_MIN))
    q = lg / (s2 if s2 > 0.0 else 1.0)
    q = q if s2 > 0.0 else -1.0
    v = math.exp(0.5 * q * t)
    v = v if (small or hz > 0.0) else 0.0  # h in the tangent plane: (n·h)^e = 0 for e > 0
    return 1.0 if t <= 0.0 else v


@jit
def specular_lobe(hx, hy, hz, hk, ci, co, nu, nv):
    """``sqrt((nu+1)(nv+1))/(8π) · (n·h)^(nu cos²φh + nv sin²φh) / ((h·k) · max(n·wi, n·wo))``
    (A&S 2000's ρ_s without its Fresnel factor), the floors of :data:`COS_FLOOR` in the denominator."""
    lobe = anisotropic_cos_power(hx, hy, hz, nu, nv)
    denom = max(hk, COS_FLOOR) * max(max(ci, co), COS_FLOOR)
    return math.sqrt((nu + 1.0) * (nv + 1.0)) / (8.0 * math.pi) * lobe / denom


@jit
def one_minus_pow5(x):
    """``1 − (1 − x)⁵ = x (5 − 10x + 10x² − 5x³ + x⁴)``, without the cancellation at small x (grazing)."""
    return x * (5.0 + x * (-10.0 + x * (10.0 + x * (-5.0 + x))))


@jit
def coupled_diffuse(rd, rs, ci, co):
    """A&S 2000's ρ_d = 28 Rd/(23π) (1 − Rs)(1 − (1 − n·wi/2)⁵)(1 − (1 − n·wo/2)⁵), one channel."""
    return 28.0 / (23.0 * math.pi) * rd * (1.0 - rs) * one_minus_pow5(0.5 * ci) * one_minus_pow5(0.5 * co)


@jit
def ashikhmin_shirley_kernel(wix, wiy, wiz, wox, woy, woz, p, c):
    """Ashikhmin-Shirley per pair (engine protocol, :mod:`brdfkit.engine`).

    ``p`` = [rd (3), rs (3), nu, nv, kd (3), ks (3), f0 (3)]; ``c`` = [variant (0 paper, 1 ngan)].
    """
    hx, hy, hz = half_vector_c(wix, wiy, wiz, wox, woy, woz)
    hk = min(max(dot3(wix, wiy, wiz, hx, hy, hz), 0.0), 1.0)
    spec = specular_lobe(hx, hy, hz, hk, wiz, woz, p[6], p[7])
    if c[0] == 1:  # Ngan et al. 2005: kd/π + ks·lobe·F(f0)
        return (
            p[8] / math.pi + p[11] * spec * f_schlick(p[14], hk),
            p[9] / math.pi + p[12] * spec * f_schlick(p[15], hk),
            p[10] / math.pi + p[13] * spec * f_schlick(p[16], hk),
        )
    return (
        coupled_diffuse(p[0], p[3], wiz, woz) + spec * f_schlick(p[3], hk),
        coupled_diffuse(p[1], p[4], wiz, woz) + spec * f_schlick(p[4], hk),
        coupled_diffuse(p[2], p[5], wiz, woz) + spec * f_schlick(p[5], hk),
    )


@register
class AshikhminShirley(BRDF):
    name = "ashikhmin-shirley"
    title = "Ashikhmin-Shirley anisotropic Phong with coupled diffuse term and Schlick Fresnel"
    reference = "Ashikhmin and Shirley, An Anisotropic Phong BRDF Model, JGT 5(2), 2000"
    isotropic = False
    spec = (
        Param(
            "variant",
            "choice",
            "paper",
            doc="paper: coupled R_d/R_s (Ashikhmin & Shirley 2000); ngan: Lambert kd + ks·lobe with "
            "Schlick f0 (Ngan, Durand & Matusik 2005)",
            choices=("paper", "ngan"),
            fit=False,
        ),
        Param("rd", "rgb", 0.5, (0.0, 1.0), "", "diffuse reflectance R_d"),
        Param("rs", "rgb", 0.05, (0.0, 1.0), "", "specular reflectance at normal incidence R_s (Schlick F0)"),
        exponent_param("nu", 100.0, "Phong exponent along the tangent +x (smaller = wider highlight in x)"),
        exponent_param("nv", 100.0, "Phong exponent along the bitangent +y", tie="nu"),
        Param("kd", "rgb", 0.5, (0.0, 1.0), "", "Lambert diffuse albedo kd (variant=ngan only)"),
        Param("ks", "rgb", 1.0, (0.0, 10.0), "", "weight of the specular lobe (variant=ngan only)",
              fit_range=(0.0, 5.0)),
        Param("f0", "rgb", 0.05, (0.0, 1.0), "", "Schlick reflectance at normal incidence (variant=ngan only)"),
    )

    def active_params(self) -> dict:
        """``params`` less the other variant's parameters."""
        unused = ("kd", "ks", "f0") if self.params["variant"] == "paper" else ("rd", "rs")
        return {k: v for k, v in self.params.items() if k not in unused}

    kernel = staticmethod(ashikhmin_shirley_kernel)
    # its float32 twin measured slower than float64 (15 vs 19 M evals per CPU-s; log1p/log/exp per pair);
    # with libmvec (brdfkit.engine.vecmath) no faster (170-188 vs 169-198 M evals/s, 2^20 pairs)
    kernel_float32 = False

    def kernel_args(self):
        return self._pack(("rd", "rs", "nu", "nv", "kd", "ks", "f0"), ("variant",))
