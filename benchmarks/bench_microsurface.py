"""Ray-tracing engines for the virtual gonioreflectometer (brdfkit.microsurfaces), rays per second.

    .venv/bin/python benchmarks/bench_microsurface.py            # table
    .venv/bin/python benchmarks/bench_microsurface.py --log2n 20 --resolution 512

Candidates (``brdfkit.microsurfaces.engines``), on the same Beckmann (α = 0.5) tile of
``2 × resolution²`` triangles:

* ``mitsuba-llvm``: Mitsuba 3's ``llvm_ad_rgb`` ``Scene.ray_intersect_preliminary``, one batch;
* ``embree``: Intel Embree via ``embreex`` (if importable), one batch;
* ``mitsuba-scalar``: Mitsuba 3's ``scalar_rgb``, one Python call per ray (2^12 rays only).

Printed per engine: *first hits* (a batch of rays from above, numpy in and out — what the tracer
asks of an engine) and *paths* (whole light paths from θi = 60°, every inter-reflection and the
periodic wrap-around, numpy bookkeeping included), the median of ``--calls`` calls, and the ratio
to Mitsuba llvm in the same run; plus whether the engines agree on the triangles hit. Last, the
rays a MERL-resolution isotropic table (90 θh × 90 θd × 180 φd bins) needs for a stated median
per-bin noise, extrapolated from the bin counts of a measured run, and the time that takes at
the measured path rate. On a shared machine read the ratios rather than the absolute rates.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from brdfkit.microsurfaces import microsurface
from brdfkit.microsurfaces.engines import available, make_engine


def _rays(tile, n, rng, theta=np.radians(40.0)):
    lx, ly = tile.size
    o = np.stack([rng.uniform(0, lx, n), rng.uniform(0, ly, n), np.full(n, tile.zmax + 1.0)], -1)
    phi = rng.uniform(0, 2 * np.pi, n)
    d = -np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.full(n, np.cos(theta))], -1)
    return o, d, np.full(n, np.inf)


def _median_time(fn, calls):
    fn()  # warm-up (Dr.Jit kernel compilation, scene build caches)
    ts = []
    for _ in range(calls):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    return statistics.median(ts)


def merl_cells(wi, wo):
    """MERL (Rusinkiewicz) bin of each (wi, wo) pair: θh (90, sqrt spacing), θd (90), φd (180)."""
    h = wi + wo
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    th = np.arccos(np.clip(h[:, 2], -1, 1))
    ph = np.arctan2(h[:, 1], h[:, 0])
    # rotate wi so that h is the pole: the difference vector
    c, s = np.cos(-ph), np.sin(-ph)
    x = c * wi[:, 0] - s * wi[:, 1]
    y = s * wi[:, 0] + c * wi[:, 1]
    z = wi[:, 2]
    ct, st = np.cos(-th), np.sin(-th)
    dx, dz = ct * x + st * z, -st * x + ct * z
    td = np.arccos(np.clip(dz, -1, 1))
    pd = np.arctan2(y, dx) % np.pi
    i = np.minimum((np.sqrt(th / (np.pi / 2)) * 90).astype(int), 89)
    j = np.minimum((td / (np.pi / 2) * 90).astype(int), 89)
    k = np.minimum((pd / np.pi * 180).astype(int), 179)
    return (i * 90 + j) * 180 + k


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--log2n", type=int, default=18, help="rays per batch (2^n)")
    ap.add_argument("--resolution", type=int, default=512)
    ap.add_argument("--calls", type=int, default=3)
    ap.add_argument("--noise", type=float, default=0.05, help="median per-bin relative noise of the MERL table")
    a = ap.parse_args()
    n = 2**a.log2n
    s = microsurface("beckmann", alpha=0.5, resolution=a.resolution)
    tile = s.tile
    rng = np.random.default_rng(0)
    o, d, mt = _rays(tile, n, rng)
    print(f"tile: {len(tile.faces):,} triangles; batch 2^{a.log2n} = {n:,} rays; median of {a.calls} calls")
    rows, faces = [], {}
    for name in ("mitsuba-llvm", "embree", "mitsuba-scalar"):
        if not available(name):
            print(f"{name:15s} not available here")
            continue
        t0 = time.perf_counter()
        eng = make_engine(tile, name)
        build = time.perf_counter() - t0
        m = n if name != "mitsuba-scalar" else min(n, 2**12)
        t_hit = _median_time(lambda: eng.intersect(o[:m], d[:m], mt[:m]), a.calls)
        faces[name] = eng.intersect(o[:m], d[:m], mt[:m])[1]
        sp = microsurface("beckmann", alpha=0.5, resolution=a.resolution, engine=name)
        mp = m // 4
        wi = np.array([np.sin(np.radians(60)), 0.0, np.cos(np.radians(60))])
        t_path = _median_time(lambda: sp.shoot(wi, mp), a.calls)
        rows.append((name, build, m / t_hit, mp / t_path))
    base = {r[0]: r for r in rows}.get("mitsuba-llvm")
    print(f"{'engine':15s} {'build s':>8s} {'first hits/s':>14s} {'paths/s':>12s} {'hits vs llvm':>13s} {'paths vs llvm':>14s}")
    for name, build, hit, path in rows:
        rh = hit / base[2] if base else float("nan")
        rp = path / base[3] if base else float("nan")
        print(f"{name:15s} {build:8.2f} {hit:14,.0f} {path:12,.0f} {rh:13.3f} {rp:14.3f}")
    if "mitsuba-llvm" in faces:
        ref = faces["mitsuba-llvm"]
        for name, f in faces.items():
            if name != "mitsuba-llvm":
                print(f"{name} hits the same triangle as mitsuba-llvm for {np.mean(f == ref[:len(f)]):.5f} of the rays")
    # MERL-resolution isotropic table: bin counts of a measured run, extrapolated
    fast = max(rows, key=lambda r: r[3])
    sp = microsurface("beckmann", alpha=0.5, resolution=a.resolution, engine=fast[0])
    n_wi, per = 64, max(n // 64, 256)
    counts = np.zeros(90 * 90 * 180)
    total = 0
    for u in (np.arange(n_wi) + 0.5) / n_wi:  # wi cosine-distributed in θ (azimuth irrelevant: isotropic)
        wi = np.array([np.sqrt(u), 0.0, np.sqrt(1 - u)])
        p = sp.shoot(wi, per)
        ok = p.status == 0
        np.add.at(counts, merl_cells(np.broadcast_to(wi, (ok.sum(), 3)).copy(), p.wo[ok]), 1)
        total += per
    filled = counts[counts > 0]
    need = total * (1.0 / a.noise**2) / np.median(filled)
    print(f"MERL table: {np.mean(counts > 0):.1%} of the 1,458,000 bins reached by {total:,} paths; "
          f"median noise {a.noise:.0%} per reached bin needs ~{need:.3g} paths "
          f"= ~{need / fast[3] / 3600:.1f} h at {fast[0]}'s {fast[3]:,.0f} paths/s (extrapolated, this machine)")


if __name__ == "__main__":
    main()
