"""The renderer's lighting in numpy: the twin of ``shaders/pipeline_lights.glsl`` and ``pipeline_brdf.glsl``.

Two kinds of material:

* an :class:`brdfkit.opengl.Material` is lit with OpenGL's fixed-function
  equation, :func:`brdfkit.opengl.shade` (GLSL twin: ``opengl_fixed.glsl``);
* any registered BRDF (a :class:`brdfkit.BRDF` instance) is lit as

  .. math::

     L_o = \\sum_i f_r(\\omega_i, \\omega_o)\\,(\\pi\\,d_i)\\,\\mathrm{att}_i\\,\\mathrm{spot}_i\\cos\\theta_i
           + L_a\\,\\bar\\rho

  with the same lights (point, directional, spot) and the same attenuation
  and spotlight factors as OpenGL. A light's ``diffuse`` colour ``d_i`` is
  read as :math:`E_\\perp/\\pi` — the irradiance it gives a surface facing it,
  divided by π — so that a Lambert surface of albedo ``kd`` facing a light of
  colour 1 reflects radiance ``kd``, exactly the value OpenGL's diffuse term
  gives with ``d_cm = kd``; the light's ``specular`` colour is not used (a
  BRDF has one response to one light). The ambient term reflects the ambient
  radiance :math:`L_a` (the light model's ambient plus every light's
  attenuated ambient colour) with :math:`\\bar\\rho`, the model's directional
  albedo at normal viewing, :math:`\\int f_r(\\omega_i, n) \\cos\\theta_i\\,d\\omega_i`,
  computed once by quadrature (:func:`ambient_albedo`). The viewer is always
  local (``wo = normalize(-P)``): physically based shading has no "infinite
  viewer" switch.

The shading frame is built from the interpolated normal ``n`` and tangent
``t``: ``t`` is made orthogonal to ``n`` (Gram–Schmidt), ``b = n × t``, and a
direction ``w`` becomes ``(w·t, w·b, w·n)`` — SPEC.md's local frame.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from .. import opengl
from ..geometry import dot, normalize, to_local
from ..opengl import Light, LightModel, light_vector

__all__ = [
    "light_vector", "orthonormal_tangent", "ambient_albedo", "brdf_shade", "shade_points",
    "DEFAULT_ENVIRONMENT", "uses_default_environment",
]

DEFAULT_ENVIRONMENT = {"name": "studio", "visible": False}
"""How ``brdfkit render`` lights a BRDF or measured material when it is given no lighting.

The built-in ``studio`` (three soft boxes, :mod:`brdfkit.render.environment`), as the gallery's
environment-lit figures use it, not drawn behind the object (the scene's ``background`` stays).
A single point light shows a near-mirror (``merl/chrome``) as a black object with a speck; the
soft boxes show it as what it is. OpenGL fixed-function materials keep the classic light
(:data:`brdfkit.render.scene.DEFAULT_LIGHTS`): environment lighting needs a BRDF."""


def uses_default_environment(scene: Any, lights_given: bool, glsl: bool = True) -> bool:
    """Whether :data:`DEFAULT_ENVIRONMENT` lights ``scene``: a BRDF material, per-pixel (phong)
    shading, neither an environment nor lights given (by the scene file or the flags), and the
    GLSL backend (``glsl``). The numpy backend's environment lighting is the reference quadrature
    over every cell of the map, minutes for a small image: asked for by name (``--env``), never
    by default, so ``--backend numpy`` keeps the point lights."""
    return (
        not scene.is_opengl
        and scene.environment is None
        and not lights_given
        and scene.shading == "phong"
        and glsl
    )


def orthonormal_tangent(n: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``t`` made orthogonal to the unit normals ``n``; any perpendicular where ``t ∥ n``."""
    u = t - n * dot(n, t)[:, None]
    length = np.linalg.norm(u, axis=-1)
    weak = length <= 1e-6
    if weak.any():
        a = np.where((np.abs(n[weak, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
        u[weak] = a - n[weak] * dot(n[weak], a)[:, None]
    return normalize(u)


def ambient_albedo(model: Any, n: int = 64) -> np.ndarray:
    """The model's directional albedo at normal viewing, ∫ f_r(wi, +z) cos θi dωi, RGB.

    Midpoint quadrature over an n × n grid in (sin²θ, φ), which is cosine-weighted,
    so the estimate is (π/n²) Σ f_r. Cached per model and parameters.
    """
    key = (type(model).__name__, getattr(model, "name", ""), repr(model), n)
    rho = _ALBEDO_CACHE.get(key)
    if rho is None:
        u = (np.arange(n) + 0.5) / n
        phi = (np.arange(n) + 0.5) / n * 2 * np.pi
        s = np.sqrt(u)[:, None]  # sin θ
        c = np.sqrt(1 - u)[:, None]
        wi = np.stack(np.broadcast_arrays(s * np.cos(phi), s * np.sin(phi), c), axis=-1).reshape(-1, 3)
        f = np.asarray(model.eval(wi, np.array([0.0, 0.0, 1.0])), dtype=np.float64)
        rho = np.clip(np.nan_to_num(np.pi * f.mean(axis=0), nan=0.0, posinf=1.0), 0.0, None)
        if len(_ALBEDO_CACHE) > 512:
            _ALBEDO_CACHE.clear()
        _ALBEDO_CACHE[key] = rho
    return rho


_ALBEDO_CACHE: dict[Any, np.ndarray] = {}


def brdf_shade(
    model: Any,
    P: np.ndarray,
    n: np.ndarray,
    t: np.ndarray,
    lights: Sequence[Light],
    light_model: LightModel,
) -> np.ndarray:
    """Radiance (N, 3) reflected toward the eye (at the origin) by a BRDF material at eye-space points ``P``."""
    P = np.asarray(P, dtype=np.float64)
    n = normalize(np.asarray(n, dtype=np.float64))
    t = orthonormal_tangent(n, np.asarray(t, dtype=np.float64))
    b = np.cross(n, t)
    v = normalize(-P)
    wo = to_local(v, t, b, n)
    ambient = np.broadcast_to(np.asarray(light_model.ambient[:3]), P.shape).copy()
    c = np.zeros(P.shape)
    for L in lights:
        vp, factor = light_vector(L, P)
        ambient += factor[:, None] * np.asarray(L.ambient[:3])
        wi = to_local(vp, t, b, n)
        ok = (wi[:, 2] > 0) & (wo[:, 2] > 0) & (factor > 0)
        if ok.any():
            f = model.eval(wi[ok], wo[ok])
            c[ok] += f * (np.pi * np.asarray(L.diffuse[:3])) * (factor[ok] * wi[ok, 2])[:, None]
    c += ambient * ambient_albedo(model)
    return c


def shade_points(material: Any, P, n, t, lights: Sequence[Light], light_model: LightModel) -> np.ndarray:
    """RGB (N, 3) at eye-space points for either kind of material (numpy path)."""
    if isinstance(material, opengl.Material):
        return opengl.shade(P, n, material, list(lights), light_model)[:, :3]
    return brdf_shade(material, P, n, t, lights, light_model)
