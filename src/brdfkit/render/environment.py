"""Environment maps for image-based lighting: files (EXR, Radiance HDR) and generated built-ins.

An environment is linear RGB radiance on an equirectangular (latitude-longitude)
grid, ``rgb`` of shape (H, W, 3), row 0 at the zenith. Directions are in the
*world* frame (the mesh's coordinates when the modelview is a pure camera
transform), +y up:

    θ = acos(d_y) ∈ [0, π] (row: v = θ/π),   φ = atan2(d_x, −d_z) (column: u = φ/(2π) + ½),

so the centre column looks down −z, the way the default camera looks. ``rotation_deg``
turns the map about +y. The radiance is piecewise constant per texel (nearest-texel
lookup): the GLSL renderer, its importance sampling and the numpy reference all use
this one reading, so their integrals agree exactly.

Built-ins (``BUILTINS``, generated, never downloaded; cached in the user cache folder,
``$BRDFKIT_CACHE_DIR`` or ``$XDG_CACHE_HOME/brdfkit`` or ``~/.cache/brdfkit``)
-----------------------------------------------------------------------------
``furnace``  uniform radiance 1 (the white furnace test).
``sky``      clear sky with sun: the Preetham, Shirley & Smits 1999 analytic daylight
             model ("A Practical Analytic Model for Daylight", SIGGRAPH 1999: Perez
             luminance distribution with the paper's turbidity-dependent coefficients,
             zenith luminance and chromaticity) for turbidity 3 and the sun 35° above the
             horizon; a sun disc (enlarged to 1.5° radius so that it covers texels)
             whose colour is the extraterrestrial sun attenuated by Rayleigh (Leckner
             1978, τ = 0.008735 λ^-4.08 m) and Ångström aerosol extinction (β from the
             turbidity as in Preetham's appendix) along Kasten & Young's air mass; the
             ground is grey (albedo 0.3) lit by sky and sun. Scaled so that a horizontal
             white Lambert surface reflects radiance 1.
``studio``   a dim grey room (radiance 0.03 to 0.08) with three soft boxes: a large key
             light (radiance 6), a fill (2) and a strip rim light (5), with soft edges.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

LUMA = np.array([0.2126, 0.7152, 0.0722])
BUILTINS = {
    "sky": "clear sky with sun (Preetham 1999 daylight model, turbidity 3, sun 35 deg high)",
    "studio": "dim studio with three soft boxes (key, fill, rim)",
    "furnace": "uniform white radiance 1 (white furnace test)",
}
_VERSION = 1  # bump when a generator changes: the cache file names carry it
_BUILTIN_SIZE = {"sky": (512, 1024), "studio": (512, 1024), "furnace": (32, 64)}
ENV_SUFFIXES = (".exr", ".hdr", ".npy")


# ---------------------------------------------------------------------------------------------
# directions and texels
# ---------------------------------------------------------------------------------------------
def texel_directions(h: int, w: int) -> np.ndarray:
    """Unit directions (H, W, 3) of the texel centres."""
    theta = (np.arange(h) + 0.5) * math.pi / h
    phi = ((np.arange(w) + 0.5) / w - 0.5) * 2 * math.pi
    st = np.sin(theta)[:, None]
    return np.stack(
        [st * np.sin(phi)[None, :], np.broadcast_to(np.cos(theta)[:, None], (h, w)), -st * np.cos(phi)[None, :]], -1
    )


def row_solid_angles(h: int, w: int) -> np.ndarray:
    """Solid angle of one texel of each row, (H,): (2π/W)(cos θ_top − cos θ_bottom)."""
    edges = np.cos(np.arange(h + 1) * math.pi / h)
    return (2 * math.pi / w) * (edges[:-1] - edges[1:])


def direction_to_texel(d: np.ndarray, h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    """(row, col) integer indices of the texel containing each unit direction (..., 3)."""
    theta = np.arccos(np.clip(d[..., 1], -1.0, 1.0))
    phi = np.arctan2(d[..., 0], -d[..., 2])
    row = np.clip(np.floor(theta / math.pi * h), 0, h - 1).astype(np.int64)
    col = np.floor((phi / (2 * math.pi) + 0.5) * w).astype(np.int64) % w
    return row, col


def rotation_y(deg: float) -> np.ndarray:
    """World → map rotation about +y by ``-deg`` (a map turned by ``deg``)."""
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])


@dataclass
class Environment:
    """An equirectangular radiance map (H, W, 3) with its orientation and strength."""

    name: str
    rgb: np.ndarray
    rotation_deg: float = 0.0
    strength: float = 1.0
    visible: bool = True  # shown behind the object
    _cdf: Any = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        a = np.asarray(self.rgb, dtype=np.float32)
        if a.ndim == 2:
            a = np.repeat(a[..., None], 3, -1)
        if a.ndim != 3 or a.shape[2] < 3 or a.shape[0] < 2 or a.shape[1] < 2:
            raise ValueError(f"environment {self.name}: expected an (H, W, 3) image, got shape {np.shape(self.rgb)}")
        a = np.ascontiguousarray(a[..., :3])
        if not np.all(np.isfinite(a)) or np.any(a < 0):
            raise ValueError(f"environment {self.name}: radiance must be finite and non-negative")
        if not a.max() > 0:
            raise ValueError(f"environment {self.name}: the map is black")
        self.rgb = a
        for what in ("rotation_deg", "strength"):
            v = getattr(self, what)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"environment: {what} must be a finite number, got {v!r}")
        if self.strength <= 0:
            raise ValueError(f"environment: strength must be positive, got {self.strength!r}")
        if not isinstance(self.visible, bool):
            raise ValueError(f"environment: visible must be true or false, got {self.visible!r}")

    @property
    def shape(self) -> tuple[int, int]:
        return self.rgb.shape[0], self.rgb.shape[1]

    def world_to_map(self) -> np.ndarray:
        return rotation_y(self.rotation_deg)

    def radiance(self, d_world: np.ndarray) -> np.ndarray:
        """Radiance (…, 3) in world directions (…, 3), nearest texel, times ``strength``."""
        d = np.asarray(d_world, dtype=np.float64) @ self.world_to_map().T
        r, c = direction_to_texel(d, *self.shape)
        return self.rgb[r, c].astype(np.float64) * self.strength

    def sampling_tables(self) -> tuple[np.ndarray, np.ndarray, float]:
        """The luminance CDFs for importance sampling: ``(marginal (H,), conditional (H, W), S)``.

        Texel weights are w = (luminance + 1 % of the mean) · Ω_row; ``marginal[r]`` is the
        cumulative share of rows 0..r, ``conditional[r, c]`` that of columns 0..c within
        row r. Within a texel the direction is uniform in solid angle, so the density of a
        direction is exactly (luminance' of its texel) / S, S = Σ w.
        """
        if self._cdf is None:
            h, w = self.shape
            lum = self.rgb.astype(np.float64) @ LUMA
            lum = lum + 0.01 * max(float(lum.mean()), 1e-12)
            wt = lum * row_solid_angles(h, w)[:, None]
            rows = wt.sum(1)
            cond = np.cumsum(wt, 1) / rows[:, None]
            cond[:, -1] = 1.0
            marg = np.cumsum(rows) / rows.sum()
            marg[-1] = 1.0
            self._cdf = (marg.astype(np.float32), cond.astype(np.float32), float(wt.sum()), lum.astype(np.float32))
        m, c, s, _ = self._cdf
        return m, c, s

    def sampling_luminance(self) -> np.ndarray:
        self.sampling_tables()
        return self._cdf[3]

    def pdf(self, d_world: np.ndarray) -> np.ndarray:
        """Solid-angle density of the luminance sampling at world directions."""
        _, _, s = self.sampling_tables()
        d = np.asarray(d_world, dtype=np.float64) @ self.world_to_map().T
        r, c = direction_to_texel(d, *self.shape)
        return self.sampling_luminance()[r, c] / s


# ---------------------------------------------------------------------------------------------
# built-in generators
# ---------------------------------------------------------------------------------------------
def _perez(theta, gamma, coef):
    """Perez et al. 1993 all-weather luminance distribution F(θ, γ) (as used by Preetham 1999)."""
    a, b, c, d, e = coef
    ct = np.maximum(np.cos(theta), 1e-3)
    return (1 + a * np.exp(b / ct)) * (1 + c * np.exp(d * gamma) + e * np.cos(gamma) ** 2)


def _preetham_coefficients(t: float) -> dict[str, tuple[float, ...]]:
    """Preetham 1999, appendix A.2: Perez coefficients for Y, x, y as linear functions of turbidity T."""
    return {
        "Y": (0.1787 * t - 1.4630, -0.3554 * t + 0.4275, -0.0227 * t + 5.3251, 0.1206 * t - 2.5771, -0.0670 * t + 0.3703),
        "x": (-0.0193 * t - 0.2592, -0.0665 * t + 0.0008, -0.0004 * t + 0.2125, -0.0641 * t - 0.8989, -0.0033 * t + 0.0452),
        "y": (-0.0167 * t - 0.2608, -0.0950 * t + 0.0092, -0.0079 * t + 0.2102, -0.0441 * t - 1.6537, -0.0109 * t + 0.0529),
    }


def _preetham_zenith(t: float, theta_s: float) -> tuple[float, float, float]:
    """Preetham 1999, appendix A.2: zenith luminance (kcd/m²) and chromaticity x, y."""
    chi = (4.0 / 9.0 - t / 120.0) * (math.pi - 2 * theta_s)
    yz = (4.0453 * t - 4.9710) * math.tan(chi) - 0.2155 * t + 2.4192
    th = np.array([theta_s**3, theta_s**2, theta_s, 1.0])
    mx = np.array([[0.00166, -0.00375, 0.00209, 0.0], [-0.02903, 0.06377, -0.03202, 0.00394],
                   [0.11693, -0.21196, 0.06052, 0.25886]])
    my = np.array([[0.00275, -0.00610, 0.00317, 0.0], [-0.04214, 0.08970, -0.04153, 0.00516],
                   [0.15346, -0.26756, 0.06670, 0.26688]])
    tt = np.array([t * t, t, 1.0])
    return yz, float(tt @ mx @ th), float(tt @ my @ th)


def _xyY_to_linear_srgb(x, y, Y):
    """CIE xyY → linear sRGB (IEC 61966-2-1 matrix, D65)."""
    yy = np.maximum(y, 1e-6)
    X = x * Y / yy
    Z = (1 - x - y) * Y / yy
    m = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]])
    return np.maximum(np.stack([X, Y, Z], -1) @ m.T, 0.0)


def _sun_transmittance(t: float, theta_s: float) -> np.ndarray:
    """Direct-beam transmittance at the sRGB primaries' wavelengths (0.61, 0.55, 0.465 µm)."""
    lam = np.array([0.610, 0.550, 0.465])
    z = math.degrees(theta_s)
    m = 1.0 / (math.cos(theta_s) + 0.50572 * (96.07995 - z) ** -1.6364)  # Kasten & Young 1989 air mass
    tau_r = 0.008735 * lam**-4.08  # Leckner 1978 Rayleigh optical depth
    beta = 0.04608 * t - 0.04586  # Ångström turbidity from T (Preetham 1999 appendix)
    tau_a = beta * lam**-1.3
    return np.exp(-m * (tau_r + tau_a))


def make_sky(h: int = 512, w: int = 1024, turbidity: float = 3.0, sun_elevation_deg: float = 35.0,
             sun_azimuth_deg: float = 50.0, sun_radius_deg: float = 1.5, ground_albedo: float = 0.3) -> np.ndarray:
    d = texel_directions(h, w)
    theta_s = math.radians(90.0 - sun_elevation_deg)
    az = math.radians(sun_azimuth_deg)
    sun = np.array([math.sin(theta_s) * math.sin(az), math.cos(theta_s), -math.sin(theta_s) * math.cos(az)])
    up = d[..., 1] > 0
    theta = np.arccos(np.clip(d[..., 1], -1, 1))
    gamma = np.arccos(np.clip(d @ sun, -1, 1))
    coef = _preetham_coefficients(turbidity)
    yz, xz, yzc = _preetham_zenith(turbidity, theta_s)
    Y = yz * _perez(theta, gamma, coef["Y"]) / _perez(0.0, theta_s, coef["Y"])
    x = xz * _perez(theta, gamma, coef["x"]) / _perez(0.0, theta_s, coef["x"])
    y = yzc * _perez(theta, gamma, coef["y"]) / _perez(0.0, theta_s, coef["y"])
    sky = _xyY_to_linear_srgb(x, y, Y)
    # the sun: a disc whose illuminance is the extraterrestrial sun's (1.1e2 klx over 6.8e-5 sr,
    # in the sky's kcd/m² units) dimmed by the atmosphere; spread over the enlarged disc
    disc_sr = 2 * math.pi * (1 - math.cos(math.radians(sun_radius_deg)))
    e_sun = 110.0 * _sun_transmittance(turbidity, theta_s)  # klx per channel, white extraterrestrial sun
    in_sun = (gamma < math.radians(sun_radius_deg)) & up
    rgb = np.where(up[..., None], sky, 0.0)
    rgb[in_sun] = e_sun / disc_sr
    # horizontal irradiance from what is above the horizon, then a grey ground lit by it
    om = row_solid_angles(h, w)[:, None, None]
    e_h = float(((rgb @ LUMA)[..., None] * np.maximum(d[..., 1:2], 0.0) * om).sum())
    e_rgb = (rgb * np.maximum(d[..., 1:2], 0.0) * om).sum((0, 1))
    rgb[~up] = ground_albedo * e_rgb / math.pi
    return (rgb * (math.pi / e_h)).astype(np.float32)  # a horizontal white Lambert surface: radiance 1


def _soft_box(d: np.ndarray, centre_dir, width_deg: float, height_deg: float, soft_deg: float) -> np.ndarray:
    """A rectangular soft box seen from the origin: 1 inside, smooth falloff over ``soft_deg`` at the edges."""
    c = np.asarray(centre_dir, dtype=np.float64)
    c /= np.linalg.norm(c)
    right = np.cross(c, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    upv = np.cross(right, c)
    z = d @ c
    with np.errstate(all="ignore"):
        ax = np.degrees(np.arctan2(d @ right, z))
        ay = np.degrees(np.arctan2(d @ upv, z))

    def edge(a, half):
        return np.clip((half - np.abs(a)) / soft_deg + 0.5, 0.0, 1.0)

    m = edge(ax, width_deg / 2) * edge(ay, height_deg / 2)
    return np.where(z > 0, m * m * (3 - 2 * m), 0.0)


def make_studio(h: int = 512, w: int = 1024) -> np.ndarray:
    d = texel_directions(h, w)
    base = 0.03 + 0.05 * np.clip(d[..., 1] * 0.5 + 0.5, 0, 1)  # darker floor, lighter ceiling
    rgb = np.repeat(base[..., None], 3, -1)
    boxes = (  # (direction, width, height, softness, radiance)
        ((-1.0, 0.9, 0.9), 45.0, 35.0, 6.0, (6.0, 6.0, 5.8)),  # key: above left, in front
        ((1.2, 0.2, 0.5), 35.0, 30.0, 10.0, (1.9, 2.0, 2.1)),  # fill: right, low
        ((0.6, 0.5, -1.0), 10.0, 60.0, 3.0, (5.0, 5.0, 5.0)),  # rim strip behind right
    )
    for c, bw, bh, soft, rad in boxes:
        m = _soft_box(d, c, bw, bh, soft)
        rgb = rgb * (1 - m[..., None]) + m[..., None] * np.asarray(rad)
    return rgb.astype(np.float32)


def make_furnace(h: int = 32, w: int = 64) -> np.ndarray:
    return np.ones((h, w, 3), np.float32)


_GENERATORS = {"sky": make_sky, "studio": make_studio, "furnace": make_furnace}


# ---------------------------------------------------------------------------------------------
# cache and files
# ---------------------------------------------------------------------------------------------
def cache_dir() -> Path:
    """``$BRDFKIT_CACHE_DIR``, else ``$XDG_CACHE_HOME/brdfkit``, else ``~/.cache/brdfkit``
    (:func:`brdfkit.engine.cache.cache_root`: the built-in maps do not depend on the source version)."""
    from ..engine.cache import cache_root

    return cache_root()


def builtin_map(name: str) -> np.ndarray:
    """A built-in map, generated on first use and then read from the cache (written atomically)."""
    if name not in _GENERATORS:
        raise ValueError(f"unknown environment {name!r}; built-ins: {', '.join(BUILTINS)} (or an .exr/.hdr path)")
    h, w = _BUILTIN_SIZE[name]
    path = cache_dir() / "env" / f"{name}-v{_VERSION}-{w}x{h}.npy"
    if path.is_file():
        try:
            a = np.load(path, allow_pickle=False)
            if a.shape == (h, w, 3) and a.dtype == np.float32 and np.all(np.isfinite(a)):
                return a
        except (OSError, ValueError):
            pass  # a damaged cache file: build it again
    a = _GENERATORS[name](h, w)
    try:
        from ..fileio import atomic_open

        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_open(path, "wb") as f:
            np.save(f, a, allow_pickle=False)
    except OSError:
        pass  # an unwritable cache only costs the rebuild next time
    return a


def read_hdr(path: str | os.PathLike) -> np.ndarray:
    """A Radiance RGBE (.hdr / .pic) image as (H, W, 3) float32: flat or new-style run-length rows,
    ``-Y H +X W`` orientation (the common one)."""
    data = Path(path).read_bytes()
    pos = 0

    def line() -> bytes:
        nonlocal pos
        end = data.find(b"\n", pos)
        if end < 0:
            raise ValueError(f"{path}: not a Radiance HDR file (truncated header)")
        out = data[pos:end]
        pos = end + 1
        return out

    first = line()
    if not first.startswith(b"#?"):
        raise ValueError(f"{path}: not a Radiance HDR file (no #? signature)")
    while True:
        ln = line()
        if ln.startswith(b"FORMAT=") and ln.strip() != b"FORMAT=32-bit_rle_rgbe":
            raise ValueError(f"{path}: only 32-bit_rle_rgbe Radiance files are supported")
        if ln.strip() == b"":
            break
    res = line().split()
    if len(res) != 4 or res[0] != b"-Y" or res[2] != b"+X":
        raise ValueError(f"{path}: only the '-Y H +X W' orientation is supported")
    h, w = int(res[1]), int(res[3])
    if h < 1 or w < 1:
        raise ValueError(f"{path}: bad image size")
    buf = np.frombuffer(data, np.uint8, offset=pos)
    out = np.empty((h, w, 4), np.uint8)
    i = 0
    try:
        for r in range(h):
            if 8 <= w < 32768 and buf[i] == 2 and buf[i + 1] == 2 and (int(buf[i + 2]) << 8 | int(buf[i + 3])) == w:
                i += 4
                for ch in range(4):
                    c = 0
                    while c < w:
                        n = int(buf[i])
                        i += 1
                        if n > 128:
                            n -= 128
                            out[r, c:c + n, ch] = buf[i]
                            i += 1
                        else:
                            out[r, c:c + n, ch] = buf[i:i + n]
                            i += n
                        c += n
            else:
                out[r] = buf[i:i + 4 * w].reshape(w, 4)
                i += 4 * w
    except (IndexError, ValueError):
        raise ValueError(f"{path}: truncated or corrupt Radiance HDR data") from None
    e = out[..., 3].astype(np.int32)
    scale = np.where(e > 0, np.ldexp(1.0, e - 136), 0.0)  # (m + 0.5) 2^(e − 128) / 256
    return ((out[..., :3].astype(np.float64) + 0.5) * scale[..., None]).astype(np.float32)


def write_hdr(path: str | os.PathLike, rgb: np.ndarray) -> None:
    """Write (H, W, 3) radiance as a flat (uncompressed) Radiance RGBE file, atomically."""
    from ..fileio import atomic_open

    a = np.asarray(rgb, dtype=np.float64)
    h, w = a.shape[:2]
    m = a.max(-1)
    mant, e = np.frexp(m)
    ok = m > 1e-32
    scale = np.where(ok, mant * 256.0 / np.where(ok, m, 1.0), 0.0)
    px = np.zeros((h, w, 4), np.uint8)
    px[..., :3] = np.clip(np.floor(a * scale[..., None]), 0, 255).astype(np.uint8)
    px[..., 3] = np.where(ok, e + 128, 0).astype(np.uint8)
    with atomic_open(path, "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {h} +X {w}\n".encode() + px.tobytes())


def read_map(path: str | os.PathLike) -> np.ndarray:
    p = Path(path)
    if not p.is_file():
        raise OSError(f"environment map not found: {p}")
    suf = p.suffix.lower()
    if suf == ".hdr":
        return read_hdr(p)
    if suf == ".npy":
        try:
            return np.asarray(np.load(p, allow_pickle=False), dtype=np.float32)
        except ValueError as e:
            raise ValueError(f"{p}: not a numpy array file ({e})") from None
    if suf == ".exr":
        from .image import read_exr

        try:
            a = read_exr(p)
        except Exception as e:
            raise ValueError(f"{p}: cannot read EXR ({e})") from None
        return a[..., :3]
    raise ValueError(f"environment map must end in {', '.join(ENV_SUFFIXES)}; got {p.name!r}")


ENV_FIELDS = ("name", "path", "rotation_deg", "strength", "samples", "visible")


def environment_from_spec(spec: Any, base_dir: str | os.PathLike | None = None) -> tuple[Environment, int | None]:
    """An :class:`Environment` (and the ``samples`` it asks for, or None) from a built-in name,
    a path, or a scene file's ``{"name"|"path", "rotation_deg", "strength", "samples", "visible"}``."""
    if isinstance(spec, Environment):
        return spec, None
    if isinstance(spec, (str, os.PathLike)):
        s = os.fspath(spec)
        spec = {"name": s} if s in BUILTINS else {"path": s}
    if not isinstance(spec, Mapping):
        raise ValueError('environment must be a built-in name, a path, or {"name"|"path": ..., ...}')
    extra = set(spec) - set(ENV_FIELDS)
    if extra:
        raise ValueError(f"environment: unknown field(s) {', '.join(sorted(extra))}; valid: {', '.join(ENV_FIELDS)}")
    if ("name" in spec) == ("path" in spec):
        raise ValueError("environment: give exactly one of 'name' (a built-in) or 'path' (an .exr/.hdr file)")
    if "name" in spec:
        name = spec["name"]
        if not isinstance(name, str):
            raise ValueError("environment name must be a string")
        rgb = builtin_map(name)
    else:
        p = spec["path"]
        if not isinstance(p, str):
            raise ValueError("environment path must be a string")
        if base_dir is not None and not os.path.isabs(p):
            p = os.path.join(os.fspath(base_dir), p)
        rgb = read_map(p)
        name = Path(p).name
    samples = spec.get("samples")
    if samples is not None:
        samples = check_samples(samples)
    env = Environment(
        name, rgb, rotation_deg=spec.get("rotation_deg", 0.0), strength=spec.get("strength", 1.0),
        visible=spec.get("visible", True),
    )
    return env, samples


MAX_SAMPLES = 1 << 16


def check_samples(n: Any) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= int(n) <= MAX_SAMPLES:
        raise ValueError(f"samples must be an integer in [1, {MAX_SAMPLES}], got {n!r}")
    return int(n)


__all__ = [
    "Environment", "BUILTINS", "builtin_map", "environment_from_spec", "read_hdr", "write_hdr", "read_map",
    "texel_directions", "row_solid_angles", "direction_to_texel", "cache_dir", "check_samples", "make_sky",
    "make_studio", "make_furnace",
]
