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
                                                # or {"measured": "merl/gold-metallic-paint" or PATH}
                                                # or {"merl": PATH} (a MERL .binary, UTIA .bin or RGL .bsdf)
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
Relative mesh and measured-file paths are resolved against the scene file's folder
(``measured``: when the file is there).

A scene file is untrusted input: every field is checked before anything is
built, and a bad one is a one-line ``ValueError`` that names it (``scene
field 'size': ...``), which ``brdfkit render`` prints as ``brdfkit: error:``
with exit status 2. Sizes are integers in [1, 8192]; the built-in meshes'
tessellation options are bounded (:data:`brdfkit.render.meshes.TESSELLATION_LIMITS`);
JSON nested deeper than :data:`MAX_DEPTH` is refused. The keys in
:data:`OPEN_FIELDS` (``environment``) are accepted here and left to the
code that renders them.
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
from ..jsonsafe import nesting_exceeds
from .camera import camera_matrices
from .image import TONEMAPS, save_image, to_display, to_uint8
from .meshes import BUILTIN, Mesh, mesh_from_spec
from .renderer import SHADINGS, Scene, render_linear

SCENE_FIELDS = (
    "mesh", "camera", "size", "lights", "light_model", "material", "shading",
    "background", "antialias", "tonemap", "exposure", "srgb", "environment",
)
OPEN_FIELDS = ("environment",)
"""Scene keys this module accepts without interpreting them (image-based lighting reads ``environment``)."""

MAX_DEPTH = 32
"""Deepest JSON nesting a scene file may have (the deepest valid scene needs 4)."""

MAX_SIZE = 8192

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
        from ..params import to_float

        if not isinstance(self.tonemap, str) or self.tonemap not in TONEMAPS:
            raise ValueError(f"tonemap must be one of {', '.join(TONEMAPS)}; got {self.tonemap!r}")
        self.exposure = to_float(self.exposure, "exposure")
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
        from ..sources import MEASURED, resolve

        if "measured" in spec:
            if not isinstance(spec["measured"], str):
                raise ValueError(f"material 'measured' must be a material name (a string), got {spec['measured']!r}")
            return resolve(spec["measured"], kinds=MEASURED)
        if not isinstance(spec["merl"], (str, os.PathLike)) or not str(spec["merl"]):
            raise ValueError(f"material 'merl' must be a file name (a string), got {spec['merl']!r}")
        return resolve(spec["merl"], kinds=("merl", "bin", "rgl"))  # any measured file: MERL, UTIA, RGL
    if "model" in spec:
        extra = set(spec) - {"model", "params"}
        if extra:
            raise ValueError(f"material: unknown field(s) {', '.join(sorted(extra))}; use model and params")
        from ..sources import resolve

        params = spec.get("params", {}) or {}
        if not isinstance(spec["model"], str):
            raise ValueError(f"material 'model' must be a model name (a string), got {spec['model']!r}")
        if not isinstance(params, Mapping):
            raise ValueError("material params must be an object of name: value")
        return resolve(spec["model"], {str(k): v for k, v in params.items()})
    raise ValueError(_MATERIAL_FORMS)


def _size(value: Any) -> tuple[int, int]:
    """``[width, height]``: two integers in [1, :data:`MAX_SIZE`] (1e400, 0, 64.5, true and "64" are errors)."""
    from ..params import to_float

    if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__len__") or len(value) != 2:
        raise ValueError(f"size must be [width, height] (two integers), got {_short(value)}")
    out = []
    for name, x in zip(("width", "height"), value):
        if isinstance(x, str):
            raise ValueError(f"size {name} must be an integer, got {x!r}")
        f = to_float(x, f"size {name}")
        if f != int(f):
            raise ValueError(f"size {name} must be an integer, got {x!r}")
        if not 1 <= f <= MAX_SIZE:
            raise ValueError(f"size {name} must be in [1, {MAX_SIZE}], got {int(f)}")
        out.append(int(f))
    return out[0], out[1]


def _short(value: Any) -> str:
    r = repr(value)
    return r if len(r) <= 80 else r[:60] + f"... ({len(r)} characters)"


def _numbers(value: Any, what: str, sizes: tuple[int, ...]) -> None:
    """Check that ``value`` is a finite number (if 1 in ``sizes``) or a list of finite numbers of one of ``sizes``."""
    from ..params import to_float

    if isinstance(value, (list, tuple)):
        if len(value) not in sizes or any(isinstance(x, (list, tuple, dict, str)) for x in value):
            raise ValueError(f"{what} must be a list of {' or '.join(str(n) for n in sizes if n > 1)} numbers, got {_short(value)}")
        for x in value:
            to_float(x, what)
        return
    if 1 not in sizes:
        raise ValueError(f"{what} must be a list of {' or '.join(str(n) for n in sizes)} numbers, got {_short(value)}")
    to_float(value, what)


def _check_object(obj: Any, what: str, bools: tuple[str, ...] = ()) -> None:
    """An OpenGL light / light model / material object: every field a finite number or list of numbers
    (or a boolean for the names in ``bools``); unknown names are left to :mod:`brdfkit.opengl`."""
    if not isinstance(obj, Mapping):
        raise ValueError(f"{what} must be an object, got {type(obj).__name__}")
    for k, v in obj.items():
        if k in bools:
            if not isinstance(v, bool):
                raise ValueError(f"{what} field '{k}' must be true or false, got {_short(v)}")
        else:
            _numbers(v, f"{what} field '{k}'", (1, 3, 4))


def _field(name: str, fn, *args):
    """``fn(*args)`` with its ``ValueError`` prefixed by the scene field it concerns."""
    try:
        return fn(*args)
    except ValueError as e:
        msg = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise ValueError(f"scene field '{name}': {msg}") from None
    except (TypeError, OverflowError, RecursionError) as e:  # a type no check above foresaw: still one line
        raise ValueError(f"scene field '{name}': invalid value ({type(e).__name__}: {e})") from None


def _check_fields(obj: Mapping[str, Any]) -> None:
    """Type checks of a scene object's fields (before anything is built)."""
    if "camera" in obj and obj["camera"] is not None and not isinstance(obj["camera"], Mapping):
        raise ValueError(
            f"scene field 'camera': must be an object ({{\"eye\": [x,y,z], ...}} or {{\"projection\", \"modelview\"}}), got {type(obj['camera']).__name__}"
        )
    if isinstance(obj.get("camera"), Mapping):
        for k, v in obj["camera"].items():
            if k in ("projection", "modelview"):
                if not isinstance(v, (list, tuple)) or len(v) != 4:
                    raise ValueError(f"scene field 'camera': {k} must be a 4x4 matrix (list of 4 rows)")
                for row in v:
                    _field("camera", _numbers, row, f"camera {k} row", (4,))
            else:
                _field("camera", _numbers, v, f"camera {k}", (1, 3))
    if "size" in obj:
        _field("size", _size, obj["size"])
    if "background" in obj:
        _field("background", _numbers, obj["background"], "background", (3, 4))
    if "lights" in obj and obj["lights"] is not None:
        if not isinstance(obj["lights"], (list, tuple)):
            raise ValueError("scene field 'lights': must be a list of light objects")
        for i, L in enumerate(obj["lights"]):
            _field("lights", _check_object, L, f"light {i}")
    if obj.get("light_model") is not None:
        _field("light_model", _check_object, obj["light_model"], "light_model", ("local_viewer",))
    for k in ("shading", "tonemap"):
        if k in obj and not isinstance(obj[k], str):
            raise ValueError(f"scene field '{k}': must be a name (a string), got {_short(obj[k])}")
    if "shading" in obj and obj["shading"] not in SHADINGS:
        # checked here, so that the message names the scene field (the renderer's own says "shading must be")
        raise ValueError(f"scene field 'shading': must be one of {', '.join(SHADINGS)}, got {_short(obj['shading'])}")
    for k in ("antialias", "srgb"):
        if k in obj and not isinstance(obj[k], bool):
            raise ValueError(f"scene field '{k}': must be true or false, got {_short(obj[k])}")
    mat = obj.get("material")
    if isinstance(mat, Mapping) and isinstance(mat.get("opengl"), Mapping):
        _field("material", _check_object, mat["opengl"], "opengl material")
    mesh = obj.get("mesh")
    if mesh is not None and not isinstance(mesh, (str, Mapping, Mesh)):
        raise ValueError(
            f"scene field 'mesh': must be a built-in name ({', '.join(BUILTIN)}), a file path, or an object with 'builtin' or 'path'; got {_short(mesh)}"
        )
    if isinstance(mesh, Mapping) and "path" in mesh and not isinstance(mesh["path"], str):
        raise ValueError(f"scene field 'mesh': 'path' must be a file name (a string), got {_short(mesh['path'])}")
    if isinstance(mat, Mapping) and "merl" in mat and not isinstance(mat["merl"], str):
        raise ValueError(f"scene field 'material': 'merl' must be a file name (a string), got {_short(mat['merl'])}")


def _beside_scene(spec: Mapping[str, Any], base_dir) -> Mapping[str, Any]:
    """``{"measured": PATH}`` with a relative file path: the file beside the scene file, when it is there."""
    from ..sources import FILE_KINDS

    v = spec["measured"]
    if isinstance(v, str) and not os.path.isabs(v) and os.path.splitext(v)[1].lower() in FILE_KINDS:
        there = os.path.join(os.fspath(base_dir), v)
        if os.path.isfile(there):
            return {**spec, "measured": there}
    return spec


def scene_from_json(obj: Mapping[str, Any], base_dir: str | os.PathLike | None = None) -> tuple[Scene, Look]:
    """A :class:`Scene` and its :class:`Look` from a scene file's object."""
    if not isinstance(obj, Mapping):
        raise ValueError("a scene must be a JSON object")
    extra = set(obj) - set(SCENE_FIELDS) - set(OPEN_FIELDS)
    if extra:
        raise ValueError(
            f"scene: unknown field(s) {', '.join(sorted(map(str, extra)))}; valid fields: {', '.join(dict.fromkeys(SCENE_FIELDS + OPEN_FIELDS))}"
        )
    _check_fields(obj)
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
    if isinstance(mat_spec, Mapping) and "measured" in mat_spec and base_dir is not None:
        mat_spec = _beside_scene(mat_spec, base_dir)
    scene = make_scene(
        mesh=_field("mesh", mesh_from_spec, mesh_spec),
        material=_field("material", material_from_spec, mat_spec),
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
    look = Look(  # its errors name tonemap, exposure or srgb
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
    if p.stat().st_size > 16 << 20:
        raise ValueError(f"scene file {p} is larger than 16 MiB; a scene names its mesh files instead of holding them")
    try:
        text = p.read_bytes().decode("utf-8")
    except UnicodeDecodeError as e:
        raise ValueError(f"scene file {p} is not UTF-8 text (byte {e.start})") from None
    if nesting_exceeds(text, MAX_DEPTH):
        raise ValueError(f"scene file {p} nests JSON deeper than {MAX_DEPTH} levels")
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as e:
        raise ValueError(f"scene file {p} is not valid JSON: {e.msg} (line {e.lineno})") from None
    except (RecursionError, ValueError) as e:  # e.g. an integer of more than 4300 digits
        raise ValueError(f"scene file {p} is not valid JSON: {str(e).splitlines()[0] if str(e) else type(e).__name__}") from None
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
    w, h = _field("size", _size, size)
    m = mesh if isinstance(mesh, Mesh) else _field("mesh", mesh_from_spec, mesh)
    if camera is not None and not isinstance(camera, Mapping):
        raise ValueError(f"scene field 'camera': must be an object, got {type(camera).__name__}")
    projection, modelview = _field("camera", camera_matrices, camera, w / h)
    if lights is None:
        ls = list(DEFAULT_LIGHTS)
    elif not isinstance(lights, (list, tuple)):
        raise ValueError("lights must be a list of light objects")
    else:
        ls = [_field("lights", opengl.light_from_json, L) for L in lights]
    if not isinstance(antialias, bool):
        raise ValueError(f"antialias must be true or false, got {antialias!r}")
    if isinstance(background, (str, bytes, Mapping)) or not hasattr(background, "__len__"):
        raise ValueError(f"scene field 'background': must be r,g,b or r,g,b,a in [0, 1], got {_short(background)}")
    return Scene(
        mesh=m,
        projection=projection,
        modelview=modelview,
        size=(w, h),
        lights=ls,
        light_model=_field("light_model", opengl.light_model_from_json, light_model),
        material=_field("material", material_from_spec, material),
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
