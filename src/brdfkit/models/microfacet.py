"""The modern microfacet BRDF (Walter, Marschner, Li & Torrance 2007).

Reference: B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models
for Refraction through Rough Surfaces", EGSR 2007 (eq. 20 for reflection);
anisotropic distributions and Λ functions from E. Heitz, "Understanding the
Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), 2014.

    f_r(wi, wo) = kd/π + ks · F(wo·h) · D(h) · G(wi, wo) / (4 (n·wi)(n·wo))

with ``h = normalize(wi + wo)``.

* ``D`` (:mod:`brdfkit.terms.distributions`): normalised Beckmann
  ``exp(−(h_x²/α_x² + h_y²/α_y²)/h_z²)/(π α_x α_y h_z⁴)`` or GGX
  ``1/(π α_x α_y (h_x²/α_x² + h_y²/α_y² + h_z²)²)``; α_x runs along the
  tangent +x. α is the RMS slope for Beckmann and the GGX width, never a
  "perceptual" remapping.
* ``G`` (:mod:`brdfkit.terms.shadowing`): ``"smith"`` the separable Smith
  ``G1(wi) G1(wo)`` with ``G1 = 1/(1 + Λ)`` and each distribution's exact Λ
  (Beckmann with erf, GGX closed form); ``"smith-correlated"`` the
  height-correlated ``1/(1 + Λ(wi) + Λ(wo))``; ``"v-groove"`` the
  Cook-Torrance ``min(1, 2(n·h)(n·wo)/(wo·h), 2(n·h)(n·wi)/(wi·h))``.
* ``F`` (:mod:`brdfkit.terms.fresnel`) at ``c = wo·h``: ``"conductor"`` exact
  for the complex index ``eta + i·k``; ``"dielectric"`` exact dielectric with
  index ``eta`` (``k`` unused); ``"schlick"`` ``f0 + (1 − f0)(1 − c)⁵``;
  ``"none"`` F = 1.

Roughness rule
--------------
``alpha`` sets ``alpha_x = alpha_y`` (isotropic); giving ``alpha_x`` and/or
``alpha_y`` instead makes the surface anisotropic (one that is left out takes
the default 0.2). Giving ``alpha`` together with an ``alpha_x``/``alpha_y`` of a
different value is an error. ``m.params`` always holds the effective
``alpha_x`` and ``alpha_y``, and ``alpha`` equal to them when they are equal,
``None`` otherwise (so ``bk.model("microfacet", **m.params)`` round-trips, and
``m.with_params(alpha=...)`` / ``m.with_params(alpha_x=...)`` switch modes).

Range of α: [0.001, 1]. Below 0.001 the lobe is narrower than float32 can
resolve directions near the normal (cos θ steps of 6e-8, i.e. ~3.5e-4 rad) and
the peak D = 1/(π α²) exceeds 3e5; above 1 (RMS slope of 45° for Beckmann) the
single-scattering microfacet model is far outside the regime it was derived and
validated for: already at α = 1 with F = 1 and separable Smith it reflects only
46 % (Beckmann) / 31 % (GGX) of the light arriving along the normal (measured by
quadrature; the rest would need multiple scattering). The GLSL port should use
the same bounds.

==============  ======  =====================  ============  ==========================================
parameter       kind    default                range         meaning
==============  ======  =====================  ============  ==========================================
distribution    choice  ggx                    beckmann|ggx  microfacet normal distribution D
alpha           scalar  0.2                    [0.001, 1]    isotropic roughness (sets alpha_x=alpha_y)
alpha_x         scalar  0.2                    [0.001, 1]    roughness along the tangent +x
alpha_y         scalar  0.2                    [0.001, 1]    roughness along the bitangent +y
shadowing       choice  smith                  smith | smith-correlated | v-groove
fresnel         choice  conductor              conductor | dielectric | schlick | none
eta             rgb     gold 0.143,0.375,1.442 [0.01, 10]    real part of the index (conductor, dielectric)
k               rgb     gold 3.983,2.386,1.603 [0, 20]       imaginary part (conductor only)
f0              rgb     0.967,0.802,0.324      [0, 1]        normal-incidence reflectance (schlick only)
kd              rgb     0                      [0, 1]        diffuse albedo (kd/π)
ks              rgb     1                      [0, 1]        specular weight
multiscatter    bool    false                  true | false  add Kulla-Conty multiple-scattering lobe
==============  ======  =====================  ============  ==========================================

The gold indices are the RGB values Mitsuba uses for ``Au``; ``f0`` is gold's
normal-incidence reflectance from those indices.
"""

from __future__ import annotations

from typing import Any

import numpy as np

import math

from ..engine import jit
from ..geometry import half_vector_c
from ..params import Param, kd_param, ks_param
from ..registry import register
from ..terms.distributions import GGX, d_of, lambda_ggx_parts, lambda_of
from ..terms.fresnel import f_conductor, f_dielectric, f_schlick, fresnel_conductor, fresnel_dielectric_cook, fresnel_schlick
from ..terms.shadowing import g1_smith, g_smith_separable_parts, g_vgroove
from ..terms import multiscatter as _ms
from ..terms.multiscatter import N_MU, compensation, lookup_uniform
from .base import BRDF

GOLD_ETA = (0.143119, 0.374957, 1.442479)
GOLD_K = (3.983160, 2.385721, 1.603215)
GOLD_F0 = (0.966663, 0.802190, 0.324049)

ALPHA_RANGE = (1e-3, 1.0)
ALPHA_DEFAULT = 0.2

_ALPHA = Param(
    "alpha", "scalar", ALPHA_DEFAULT, ALPHA_RANGE, "",
    "isotropic roughness (Beckmann RMS slope / GGX width); sets alpha_x = alpha_y. "
    "Reported as None when alpha_x != alpha_y",
    log_scale=True, fit=False,
)
_ALPHA_X = Param("alpha_x", "scalar", ALPHA_DEFAULT, ALPHA_RANGE, "",
                 "roughness along the tangent +x (anisotropic use)", log_scale=True)
_ALPHA_Y = Param("alpha_y", "scalar", ALPHA_DEFAULT, ALPHA_RANGE, "",
                 "roughness along the bitangent +y (anisotropic use)", log_scale=True, tie="alpha_x")

# cosines are floored in the 1/(4 cos cos) factor so that it stays finite (kernels compute in float64)
COS_FLOOR = 1e-150

#: kernel choice indices (the order of the Param choices below)
SMITH, SMITH_CORRELATED, V_GROOVE = 0, 1, 2
CONDUCTOR, DIELECTRIC, SCHLICK, NO_FRESNEL = 0, 1, 2, 3


def resolve_roughness(model: str, given: dict[str, Any], by_name: dict[str, Param]) -> dict[str, Any]:
    """Apply the alpha / alpha_x / alpha_y rule to the given keyword parameters (in place copy)."""
    params = dict(given)
    if "alpha" in params and params["alpha"] is None:
        del params["alpha"]
    if "alpha" in params:
        a = by_name["alpha"].validate(model, params["alpha"])
        for n in ("alpha_x", "alpha_y"):
            if n in params:
                v = by_name[n].validate(model, params[n])
                if v != a:
                    raise ValueError(
                        f"{model}: give either 'alpha' (isotropic) or 'alpha_x'/'alpha_y' (anisotropic), "
                        f"not both with different values; got alpha={a:g}, {n}={v:g}"
                    )
        params["alpha"] = params["alpha_x"] = params["alpha_y"] = a
    return params


def fresnel_term(kind: str, c: np.ndarray, p: dict[str, Any], dtype) -> np.ndarray:
    """F(c) with shape ``c.shape + (3,)`` for the model's ``fresnel`` choice."""
    c3 = c[..., None]
    if kind == "conductor":
        return fresnel_conductor(c3, p["eta"], p["k"]).astype(dtype, copy=False)
    if kind == "dielectric":
        return fresnel_dielectric_cook(c3, p["eta"]).astype(dtype, copy=False)
    if kind == "schlick":
        return fresnel_schlick(p["f0"], c3).astype(dtype, copy=False)
    return np.ones(c.shape + (3,), dtype=dtype)


@jit(inline=True)
def fresnel_of(kind, c, eta, k, f0):
    """F(c) for the ``fresnel`` choice index ``kind`` (one channel)."""
    if kind == CONDUCTOR:
        return f_conductor(c, eta, k)
    if kind == DIELECTRIC:
        return f_dielectric(c, eta)
    if kind == SCHLICK:
        return f_schlick(f0, c)
    return 1.0


@jit(inline=True)
def shadowing_of(kind, dist, wix, wiy, wiz, wox, woy, woz, hz, lh, vh, ax, ay):
    """G for the ``shadowing`` choice index ``kind``: separable Smith, height-correlated Smith, V-groove."""
    if kind == V_GROOVE:
        return g_vgroove(hz, woz, wiz, vh, lh)
    if kind == SMITH and dist == GGX:  # GGX's Λ is a ratio: G1·G1 with one division
        ni, di = lambda_ggx_parts(wix, wiy, wiz, ax, ay)
        no, do = lambda_ggx_parts(wox, woy, woz, ax, ay)
        return g_smith_separable_parts(ni, di, no, do)
    lam_i = lambda_of(dist, wix, wiy, wiz, ax, ay)
    lam_o = lambda_of(dist, wox, woy, woz, ax, ay)
    if kind == SMITH:
        return g1_smith(lam_i) * g1_smith(lam_o)
    return g1_smith(lam_i + lam_o)


@jit
def microfacet_kernel(wix, wiy, wiz, wox, woy, woz, p, c):
    """Walter et al. (2007) eq. 20: kd/π + ks·F(c)·D(h)·G/(4 (n·wi)(n·wo)), per RGB channel.

    ``p = [alpha_x, alpha_y, eta(3), k(3), f0(3), kd(3), ks(3)]``, then, with ``multiscatter``,
    ``[ms_scale(3), missing(N_MU)]`` (see :func:`brdfkit.terms.multiscatter.setup`);
    ``c = [distribution, shadowing, fresnel, multiscatter]`` (indices into the Param choices, 0/1).
    """
    ax = p[0]
    ay = p[1]
    hx, hy, hz = half_vector_c(wix, wiy, wiz, wox, woy, woz)  # h_z > 0: both directions are above the horizon
    lh = wix * hx + wiy * hy + wiz * hz
    vh = wox * hx + woy * hy + woz * hz
    cc = min(max(0.5 * (lh + vh), 0.0), 1.0)  # wi·h = wo·h; the mean keeps F reciprocal to the last bit
    D = d_of(c[0], hx, hy, hz, ax, ay)
    G = shadowing_of(c[1], c[0], wix, wiy, wiz, wox, woy, woz, hz, lh, vh, ax, ay)
    geo = G / (4.0 * max(wiz, COS_FLOOR) * max(woz, COS_FLOOR))
    # ks·F·D first (finite, at most 1/(π α²)), then G/(4 cos cos) (finite thanks to the floor)
    sr = (p[14] * fresnel_of(c[2], cc, p[2], p[5], p[8]) * D) * geo
    sg = (p[15] * fresnel_of(c[2], cc, p[3], p[6], p[9]) * D) * geo
    sb = (p[16] * fresnel_of(c[2], cc, p[4], p[7], p[10]) * D) * geo
    if c[3]:  # multiple scattering between microfacets (Kulla & Conty 2017; terms/multiscatter.py)
        m_i = lookup_uniform(p, 20, N_MU, wiz)  # missing energy 1 − E(μi)
        m_o = lookup_uniform(p, 20, N_MU, woz)
        sr += compensation(m_i, m_o, p[17])
        sg += compensation(m_i, m_o, p[18])
        sb += compensation(m_i, m_o, p[19])
    return sr + p[11] / math.pi, sg + p[12] / math.pi, sb + p[13] / math.pi


@register
class Microfacet(BRDF):
    name = "microfacet"
    title = "microfacet BRDF (Walter et al. 2007): Beckmann/GGX, Smith/V-groove, Fresnel"
    reference = (
        "Walter, Marschner, Li, Torrance, Microfacet Models for Refraction through Rough Surfaces, "
        "EGSR 2007; Heitz, Understanding the Masking-Shadowing Function, JCGT 2014"
    )
    isotropic = False
    spec = (
        Param("distribution", "choice", "ggx", choices=("beckmann", "ggx"),
              doc="microfacet normal distribution D", fit=False),
        _ALPHA,
        _ALPHA_X,
        _ALPHA_Y,
        Param("shadowing", "choice", "smith", choices=("smith", "smith-correlated", "v-groove"),
              doc="masking-shadowing G: separable Smith G1·G1, height-correlated Smith, or Cook-Torrance V-groove",
              fit=False),
        Param("fresnel", "choice", "conductor", choices=("conductor", "dielectric", "schlick", "none"),
              doc="Fresnel term at c = wo·h", fit=False),
        Param("eta", "rgb", GOLD_ETA, (0.01, 10.0), "",
              "real refractive index (conductor and dielectric Fresnel); default gold"),
        Param("k", "rgb", GOLD_K, (0.0, 20.0), "", "extinction coefficient (conductor Fresnel); default gold"),
        Param("f0", "rgb", GOLD_F0, (0.0, 1.0), "", "normal-incidence reflectance (Schlick Fresnel)"),
        kd_param(0.0),
        ks_param(1.0, "specular weight (scales the microfacet term)"),
        Param("multiscatter", "bool", False, fit=False,
              doc="add the energy lost to multiple scattering between facets (Kulla & Conty 2017, "
                  "Fresnel-weighted; brdfkit.terms.multiscatter)"),
    )

    #: ``_from_valid`` builds the same object as ``__init__`` from validated values: ``__init__`` only
    #: resolves the alpha aliases before validating, and ``_init_valid`` derives the rest
    from_valid_is_init = True

    def __init__(self, **params: Any) -> None:
        by_name = {p.name: p for p in self.spec}
        super().__init__(**resolve_roughness(self.name, params, by_name))

    def _init_valid(self, params: dict[str, Any]) -> None:
        ax, ay = params["alpha_x"], params["alpha_y"]
        params["alpha"] = ax if ax == ay else None
        self.isotropic = ax == ay  # per instance; the class (info) says "can be anisotropic"
        super()._init_valid(params)

    def active_params(self) -> dict[str, Any]:
        """``params`` less what the options switch off: eta/k/f0 by Fresnel, alpha vs alpha_x/alpha_y."""
        unused = {
            "conductor": ("f0",),
            "dielectric": ("k", "f0"),
            "schlick": ("eta", "k"),
            "none": ("eta", "k", "f0"),
        }[self.params["fresnel"]]
        unused += ("alpha_x", "alpha_y") if self.isotropic else ("alpha",)
        return {k: v for k, v in self.params.items() if k not in unused}

    def with_params(self, **changes: Any) -> "Microfacet":
        """A copy with some parameters changed; ``alpha`` and ``alpha_x``/``alpha_y`` replace each other."""
        new = dict(self.params)
        if "alpha" in changes:
            new.pop("alpha_x", None)
            new.pop("alpha_y", None)
        elif "alpha_x" in changes or "alpha_y" in changes:
            new.pop("alpha", None)
        new.update(changes)
        return type(self)(**new)

    kernel = staticmethod(microfacet_kernel)

    def kernel_args(self):
        p, c = self._pack(("alpha_x", "alpha_y", "eta", "k", "f0", "kd", "ks"),
                          ("distribution", "shadowing", "fresnel", "multiscatter"))
        if not self.params["multiscatter"]:
            return p, c
        hit = self._cache.get("multiscatter")
        if hit is None:  # the material's compensation: 1 − E(μ_j) at its α, and the RGB lobe scale
            prm = self.params
            missing, scale = _ms.setup(prm, lambda mu: fresnel_term(prm["fresnel"], mu, prm, np.dtype(np.float64)))
            hit = self._cache["multiscatter"] = (np.ascontiguousarray(np.concatenate([p, scale, missing])), c)
        return hit


__all__ = ["Microfacet", "microfacet_kernel", "GOLD_ETA", "GOLD_K", "GOLD_F0", "resolve_roughness", "fresnel_term"]
