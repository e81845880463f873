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
an RGL ``.bsdf`` file (Dupuy & Jakob 2018)      ``measured`` (its ``filename``:   yes
                                                the file's absolute path)
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
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .. import fileio
from ..models.base import BRDF
from .approx import _is_eon, _plain, conductor_f0_f82  # noqa: F401 (conductor_f0_f82: public)
from .gltf import _gltf_uses, gltf_bytes, gltf_params, uv_sphere  # noqa: F401 (uv_sphere: public)
from .materialx import materialx_document, materialx_text, openpbr_params
from .mitsuba import mitsuba_dict, mitsuba_eval, mitsuba_xml  # noqa: F401 (mitsuba_eval: public)


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


def _target_name(d: dict[str, Any]) -> str:
    if d["type"] == "blendbsdf":
        return f"blendbsdf({d['bsdf_0']['type']}, {d['bsdf_1']['type']})"
    return d["type"]


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


def _json_text(obj: Any) -> str:
    return json.dumps(_plain(obj), indent=2) + "\n"


__all__ = [
    "FORMATS", "ExportResult", "export", "mitsuba_dict", "mitsuba_xml", "mitsuba_eval", "openpbr_params",
    "materialx_document", "materialx_text", "gltf_params", "gltf_bytes", "uv_sphere", "conductor_f0_f82",
]
