"""The textures of the GLSL twins of the RGL and UTIA readers (``shaders/rgl.glsl``, ``shaders/utia.glsl``).

One description of each table layout, used by the renderer and :func:`brdfkit.render.glsl.eval_glsl`
(moderngl) and by the explorer (``POST /api/measured/file`` sends :func:`pack`'s bytes; the page
uploads the same arrays as WebGL 2 textures).

A :class:`TableSet` names the shader file, its textures (:class:`Texture`: the ``sampler2D`` /
``sampler3D`` uniform, float32 data of shape ``(height, width, components)`` or ``(depth, height,
width, components)``, components 1 (R32F) or 4 (RGBA32F), read with ``texelFetch`` only) and its
``int`` uniforms. Textures are bound to consecutive units from :data:`FIRST_UNIT` (the renderer and the
page use units 0-7 for their own textures).

=========  ============  ====================================================================
format     shader        textures (see the shader file's header for what each texel holds)
=========  ============  ====================================================================
``rgl``    rgl.glsl      ``u_rgl_warp`` (3D: VNDF, its conditional and marginal CDFs),
                         ``u_rgl_rgb`` (3D), ``u_rgl_ndf``, ``u_rgl_sigma``, ``u_rgl_axes`` (2D)
``utia``   utia.glsl     ``u_utia`` (3D, 48 × 6 × 288)
=========  ============  ====================================================================

The arrays are the readers' own working tables (:class:`brdfkit.measured.rgl.RGLBRDF`'s
normalised VNDF and CDFs computed in float64, spectra already converted to RGB;
:class:`brdfkit.measured.utia.UTIABRDF`'s table), rounded once to float32.

:func:`table_set` builds a model's set once: the last two sets are held (a :class:`brdfkit.memo.Held`), keyed
by :func:`brdfkit.render.glsl.table_key` (a digest of the set, so two models read from the same
file share one), and their arrays are read-only. An anisotropic RGL set takes tens of MB and its
build about three times that for a moment; the renderer asks for a model's key (which needs the
set) and then for its set, and may ask again for each frame or evaluation.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..memo import Held

FIRST_UNIT = 8
#: the formats with a table set here (a model's class ``name``)
FORMATS = ("rgl", "utia")


@dataclass(frozen=True)
class Texture:
    uniform: str
    data: np.ndarray  # float32, (h, w, c) or (d, h, w, c)

    @property
    def dims(self) -> int:
        return self.data.ndim - 1

    @property
    def size(self) -> tuple[int, ...]:
        """(width, height[, depth]), as OpenGL counts them."""
        return tuple(int(n) for n in self.data.shape[-2::-1])

    @property
    def components(self) -> int:
        return int(self.data.shape[-1])


@dataclass(frozen=True)
class TableSet:
    format: str
    shader: str
    textures: tuple[Texture, ...]
    ints: dict[str, int] = field(default_factory=dict)


def read_only(a: np.ndarray) -> np.ndarray:
    """``a``, made read-only (a held array must not be changed by whoever got it)."""
    a.flags.writeable = False
    return a


def format_of(model: Any) -> str | None:
    """``"rgl"`` or ``"utia"`` for a model (instance or class) read from such a file, else None."""
    cls = model if isinstance(model, type) else type(model)
    name = getattr(cls, "name", None)
    return name if name in FORMATS and getattr(cls, "measured", False) else None


def _f32(a) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float32)


def rgl_tables(model: Any) -> TableSet:
    """The textures of ``rgl.glsl`` for an :class:`~brdfkit.measured.rgl.RGLBRDF`."""
    warp = model._vndf
    n_phi, n_theta, h, w = model.resolution
    s = n_phi * n_theta
    hv, wv = warp.h, warp.w
    t = np.zeros((s, hv, wv, 4), dtype=np.float64)
    t[..., 0] = warp.data.reshape(s, hv, wv)
    t[..., :wv - 1, 1] = warp.cond.reshape(s, hv, wv - 1)
    t[:, :hv - 1, :, 2] = warp.marg[:, :, None]
    rgb = np.zeros((s, h, w, 4), dtype=np.float64)
    rgb[..., :3] = model._rgb.reshape(s, h, w, 3)
    axes = np.zeros((2, max(n_phi, n_theta), 1))
    axes[0, :n_phi, 0] = model._phi
    axes[1, :n_theta, 0] = model._theta
    textures = (
        Texture("u_rgl_warp", _f32(t)),
        Texture("u_rgl_rgb", _f32(rgb)),
        Texture("u_rgl_ndf", _f32(model._ndf[..., None])),
        Texture("u_rgl_sigma", _f32(model._sigma[..., None])),
        Texture("u_rgl_axes", _f32(axes)),
    )
    ints = {"u_rgl_n_phi": n_phi, "u_rgl_n_theta": n_theta, "u_rgl_isotropic": int(model.mitsuba_isotropic),
            "u_rgl_reduction": int(model.reduction), "u_rgl_jacobian": int(model.jacobian)}
    return TableSet("rgl", "rgl.glsl", textures, ints)


def utia_tables(model: Any) -> TableSet:
    """The texture of ``utia.glsl`` for a :class:`~brdfkit.measured.utia.UTIABRDF`:
    ``(θi·48 + φi, θv, φv, rgba)``."""
    tab = np.moveaxis(np.asarray(model.table), 0, -1)  # (θi, φi, θv, φv, 3)
    ti, pi_, tv, pv, _ = tab.shape
    rgba = np.zeros((ti * pi_, tv, pv, 4))
    rgba[..., :3] = tab.reshape(ti * pi_, tv, pv, 3)
    return TableSet("utia", "utia.glsl", (Texture("u_utia", _f32(rgba)),))


_BUILDERS = {"rgl": rgl_tables, "utia": utia_tables}
_SETS = Held(2)  # the table sets of the last two models asked for


def _format_or_error(model: Any) -> str:
    fmt = format_of(model)
    if fmt is None:
        raise ValueError(f"no GLSL table set for {model!r} (only RGL .bsdf and UTIA .bin models have one)")
    return fmt


def _built(model: Any, fmt: str) -> TableSet:
    ts = _BUILDERS[fmt](model)
    for t in ts.textures:
        read_only(t.data)
    return ts


#: the attribute a model's table key is kept in once computed (:func:`brdfkit.render.glsl.table_key` too)
KEY_ATTR = "_bk_table_key"


def kept_key(model: Any, compute: Callable[[], str]) -> str:
    """``model``'s table key, computed once by ``compute()`` and kept on the instance (:data:`KEY_ATTR`)."""
    key = getattr(model, KEY_ATTR, None)
    if key is None:
        key = compute()
        try:
            object.__setattr__(model, KEY_ATTR, key)
        except AttributeError:  # pragma: no cover - a model without a __dict__
            pass
    return key


def table_set(model: Any) -> TableSet:
    """The :class:`TableSet` of an RGL or UTIA model; ``ValueError`` for any other.

    Built once and held (the last two models' sets, keyed by :func:`table_set_key`, which is
    :func:`brdfkit.render.glsl.table_key` for such a model): its arrays are read-only; copy one to change it."""
    fmt = _format_or_error(model)
    key = kept_key(model, lambda: table_set_key(model))  # a model not seen before: its set is built and held
    return _SETS.get(key, lambda: _built(model, fmt))


def table_set_key(model: Any) -> str:
    """The key of an RGL or UTIA model's table set (:func:`brdfkit.render.glsl.table_key` for such a
    model): ``format:`` and a digest of the set's ints and textures. Builds the set and holds it
    under that key, so that :func:`table_set` finds it."""
    ts = _built(model, _format_or_error(model))
    h = hashlib.blake2b(repr(sorted(ts.ints.items())).encode(), digest_size=16)
    for t in ts.textures:
        h.update(repr(t.data.shape).encode())
        h.update(np.ascontiguousarray(t.data))  # the bytes of tobytes(), without copying them
    key = f"{ts.format}:{h.hexdigest()}"
    _SETS.get(key, lambda: ts)
    return key


# ---------------------------------------------------------------------------
# the explorer's transfer format
# ---------------------------------------------------------------------------
def header(ts: TableSet, **extra: Any) -> dict[str, Any]:
    """The JSON header of :func:`pack`: format, shader, ints, and per texture its uniform,
    dims, size, components, unit and byte offset in the data part."""
    rows, offset = [], 0
    for k, t in enumerate(ts.textures):
        rows.append({"uniform": t.uniform, "dims": t.dims, "size": list(t.size), "components": t.components,
                     "unit": FIRST_UNIT + k, "offset": offset})
        offset += t.data.nbytes
    return {"format": ts.format, "shader": ts.shader, "ints": dict(ts.ints), "textures": rows, "bytes": offset, **extra}


def pack(ts: TableSet, **extra: Any) -> bytes:
    """``uint32`` (little-endian) length of a UTF-8 JSON :func:`header` padded with spaces to a
    multiple of 4 bytes, the header, then every texture's float32 data (little-endian, C order)."""
    head = json.dumps(header(ts, **extra), separators=(",", ":"), allow_nan=False).encode("utf-8")
    head += b" " * (-len(head) % 4)
    parts = [np.uint32(len(head)).astype("<u4").tobytes(), head]
    parts += [np.ascontiguousarray(t.data, dtype="<f4").tobytes() for t in ts.textures]
    return b"".join(parts)


def unpack(data: bytes) -> tuple[dict[str, Any], list[np.ndarray]]:
    """The header and the textures' arrays of :func:`pack`'s bytes (for tests)."""
    n = int(np.frombuffer(data[:4], "<u4")[0])
    head = json.loads(data[4:4 + n].decode("utf-8"))
    body = data[4 + n:]
    arrays = []
    for row in head["textures"]:
        shape = tuple(row["size"][::-1]) + (row["components"],)
        count = int(np.prod(shape))
        arrays.append(np.frombuffer(body, "<f4", count=count, offset=row["offset"]).reshape(shape))
    return head, arrays


__all__ = ["Texture", "TableSet", "FIRST_UNIT", "FORMATS", "format_of", "rgl_tables", "utia_tables", "table_set",
           "table_set_key", "kept_key", "read_only", "header", "pack", "unpack"]
