"""The OpenGL fixed-function lighting model (OpenGL 2.1, §2.14.1), exactly.

This is the "classic" per-vertex lighting of OpenGL 1.x/2.x that the lecture
starts from: emission, a global ambient term, and per light an ambient, a
diffuse (Lambert) and a specular (Blinn's half-vector) term, scaled by
distance attenuation and a spotlight factor, summed and clamped to [0, 1]::

    c = e_cm + a_cm * a_cs
        + Σ_i att_i * spot_i * [ a_cm * a_cli
                                 + (n ⊙ VP_i) d_cm * d_cli
                                 + f_i (n ⊙ h_i)^s_rm * s_cm * s_cli ]

with ``⊙`` the dot product clamped at 0, ``VP_i`` the unit vector from the
vertex toward light ``i``, ``h_i = normalize(VP_i + VE)`` where ``VE`` is the
unit vector toward the eye (the origin of eye space) for a *local viewer* and
``(0, 0, 1)`` otherwise, and ``f_i = 1`` when ``n ⊙ VP_i > 0``, else 0 (no
highlight on the unlit side). For a positional light (``w != 0``)::

    att_i = 1 / (k_c + k_l d + k_q d²)          d = |P_i − V|

and ``att_i = 1`` for a directional one (``w = 0``, ``P_i`` is then a
direction toward the light). The spotlight factor is 1 for a cutoff of 180°,
otherwise, with ``ŝ`` the normalised spot direction,
``spot_i = max(−VP_i · ŝ, 0)^e`` inside the cone (``−VP_i·ŝ ≥ cos cutoff``)
and 0 outside. The alpha of the result is the material's diffuse alpha.

Everything is in eye space, as in OpenGL: vertex positions and normals after
the modelview transform, light positions as OpenGL stores them (transformed by
the modelview current at ``glLightfv`` time). Normals are normalised (as with
``GL_NORMALIZE``). Only front-face (one-sided) lighting is modelled.

Defaults are OpenGL's: :class:`Material` defaults to ambient 0.2, diffuse
0.8, specular 0, emission 0, shininess 0; :class:`LightModel` to ambient 0.2
and an infinite viewer; :class:`Light` to ``GL_LIGHT0``'s values (white
diffuse and specular, black ambient, directional along +z, attenuation
(1, 0, 0), no spot).

:data:`MATERIALS` is the lecture's table of twelve materials (the classic
"OpenGL/VRML material" table), with shininess stored as the OpenGL exponent,
i.e. the table's fraction × 128.

Reference: M. Segal and K. Akeley, *The OpenGL Graphics System: A
Specification, Version 2.1*, 2006, §2.14.1 "Lighting".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any, Mapping, Sequence

import numpy as np

from ..geometry import dot, normalize

__all__ = [
    "Material",
    "MATERIALS",
    "Light",
    "LightModel",
    "shade",
    "light_vector",
    "material_from_json",
    "light_from_json",
    "light_model_from_json",
    "MAX_LIGHTS",
]

MAX_LIGHTS = 8
"""OpenGL guarantees at least eight lights (``GL_MAX_LIGHTS``); the renderer supports eight."""


def _rgba(name: str, value: Any, alpha: float = 1.0) -> tuple[float, float, float, float]:
    """A colour as an RGBA tuple: a scalar (grey), RGB (alpha filled in) or RGBA."""
    if isinstance(value, (str, bytes, bool)):
        raise ValueError(f"{name} must be a number, an RGB or an RGBA colour, got {value!r}")
    try:
        arr = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, an RGB or an RGBA colour, got {value!r}") from None
    if arr.size == 1:
        arr = np.array([arr[0]] * 3 + [alpha])
    elif arr.size == 3:
        arr = np.append(arr, alpha)
    elif arr.size != 4:
        raise ValueError(f"{name} must have 1, 3 or 4 components, got {arr.size}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {arr.tolist()}")
    return tuple(float(x) for x in arr)  # type: ignore[return-value]


def _vec(name: str, value: Any, n: int) -> tuple[float, ...]:
    try:
        arr = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be {n} numbers, got {value!r}") from None
    if arr.size != n or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be {n} finite numbers, got {value!r}")
    return tuple(float(x) for x in arr)


def _nonneg(name: str, value: Any) -> float:
    try:
        f = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(f) or f < 0:
        raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    return f


@dataclass(frozen=True)
class Material:
    """An OpenGL material (``glMaterial``). Colours are RGBA (RGB or a scalar are accepted).

    ``shininess`` is the OpenGL specular exponent, in [0, 128].
    """

    ambient: Any = (0.2, 0.2, 0.2, 1.0)
    diffuse: Any = (0.8, 0.8, 0.8, 1.0)
    specular: Any = (0.0, 0.0, 0.0, 1.0)
    shininess: float = 0.0
    emission: Any = (0.0, 0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        for f in ("ambient", "diffuse", "specular", "emission"):
            object.__setattr__(self, f, _rgba(f"material {f}", getattr(self, f)))
        s = _nonneg("material shininess", self.shininess)
        if s > 128:
            raise ValueError(f"material shininess must be in [0, 128] (OpenGL's range), got {s:g}")
        object.__setattr__(self, "shininess", s)


@dataclass(frozen=True)
class Light:
    """An OpenGL light (``glLight``), position and spot direction in eye space.

    ``position`` is ``(x, y, z, w)``: ``w = 0`` makes a directional light shining
    *from* direction ``(x, y, z)``; ``w != 0`` a point light at ``xyz / w``
    (three numbers mean ``w = 1``, a point light).
    Colours are linear RGBA, usually in [0, 1] (not enforced; OpenGL clamps the sum).
    Attenuation coefficients are >= 0: ``constant`` (unitless), ``linear`` (per
    eye-space unit), ``quadratic`` (per unit²); they apply to point lights only.
    ``spot_direction`` is an eye-space vector (normalised when used);
    ``spot_exponent`` is in [0, 128]; ``spot_cutoff`` is in degrees: 180 (no spot) or [0, 90].
    """

    position: Any = (0.0, 0.0, 1.0, 0.0)
    ambient: Any = (0.0, 0.0, 0.0, 1.0)
    diffuse: Any = (1.0, 1.0, 1.0, 1.0)
    specular: Any = (1.0, 1.0, 1.0, 1.0)
    constant_attenuation: float = 1.0
    linear_attenuation: float = 0.0
    quadratic_attenuation: float = 0.0
    spot_direction: Any = (0.0, 0.0, -1.0)
    spot_exponent: float = 0.0
    spot_cutoff: float = 180.0

    def __post_init__(self) -> None:
        pos = np.asarray(self.position, dtype=np.float64).reshape(-1) if not isinstance(self.position, str) else None
        if pos is None or pos.size not in (3, 4):
            raise ValueError(f"light position must be x,y,z or x,y,z,w (eye space), got {self.position!r}")
        if pos.size == 3:
            pos = np.append(pos, 1.0)
        object.__setattr__(self, "position", _vec("light position", pos, 4))
        for f in ("ambient", "diffuse", "specular"):
            object.__setattr__(self, f, _rgba(f"light {f}", getattr(self, f)))
        for f in ("constant_attenuation", "linear_attenuation", "quadratic_attenuation"):
            object.__setattr__(self, f, _nonneg(f"light {f}", getattr(self, f)))
        object.__setattr__(self, "spot_direction", _vec("light spot_direction", self.spot_direction, 3))
        e = _nonneg("light spot_exponent", self.spot_exponent)
        if e > 128:
            raise ValueError(f"light spot_exponent must be in [0, 128], got {e:g}")
        object.__setattr__(self, "spot_exponent", e)
        c = _nonneg("light spot_cutoff", self.spot_cutoff)
        if not (c == 180.0 or 0.0 <= c <= 90.0):
            raise ValueError(f"light spot_cutoff must be 180 (no spot) or in [0, 90] degrees, got {c:g}")
        object.__setattr__(self, "spot_cutoff", c)
        if self.is_spot and float(np.linalg.norm(self.spot_direction)) == 0.0:
            raise ValueError("light spot_direction must not be the zero vector")

    @property
    def is_positional(self) -> bool:
        return self.position[3] != 0.0

    @property
    def is_spot(self) -> bool:
        return self.spot_cutoff != 180.0


@dataclass(frozen=True)
class LightModel:
    """``glLightModel``: the global ambient colour and the local-viewer switch."""

    ambient: Any = (0.2, 0.2, 0.2, 1.0)
    local_viewer: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "ambient", _rgba("light_model ambient", self.ambient))
        if not isinstance(self.local_viewer, (bool, np.bool_)):
            raise ValueError(f"light_model local_viewer must be true or false, got {self.local_viewer!r}")
        object.__setattr__(self, "local_viewer", bool(self.local_viewer))


# The lecture's material table: ambient RGB, diffuse RGB, specular RGB, shininess as a fraction of 128.
_TABLE = """
emerald   0.0215 0.1745 0.0215      0.07568 0.61424 0.07568   0.633 0.727811 0.633            0.6
jade      0.135 0.2225 0.1575       0.54 0.89 0.63            0.316228 0.316228 0.316228      0.1
obsidian  0.05375 0.05 0.06625      0.18275 0.17 0.22525      0.332741 0.328634 0.346435      0.3
pearl     0.25 0.20725 0.20725      1 0.829 0.829             0.296648 0.296648 0.296648      0.088
ruby      0.1745 0.01175 0.01175    0.61424 0.04136 0.04136   0.727811 0.626959 0.626959      0.6
turquoise 0.1 0.18725 0.1745        0.396 0.74151 0.69102     0.297254 0.30829 0.306678       0.1
brass     0.329412 0.223529 0.027451 0.780392 0.568627 0.113725 0.992157 0.941176 0.807843    0.21794872
bronze    0.2125 0.1275 0.054       0.714 0.4284 0.18144      0.393548 0.271906 0.166721      0.2
chrome    0.25 0.25 0.25            0.4 0.4 0.4               0.774597 0.774597 0.774597      0.6
copper    0.19125 0.0735 0.0225     0.7038 0.27048 0.0828     0.256777 0.137622 0.086014      0.1
gold      0.24725 0.1995 0.0745     0.75164 0.60648 0.22648   0.628281 0.555802 0.366065      0.4
silver    0.19225 0.19225 0.19225   0.50754 0.50754 0.50754   0.508273 0.508273 0.508273      0.4
"""


def _parse_table(text: str) -> dict[str, Material]:
    out: dict[str, Material] = {}
    for line in text.strip().splitlines():
        name, *nums = line.split()
        v = [float(x) for x in nums]
        out[name] = Material(
            ambient=v[0:3], diffuse=v[3:6], specular=v[6:9], shininess=v[9] * 128.0, emission=(0.0, 0.0, 0.0)
        )
    return out


MATERIALS: dict[str, Material] = _parse_table(_TABLE)
"""The lecture's twelve materials, in the lecture's order; shininess is the GL exponent (fraction × 128)."""


# --------------------------------------------------------------------------- shading
def light_vector(L: Light, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors ``VP`` from eye-space points ``P`` (N, 3) toward light ``L``, and ``att × spot`` (N,).

    The attenuation and spotlight factors of the module docstring (OpenGL 2.1
    §2.14.1); shared by :func:`shade` and the BRDF path of
    :mod:`brdfkit.render.lighting`.
    """
    pos = np.asarray(L.position, dtype=np.float64)
    if L.is_positional:
        to_light = pos[:3] / pos[3] - P
        d = np.sqrt(dot(to_light, to_light))
        vp = to_light / np.where(d > 0, d, 1.0)[:, None]
        factor = 1.0 / (L.constant_attenuation + L.linear_attenuation * d + L.quadratic_attenuation * d * d)
    else:
        vp = np.broadcast_to(normalize(pos[:3]), P.shape)
        factor = np.ones(P.shape[0])
    if L.is_spot:
        sd = normalize(np.asarray(L.spot_direction, dtype=np.float64))
        cos_s = -(vp @ sd)  # −VP · ŝ
        inside = cos_s >= math.cos(math.radians(L.spot_cutoff))
        factor = factor * np.where(inside, np.power(np.maximum(cos_s, 0.0), L.spot_exponent), 0.0)
    return vp, factor


def shade(
    positions: Any,
    normals: Any,
    material: Material | str,
    lights: Sequence[Light] | Light = (),
    light_model: LightModel | None = None,
) -> np.ndarray:
    """The lit colour of vertices, exactly as OpenGL's fixed-function lighting computes it.

    ``positions`` (N, 3) or (N, 4) and ``normals`` (N, 3) are in eye space (the
    eye at the origin looking down −z); normals are normalised here. Returns
    (N, 4) RGBA in [0, 1] (float64). ``material`` may be a :data:`MATERIALS` name.
    """
    if isinstance(material, str):
        material = material_from_json(material)
    if isinstance(lights, Light):
        lights = (lights,)
    lights = tuple(lights)
    if len(lights) > MAX_LIGHTS:
        raise ValueError(f"at most {MAX_LIGHTS} lights are supported (GL_MAX_LIGHTS), got {len(lights)}")
    lm = light_model if light_model is not None else LightModel()

    P = np.asarray(positions, dtype=np.float64)
    N = np.asarray(normals, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] not in (3, 4):
        raise ValueError(f"positions must have shape (N, 3) or (N, 4), got {P.shape}")
    if P.shape[1] == 4:
        w = P[:, 3:4]
        if np.any(w == 0):
            raise ValueError("positions with w = 0 are not points")
        P = P[:, :3] / w
    if N.shape != P.shape:
        raise ValueError(f"normals must have shape {P.shape} like positions, got {N.shape}")
    n = normalize(N)

    a_cm = np.array(material.ambient[:3])
    d_cm = np.array(material.diffuse[:3])
    s_cm = np.array(material.specular[:3])
    e_cm = np.array(material.emission[:3])
    srm = material.shininess

    c = np.broadcast_to(e_cm + a_cm * np.array(lm.ambient[:3]), P.shape).copy()
    if lm.local_viewer:
        ve = normalize(-P)
    else:
        ve = np.broadcast_to(np.array([0.0, 0.0, 1.0]), P.shape)

    for L in lights:
        vp, factor = light_vector(L, P)
        ndotl = dot(n, vp)
        lit = ndotl > 0
        diff = np.maximum(ndotl, 0.0)
        h = normalize(vp + ve)
        ndoth = np.maximum(dot(n, h), 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            spec = np.where(lit, np.power(ndoth, srm), 0.0)
        term = (
            np.array(L.ambient[:3]) * a_cm
            + diff[:, None] * (np.array(L.diffuse[:3]) * d_cm)
            + spec[:, None] * (np.array(L.specular[:3]) * s_cm)
        )
        c += factor[:, None] * term

    out = np.empty((P.shape[0], 4))
    out[:, :3] = np.clip(c, 0.0, 1.0)
    out[:, 3] = min(max(material.diffuse[3], 0.0), 1.0)
    return out


# --------------------------------------------------------------------------- JSON helpers
def _from_mapping(cls, what: str, obj: Mapping[str, Any]):
    if not isinstance(obj, Mapping):
        raise ValueError(f"{what} must be an object, got {type(obj).__name__}")
    names = [f.name for f in fields(cls)]
    for k in obj:
        if k not in names:
            raise ValueError(f"{what}: unknown field {k!r}; valid fields: {', '.join(names)}")
    return cls(**dict(obj))


def material_from_json(obj: Any) -> Material:
    """A :class:`Material` from a table name or an object with the field names."""
    if isinstance(obj, Material):
        return obj
    if isinstance(obj, str):
        if obj not in MATERIALS:
            raise ValueError(f"unknown material {obj!r}; valid materials: {', '.join(MATERIALS)}")
        return MATERIALS[obj]
    return _from_mapping(Material, "opengl material", obj)


def light_from_json(obj: Any) -> Light:
    if isinstance(obj, Light):
        return obj
    return _from_mapping(Light, "light", obj)


def light_model_from_json(obj: Any) -> LightModel:
    if obj is None:
        return LightModel()
    if isinstance(obj, LightModel):
        return obj
    return _from_mapping(LightModel, "light_model", obj)
