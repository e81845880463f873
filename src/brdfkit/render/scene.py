"""Scene files (JSON) and the one-call API: ``render(scene) -> Frame``.

A scene file (SPEC.md, ``brdfkit render --scene scene.json -o out.png``)::

    {
      "mesh": "teapot",                         # built-in name, OBJ/PLY path, or
                                                # {"builtin": "sphere", "segments": 16, "rings": 8}
      "camera": {"eye": [0, 0.5, 3.6], "target": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 36},
                # or {"projection": 4x4, "modelview": 4x4}, row-major, OpenGL conventions
      "size": [512, 512],
      "lights": [{"position": [2, 3, 4, 1], "diffuse": [1, 1, 1], "specular": [1, 1, 1],
                  "quadratic_attenuation": 0.01}],          # opengl.Light fields, eye space
      "light_model": {"ambient": [0.2, 0.2, 0.2], "local_viewer": false},
      "material": {"opengl": "gold"},            # or {"opengl": {ambient, diffuse, specular,
                                                # emission, shininess}} or {"model": NAME, "params": {...}}
                                                # or {"measured": "merl/gold-metallic-paint"} or {"merl": PATH}
      "shading": "phong",                        # flat | gouraud | phong
      "background": [0, 0, 0, 1],
      "antialias": true,
      "tonemap": "aces", "exposure": 1.0, "srgb": true,    # optional; defaults depend on the material
      "environment": {"name": "sky", "samples": 64}       # optional: image-based lighting instead of
                                                # the lights; see brdfkit.render.environment
    }

Every field is optional: the defaults are the teapot, the default camera
(:data:`brdfkit.render.camera.DEFAULT_CAMERA`), 512×512, one white
directional light from the upper left (:data:`DEFAULT_LIGHTS`), OpenGL's
light model, gold, Phong shading, an opaque black background, antialiasing.
Relative mesh and MERL paths are resolved against the scene file's folder.
Measured materials render through the GLSL backend too: their MERL table is
a 3D texture (``shaders/measured.glsl``; a Neural-BRDF material is tabulated
at the MERL bin centres first).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .. import opengl
from .camera import camera_matrices
from .image import TONEMAPS, save_image, to_display, to_uint8
from .meshes import BUILTIN, Mesh, mesh_from_spec
from .renderer import Scene, render_linear

SCENE_FIELDS = (
    "mesh", "camera", "size", "lights", "light_model", "material", "shading",
    "background", "antialias", "tonemap", "exposure", "srgb", "environment",
)

DEFAULT_LIGHTS = (opengl.Light(position=(-1.0, 1.2, 1.5, 0.0), diffuse=(1, 1, 1), specular=(1, 1, 1)),)
"""One white directional light from the upper left, in front (eye space)."""


@dataclass
class Look:
    """How the linear frame becomes a picture (see :mod:`brdfkit.render.image`)."""

    tonemap: str = "clamp"
    exposure: float = 1.0
    srgb: bool = False

    def __post_init__(self) -> None:
        if self.tonemap not in TONEMAPS:
            raise ValueError(f"tonemap must be one of {', '.join(TONEMAPS)}; got {self.tonemap!r}")
        try:
            self.exposure = float(self.exposure)
        except (TypeError, ValueError):
            raise ValueError(f"exposure must be a positive number, got {self.exposure!r}") from None
        if not np.isfinite(self.exposure) or self.exposure <= 0:
            raise ValueError(f"exposure must be a positive number, got {self.exposure!r}")
        if not isinstance(self.srgb, (bool, np.bool_)):
            raise ValueError(f"srgb must be true or false, got {self.srgb!r}")


def default_look(material: Any) -> Look:
    """``clamp``, no sRGB for OpenGL materials (what OpenGL shows); ``aces`` + sRGB for BRDFs."""
    if isinstance(material, opengl.Material):
        return Look("clamp", 1.0, False)
    return Look("aces", 1.0, True)


@dataclass
class Frame:
    """A rendered frame: ``linear`` (H, W, 4) float32 premultiplied, ``display`` (H, W, 4) in [0, 1]."""

    linear: np.ndarray
    display: np.ndarray
    scene: Scene
    look: Look

    def save(self, path: str | os.PathLike) -> None:
        save_image(path, self.linear, self.display)

    @property
    def uint8(self) -> np.ndarray:
        return to_uint8(self.display)


_MATERIAL_FORMS = (
    'material must be {"opengl": NAME or {...}}, {"model": NAME, "params": {...}}, {"measured": NAME} or {"merl": PATH}'
)


def material_from_spec(spec: Any) -> Any:
    """``{"opengl": name | {...}}`` or ``{"model": NAME, "params": {...}}`` (or a Material / BRDF as is)."""
    from ..models.base import BRDF

    if isinstance(spec, (opengl.Material, BRDF)):
        return spec
    if isinstance(spec, str):
        return opengl.material_from_json(spec)
    if not isinstance(spec, Mapping):
        raise ValueError(_MATERIAL_FORMS)
    if "opengl" in spec:
        if set(spec) != {"opengl"}:
            raise ValueError("material with 'opengl' takes no other field")
        return opengl.material_from_json(spec["opengl"])
    if "measured" in spec or "merl" in spec:
        if len(spec) != 1:
            raise ValueError("material with 'measured' or 'merl' takes no other field")
        from .. import measured

        if "measured" in spec:
            return measured.material(spec["measured"])
        return measured.load_merl(spec["merl"])
    if "model" in spec:
        extra = set(spec) - {"model", "params"}
        if extra:
            raise ValueError(f"material: unknown field(s) {', '.join(sorted(extra))}; use model and params")
        import brdfkit as bk

        params = spec.get("params", {}) or {}
        if not isinstance(params, Mapping):
            raise ValueError("material params must be an object of name: value")
        return bk.model(spec["model"], **dict(params))
    raise ValueError(_MATERIAL_FORMS)


def _size(value: Any) -> tuple[int, int]:
    try:
        w, h = (int(x) for x in value)
    except (TypeError, ValueError):
        raise ValueError(f"size must be [width, height], got {value!r}") from None
    return w, h


def scene_from_json(obj: Mapping[str, Any], base_dir: str | os.PathLike | None = None) -> tuple[Scene, Look]:
    """A :class:`Scene` and its :class:`Look` from a scene file's object."""
    if not isinstance(obj, Mapping):
        raise ValueError("a scene must be a JSON object")
    extra = set(obj) - set(SCENE_FIELDS)
    if extra:
        raise ValueError(f"scene: unknown field(s) {', '.join(sorted(extra))}; valid fields: {', '.join(SCENE_FIELDS)}")
    mesh_spec = obj.get("mesh", "teapot")
    if isinstance(mesh_spec, str) and mesh_spec not in BUILTIN and base_dir is not None and not os.path.isabs(mesh_spec):
        mesh_spec = os.path.join(os.fspath(base_dir), mesh_spec)
    if isinstance(mesh_spec, Mapping) and "path" in mesh_spec and base_dir is not None:
        mesh_spec = dict(mesh_spec)
        if not os.path.isabs(mesh_spec["path"]):
            mesh_spec["path"] = os.path.join(os.fspath(base_dir), mesh_spec["path"])
    mat_spec = obj.get("material", {"opengl": "gold"})
    if isinstance(mat_spec, Mapping) and "merl" in mat_spec and base_dir is not None:
        if not os.path.isabs(mat_spec["merl"]):
            mat_spec = {"merl": os.path.join(os.fspath(base_dir), mat_spec["merl"])}
    scene = make_scene(
        mesh=mesh_from_spec(mesh_spec),
        material=mat_spec,
        shading=obj.get("shading", "phong"),
        size=obj.get("size", (512, 512)),
        camera=obj.get("camera"),
        lights=obj.get("lights"),
        light_model=obj.get("light_model"),
        background=obj.get("background", (0.0, 0.0, 0.0, 1.0)),
        antialias=obj.get("antialias", True),
    )
    if obj.get("environment") is not None:
        from .environment import environment_from_spec

        env, samples = environment_from_spec(obj["environment"], base_dir=base_dir)
        scene = Scene(**{**scene.__dict__, "environment": env, "samples": samples or scene.samples})
    look = default_look(scene.material)
    look = Look(
        obj.get("tonemap", look.tonemap),
        obj.get("exposure", look.exposure),
        obj.get("srgb", look.srgb),
    )
    return scene, look


def read_scene_file(path: str | os.PathLike) -> dict[str, Any]:
    """A scene file's JSON object (not yet validated field by field)."""
    p = Path(path)
    if not p.is_file():
        raise OSError(f"scene file not found: {p}")
    try:
        obj = json.loads(p.read_text(encoding="utf-8"))
    except json.JSONDecodeError as e:
        raise ValueError(f"scene file {p} is not valid JSON: {e.msg} (line {e.lineno})") from None
    if not isinstance(obj, dict):
        raise ValueError("a scene must be a JSON object")
    return obj


def load_scene(path: str | os.PathLike) -> tuple[Scene, Look]:
    """Read a scene file; relative paths in it are resolved against its folder."""
    return scene_from_json(read_scene_file(path), base_dir=Path(path).parent)


def make_scene(
    mesh: Any = "teapot",
    material: Any = "gold",
    shading: str = "phong",
    size: tuple[int, int] = (512, 512),
    camera: Mapping[str, Any] | None = None,
    lights: Any = None,
    light_model: Any = None,
    background=(0.0, 0.0, 0.0, 1.0),
    antialias: bool = True,
) -> Scene:
    """A :class:`Scene` from friendly arguments (names or objects); the scene-file fields, by keyword."""
    w, h = _size(size)
    if h <= 0:
        raise ValueError(f"size must be positive, got {(w, h)}")
    m = mesh if isinstance(mesh, Mesh) else mesh_from_spec(mesh)
    projection, modelview = camera_matrices(camera, w / h)
    if lights is None:
        ls = list(DEFAULT_LIGHTS)
    elif not isinstance(lights, (list, tuple)):
        raise ValueError("lights must be a list of light objects")
    else:
        ls = [opengl.light_from_json(L) for L in lights]
    if not isinstance(antialias, bool):
        raise ValueError(f"antialias must be true or false, got {antialias!r}")
    return Scene(
        mesh=m,
        projection=projection,
        modelview=modelview,
        size=(w, h),
        lights=ls,
        light_model=opengl.light_model_from_json(light_model),
        material=material_from_spec(material),
        shading=shading,
        background=tuple(background),
        antialias=antialias,
    )


def render(scene: Scene, look: Look | None = None, backend: str = "auto") -> Frame:
    """Render ``scene``; ``look`` defaults to :func:`default_look` of its material."""
    look = look or default_look(scene.material)
    linear = render_linear(scene, backend)
    display = to_display(linear, look.tonemap, look.exposure, look.srgb, scene.background)
    return Frame(linear, display, scene, look)
