"""MaterialX documents: OpenPBR Surface (and Standard Surface under its names, and EON's bare
``oren_nayar_diffuse_bsdf``), built with the ``MaterialX`` package and validated against its
standard libraries.

Which source becomes which parameters, and when exactly: :mod:`brdfkit.interchange.export`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..models.base import BRDF
from .approx import _rgb, _is, _is_eon, eon_roughness, _is_isotropic, _target_params, conductor_f0_f82


def _openpbr_direct(model: BRDF) -> tuple[dict[str, Any] | None, bool, str]:
    p = model.params
    if _is(model, "lambert"):
        return {"base_weight": 1.0, "base_color": _rgb(p["kd"]), "base_metalness": 0.0, "specular_weight": 0.0}, True, (
            "lambert -> base_color = kd, specular_weight = 0"
        )
    if _is_eon(model):
        return {"base_weight": 1.0, "base_color": _rgb(p["kd"]), "base_metalness": 0.0, "specular_weight": 0.0,
                "base_diffuse_roughness": eon_roughness(p)}, True, (
            "oren-nayar eon -> base_color = kd, base_diffuse_roughness = min(sigma, 1), specular_weight = 0 "
            "(OpenPBR's diffuse is EON)"
        )
    if _is(model, "microfacet") and p["distribution"] == "ggx":
        ax, ay = float(p["alpha_x"]), float(p["alpha_y"])
        a = max(ax, ay)
        aniso = 0.0
        if ax != ay:  # invert αt = r²·sqrt(2/(1+(1−a)²)), αb = (1−a)αt (tangent axis = the larger α)
            aniso = 1.0 - min(ax, ay) / a
        r = math.sqrt(a / math.sqrt(2.0 / (1.0 + (1.0 - aniso) ** 2)))
        ks = float(np.mean(_rgb(p["ks"])))
        out = {"base_weight": 1.0, "specular_weight": min(ks, 1.0), "specular_roughness": min(r, 1.0),
               "specular_roughness_anisotropy": aniso}
        if ay > ax:
            # OpenPBR has no rotation input: its anisotropy runs along the tangent (x)
            extra = "; OpenPBR has no anisotropy rotation, so alpha_y > alpha_x is written along the tangent"
        else:
            extra = ""
        if p["fresnel"] == "conductor":
            f0, tint = conductor_f0_f82(p["eta"], p["k"])
            out.update(base_color=f0.tolist(), base_metalness=1.0, specular_color=tint.tolist())
            return out, False, "conductor -> metal: base_color = F0(eta, k), specular_color = F82 tint" + extra
        if p["fresnel"] == "schlick":
            out.update(base_color=_rgb(p["f0"]), base_metalness=1.0, specular_color=[1.0, 1.0, 1.0])
            return out, False, "schlick conductor -> metal: base_color = f0" + extra
        if p["fresnel"] == "dielectric":
            eta = float(np.mean(_rgb(p["eta"])))
            out.update(base_color=_rgb(p["kd"]), base_metalness=0.0, specular_ior=min(max(eta, 1.0), 5.0),
                       specular_color=[1.0, 1.0, 1.0])
            return out, False, "dielectric -> base_color = kd, specular_ior = eta" + extra
    return None, False, ""


def openpbr_params(model: BRDF, metric: str = "ngan", data=None) -> tuple[dict[str, Any], dict[str, Any]]:
    """OpenPBR Surface parameters for a model, and what went into them."""
    from .targets import OpenPBRSurface

    def fixed(full):
        out = {"base_weight": 1.0}
        if _is_isotropic(model):
            out["specular_roughness_anisotropy"] = full["specular_roughness_anisotropy"]
        return out

    return _target_params(OpenPBRSurface, "the OpenPBR formula", _openpbr_direct, model, metric, data, fixed)


_SS_NAMES = {  # OpenPBR -> Standard Surface
    "base_weight": "base",
    "base_color": "base_color",
    "base_metalness": "metalness",
    "specular_weight": "specular",
    "specular_color": "specular_color",
    "specular_roughness": "specular_roughness",
    "specular_ior": "specular_IOR",
    "specular_roughness_anisotropy": "specular_anisotropy",
    "base_diffuse_roughness": "diffuse_roughness",
}


#: inputs written only where they differ from 0 (their default in both shading models)
_ZERO_DEFAULT = ("base_diffuse_roughness",)


def materialx_document(params: dict[str, Any], name: str = "brdfkit", eon: bool = False):
    """A MaterialX document with an open_pbr_surface and a standard_surface material; validated.

    ``eon``: add a third material, ``oren_nayar_diffuse_bsdf`` (color = base_color, roughness =
    base_diffuse_roughness, energy_compensation = true) in a ``surface`` shader: the EON model itself.
    """
    import MaterialX as mx

    doc = mx.createDocument()
    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    doc.importLibrary(lib)
    safe = "".join(ch if ch.isalnum() or ch == "_" else "_" for ch in name) or "brdfkit"
    if safe[0].isdigit():
        safe = "m_" + safe

    def put(node, key: str, v: Any) -> None:
        if isinstance(v, (list, tuple, np.ndarray)):
            node.setInputValue(key, mx.Color3(*[float(x) for x in v]))
        else:
            node.setInputValue(key, float(v))

    opbr = doc.addNode("open_pbr_surface", f"SR_{safe}_openpbr", "surfaceshader")
    std = doc.addNode("standard_surface", f"SR_{safe}_standard", "surfaceshader")
    for k, v in params.items():
        if k in _ZERO_DEFAULT and float(v) == 0.0:
            continue
        put(opbr, k, v)
        if k in _SS_NAMES:
            put(std, _SS_NAMES[k], v)
    doc.addMaterialNode(f"M_{safe}_openpbr", opbr)
    doc.addMaterialNode(f"M_{safe}_standard", std)
    if eon:
        bsdf = doc.addNode("oren_nayar_diffuse_bsdf", f"BSDF_{safe}_eon", "BSDF")
        put(bsdf, "color", params["base_color"])
        put(bsdf, "roughness", params["base_diffuse_roughness"])
        bsdf.setInputValue("energy_compensation", True)
        surf = doc.addNode("surface", f"SR_{safe}_eon", "surfaceshader")
        surf.setConnectedNode("bsdf", bsdf)
        doc.addMaterialNode(f"M_{safe}_eon", surf)
    ok, msg = doc.validate()
    if not ok:  # pragma: no cover - our own document; a failure is a bug
        raise RuntimeError(f"MaterialX validation failed: {msg.strip()}")
    return doc


def materialx_text(doc) -> str:
    import MaterialX as mx

    opts = mx.XmlWriteOptions()
    opts.elementPredicate = lambda e: not e.hasSourceUri()  # leave the standard libraries out
    return mx.writeToXmlString(doc, opts)
