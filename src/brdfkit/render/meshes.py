"""Triangle meshes for the renderer: built-in sphere, torus and Utah teapot; OBJ/PLY through trimesh.

Every mesh carries per-vertex unit normals and unit tangents. The tangent is
the local frame's ``+x`` axis, the anisotropy direction of models such as
Ward's (SPEC.md): on the built-in sphere and torus it runs *around* the
y axis (along the parametric direction φ), on the teapot along the patch
direction that circles the body's axis — so an anisotropic BRDF shows the
"brushed" look of a lathe-turned object. Loaded meshes get the same kind of
tangent generated from their normals: ``normalize(ŷ × n)`` (``x̂ × n`` where
the normal is parallel to ŷ).

All built-in meshes are centred at the origin, y up, and fit in the unit
sphere (the plane excepted: a square of half-size ``half_size``). Lengths are
in scene units.

Limits (a scene file is untrusted input): the tessellation options are
bounded (:data:`TESSELLATION_LIMITS`, at most about a million vertices), and
every mesh is validated when it is built: finite coordinates (at most
:data:`MAX_COORD` in magnitude, so that float32 and the normalisation cannot
overflow), face indices in range, and at least one triangle of non-zero area;
a loaded mesh's zero-area triangles are dropped.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from .. import geometry

BUILTIN = ("sphere", "torus", "teapot", "plane")

TESSELLATION_LIMITS = {
    ("sphere", "segments"): (3, 1024),
    ("sphere", "rings"): (2, 512),
    ("torus", "segments"): (3, 1024),
    ("torus", "sides"): (3, 512),
    ("plane", "divisions"): (1, 1024),
    ("teapot", "subdivisions"): (1, 64),
}
"""Inclusive bounds of the built-in meshes' integer options (sphere: at most 525 825 vertices)."""

SIZE_LIMITS = {
    ("sphere", "radius"): (1e-6, 1e6),
    ("torus", "major"): (1e-6, 1e6),
    ("torus", "minor"): (1e-6, 1e6),
    ("plane", "half_size"): (1e-6, 1e6),
}
"""Inclusive bounds of the built-in meshes' lengths."""

MAX_COORD = 1e30
"""Largest vertex coordinate magnitude accepted (float32 holds 3.4e38; the normalisation squares lengths)."""


def _option_int(mesh: str, name: str, value) -> int:
    """A tessellation option as an int within :data:`TESSELLATION_LIMITS`; one-line ValueError naming it."""
    from ..params import to_float

    lo, hi = TESSELLATION_LIMITS[(mesh, name)]
    what = f"mesh {mesh} option '{name}'"
    f = to_float(value, what)
    if f != int(f):
        raise ValueError(f"{what} must be an integer, got {value!r}")
    if not lo <= f <= hi:
        raise ValueError(f"{what} must be in [{lo}, {hi}], got {int(f)}")
    return int(f)


def _option_length(mesh: str, name: str, value) -> float:
    from ..params import to_float

    lo, hi = SIZE_LIMITS[(mesh, name)]
    what = f"mesh {mesh} option '{name}'"
    f = to_float(value, what)
    if not lo <= f <= hi:
        raise ValueError(f"{what} must be in [{lo:g}, {hi:g}], got {f:g}")
    return f


def triangle_areas(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area of every triangle (float64; 0 for a degenerate one)."""
    P = np.asarray(positions, dtype=np.float64)
    F = np.asarray(faces)
    return 0.5 * np.linalg.norm(np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]]), axis=1)


@dataclass
class Mesh:
    """Indexed triangle mesh: float32 ``positions``/``normals``/``tangents`` (V, 3), int32 ``faces`` (F, 3)."""

    positions: np.ndarray
    normals: np.ndarray
    tangents: np.ndarray
    faces: np.ndarray
    name: str = "mesh"

    def __post_init__(self) -> None:
        try:
            p64 = np.asarray(self.positions, dtype=np.float64)
        except (TypeError, ValueError, OverflowError):
            raise ValueError("mesh positions must be numbers") from None
        if p64.size and (not np.all(np.isfinite(p64)) or np.abs(p64).max() > MAX_COORD):
            raise ValueError(f"mesh {self.name}: vertex coordinates must be finite and at most {MAX_COORD:g} in magnitude")
        self.positions = np.ascontiguousarray(p64, dtype=np.float32)
        self.normals = np.ascontiguousarray(geometry.normalize(np.asarray(self.normals, dtype=np.float64)), dtype=np.float32)
        self.tangents = np.ascontiguousarray(geometry.normalize(np.asarray(self.tangents, dtype=np.float64)), dtype=np.float32)
        self.faces = np.ascontiguousarray(self.faces, dtype=np.int32)
        v = len(self.positions)
        if self.positions.ndim != 2 or self.positions.shape[1] != 3:
            raise ValueError(f"mesh positions must have shape (V, 3), got {self.positions.shape}")
        if self.normals.shape != (v, 3) or self.tangents.shape != (v, 3):
            raise ValueError("mesh normals and tangents must have the shape of the positions")
        if self.faces.ndim != 2 or self.faces.shape[1] != 3 or len(self.faces) == 0:
            raise ValueError(f"mesh faces must have shape (F, 3) with F > 0, got {self.faces.shape}")
        if self.faces.min() < 0 or self.faces.max() >= v:
            raise ValueError(f"mesh {self.name}: faces index vertices that do not exist (valid 0..{v - 1})")
        if not np.any(triangle_areas(self.positions, self.faces) > 0):
            raise ValueError(f"mesh {self.name}: every triangle is degenerate (zero area); nothing to render")
        if not (np.all(np.isfinite(self.normals)) and np.all(np.isfinite(self.tangents))):
            raise ValueError(f"mesh {self.name}: normals and tangents must be finite")

    @property
    def n_triangles(self) -> int:
        return int(len(self.faces))

    @property
    def n_vertices(self) -> int:
        return int(len(self.positions))


def _fit_unit_sphere(P: np.ndarray) -> np.ndarray:
    """Points moved so that their bounding box is centred at the origin, then scaled so that
    the farthest is at distance 1 (left unscaled if they all coincide)."""
    lo, hi = P.min(0), P.max(0)
    P = P - (lo + hi) / 2
    r = np.linalg.norm(P, axis=1).max()
    return P / (r if r > 0 else 1.0)


def _grid_faces(rows: int, cols: int, offset: int = 0) -> np.ndarray:
    """Two triangles per cell of a (rows+1) × (cols+1) vertex grid, counter-clockwise seen from outside."""
    r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    a = r * (cols + 1) + c
    b = a + 1
    d = a + (cols + 1)
    e = d + 1
    tri1 = np.stack([a, d, b], axis=-1).reshape(-1, 3)
    tri2 = np.stack([b, d, e], axis=-1).reshape(-1, 3)
    return np.concatenate([tri1, tri2]) + offset


def sphere(segments: int = 64, rings: int = 32, radius: float = 1.0) -> Mesh:
    """UV sphere about the y axis: ``segments`` around, ``rings`` from pole to pole."""
    segments, rings = _option_int("sphere", "segments", segments), _option_int("sphere", "rings", rings)
    radius = _option_length("sphere", "radius", radius)
    theta = np.linspace(0, np.pi, rings + 1)[:, None]  # from +y
    phi = np.linspace(0, 2 * np.pi, segments + 1)[None, :]
    st, ct = np.sin(theta), np.cos(theta)
    n = np.stack(np.broadcast_arrays(st * np.sin(phi), ct, st * np.cos(phi)), axis=-1).reshape(-1, 3)
    t = np.stack(np.broadcast_arrays(np.cos(phi), 0 * theta, -np.sin(phi)), axis=-1).reshape(-1, 3)
    faces = _grid_faces(rings, segments)
    # drop the zero-area triangles at the poles
    p = n * radius
    area = np.linalg.norm(np.cross(p[faces[:, 1]] - p[faces[:, 0]], p[faces[:, 2]] - p[faces[:, 0]]), axis=1)
    return Mesh(p, n, t, faces[area > 1e-12 * radius * radius], name=f"sphere({segments}x{rings})")


def torus(segments: int = 96, sides: int = 48, major: float = 0.7, minor: float = 0.3) -> Mesh:
    """Torus about the y axis: major radius ``major``, tube radius ``minor``."""
    segments, sides = _option_int("torus", "segments", segments), _option_int("torus", "sides", sides)
    major, minor = _option_length("torus", "major", major), _option_length("torus", "minor", minor)
    u = np.linspace(0, 2 * np.pi, segments + 1)[None, :]  # around y
    v = np.linspace(0, 2 * np.pi, sides + 1)[:, None]  # around the tube
    cu, su, cv, sv = np.cos(u), np.sin(u), np.cos(v), np.sin(v)
    n = np.stack(np.broadcast_arrays(cv * su, sv, cv * cu), axis=-1)
    centre = np.stack(np.broadcast_arrays(major * su, 0 * v, major * cu), axis=-1)
    p = centre + minor * n
    t = np.stack(np.broadcast_arrays(cu, 0 * v, -su), axis=-1)
    faces = _grid_faces(sides, segments)
    # grid rows run along v; make the winding counter-clockwise from outside
    faces = faces[:, ::-1]
    return Mesh(p.reshape(-1, 3), n.reshape(-1, 3), t.reshape(-1, 3), faces, name=f"torus({segments}x{sides})")


def plane(divisions: int = 32, half_size: float = 1.0) -> Mesh:
    """A square in the plane y = 0, normal +y, tangent +x, ``divisions`` cells a side."""
    k = _option_int("plane", "divisions", divisions)
    half_size = _option_length("plane", "half_size", half_size)
    g = np.linspace(-half_size, half_size, k + 1)
    z, x = np.meshgrid(g, g, indexing="ij")  # rows along +z, columns along +x
    p = np.stack([x, np.zeros_like(x), z], axis=-1).reshape(-1, 3)
    n = np.broadcast_to([0.0, 1.0, 0.0], p.shape)
    t = np.broadcast_to([1.0, 0.0, 0.0], p.shape)
    # rows grow along +z and columns along +x: (a, d, b) is counter-clockwise seen from +y
    return Mesh(p, n, t, _grid_faces(k, k), name=f"plane({k})")


def _bernstein(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    s = 1 - t
    b = np.stack([s**3, 3 * t * s**2, 3 * t * t * s, t**3], axis=-1)
    db = np.stack([-3 * s**2, 3 * s**2 - 6 * t * s, 6 * t * s - 3 * t * t, 3 * t * t], axis=-1)
    return b, db


def teapot(subdivisions: int = 12) -> Mesh:
    """Newell's Utah teapot: each of its 32 bicubic Bezier patches tessellated into a grid.

    The patch data is in :mod:`brdfkit.render.teapot_data`. Normals are the
    exact patch normals ``∂P/∂v × ∂P/∂u`` (taken a hair inside the patch where
    a row of control points collapses to a point, as at the lid's knob and the
    bottom's centre). Newell's z-up coordinates are turned y-up, centred and
    scaled into the unit sphere.
    """
    from .teapot_data import PATCHES, VERTICES

    k = _option_int("teapot", "subdivisions", subdivisions)
    cp = np.asarray(VERTICES, dtype=np.float64)
    t = np.linspace(0.0, 1.0, k + 1)
    eps = 1e-4
    ts = np.clip(t, eps, 1 - eps)  # for the degenerate-edge fallback
    b, db = _bernstein(t)
    bs, dbs = _bernstein(ts)
    pos, nrm, tan, faces = [], [], [], []
    for idx in PATCHES:
        C = cp[list(idx)].reshape(4, 4, 3)
        P = np.einsum("ui,vj,ijk->uvk", b, b, C)
        Pu = np.einsum("ui,vj,ijk->uvk", db, b, C)
        Pv = np.einsum("ui,vj,ijk->uvk", b, db, C)
        N = np.cross(Pv, Pu)
        bad = np.linalg.norm(N, axis=-1) < 1e-9
        if bad.any():
            Pu2 = np.einsum("ui,vj,ijk->uvk", dbs, bs, C)
            Pv2 = np.einsum("ui,vj,ijk->uvk", bs, dbs, C)
            N = np.where(bad[..., None], np.cross(Pv2, Pu2), N)
            Pv = np.where((np.linalg.norm(Pv, axis=-1) < 1e-9)[..., None], Pv2, Pv)
        faces.append(_grid_faces(k, k, offset=sum(len(x) for x in pos)))
        pos.append(P.reshape(-1, 3))
        nrm.append(N.reshape(-1, 3))
        tan.append(Pv.reshape(-1, 3))
    P = np.concatenate(pos)
    N = np.concatenate(nrm)
    T = np.concatenate(tan)
    F = np.concatenate(faces)
    # z-up -> y-up: (x, y, z) -> (x, z, -y) (a rotation, keeps handedness)
    rot = lambda a: np.stack([a[:, 0], a[:, 2], -a[:, 1]], axis=-1)  # noqa: E731
    P, N, T = rot(P), rot(N), rot(T)
    P = _fit_unit_sphere(P)
    # orient the winding like the normals
    e = np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])
    flip = np.einsum("ij,ij->i", e, N[F].sum(axis=1)) < 0
    F[flip] = F[flip][:, ::-1]
    area = np.linalg.norm(e, axis=1)
    return Mesh(P, N, T, F[area > 1e-14], name=f"teapot({k})")


def generated_tangents(normals: np.ndarray) -> np.ndarray:
    """Tangents circling the y axis: ``normalize(ŷ × n)``, or ``x̂ × n`` where n ∥ ŷ."""
    n = geometry.normalize(np.asarray(normals, dtype=np.float64))
    t = np.cross(np.array([0.0, 1.0, 0.0]), n)
    weak = np.linalg.norm(t, axis=1) < 1e-3
    if weak.any():
        t[weak] = np.cross(np.array([1.0, 0.0, 0.0]), n[weak])
    return geometry.normalize(t)


def _read_trimesh(path: str):
    """``trimesh.load`` of ``path``; OBJ text is decoded here (UTF-8, else Latin-1), so that a stray
    non-UTF-8 byte (a comment, a material name) does not send trimesh looking for an optional
    charset detector."""
    import io

    import trimesh

    ext = os.path.splitext(path)[1].lower().lstrip(".")
    if ext == "obj":
        raw = open(path, "rb").read()
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError:
            text = raw.decode("latin-1")  # every byte is a character: geometry lines are ASCII anyway
        with np.errstate(all="ignore"):  # huge coordinates overflow in trimesh's merging: checked after
            return trimesh.load(io.BytesIO(text.encode("utf-8")), file_type="obj", force="mesh", process=True)
    try:
        with np.errstate(all="ignore"):
            return trimesh.load(path, force="mesh", process=True)
    except ModuleNotFoundError as e:
        if "charset" in str(e):
            raise ValueError("the file is text but not UTF-8; save it as UTF-8 (or ASCII)") from None
        raise


def load_mesh(path: str | os.PathLike, normalize: bool = True) -> Mesh:
    """An OBJ/PLY/STL/... file through trimesh; smooth vertex normals if the file has none.

    ``normalize`` centres the mesh's bounding box at the origin and scales it so that
    its farthest vertex is at distance 1. Zero-area triangles are dropped; a file
    whose coordinates are not finite (or beyond :data:`MAX_COORD`), or whose
    triangles all have zero area, is a one-line ``ValueError``.
    """
    import trimesh

    if not isinstance(path, (str, os.PathLike)):
        raise ValueError(f"mesh path must be a string, got {path!r}")
    path = os.fspath(path)
    if not os.path.exists(path):
        raise OSError(f"mesh file not found: {path}")
    if os.path.isdir(path):
        raise ValueError(f"mesh path {path} is a folder, not a file")
    try:
        tm = _read_trimesh(path)
    except Exception as e:  # trimesh raises many kinds
        msg = str(e).strip().splitlines()
        raise ValueError(f"cannot read mesh {path}: {msg[0] if msg else type(e).__name__}") from None
    if not isinstance(tm, trimesh.Trimesh) or len(tm.faces) == 0:
        raise ValueError(f"{path} holds no triangles")
    P = np.asarray(tm.vertices, dtype=np.float64)
    F = np.asarray(tm.faces, dtype=np.int64)
    name = os.path.basename(path)
    if P.ndim != 2 or P.shape[1] != 3 or len(P) == 0 or F.ndim != 2 or F.shape[1] != 3:
        raise ValueError(f"mesh {name}: malformed vertices or faces (shapes {P.shape} and {F.shape}); each vertex needs x y z")
    if not np.all(np.isfinite(P)) or np.abs(P).max() > MAX_COORD:
        raise ValueError(f"mesh {name}: vertex coordinates must be finite and at most {MAX_COORD:g} in magnitude")
    if F.min() < 0 or F.max() >= len(P):
        raise ValueError(f"mesh {name}: faces index vertices that do not exist")
    if normalize:
        P = _fit_unit_sphere(P)
    area = triangle_areas(P.astype(np.float32), F)  # as the renderer will see them (float32)
    keep = area > 0
    if not keep.any():
        raise ValueError(f"mesh {name}: every triangle is degenerate (zero area); nothing to render")
    with np.errstate(all="ignore"):
        N = np.array(tm.vertex_normals, dtype=np.float64)  # a copy: trimesh caches a read-only array
    bad = ~np.isfinite(N).all(axis=1) | (np.linalg.norm(np.nan_to_num(N), axis=1) < 1e-12)
    if bad.any():  # vertices only on dropped triangles, or cancelling normals: area-weighted face normals
        fn = np.cross(P[F[keep, 1]] - P[F[keep, 0]], P[F[keep, 2]] - P[F[keep, 0]])
        acc = np.zeros_like(P)
        for j in range(3):
            np.add.at(acc, F[keep, j], fn)
        ok = np.linalg.norm(acc, axis=1) > 0
        fix = bad & ok
        N[fix] = acc[fix]
        N[bad & ~ok] = (0.0, 1.0, 0.0)  # a vertex no kept triangle uses: never drawn
    return Mesh(P, N, generated_tangents(N), F[keep], name=name)


def builtin(name: str, **kwargs: Any) -> Mesh:
    """A built-in mesh by name (``sphere``, ``torus``, ``teapot``, ``plane``) with its keyword options."""
    makers = {"sphere": sphere, "torus": torus, "teapot": teapot, "plane": plane}
    if not isinstance(name, str) or name not in makers:
        raise ValueError(f"unknown built-in mesh {name!r}; valid: {', '.join(BUILTIN)} (or an OBJ/PLY path)")
    valid = [k for (m, k) in (*TESSELLATION_LIMITS, *SIZE_LIMITS) if m == name]
    extra = sorted(set(kwargs) - set(valid))
    if extra:
        raise ValueError(f"mesh {name}: unknown option(s) {', '.join(map(str, extra))}; valid: {', '.join(valid)}")
    return makers[name](**kwargs)


def mesh_from_spec(spec: Any) -> Mesh:
    """A mesh from a scene file's ``mesh``: a built-in name, a path, or ``{"builtin": name, ...options}`` /
    ``{"path": file}``."""
    if isinstance(spec, Mesh):
        return spec
    if isinstance(spec, str):
        if spec in BUILTIN:
            return builtin(spec)
        return load_mesh(spec)
    if isinstance(spec, Mapping):
        spec = dict(spec)
        if "builtin" in spec:
            name = spec.pop("builtin")
            return builtin(name, **spec)
        if "path" in spec:
            extra = sorted(set(spec) - {"path", "normalize"})
            if extra:
                raise ValueError(f"mesh with 'path': unknown field(s) {', '.join(map(str, extra))}; valid: path, normalize")
            if not isinstance(spec["path"], str) or not spec["path"]:
                raise ValueError(f"mesh 'path' must be a file name (a string), got {spec['path']!r}")
            norm = spec.get("normalize", True)
            if not isinstance(norm, bool):
                raise ValueError(f"mesh 'normalize' must be true or false, got {norm!r}")
            return load_mesh(spec["path"], normalize=norm)
    raise ValueError(
        f"mesh must be a built-in name ({', '.join(BUILTIN)}), a file path, or an object with 'builtin' or 'path'; got {spec!r}"
    )
