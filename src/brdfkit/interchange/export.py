"""Export a model to Mitsuba 3, MaterialX (OpenPBR Surface + Standard Surface) or glTF 2.0.

``export(model, fmt, path)`` writes the file (atomically, :mod:`brdfkit.fileio`)
and returns an :class:`ExportResult`: which target material was written, its
parameters, whether the target expresses the model exactly, and otherwise the
approximation error (``error``; ``None`` when exact) in the fitter's metric
(:mod:`brdfkit.measured.fit`, default ``"ngan"``: cosine-weighted RMS of
f_r in 1/sr over pairs within 80° of the normal) and relative to the source's
own RMS (``relative_error``).

Mitsuba 3 (``fmt="mitsuba"``)
-----------------------------
Written as a Mitsuba 3 XML ``<bsdf version="3.0.0" ...>`` (``mi.load_file``
returns the BSDF) to a ``.xml`` path, or as the dict for ``mi.load_dict`` to a
``.json`` path.

==============================================  ===============================  ======
source                                          Mitsuba BSDF                     exact
==============================================  ===============================  ======
``lambert``                                     ``diffuse`` (reflectance = kd)    yes
``microfacet`` ggx, smith, conductor, kd = 0    ``roughconductor``                yes
``microfacet`` ggx, smith, conductor, kd > 0    ``blendbsdf`` of ``diffuse`` and  yes
                                                ``roughconductor`` (weights w,
                                                1 − w; reflectances rescaled)
``microfacet`` beckmann, smith, conductor       as above                          no: Mitsuba's Beckmann G1 is
                                                                                  Walter's rational approximation
``microfacet`` smith, dielectric, isotropic     ``roughplastic`` (the same        no: its diffuse term is
                                                specular lobe; diffuse_reflectance Fresnel-coupled
                                                by least squares)
anything else (other models, other Fresnel /    fitted (:func:`brdfkit.fit`) as   no
shadowing choices, measured data, .brdf files)  the ggx/smith/conductor
                                                ``microfacet`` with kd, then the
                                                exact mapping above
==============================================  ===============================  ======

For the not-exact direct mappings the error is measured by evaluating the
written BSDF in Mitsuba itself (``scalar_rgb``) on the fitter's samples.

MaterialX (``fmt="materialx"``)
-------------------------------
A ``.mtlx`` document with an ``open_pbr_surface`` node and a
``standard_surface`` node (each under its own ``surfacematerial``), built with
the ``MaterialX`` package and checked with its ``Document.validate`` against
the standard data libraries before it is written. The OpenPBR parameters come
from :class:`~brdfkit.interchange.targets.OpenPBRSurface`: directly for
``lambert`` (exact) and for GGX conductors (metal: base_color = F0 = the
conductor's Fresnel reflectance at normal incidence from eta, k;
specular_color = the F82 tint that makes the F82-tint Fresnel equal the
conductor's at 82°; exact only at those two angles, error stated), by fitting
otherwise (the direct mapping is the fit's first start). Standard Surface gets
the same values under its names (base, base_color, metalness, specular,
specular_color, specular_roughness, specular_IOR, specular_anisotropy,
diffuse_roughness); its own error is not measured.

``oren-nayar`` ``variant="eon"`` (Portsmouth, Kutz & Hill 2025) is exact twice over:
OpenPBR 1.1's diffuse base IS that model (base_color = kd, base_diffuse_roughness =
r = min(σ, 1), specular_weight = 0), and the document gets a third material, the bare
``oren_nayar_diffuse_bsdf`` (color = kd, roughness = r, energy_compensation = true)
in a ``surface`` (MaterialX 1.39). Standard Surface's ``diffuse_roughness`` drives the
uncompensated (qualitative) Oren-Nayar: close, not the same model.

glTF (``fmt="gltf"``)
---------------------
A binary ``.glb`` (pygltflib) with a UV sphere (positions, normals) and the
material as ``pbrMetallicRoughness`` plus ``KHR_materials_ior`` and
``KHR_materials_specular`` when they differ from their defaults. Parameters
from :class:`~brdfkit.interchange.targets.GltfPBR`: exact for ``lambert``
(specularFactor 0) and for a GGX/smith/Schlick ``microfacet`` with kd = 0,
ks = 1, isotropic (metallic 1, baseColor = f0, roughness = sqrt(alpha)), and for
``oren-nayar`` ``variant="eon"`` (baseColor = kd, specularFactor 0, and the draft
``KHR_materials_diffuse_roughness`` with diffuseRoughnessFactor = r = min(σ, 1), whose
diffuse lobe is OpenPBR's EON); fitted otherwise.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .. import fileio
from ..models.base import BRDF
from ..params import to_jsonable

FORMATS = ("mitsuba", "materialx", "gltf")


@dataclass
class ExportResult:
    """What :func:`export` wrote and how well it represents the model."""

    format: str
    path: str
    target: str  # e.g. "roughconductor", "blendbsdf(diffuse, roughconductor)", "open_pbr_surface"
    params: dict[str, Any]  # the target's parameters as written
    exact: bool
    error: float | None  # None when exact
    relative_error: float | None
    metric: str = "ngan"
    method: str = "direct"  # "direct" (a mapping) or "fit"
    source: str = ""
    note: str = ""
    extra: dict[str, Any] = field(default_factory=dict)

    def __float__(self) -> float:
        return 0.0 if self.error is None else float(self.error)

    def to_json(self) -> dict[str, Any]:
        out = {
            "format": self.format,
            "path": self.path,
            "source": self.source,
            "target": self.target,
            "params": _plain(self.params),
            "exact": self.exact,
            "error": self.error,
            "relative_error": self.relative_error,
            "metric": self.metric,
            "method": self.method,
            "note": self.note,
        }
        out.update(_plain(self.extra))
        return out


def _plain(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return [_plain(v) for v in obj.tolist()]
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def _rgb(v) -> list[float]:
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.size == 1:
        a = np.repeat(a, 3)
    return [float(x) for x in a]


# --------------------------------------------------------------------------- errors
class _AsSamplable(BRDF):
    """Lets the fitter sample any model: its samples cover every azimuth φh, so they
    are a valid sample of an anisotropic model too (the fitter itself only checks)."""

    name = "export-source"
    isotropic = True
    spec = ()

    def __init__(self, inner: BRDF) -> None:
        super().__init__()
        self.inner = inner
        self.label = inner.label or inner.name or "model"

    def eval(self, wi, wo):
        return self.inner.eval(wi, wo)


def _samples(model: BRDF, n: int = 3000, seed: int = 0):
    from ..measured.fit import sample

    return sample(_AsSamplable(model), n=n, seed=seed)


def _errors(approx_values: np.ndarray, data, metric: str) -> tuple[float, float]:
    """(absolute, relative) error of values at the samples, in the fitter's metric."""
    from ..measured.fit import _transform

    T = _transform(metric)
    c = data.cos_i[:, None]
    t = T(data.f, c)
    d = T(np.asarray(approx_values, np.float64), c) - t
    err = float(np.sqrt(np.mean(data.w[:, None] * d * d)))
    norm = float(np.sqrt(np.mean(data.w[:, None] * t * t)))
    return err, (err / norm if norm > 0 else (0.0 if err == 0 else math.inf))


def _fit(target: type[BRDF], model: BRDF, data, metric: str, fixed: dict[str, Any], start: dict[str, Any] | None = None):
    """Fit ``target``'s parameters to the source samples; ``start`` becomes the first start (the defaults)."""
    from ..measured.fit import fit

    cls = target
    if start:
        spec = tuple(replace(p, default=start[p.name]) if p.name in start else p for p in target.spec)
        cls = type(target.__name__, (target,), {"spec": spec, "__module__": target.__module__})
    return fit(cls, data.source, fixed=fixed, metric=metric, data=data, starts=3, candidates=24)


# --------------------------------------------------------------------------- sources
def _is(model: BRDF, name: str) -> bool:
    return type(model).name == name


def _is_eon(model: BRDF) -> bool:
    return _is(model, "oren-nayar") and model.params["variant"] == "eon"


def eon_roughness(params: dict[str, Any]) -> float:
    """EON's roughness r of an ``oren-nayar`` ``variant="eon"`` model: min(σ, 1) (:mod:`brdfkit.models.oren_nayar`)."""
    return min(float(params["sigma"]), 1.0)


def _microfacet_conductor(params: dict[str, Any]) -> tuple[dict[str, Any], bool]:
    """The Mitsuba dict of a microfacet conductor (+ Lambert) model, and whether values had to be clamped.

    Mitsuba accepts reflectances in [0, 1] only: kd/π + ks·f_spec becomes the blend
    (1 − w)·diffuse(kd/(1 − w)) + w·roughconductor(ks/w), exact when max ks + max kd <= 1
    (w = max ks); otherwise the two reflectances are clamped to 1 (not exact).
    """
    dist = params["distribution"]
    cond = {
        "type": "roughconductor",
        "distribution": dist,
        "alpha_u": float(params["alpha_x"]),
        "alpha_v": float(params["alpha_y"]),
        "eta": {"type": "rgb", "value": _rgb(params["eta"])},
        "k": {"type": "rgb", "value": _rgb(params["k"])},
    }
    kd = np.asarray(_rgb(params["kd"]))
    ks = np.asarray(_rgb(params["ks"]))
    if kd.max() <= 0:
        cond["specular_reflectance"] = {"type": "rgb", "value": ks.tolist()}
        return cond, False
    if ks.max() <= 0:
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": kd.tolist()}}, False
    fits = ks.max() + kd.max() <= 1
    w = float(ks.max()) if fits else float(ks.max() / (ks.max() + kd.max()))
    rs, rd = ks / w, kd / (1 - w)
    clamped = bool(rs.max() > 1 or rd.max() > 1)
    cond["specular_reflectance"] = {"type": "rgb", "value": np.minimum(rs, 1).tolist()}
    return {
        "type": "blendbsdf",
        "weight": w,
        "bsdf_0": {"type": "diffuse", "reflectance": {"type": "rgb", "value": np.minimum(rd, 1).tolist()}},
        "bsdf_1": cond,
    }, clamped


def _target_name(d: dict[str, Any]) -> str:
    if d["type"] == "blendbsdf":
        return f"blendbsdf({d['bsdf_0']['type']}, {d['bsdf_1']['type']})"
    return d["type"]


# --------------------------------------------------------------------------- Mitsuba
MITSUBA_VARIANT = "scalar_rgb"


def _mitsuba():
    import mitsuba as mi

    return mi


class _Variant:
    """Use Mitsuba's scalar_rgb variant for a while and restore the caller's afterwards."""

    def __enter__(self):
        mi = _mitsuba()
        self.old = mi.variant()
        if self.old != MITSUBA_VARIANT:
            mi.set_variant(MITSUBA_VARIANT)
        return mi

    def __exit__(self, *exc):
        if self.old and self.old != MITSUBA_VARIANT:
            _mitsuba().set_variant(self.old)


def _mitsuba_errors(d: dict[str, Any], data, metric: str) -> tuple[float, float]:
    """The error of a Mitsuba BSDF dict at the samples, evaluated by Mitsuba (which must be installed)."""
    try:
        values = mitsuba_eval(d, data.wi, data.wo)
    except ImportError:
        raise ValueError(
            "measuring this export's error needs Mitsuba 3 (pip install mitsuba); the mapping is not exact"
        ) from None
    return _errors(values, data, metric)


def mitsuba_eval(bsdf: Any, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """f_r of a Mitsuba BSDF (a ``load_dict`` dict or a loaded BSDF) in OUR convention.

    Mitsuba's ``si.wi`` is our ``wo`` (toward the viewer), its ``eval`` direction
    is our ``wi`` and its value includes cos θ of our ``wi``, which is divided out.
    """
    with _Variant() as mi:
        b = mi.load_dict(bsdf) if isinstance(bsdf, dict) else bsdf
        ctx = mi.BSDFContext()
        si = mi.SurfaceInteraction3f()
        si.sh_frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))
        out = np.zeros((len(wi), 3))
        for j, (a, v) in enumerate(zip(np.asarray(wi, float), np.asarray(wo, float))):
            if a[2] <= 0 or v[2] <= 0:
                continue
            si.wi = mi.Vector3f(*map(float, v))
            r = b.eval(ctx, si, mi.Vector3f(*map(float, a)))
            out[j] = [r[0] / a[2], r[1] / a[2], r[2] / a[2]]
    return out


def mitsuba_xml(d: dict[str, Any], ident: str = "material") -> str:
    """A Mitsuba 3 XML document whose root is the BSDF of a ``load_dict`` dict."""

    def value(k: str, v: Any, pad: str) -> list[str]:
        if isinstance(v, dict) and v.get("type") == "rgb":
            return [f'{pad}<rgb name="{k}" value="{", ".join(f"{x:.17g}" for x in v["value"])}"/>']
        if isinstance(v, dict):
            return obj(v, pad, name=None)
        if isinstance(v, bool):
            return [f'{pad}<boolean name="{k}" value="{str(v).lower()}"/>']
        if isinstance(v, (int, float)):
            return [f'{pad}<float name="{k}" value="{float(v):.17g}"/>']
        return [f'{pad}<string name="{k}" value="{v}"/>']

    def obj(o: dict[str, Any], pad: str, name: str | None, root: bool = False) -> list[str]:
        attrs = f' version="3.0.0" type="{o["type"]}" id="{ident}"' if root else f' type="{o["type"]}"'
        lines = [f"{pad}<bsdf{attrs}>"]
        for k, v in o.items():
            if k != "type":
                lines += value(k, v, pad + "    ")
        lines.append(f"{pad}</bsdf>")
        return lines

    head = "<?xml version='1.0' encoding='utf-8'?>\n<!-- written by brdfkit (brdfkit export --to mitsuba) -->\n"
    return head + "\n".join(obj(d, "", None, root=True)) + "\n"


def mitsuba_dict(model: BRDF, metric: str = "ngan", data=None) -> tuple[dict[str, Any], dict[str, Any]]:
    """The ``mi.load_dict`` dict for a model, and what went into it (exact, error, method, note)."""
    p = model.params
    info: dict[str, Any] = {"exact": False, "error": None, "relative_error": None, "method": "direct", "note": ""}
    if _is(model, "lambert"):
        info.update(exact=True, note="lambert -> diffuse")
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": _rgb(p["kd"])}}, info
    multiscatter = bool(p.get("multiscatter", False))
    if _is(model, "microfacet") and p["shadowing"] == "smith" and not multiscatter:
        if p["fresnel"] == "conductor":
            d, clamped = _microfacet_conductor(p)
            if p["distribution"] == "ggx" and not clamped:
                info.update(exact=True, note="microfacet ggx conductor -> Mitsuba's roughconductor (same D, G1, Fresnel)")
                return d, info
            data = data if data is not None else _samples(model)
            info["error"], info["relative_error"] = _mitsuba_errors(d, data, metric)
            info["note"] = (
                "kd + ks > 1: Mitsuba's reflectances are clamped to 1" if clamped else
                "Mitsuba's Beckmann G1 is Walter et al.'s rational approximation (<= 0.7 % from the exact Smith G1)"
            ) + "; error measured in Mitsuba"
            return d, info
        eta = np.asarray(_rgb(p["eta"]))
        if p["fresnel"] == "dielectric" and p["alpha_x"] == p["alpha_y"] and np.ptp(eta) == 0 and eta[0] > 1:
            d = {
                "type": "roughplastic",
                "distribution": p["distribution"],
                "alpha": float(p["alpha_x"]),
                "int_ior": float(eta[0]),
                "ext_ior": 1.0,
                "specular_reflectance": {"type": "rgb", "value": np.clip(_rgb(p["ks"]), 0, 1).tolist()},
                "diffuse_reflectance": {"type": "rgb", "value": np.clip(_rgb(p["kd"]), 0, 1).tolist()},
                "nonlinear": False,
            }
            data = data if data is not None else _samples(model)
            # roughplastic's diffuse lobe is diffuse_reflectance times a Fresnel-transmittance shape
            # g(wi, wo) (linear in it with nonlinear=false), not kd/π: choose the reflectance by
            # weighted least squares on the samples, per channel, with g and the specular part
            # evaluated by Mitsuba itself
            try:
                spec = mitsuba_eval(dict(d, diffuse_reflectance={"type": "rgb", "value": [0.0] * 3}), data.wi, data.wo)
                g = mitsuba_eval(dict(d, diffuse_reflectance={"type": "rgb", "value": [1.0] * 3},
                                      specular_reflectance={"type": "rgb", "value": [0.0] * 3}), data.wi, data.wo)
            except ImportError:
                raise ValueError("measuring this export's error needs Mitsuba 3 (pip install mitsuba)") from None
            wc2 = data.w[:, None] * data.cos_i[:, None] ** 2
            rd = np.sum(wc2 * g * (data.f - spec), axis=0) / np.maximum(np.sum(wc2 * g * g, axis=0), 1e-300)
            d["diffuse_reflectance"] = {"type": "rgb", "value": np.clip(rd, 0.0, 1.0).tolist()}
            info["error"], info["relative_error"] = _mitsuba_errors(d, data, metric)
            info["note"] = ("roughplastic: same specular lobe; its diffuse term is Fresnel-coupled, so its "
                            "diffuse_reflectance is fitted by least squares; error measured in Mitsuba")
            return d, info
    # everything else: the closest ggx/smith/conductor microfacet with a Lambert term, by our fitter
    # (ks free as well, so that kd + ks <= 1 stays reachable: Mitsuba's reflectances must lie in [0, 1])
    data = data if data is not None else _samples(model)
    fixed = {"distribution": "ggx", "fresnel": "conductor", "shadowing": "smith"}
    if _is(model, "microfacet") and max(_rgb(p["kd"])) == 0.0:
        # no diffuse term in the source: none in the fit either (a free kd would settle at a few 1e-3
        # and push kd + ks over 1, which Mitsuba's blend then has to clamp)
        fixed["kd"] = 0.0
    start = None
    if _is(model, "microfacet"):  # another microfacet variant: its own values are the first start
        start = {k: p[k] for k in ("alpha_x", "alpha_y", "kd", "ks") if p.get(k) is not None}
        if p["fresnel"] == "conductor":
            start.update(eta=p["eta"], k=p["k"])
    r = _fit(_microfacet_target(model), model, data, metric, fixed, start=start)
    d, clamped = _microfacet_conductor(r.params)
    info.update(method="fit", note=f"fitted as microfacet ggx/smith/conductor + Lambert ({r.n_free} free values)")
    if clamped:
        info["error"], info["relative_error"] = _mitsuba_errors(d, data, metric)
        info["note"] += "; kd + ks > 1 clamped for Mitsuba, error measured in Mitsuba"
    else:
        info["error"], info["relative_error"] = _errors(r.model.eval(data.wi, data.wo), data, metric)
    info["fit"] = r.to_json()
    return d, info


def _microfacet_target(model: BRDF) -> type[BRDF]:
    """The microfacet class to fit: as registered for an isotropic source; for an anisotropic one
    a variant whose alpha_x and alpha_y are fitted independently (the fitter ties them for
    anisotropic-capable models, and ``alpha`` would tie them again)."""
    from .. import registry

    cls = registry.get("microfacet")
    if model.isotropic:
        return cls
    spec = tuple(replace(p, fit=False) if p.name == "alpha" else p for p in cls.spec)
    return type("MicrofacetAnisotropicFit", (cls,), {"spec": spec, "isotropic": True, "__module__": cls.__module__})


def _is_isotropic(model: BRDF) -> bool:
    return bool(model.isotropic)


# --------------------------------------------------------------------------- OpenPBR / MaterialX
def conductor_f0_f82(eta, k) -> tuple[np.ndarray, np.ndarray]:
    """(F0, F82 tint) of a conductor: its Fresnel reflectance at normal incidence, and the tint
    that makes the F82-tint model equal its reflectance at the F82 angle (cos θ = 1/7)."""
    from ..terms.fresnel import fresnel_conductor
    from .targets import F82_MU

    eta = np.asarray(_rgb(eta))
    k = np.asarray(_rgb(k))
    f0 = np.asarray(fresnel_conductor(np.ones(3), eta, k), np.float64).reshape(3)
    f82 = np.asarray(fresnel_conductor(np.full(3, F82_MU), eta, k), np.float64).reshape(3)
    s82 = f0 + (1 - f0) * (1 - F82_MU) ** 5
    return f0, np.clip(f82 / s82, 0.0, 1.0)


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


def _target_params(target, what: str, direct_fn, model: BRDF, metric: str, data, fixed_fn=None):
    """A target material's parameters for ``model``: the direct mapping ``direct_fn(model)`` where
    it is exact; otherwise fitted to the target's formula (:mod:`.targets`) from the direct mapping
    (or the defaults), keeping whichever is closer. ``fixed_fn(full)`` gives parameters held fixed."""
    direct, exact, note = direct_fn(model)
    info: dict[str, Any] = {"exact": exact, "error": None, "relative_error": None, "method": "direct", "note": note}
    full = {p.name: p.validate(target.name, p.default) for p in target.spec}
    if direct is not None:
        full.update({k: (np.asarray(v) if isinstance(v, list) else v) for k, v in direct.items()})
    if exact:
        return to_jsonable(full), info
    data = data if data is not None else _samples(model)
    e0, r0 = _errors(target(**full).eval(data.wi, data.wo), data, metric)
    r = _fit(target, model, data, metric, fixed_fn(full) if fixed_fn else {}, start=full)
    e1, r1 = _errors(r.model.eval(data.wi, data.wo), data, metric)
    if direct is None or e1 < e0:
        full = dict(r.params)
        info.update(method="fit", error=e1, relative_error=r1,
                    note=(note + "; " if note else "") + f"fitted to {what} (brdfkit.interchange.targets)")
        info["fit"] = r.to_json()
    else:
        info.update(error=e0, relative_error=r0)
    return to_jsonable(full), info


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


# --------------------------------------------------------------------------- glTF
def _gltf_direct(model: BRDF) -> tuple[dict[str, Any] | None, bool, str]:
    p = model.params
    if _is(model, "lambert"):
        return {"base_color": _rgb(p["kd"]), "metallic": 0.0, "roughness": 1.0, "specular": 0.0}, True, (
            "lambert -> baseColor = kd, KHR_materials_specular.specularFactor = 0"
        )
    if _is_eon(model):
        return {"base_color": _rgb(p["kd"]), "metallic": 0.0, "roughness": 1.0, "specular": 0.0,
                "diffuse_roughness": eon_roughness(p)}, True, (
            "oren-nayar eon -> baseColor = kd, specularFactor = 0, "
            "KHR_materials_diffuse_roughness.diffuseRoughnessFactor = min(sigma, 1)"
        )
    if _is(model, "microfacet") and p["distribution"] == "ggx":
        ax, ay = float(p["alpha_x"]), float(p["alpha_y"])
        a = math.sqrt(ax * ay)
        kd = np.asarray(_rgb(p["kd"]))
        ks = np.asarray(_rgb(p["ks"]))
        rough = math.sqrt(a)
        if p["fresnel"] in ("schlick", "conductor"):
            if p["fresnel"] == "schlick":
                f0 = np.asarray(_rgb(p["f0"]))
            else:
                f0, _ = conductor_f0_f82(p["eta"], p["k"])
            exact = (p["fresnel"] == "schlick" and p["shadowing"] == "smith" and ax == ay and kd.max() == 0
                     and np.all(ks == 1) and not p.get("multiscatter", False))
            return {"base_color": np.clip(f0, 0, 1).tolist(), "metallic": 1.0, "roughness": rough}, exact, (
                "metal: baseColor = f0, roughness = sqrt(alpha)"
            )
        if p["fresnel"] == "dielectric":
            eta = float(np.mean(_rgb(p["eta"])))
            return {"base_color": kd.tolist(), "metallic": 0.0, "roughness": rough, "ior": min(max(eta, 1.0), 5.0),
                    "specular": float(min(ks.max(), 1.0))}, False, "dielectric: baseColor = kd, ior = eta"
    return None, False, ""


def gltf_params(model: BRDF, metric: str = "ngan", data=None) -> tuple[dict[str, Any], dict[str, Any]]:
    """glTF metallic-roughness (+ior, +specular) parameters for a model, and what went into them."""
    from .targets import GltfPBR

    return _target_params(GltfPBR, "the glTF BRDF", _gltf_direct, model, metric, data)


def uv_sphere(n_lat: int = 32, n_lon: int = 64) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A closed unit UV sphere (+y up): positions, normals (= positions), float32, and uint32
    triangle indices, counter-clockwise seen from outside; the poles and the seam are shared vertices."""
    th = np.arange(1, n_lat) * (np.pi / n_lat)
    ph = np.arange(n_lon) * (2 * np.pi / n_lon)
    T, P = np.meshgrid(th, ph, indexing="ij")
    ring = np.stack([np.sin(T) * np.cos(P), np.cos(T), -np.sin(T) * np.sin(P)], axis=-1).reshape(-1, 3)
    pos = np.concatenate([[[0.0, 1.0, 0.0]], ring, [[0.0, -1.0, 0.0]]])
    south = len(pos) - 1

    def v(i, j):  # ring i (0-based), azimuth j
        return 1 + i * n_lon + (j % n_lon)

    idx = []
    for j in range(n_lon):
        idx.append((0, v(0, j), v(0, j + 1)))
        idx.append((south, v(n_lat - 2, j + 1), v(n_lat - 2, j)))
    for i in range(n_lat - 2):
        for j in range(n_lon):
            a, b, c, d = v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)
            idx += [(a, b, c), (a, c, d)]
    pos = pos.astype(np.float32)
    nrm = pos / np.linalg.norm(pos, axis=1, keepdims=True)
    return pos, nrm.astype(np.float32), np.asarray(idx, dtype=np.uint32)


def gltf_bytes(params: dict[str, Any], name: str = "brdfkit") -> bytes:
    """A .glb (binary glTF 2.0) with a UV sphere and the material."""
    import pygltflib as g

    pos, nrm, idx = uv_sphere()
    blob = pos.tobytes() + nrm.tobytes() + idx.tobytes()
    n_pos, n_idx = len(pos), idx.size
    bc = [float(x) for x in params["base_color"]]
    material = g.Material(
        name=name,
        pbrMetallicRoughness=g.PbrMetallicRoughness(
            baseColorFactor=bc + [1.0], metallicFactor=float(params["metallic"]), roughnessFactor=float(params["roughness"])
        ),
        doubleSided=False,
    )
    ext: dict[str, Any] = {}
    if abs(float(params["ior"]) - 1.5) > 0:
        ext["KHR_materials_ior"] = {"ior": float(params["ior"])}
    sc = [float(x) for x in params["specular_color"]]
    if float(params["specular"]) != 1.0 or sc != [1.0, 1.0, 1.0]:
        ext["KHR_materials_specular"] = {"specularFactor": float(params["specular"]), "specularColorFactor": sc}
    if float(params.get("diffuse_roughness", 0.0)) > 0:
        ext["KHR_materials_diffuse_roughness"] = {"diffuseRoughnessFactor": float(params["diffuse_roughness"])}
    if ext:
        material.extensions = ext
    gl = g.GLTF2(
        asset=g.Asset(generator="brdfkit export", version="2.0"),
        scene=0,
        scenes=[g.Scene(nodes=[0])],
        nodes=[g.Node(mesh=0, name=name)],
        meshes=[g.Mesh(name="sphere", primitives=[g.Primitive(attributes=g.Attributes(POSITION=0, NORMAL=1), indices=2, material=0)])],
        materials=[material],
        accessors=[
            g.Accessor(bufferView=0, componentType=g.FLOAT, count=n_pos, type=g.VEC3,
                       max=pos.max(axis=0).tolist(), min=pos.min(axis=0).tolist()),
            g.Accessor(bufferView=1, componentType=g.FLOAT, count=n_pos, type=g.VEC3),
            g.Accessor(bufferView=2, componentType=g.UNSIGNED_INT, count=n_idx, type=g.SCALAR),
        ],
        bufferViews=[
            g.BufferView(buffer=0, byteOffset=0, byteLength=pos.nbytes, target=g.ARRAY_BUFFER),
            g.BufferView(buffer=0, byteOffset=pos.nbytes, byteLength=nrm.nbytes, target=g.ARRAY_BUFFER),
            g.BufferView(buffer=0, byteOffset=pos.nbytes + nrm.nbytes, byteLength=idx.nbytes, target=g.ELEMENT_ARRAY_BUFFER),
        ],
        buffers=[g.Buffer(byteLength=len(blob))],
        extensionsUsed=sorted(ext),
    )
    gl.set_binary_blob(blob)
    return b"".join(gl.save_to_bytes())


# --------------------------------------------------------------------------- the entry point
SUFFIXES = {"mitsuba": (".xml", ".json"), "materialx": (".mtlx",), "gltf": (".glb",)}


def _check_path(path: str | os.PathLike, fmt: str) -> Path:
    import sys

    return fileio.check_output_path(path, what=f"{fmt} export", suffixes=SUFFIXES[fmt],
                                    notify=lambda msg: print(msg, file=sys.stderr))


def export(model: BRDF, fmt: str, path: str | os.PathLike, *, metric: str = "ngan",
           name: str | None = None) -> ExportResult:
    """Write ``model`` as a ``fmt`` material to ``path``; see the module docstring.

    ``fmt``: ``"mitsuba"`` (``.xml``, or ``.json`` for the ``mi.load_dict`` dict),
    ``"materialx"`` (``.mtlx``) or ``"gltf"`` (``.glb``). Returns an :class:`ExportResult`
    (``error`` is None where the target expresses the model exactly).
    """
    from ..measured.fit import METRICS

    if fmt not in FORMATS:
        raise ValueError(f"unknown export format {fmt!r}; valid formats: {', '.join(FORMATS)}")
    if metric not in METRICS:
        raise ValueError(f"unknown metric {metric!r}; valid metrics: {', '.join(METRICS)}")
    if not isinstance(model, BRDF) and isinstance(getattr(model, "model", None), BRDF):
        model = model.model  # a FitResult: its fitted model
    if not isinstance(model, BRDF):
        raise ValueError(f"export: expected a model, got {type(model).__name__}")
    p = _check_path(path, fmt)
    label = name or str(model.label or type(model).name or "material")
    if fmt == "mitsuba":
        d, info = mitsuba_dict(model, metric)
        text = _json_text(d) if p.suffix.lower() == ".json" else mitsuba_xml(d)
        fileio.write_text(p, text)
        target, params = _target_name(d), d
    elif fmt == "materialx":
        params, info = openpbr_params(model, metric)
        eon = _is_eon(model)
        doc = materialx_document(params, name=Path(label).stem, eon=eon)
        fileio.write_text(p, materialx_text(doc))
        target = "open_pbr_surface (+ standard_surface" + (", oren_nayar_diffuse_bsdf)" if eon else ")")
    else:
        params, info = gltf_params(model, metric)
        fileio.write_bytes(p, gltf_bytes(params, name=Path(label).stem))
        ext = [e for e in ("KHR_materials_ior", "KHR_materials_specular", "KHR_materials_diffuse_roughness")
               if _gltf_uses(params, e)]
        target = "pbrMetallicRoughness" + "".join(f" + {e}" for e in ext)
    exact = bool(info["exact"])
    extra = {k: v for k, v in info.items() if k == "fit"}
    return ExportResult(
        format=fmt, path=str(p), target=target, params=_plain(params), exact=exact,
        error=None if exact else info["error"], relative_error=None if exact else info["relative_error"],
        metric=metric, method=info["method"], source=label, note=info["note"], extra=extra,
    )


def _gltf_uses(params: dict[str, Any], ext: str) -> bool:
    if ext == "KHR_materials_ior":
        return float(params["ior"]) != 1.5
    if ext == "KHR_materials_diffuse_roughness":
        return float(params.get("diffuse_roughness", 0.0)) > 0
    return float(params["specular"]) != 1.0 or [float(x) for x in params["specular_color"]] != [1.0, 1.0, 1.0]


def _json_text(obj: Any) -> str:
    return json.dumps(_plain(obj), indent=2) + "\n"


__all__ = [
    "FORMATS", "ExportResult", "export", "mitsuba_dict", "mitsuba_xml", "mitsuba_eval", "openpbr_params",
    "materialx_document", "materialx_text", "gltf_params", "gltf_bytes", "uv_sphere", "conductor_f0_f82",
]
