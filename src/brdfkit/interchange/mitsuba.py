"""Mitsuba 3 materials: the BSDF dict for ``mi.load_dict``, its XML, and its values evaluated
in Mitsuba itself (``scalar_rgb``) to measure an approximation's error.

Which source becomes which BSDF, and when exactly: :mod:`brdfkit.interchange.export`.
"""

from __future__ import annotations

import os
from typing import Any
from xml.sax.saxutils import escape

import numpy as np

from ..models.base import BRDF
from .approx import _rgb, _samples, _errors, _fit, _is, _microfacet_conductor, _microfacet_target


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
        return [f'{pad}<string name="{k}" value="{escape(str(v), {chr(34): "&quot;"})}"/>']

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


def _rgl_file(model: BRDF) -> str | None:
    """The absolute path of the RGL file an RGL model was read from, if it is still there."""
    from ..measured.rgl import RGLBRDF

    src = getattr(model, "source", "") if isinstance(model, RGLBRDF) else ""
    return os.path.abspath(src) if src and os.path.isfile(src) else None


def mitsuba_dict(model: BRDF, metric: str = "ngan", data=None) -> tuple[dict[str, Any], dict[str, Any]]:
    """The ``mi.load_dict`` dict for a model, and what went into it (exact, error, method, note)."""
    p = model.params
    info: dict[str, Any] = {"exact": False, "error": None, "relative_error": None, "method": "direct", "note": ""}
    rgl_file = _rgl_file(model)
    if rgl_file is not None:
        info.update(exact=True, note="RGL .bsdf file -> Mitsuba's measured plugin, which reads the file itself "
                                     "(referenced by its absolute path: keep it there)")
        return {"type": "measured", "filename": rgl_file}, info
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
