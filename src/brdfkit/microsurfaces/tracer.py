"""Tracing light through a periodic microsurface tile: masking, shadowing, every inter-reflection.

Rays live in the tile's base frame (:mod:`brdfkit.microsurfaces.surfaces`). A ray that leaves the
tile through a side re-enters through the opposite side (the surface is periodic, so this is the
same as an infinite surface); one that rises through the plane ``z = zmax`` can meet nothing more
and has left the surface. At a hit, the ray reflects specularly about the triangle's normal (in
the world frame), its weight multiplied by the facet's Fresnel reflectance at the local angle of
incidence, and goes on from the hit point nudged off the facet.

A ray that is still inside after ``max_bounces`` reflections, that wraps around more than
``MAX_WRAPS`` times without meeting anything, or that reaches a facet from below (a crack at
float32 precision) is *lost*; the results count lost rays and never hide them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..geometry import dot, reflect
from .engines import MitsubaEngine
from .surfaces import Scales, Tile

MAX_WRAPS = 4000
#: offset of a ray's origin off the facet it left, in units of the tile's extent
EPS_REL = 2e-6


def _box_exit(tile: Tile, zmax: float, o: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance to where the ray leaves the tile's box and through which face (0: x, 1: y, 2: top)."""
    lx, ly = tile.size
    with np.errstate(divide="ignore", invalid="ignore"):
        tx = np.where(d[:, 0] > 0, (lx - o[:, 0]) / d[:, 0], np.where(d[:, 0] < 0, -o[:, 0] / d[:, 0], np.inf))
        ty = np.where(d[:, 1] > 0, (ly - o[:, 1]) / d[:, 1], np.where(d[:, 1] < 0, -o[:, 1] / d[:, 1], np.inf))
        tz = np.where(d[:, 2] > 0, (zmax - o[:, 2]) / d[:, 2], np.inf)
    t = np.stack([tx, ty, tz], axis=-1)
    side = np.argmin(t, axis=-1)
    return np.maximum(t[np.arange(len(o)), side], 0.0), side


def propagate(engine: MitsubaEngine, tile: Tile, o: np.ndarray, d: np.ndarray):
    """Follow rays (base frame) through the periodic tile to their first hit or out through the top.

    Returns ``(p, face, status)``: the hit point (or exit point), the triangle hit (−1 if none), and
    ``status`` 1 = hit, 0 = escaped through the top, −1 = lost (wrapped ``MAX_WRAPS`` times).
    """
    lx, ly = tile.size
    zmax = tile.zmax
    p = np.array(o, dtype=np.float64)
    face = np.full(len(p), -1, dtype=np.int64)
    status = np.full(len(p), -1, dtype=np.int8)
    todo = np.arange(len(p))
    for _ in range(MAX_WRAPS):
        if len(todo) == 0:
            break
        po, dd = p[todo], d[todo]
        tb, side = _box_exit(tile, zmax, po, dd)
        t, f = engine.intersect(po, dd, tb)
        hit = f >= 0
        stuck = ~hit & ~np.isfinite(tb)  # straight down and through a crack: nothing ahead, lost
        pn = po + np.where(hit, t, np.where(stuck, 0.0, tb))[:, None] * dd
        top = ~hit & ~stuck & (side == 2)
        wrap = ~hit & ~stuck & ~top
        # re-enter through the opposite side exactly (no drift through the modulo)
        wx = wrap & (side == 0)
        wy = wrap & (side == 1)
        pn[wx, 0] = np.where(dd[wx, 0] > 0, 0.0, lx)
        pn[wy, 1] = np.where(dd[wy, 1] > 0, 0.0, ly)
        p[todo] = pn
        face[todo[hit]] = f[hit]
        status[todo[hit]] = 1
        status[todo[top]] = 0
        todo = todo[wrap]
    return p, face, status


@dataclass
class Paths:
    """What happened to a batch of rays: world exit directions, RGB weights, bounce counts, status.

    ``status`` 0 = left the surface, −1 = lost. ``bounces`` counts reflections (0: never hit,
    which a ray arriving from above cannot do).
    """

    wo: np.ndarray
    weight: np.ndarray
    bounces: np.ndarray
    status: np.ndarray
    points: list | None = None  # base-frame vertices of each path, when recorded


def trace(engine: MitsubaEngine, tile: Tile, scales: Scales, o: np.ndarray, w_world: np.ndarray,
          fresnel: Callable[[np.ndarray], np.ndarray], max_bounces: int, record: bool = False) -> Paths:
    """Trace rays from base-frame points ``o`` travelling along world directions ``w_world`` until they leave.

    ``fresnel(cos)`` gives the facet reflectance ``(n, 3)`` at local incidence cosines ``(n,)``.
    """
    n = len(o)
    eps = EPS_REL * max(*tile.size, tile.zmax - tile.zmin)
    p = np.array(o, dtype=np.float64)
    w = np.array(w_world, dtype=np.float64)
    weight = np.ones((n, 3))
    bounces = np.zeros(n, dtype=np.int64)
    status = np.full(n, -1, dtype=np.int8)
    points = [[row.copy()] for row in p] if record else None
    todo = np.arange(n)
    for _ in range(max_bounces + 1):
        if len(todo) == 0:
            break
        sc = scales.take(todo)
        d = sc.to_base_dir(w[todo])
        ph, face, st = propagate(engine, tile, p[todo], d)
        if record:
            for k, r in enumerate(todo):
                points[r].append(ph[k].copy())
        status[todo[st == 0]] = 0
        hit = st == 1
        idx = todo[hit]
        if len(idx) == 0:
            todo = idx
            break
        nb = tile.normals[face[hit]]
        from_below = dot(d[hit], nb) > 0
        nw = sc.take(hit).world_normal(nb)
        wi = w[idx]
        cos = np.clip(-dot(wi, nw), 0.0, 1.0)
        w[idx] = reflect(-wi, nw)  # geometry's reflect takes the direction toward the light, not of travel
        weight[idx] *= fresnel(cos)
        bounces[idx] += 1
        p[idx] = ph[hit] + eps * nb
        keep = ~from_below & (bounces[idx] <= max_bounces)
        todo = idx[keep]
    # still inside after max_bounces reflections, or entered a crack: lost (status stays -1)
    status[todo] = -1
    if record:
        points = [np.array(q) for q in points]
    return Paths(w, weight, bounces, status, points)
