"""The reflectance formulas of the export targets, as brdfkit models (numpy), for fitting and errors.

An export writes parameters of another system's material model. Where that
model is not one of ours, this module evaluates it, so that the fitter
(:func:`brdfkit.fit`) can choose the target's parameters and the export can
state how far the written material is from the source. These classes are not
in the registry (they are the targets' models, not published BRDFs of our
lecture); they follow the :class:`~brdfkit.models.base.BRDF` contract.

:class:`GltfPBR`
    glTF 2.0 metallic-roughness (Khronos, glTF 2.0 specification, Appendix B
    "BRDF Implementation") with ``KHR_materials_ior`` and
    ``KHR_materials_specular`` (the Fresnel term of that extension's
    "Implementation" section)::

        α    = roughness²
        f0_d = min(((ior − 1)/(ior + 1))² · specular_color, 1) · specular
        F0   = lerp(f0_d, base_color, metallic)
        F90  = lerp(specular, 1, metallic)
        F    = F0 + (F90 − F0)(1 − v·h)⁵
        f_r  = (1 − metallic)(1 − F) · base_color/π  +  F · D(h) · G1(l) G1(v) / (4 (n·l)(n·v))

    with the GGX (Trowbridge-Reitz) ``D`` and the separable Smith ``G1`` of
    Appendix B (Walter et al. 2007 eqs. 33, 34). ``specular = 0`` leaves a pure
    Lambert ``base_color/π``; ``metallic = 1`` leaves the Schlick-Fresnel GGX
    conductor with ``F0 = base_color``. With the draft ``KHR_materials_diffuse_roughness``
    (``diffuse_roughness`` = its ``diffuseRoughnessFactor`` r > 0) the diffuse
    ``base_color/π`` becomes the EON lobe of OpenPBR, ``f_EON(base_color, r)``
    (:mod:`brdfkit.models.eon`: ``oren-nayar`` ``variant="eon"`` with ``sigma = r``).
    Not fitted (held at its value, 0 unless a direct mapping sets it).

:class:`OpenPBRSurface`
    The reflection of an opaque OpenPBR Surface (Academy Software Foundation,
    OpenPBR Surface specification v1.1): a metal and a dielectric base mixed by
    ``base_metalness``, one GGX specular lobe with
    ``α = specular_roughness²`` (anisotropy as the specification maps it:
    αt = α·sqrt(2/(1 + (1 − a)²)), αb = (1 − a)·αt)::

        metal      F82-tint Schlick (Hoffman 2019; Kutz, Hasan & Edmondson 2021):
                   F(μ) = S(μ) − μ(1 − μ)⁶ · S(μ̄)(1 − t)/(μ̄(1 − μ̄)⁶),
                   S(μ) = F0 + (1 − F0)(1 − μ)⁵,  F0 = base_weight·base_color,
                   t = specular_color, μ̄ = 1/7
                   f = specular_weight · F · D G1 G1 / (4 (n·l)(n·v))
        dielectric F_d = the exact unpolarised Fresnel reflectance at specular_ior
                   f = specular_weight·specular_color·F_d · D G1 G1/(4 (n·l)(n·v))
                       + (1 − specular_weight·F_d) · base_weight·base_color/π

    With ``base_diffuse_roughness`` r > 0 the diffuse ``base_weight·base_color/π`` is the
    specification's EON lobe ``f_EON(base_weight·base_color, r)`` (:mod:`brdfkit.models.eon`;
    not fitted, held at its value). The specification layers the specular lobe over the diffuse base with
    energy conservation whose exact form it leaves to the renderer; the
    (1 − specular_weight·F_d(v·h)) factor here is the simplest such coupling
    (that of glTF). The error an export reports is measured against this
    formula.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from ..geometry import half_vector
from ..models.base import BRDF
from ..models.oren_nayar import OrenNayar
from ..params import Param
from ..terms.distributions import ggx
from ..terms.fresnel import fresnel_dielectric_cook
from ..terms.shadowing import smith_g1

_COS_FLOOR = 1e-7
F82_MU = 1.0 / 7.0  # cos θ of the F82 angle (81.79°), as the F82-tint model defines it


def _ggx_lobe(wi, wo, ax, ay):
    """D(h)·G1(wi)·G1(wo)/(4 cos θi cos θo) of GGX with the separable Smith G (Walter et al. 2007) and c = wi·h."""
    dt = wi.dtype.type
    h = half_vector(wi, wo)
    c = np.clip(np.einsum("...i,...i->...", wi, h), 0, 1)
    D = ggx(h, ax, ay)
    G = smith_g1(wi, ax, ay, "ggx") * smith_g1(wo, ax, ay, "ggx")
    lobe = D * G / (dt(4) * np.maximum(wi[..., 2], dt(_COS_FLOOR)) * np.maximum(wo[..., 2], dt(_COS_FLOOR)))
    return np.minimum(lobe, np.finfo(wi.dtype).max / 4)[..., None], c[..., None]


def _diffuse(albedo, roughness: float, wi, wo):
    """The diffuse lobe: Lambert ``albedo/π`` at roughness 0 (exactly the former formula), else the
    EON lobe of OpenPBR / KHR_materials_diffuse_roughness (``oren-nayar`` ``variant="eon"``, ``sigma = r``)."""
    dt = wi.dtype.type
    if roughness <= 0:
        return albedo / dt(math.pi)
    rgb = np.broadcast_to(np.asarray(albedo, dtype=np.float64), (3,))
    return OrenNayar(kd=np.clip(rgb, 0.0, 1.0), sigma=float(roughness), variant="eon").eval(wi, wo)


def _schlick5(c):
    m = 1 - c
    m2 = m * m
    return m2 * m2 * m


class GltfPBR(BRDF):
    """glTF 2.0 metallic-roughness with KHR_materials_ior and KHR_materials_specular (see the module docstring)."""

    name: ClassVar[str] = "gltf-pbr"
    title: ClassVar[str] = "glTF 2.0 metallic-roughness (+ KHR_materials_ior, KHR_materials_specular)"
    reference: ClassVar[str] = "Khronos glTF 2.0 specification, Appendix B; KHR_materials_ior; KHR_materials_specular"
    isotropic: ClassVar[bool] = True
    spec: ClassVar[tuple[Param, ...]] = (
        Param("base_color", "rgb", (0.8, 0.8, 0.8), (0.0, 1.0), doc="baseColorFactor (linear RGB)"),
        Param("metallic", "scalar", 0.0, (0.0, 1.0), doc="metallicFactor"),
        Param("roughness", "scalar", 0.5, (0.0, 1.0), doc="roughnessFactor; α = roughness²", fit_range=(0.03, 1.0)),
        Param("ior", "scalar", 1.5, (1.0, 5.0), doc="KHR_materials_ior.ior"),
        Param("specular", "scalar", 1.0, (0.0, 1.0), doc="KHR_materials_specular.specularFactor"),
        Param("specular_color", "rgb", (1.0, 1.0, 1.0), (0.0, 1.0), doc="KHR_materials_specular.specularColorFactor"),
        Param("diffuse_roughness", "scalar", 0.0, (0.0, 1.0), doc="KHR_materials_diffuse_roughness.diffuseRoughnessFactor "
              "(EON diffuse; 0 = Lambert)", fit=False),
    )

    def _eval(self, wi, wo, p):
        dt = wi.dtype.type
        a = max(p["roughness"] * p["roughness"], dt(1e-6))
        lobe, c = _ggx_lobe(wi, wo, a, a)
        m = p["metallic"]
        ior = p["ior"]
        f0_d = np.minimum(((ior - 1) / (ior + 1)) ** 2 * p["specular_color"], 1) * p["specular"]
        F0 = f0_d + (p["base_color"] - f0_d) * m
        F90 = p["specular"] + (1 - p["specular"]) * m
        F = F0 + (F90 - F0) * _schlick5(c)
        diffuse = _diffuse(p["base_color"], float(p["diffuse_roughness"]), wi, wo)
        return (1 - m) * (1 - F) * diffuse + F * lobe


def f82_tint_fresnel(c, f0, tint):
    """The F82-tint Schlick Fresnel of OpenPBR's metal (Hoffman 2019; Kutz et al. 2021), ``c = cos θ``.

    Equals ``f0`` at c = 1 and ``tint · S(μ̄)`` at the F82 angle (c = μ̄ = 1/7).
    """
    c = np.clip(c, 0.0, 1.0)
    mb = F82_MU
    s = f0 + (1 - f0) * _schlick5(c)
    s_bar = f0 + (1 - f0) * (1 - mb) ** 5
    b = s_bar * (1 - tint) / (mb * (1 - mb) ** 6)
    return np.clip(s - c * (1 - c) ** 6 * b, 0.0, None)


def openpbr_alphas(roughness: float, anisotropy: float) -> tuple[float, float]:
    """(αt, αb) from OpenPBR's specular_roughness r and specular_roughness_anisotropy a."""
    a2 = roughness * roughness
    at = a2 * math.sqrt(2.0 / (1.0 + (1.0 - anisotropy) ** 2))
    return at, (1.0 - anisotropy) * at


class OpenPBRSurface(BRDF):
    """The reflection of an opaque OpenPBR Surface (see the module docstring)."""

    name: ClassVar[str] = "openpbr-surface"
    title: ClassVar[str] = "OpenPBR Surface (opaque: metal + dielectric base, one GGX specular lobe)"
    reference: ClassVar[str] = "Academy Software Foundation, OpenPBR Surface specification v1.1"
    isotropic: ClassVar[bool] = False
    spec: ClassVar[tuple[Param, ...]] = (
        Param("base_weight", "scalar", 1.0, (0.0, 1.0)),
        Param("base_color", "rgb", (0.8, 0.8, 0.8), (0.0, 1.0)),
        Param("base_metalness", "scalar", 0.0, (0.0, 1.0)),
        Param("specular_weight", "scalar", 1.0, (0.0, 1.0)),
        Param("specular_color", "rgb", (1.0, 1.0, 1.0), (0.0, 1.0)),
        Param("specular_roughness", "scalar", 0.3, (0.0, 1.0), fit_range=(0.03, 1.0)),
        Param("specular_roughness_anisotropy", "scalar", 0.0, (0.0, 1.0)),
        Param("specular_ior", "scalar", 1.5, (1.0, 5.0)),
        Param("base_diffuse_roughness", "scalar", 0.0, (0.0, 1.0), doc="EON roughness of the diffuse base (0 = Lambert)",
              fit=False),
    )

    def _eval(self, wi, wo, p):
        dt = wi.dtype.type
        at, ab = openpbr_alphas(float(p["specular_roughness"]), float(p["specular_roughness_anisotropy"]))
        lobe, c = _ggx_lobe(wi, wo, max(at, 1e-6), max(ab, 1e-6))
        m = p["base_metalness"]
        sw = p["specular_weight"]
        base = p["base_weight"] * p["base_color"]
        metal = sw * f82_tint_fresnel(c, base, p["specular_color"]) * lobe
        Fd = fresnel_dielectric_cook(c, dt(p["specular_ior"]))
        diel = sw * p["specular_color"] * Fd * lobe + (1 - sw * Fd) * _diffuse(base, float(p["base_diffuse_roughness"]), wi, wo)
        return m * metal + (1 - m) * diel


__all__ = ["GltfPBR", "OpenPBRSurface", "f82_tint_fresnel", "openpbr_alphas", "F82_MU"]
