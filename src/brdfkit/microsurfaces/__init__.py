"""A virtual gonioreflectometer: BRDFs measured by tracing light through explicit microsurfaces.

The microfacet formulas (Smith's masking G1 = 1/(1 + Λ), the V-groove G, the single-scattering
BRDF ``F D G / (4 |n·wi| |n·wo|)``) describe the reflection of a *surface*; here that surface is
built (:mod:`.surfaces`) and light is traced through it with Mitsuba 3's ray intersection
(:mod:`.engines`, :mod:`.tracer`), as Heitz 2014 ("Understanding the Masking-Shadowing Function
in Microfacet-Based BRDFs", JCGT 3(2)) and Heitz, Hanika, d'Eon & Dachsbacher 2016
("Multiple-Scattering Microfacet BSDFs with the Smith Model", SIGGRAPH) did to check them.

Estimators (all with their standard errors)
-------------------------------------------
* ``masking(wo)`` — G1(wo) as Heitz 2014 defines it (eq. 2): the visible fraction of the
  projected area of the facets that face ``wo``. Points are drawn uniformly over the macro
  surface (each carries the projected area ``(wo·m)⁺ / (n·m)`` of its facet per unit macro area)
  and a ray is traced from each toward ``wo``; ``G1 = Σ area·escaped / Σ area`` (a ratio
  estimator; its standard error by the delta method).
* ``albedo(wi)`` — rays arrive from ``wi`` uniformly over the macro surface and are traced until
  they leave (uniform over the macro surface, the rays carry equal shares of the irradiance); the
  directional albedo is the mean weight (Fresnel products) that leaves, split by the number of
  reflections.
* ``measure(wi, wo)`` — the same rays, binned: the BRDF averaged over a cone of half-angle
  ``radius`` around ``wo`` is ``(Σ weight in the cone / N) / ∫_cone cos θ dω`` (the reflected
  flux fraction is ``f cos θo dω``; the rays' uniform spread over the macro area already is the
  irradiance, so no cos θi). The cone
  is a bias of second order in ``radius`` (smaller cones, more noise).

The parameters of :func:`microsurface` are tabled in :class:`Microsurface`'s text.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from ..memo import Held
from ..models.microfacet import Microfacet, fresnel_term
from . import surfaces as _surf
from .engines import ENGINES, MitsubaEngine, available, make_engine
from .surfaces import Tile
from .tracer import EPS_REL, Paths, propagate, trace

KINDS = ("v-groove", "beckmann", "ggx")
CORR_CELLS = 6.0  # correlation length of the random tiles, in grid cells

#: tiles and engines kept between calls, the ``_KEEP`` most recently used of each (a 512² tile and its
#: engine's scene are tens of MB); keyed by the tile's parameters, so an equal tile finds its engine
_KEEP = 4
_TILES = Held(_KEEP)
_ENGINES = Held(_KEEP)


class Estimate(NamedTuple):
    """A Monte Carlo estimate and its standard error (same shapes)."""

    value: np.ndarray
    stderr: np.ndarray


class Albedo(NamedTuple):
    """Directional albedo from one ``wi``: ``total`` (3,), ``by_bounce`` (K + 1, 3) for 1..K
    reflections and "more than K" last, their standard errors, and the fraction of rays lost."""

    total: np.ndarray
    total_stderr: np.ndarray
    by_bounce: np.ndarray
    by_bounce_stderr: np.ndarray
    lost: float


def _unit_rows(w, what: str) -> np.ndarray:
    w = np.asarray(w, dtype=np.float64)
    if w.shape[-1:] != (3,):
        raise ValueError(f"microsurface: {what} must have shape (..., 3); got {w.shape}")
    n = np.linalg.norm(w, axis=-1, keepdims=True)
    if not np.all(np.isfinite(w)) or np.any(n == 0):
        raise ValueError(f"microsurface: {what} must be finite, non-zero directions")
    return w / n


def _int_param(name: str, value: Any, lo: int) -> int:
    try:
        v = int(value)
    except (TypeError, ValueError):
        raise ValueError(f"microsurface: '{name}' must be an integer; got {value!r}") from None
    if v != float(value) or v < lo:
        raise ValueError(f"microsurface: '{name}' must be an integer >= {lo}; got {value!r}")
    return v


class Microsurface:
    """An explicit microsurface and its simulated masking, albedo and BRDF (see the module text).

    ``microsurface(kind, **params)`` makes one; every parameter but ``kind`` is a keyword with a default:

    ===========  ======  ============  =========================  =======  ======================================
    parameter    kind    default       range                      unit     meaning
    ===========  ======  ============  =========================  =======  ======================================
    kind         choice  (required)    v-groove | beckmann | ggx  —        the construction: V-grooves, or a
                                                                           Gaussian heightfield (Beckmann or GGX)
    alpha        scalar  0.2           [0.001, 1]                 —        roughness (Beckmann RMS slope / GGX
                                                                           width); sets alpha_x = alpha_y; not
                                                                           for v-groove
    alpha_x      scalar  0.2           [0.001, 1]                 —        roughness along the tangent +x
    alpha_y      scalar  0.2           [0.001, 1]                 —        roughness along the bitangent +y
    angle        scalar  30            (0, 90)                    degrees  V-groove facet angle from the macro
                                                                           normal (v-groove only)
    fresnel      choice  white         white | conductor |        —        the facets' reflectance: ``white``
                                       dielectric | schlick                (F = 1, also ``none``) or microfacet's
                                                                           Fresnel with ``eta``, ``k``, ``f0``
    eta          rgb     gold          [0.01, 10]                 —        real part of the facets' index
                                                                           (conductor, dielectric)
    k            rgb     gold          [0, 20]                    —        imaginary part (conductor only)
    f0           rgb     gold's        [0, 1]                     —        normal-incidence reflectance (schlick)
    resolution   int     512           16 or more                 cells    grid cells per side of the random
                                                                           tile (beckmann, ggx)
    seed         int     0             0 or more                  —        the random tile and the rays
    engine       choice  mitsuba-llvm  mitsuba-llvm |             —        what intersects the rays
                                       mitsuba-scalar | embree             (:mod:`.engines`)
    max_bounces  int     64            1 or more                  —        reflections after which a ray counts
                                                                           as lost
    ===========  ======  ============  =========================  =======  ======================================
    """

    def __init__(self, kind: str, **params: Any) -> None:
        if kind not in KINDS:
            raise ValueError(f"unknown microsurface kind {kind!r}; valid: {', '.join(KINDS)}")
        self.kind = kind
        p = dict(params)
        self.resolution = _int_param("resolution", p.pop("resolution", 512), 16)
        self.seed = _int_param("seed", p.pop("seed", 0), 0)
        self.max_bounces = _int_param("max_bounces", p.pop("max_bounces", 64), 1)
        self.engine_name = p.pop("engine", "mitsuba-llvm")
        if self.engine_name not in ENGINES:
            raise ValueError(f"unknown microsurface engine {self.engine_name!r}; valid: {', '.join(ENGINES)}")
        self.angle = float(p.pop("angle", 30.0)) if kind == "v-groove" else None
        if kind == "v-groove" and not 0.0 < self.angle < 90.0:
            raise ValueError(f"v-groove: angle must be in (0, 90) degrees; got {self.angle!r}")
        if kind == "v-groove" and any(a in p for a in ("alpha", "alpha_x", "alpha_y")):
            raise ValueError("v-groove: takes 'angle' (degrees), not a roughness alpha")
        fresnel = p.pop("fresnel", "white")
        if fresnel == "white":
            fresnel = "none"
        dist = "ggx" if kind == "v-groove" else kind
        # the facet material and roughness are validated as microfacet validates them
        self._facet = Microfacet(distribution=dist, fresnel=fresnel, **p)
        self.alpha_x = float(self._facet.params["alpha_x"])
        self.alpha_y = float(self._facet.params["alpha_y"])
        self._rng = np.random.default_rng([self.seed, 1])

    # -- the surface -------------------------------------------------------------------
    @property
    def _tile_key(self) -> tuple:
        """The parameters that determine the tile (the same key, the same tile)."""
        return ("v-groove", self.angle) if self.kind == "v-groove" else ("gauss", self.resolution, self.seed)

    @property
    def tile(self) -> Tile:
        if self.kind == "v-groove":
            return _TILES.get(self._tile_key, lambda: _surf.v_groove(self.angle))
        return _TILES.get(self._tile_key, lambda: _surf.gaussian_field(self.resolution, CORR_CELLS, self.seed))

    @property
    def engine(self) -> MitsubaEngine:
        return _ENGINES.get(self._tile_key + (self.engine_name,), lambda: make_engine(self.tile, self.engine_name))

    def scales(self, n: int) -> _surf.Scales:
        """Base → world maps for ``n`` rays (a fresh mixture weight per ray for GGX)."""
        return _surf.scales_for(self.kind, n, self.alpha_x, self.alpha_y, self._rng)

    def model(self, shadowing: str = "smith-correlated"):
        """The analytic ``microfacet`` model with this surface's distribution and facet Fresnel."""
        if self.kind == "v-groove":
            raise ValueError("v-groove: a single groove angle has no microfacet distribution D")
        return self._facet.with_params(shadowing=shadowing)

    def fresnel(self, cos: np.ndarray) -> np.ndarray:
        """The facets' reflectance ``(n, 3)`` at local incidence cosines ``cos``."""
        return fresnel_term(self._facet.params["fresnel"], cos, self._facet.params, np.float64)

    # -- estimators --------------------------------------------------------------------
    def masking(self, wo, samples: int = 20000) -> Estimate:
        """Simulated G1(wo), shape ``wo.shape[:-1]`` (see the module text)."""
        wo = _unit_rows(wo, "wo")
        samples = _int_param("samples", samples, 2)
        flat = wo.reshape(-1, 3)
        val, err = np.empty(len(flat)), np.empty(len(flat))
        with self.engine.session():
            for r, w in enumerate(flat):
                val[r], err[r] = self._masking_one(w, samples)
        return Estimate(val.reshape(wo.shape[:-1]), err.reshape(wo.shape[:-1]))

    def _masking_one(self, wo: np.ndarray, n: int) -> tuple[float, float]:
        if wo[2] <= 0:
            return 0.0, 0.0
        tile, rng = self.tile, self._rng
        lx, ly = tile.size
        x, y = rng.uniform(0, lx, n), rng.uniform(0, ly, n)
        z, face = tile.locate(x, y)
        sc = self.scales(n)
        nb = tile.normals[face]
        nw = sc.world_normal(nb)
        area = np.maximum(nw @ wo, 0.0) / nw[:, 2]  # projected area toward wo per unit macro area
        front = np.nonzero(area > 0)[0]
        escaped = np.zeros(n)
        if len(front):
            eps = EPS_REL * max(lx, ly, tile.zmax - tile.zmin)
            o = np.stack([x[front], y[front], z[front]], axis=-1) + eps * nb[front]
            d = sc.take(front).to_base_dir(np.broadcast_to(wo, (len(front), 3)))
            _, _, st = propagate(self.engine, tile, o, d)
            escaped[front] = st == 0
        g = np.sum(area * escaped) / np.sum(area)
        u = area * escaped - g * area
        se = np.std(u, ddof=1) / (np.sqrt(n) * np.mean(area))
        return float(g), float(se)

    def shoot(self, wi: np.ndarray, n: int, record: bool = False) -> Paths:
        """Trace ``n`` rays arriving from direction ``wi`` (unit, ``wi_z > 0``) uniformly over the tile."""
        tile, rng = self.tile, self._rng
        lx, ly = tile.size
        o = np.stack([rng.uniform(0, lx, n), rng.uniform(0, ly, n), np.full(n, tile.zmax)], axis=-1)
        with self.engine.session():
            return trace(self.engine, tile, self.scales(n), o, np.broadcast_to(-wi, (n, 3)), self.fresnel,
                         self.max_bounces, record=record)

    def albedo(self, wi, bounces: int = 3, samples: int = 100000) -> Albedo | list[Albedo]:
        """Directional albedo from ``wi`` split into 1..``bounces`` reflections and the rest."""
        wi = _unit_rows(wi, "wi")
        bounces = _int_param("bounces", bounces, 1)
        samples = _int_param("samples", samples, 2)
        out = [self._albedo_one(w, bounces, samples) for w in wi.reshape(-1, 3)]
        return out[0] if wi.ndim == 1 else out

    def _albedo_one(self, wi, k: int, n: int) -> Albedo:
        if wi[2] <= 0:
            raise ValueError("microsurface: wi must be above the surface (wi_z > 0)")
        paths = self.shoot(wi, n)
        ok = (paths.status == 0)[:, None]
        contrib = paths.weight * ok
        orders = np.minimum(paths.bounces, k + 1)
        split = np.stack([contrib * (orders == b)[:, None] for b in range(1, k + 2)])  # (k+1, n, 3)
        se = lambda a: np.std(a, axis=-2, ddof=1) / np.sqrt(n)  # noqa: E731
        return Albedo(contrib.mean(0), se(contrib), split.mean(1), se(split), float(np.mean(paths.status != 0)))

    def table(self, n_theta: int = 24, n_u: int = 48, n_phi: int = 48, samples: int = 200000,
              bounces: int | None = None, progress=None):
        """The whole simulated BRDF as a model (:class:`~brdfkit.microsurfaces.table.SimulatedTable`):
        ``samples`` paths from each of ``n_theta`` incident angles, binned (see :mod:`.table`).
        ``progress``: a callable ``step(done)`` called after each incident angle."""
        from .table import simulate

        return simulate(self, n_theta, n_u, n_phi, samples, bounces, progress)

    def measure(self, wi, wo, samples: int = 200000, bounces: int | None = None, radius: float = 0.05) -> Estimate:
        """Simulated BRDF (1/sr, no cosine) at ``(wi, wo)`` pairs, shape ``(..., 3)`` like ``m.eval``.

        ``bounces`` None counts every path; an integer k only paths with exactly k reflections.
        Rays are traced once per distinct ``wi`` (``samples`` of them) and binned in a cone of
        half-angle ``radius`` (radians) around each ``wo``.
        """
        wi, wo = _unit_rows(wi, "wi"), _unit_rows(wo, "wo")
        samples = _int_param("samples", samples, 2)
        if bounces is not None:
            bounces = _int_param("bounces", bounces, 1)
        if not 0.0 < float(radius) < 0.5:
            raise ValueError(f"microsurface: radius must be in (0, 0.5) radians; got {radius!r}")
        wi, wo = np.broadcast_arrays(wi, wo)
        shape = wi.shape[:-1]
        fi, fo = wi.reshape(-1, 3), wo.reshape(-1, 3)
        val, err = np.zeros((len(fi), 3)), np.zeros((len(fi), 3))
        uniq, inv = np.unique(fi, axis=0, return_inverse=True)
        cos_r = np.cos(radius)
        for u, w in enumerate(uniq):
            rows = np.nonzero(inv.ravel() == u)[0]
            if w[2] <= 0:
                continue
            paths = self.shoot(w, samples)
            keep = paths.status == 0
            if bounces is not None:
                keep &= paths.bounces == bounces
            wts = paths.weight * keep[:, None]
            for r in rows:
                o = fo[r]
                if o[2] <= 0:
                    continue
                in_cone = (paths.wo @ o) >= cos_r
                norm = cone_cosine_integral(o, radius)
                x = wts * in_cone[:, None] / norm
                val[r], err[r] = x.mean(0), x.std(0, ddof=1) / np.sqrt(samples)
        return Estimate(val.reshape(shape + (3,)), err.reshape(shape + (3,)))


def cone_cosine_integral(o: np.ndarray, radius: float, n: int = 64) -> float:
    """``∫ max(cos θ, 0) dω`` over the cone of half-angle ``radius`` around unit ``o`` (quadrature).

    Above the horizon it is ``2π (1 − cos r) o_z`` exactly (cos θ is linear in ω, the cone is
    symmetric about ``o``); a cone that crosses the horizon is integrated numerically.
    """
    if o[2] >= np.sin(radius):
        return 2.0 * np.pi * (1.0 - np.cos(radius)) * o[2]
    # midpoint rule in (cone angle, azimuth) around o
    t = (np.arange(n) + 0.5) / n * radius
    p = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * np.pi
    tt, pp = np.meshgrid(t, p, indexing="ij")
    a = np.array([1.0, 0.0, 0.0]) if abs(o[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(o, a)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(o, e1)
    cz = np.cos(tt) * o[2] + np.sin(tt) * (np.cos(pp) * e1[2] + np.sin(pp) * e2[2])
    return float(np.sum(np.maximum(cz, 0.0) * np.sin(tt)) * (radius / n) * (2 * np.pi / (2 * n)))


def microsurface(kind: str, **params: Any) -> Microsurface:
    """An explicit microsurface ``kind`` (``"v-groove"``, ``"beckmann"``, ``"ggx"``); :class:`Microsurface`'s text
    tables the parameters (meaning, range, unit, default)."""
    return Microsurface(kind, **params)


__all__ = ["microsurface", "Microsurface", "Estimate", "Albedo", "KINDS", "ENGINES", "available",
           "cone_cosine_integral"]
