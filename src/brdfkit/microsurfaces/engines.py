"""Ray-mesh intersection engines for the microsurface tracer: Mitsuba 3's own ``ray_intersect``.

Both engines answer the same question for a batch of rays in a tile's base frame: the distance
``t < maxt`` to the first triangle hit and that triangle's index (or no hit).

* ``"mitsuba-llvm"`` — Mitsuba 3's ``llvm_ad_rgb`` variant: the whole batch in one vectorised
  ``Scene.ray_intersect_preliminary`` (Embree-class BVH traversal, all cores).
* ``"mitsuba-scalar"`` — Mitsuba 3's ``scalar_rgb`` variant, one ray per call from Python: the
  fallback where no LLVM is available, and the baseline of ``benchmarks/bench_microsurface.py``.
* ``"embree"`` — Intel Embree through the maintained ``embreex`` binding (``pip install
  'brdfkit[measure-embree]'``; the binding trimesh uses), one ``rtcIntersect`` batch per call.

Mitsuba is an optional dependency (``pip install brdfkit[measure]``). Mitsuba has one active
variant per process; each call switches to its variant and back (other parts of brdfkit use
``scalar_rgb``).
"""

from __future__ import annotations

from contextlib import contextmanager, nullcontext

import numpy as np

from .surfaces import Tile

ENGINES = ("mitsuba-llvm", "mitsuba-scalar", "embree")
_VARIANT = {"mitsuba-llvm": "llvm_ad_rgb", "mitsuba-scalar": "scalar_rgb"}


def _mitsuba():
    try:
        import mitsuba as mi
    except ImportError:
        raise ValueError("microsurface tracing needs Mitsuba 3: pip install 'brdfkit[measure]'") from None
    return mi


@contextmanager
def _variant(name: str):
    mi = _mitsuba()
    old = mi.variant()
    if old != name:
        try:
            mi.set_variant(name)
        except Exception as e:  # noqa: BLE001 -- Mitsuba raises ImportError/AttributeError by build
            raise ValueError(f"Mitsuba variant {name!r} is not available here ({e})") from None
    try:
        yield mi
    finally:
        if old and old != name:
            mi.set_variant(old)


def _embreex():
    try:
        from embreex import mesh_construction, rtcore_scene
    except ImportError:
        raise ValueError("the 'embree' microsurface engine needs the embreex binding: pip install 'brdfkit[measure-embree]'") from None
    return mesh_construction, rtcore_scene


def available(engine: str) -> bool:
    """Whether ``engine`` can run here (Mitsuba installed and its variant loadable, or embreex)."""
    if engine == "embree":
        try:
            _embreex()
            return True
        except ValueError:
            return False
    try:
        with _variant(_VARIANT[engine]) as mi:
            mi.Float(1.0)
        return True
    except (ValueError, KeyError):
        return False


class MitsubaEngine:
    """One tile as a Mitsuba mesh scene; :meth:`intersect` traces batches of rays against it."""

    def __init__(self, tile: Tile, engine: str = "mitsuba-llvm") -> None:
        if engine not in _VARIANT:
            raise ValueError(f"unknown microsurface engine {engine!r}; valid: {', '.join(ENGINES)}")
        self.engine = engine
        self.variant = _VARIANT[engine]
        with _variant(self.variant) as mi:
            mesh = mi.Mesh("microsurface", len(tile.vertices), len(tile.faces),
                           has_vertex_normals=False, has_vertex_texcoords=False)
            params = mi.traverse(mesh)
            # the buffers' own types: Float/UInt32 in vectorised variants, dynamic arrays in scalar ones
            vtype, ftype = type(params["vertex_positions"]), type(params["faces"])
            params["vertex_positions"] = vtype(np.ascontiguousarray(tile.vertices, np.float32).ravel())
            params["faces"] = ftype(np.ascontiguousarray(tile.faces, np.uint32).ravel())
            params.update()
            self.scene = mi.load_dict({"type": "scene", "surface": mesh})

    def session(self):
        """A context in which this engine's variant stays active (a switch costs ~0.1 s: hold it
        over a whole trace rather than switching at every :meth:`intersect`)."""
        return _variant(self.variant)

    def intersect(self, o: np.ndarray, d: np.ndarray, maxt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(t, face)`` of the first hits of rays ``o + t d``, ``t < maxt``; ``face = -1`` where none."""
        with _variant(self.variant) as mi:  # free when a session() already holds the variant
            if self.engine == "mitsuba-llvm":
                return self._batch(mi, o, d, maxt)
            return self._one_by_one(mi, o, d, maxt)

    def _batch(self, mi, o, d, maxt):
        o32, d32 = np.asarray(o, np.float32), np.asarray(d, np.float32)
        ray = mi.Ray3f(mi.Point3f(*(mi.Float(o32[:, c]) for c in range(3))),
                       mi.Vector3f(*(mi.Float(d32[:, c]) for c in range(3))))
        ray.maxt = mi.Float(np.asarray(maxt, np.float32))
        pi = self.scene.ray_intersect_preliminary(ray, coherent=False)
        import drjit as dr

        dr.eval(pi.t, pi.prim_index)  # one kernel for both (read one by one, each would trace again)
        t = pi.t.numpy().astype(np.float64)
        hit = np.isfinite(t) & (t < np.asarray(maxt))
        face = np.where(hit, pi.prim_index.numpy().astype(np.int64), -1)
        return t, face

    def _one_by_one(self, mi, o, d, maxt):
        n = len(o)
        t = np.full(n, np.inf)
        face = np.full(n, -1, dtype=np.int64)
        for r in range(n):
            ray = mi.Ray3f(mi.Point3f(*map(float, o[r])), mi.Vector3f(*map(float, d[r])))
            ray.maxt = float(maxt[r])
            pi = self.scene.ray_intersect_preliminary(ray)
            if pi.is_valid():
                t[r], face[r] = float(pi.t), int(pi.prim_index)
        return t, face


class EmbreeEngine:
    """One tile as an Embree scene (embreex); same :meth:`intersect` as :class:`MitsubaEngine`."""

    engine = "embree"

    def session(self):
        """Nothing to hold (see :meth:`MitsubaEngine.session`)."""
        return nullcontext()

    def __init__(self, tile: Tile) -> None:
        mesh_construction, rtcore_scene = _embreex()
        self.scene = rtcore_scene.EmbreeScene()
        self._mesh = mesh_construction.TriangleMesh(self.scene, np.ascontiguousarray(tile.vertices, np.float32),
                                                    np.ascontiguousarray(tile.faces, np.int32))

    def intersect(self, o: np.ndarray, d: np.ndarray, maxt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(t, face)`` of the first hits of rays ``o + t d``, ``t < maxt``; ``face = -1`` where none."""
        maxt = np.asarray(maxt, np.float64)
        far = np.where(np.isfinite(maxt), maxt, 3.0e38).astype(np.float32)
        r = self.scene.run(np.ascontiguousarray(o, np.float32), np.ascontiguousarray(d, np.float32),
                           dists=far, output=1)
        face = r["primID"].astype(np.int64)
        t = np.where(face >= 0, r["tfar"].astype(np.float64), np.inf)
        hit = (face >= 0) & (t < maxt)
        return t, np.where(hit, face, -1)


def make_engine(tile: Tile, engine: str):
    """The intersection engine ``engine`` (one of :data:`ENGINES`) for ``tile``."""
    if engine == "embree":
        return EmbreeEngine(tile)
    return MitsubaEngine(tile, engine)
