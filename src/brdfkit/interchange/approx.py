"""What the exporters share: which model a source is, samples and errors in the fitter's metric,
and fitting a target material where it cannot express the model exactly.

Errors are those of :mod:`brdfkit.measured.metrics` (default ``"ngan"``: cosine-weighted RMS of f_r
in 1/sr over pairs within 80° of the normal); see :mod:`brdfkit.interchange.export` for which
source maps to which target and when.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from ..models.base import BRDF
from ..params import to_jsonable


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
