"""Time the interchange paths: a .brdf model's eval (GLSL through OpenGL) against the built-in
numpy model it spells, loading a .brdf file, and each export format.

    .venv/bin/python benchmarks/bench_interchange.py [--quick]

Prints pairs per second and seconds; nothing is asserted. ``--quick`` skips the measured
materials.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import brdfkit as bk
from brdfkit.interchange.brdf_explorer import _CLASS_CACHE

DATA = Path(__file__).resolve().parents[1] / "tests" / "data"


def _pairs(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2, n, 3))
    v[..., 2] = np.abs(v[..., 2]) + 1e-3
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    return v[0], v[1]


def _best(f, repeat: int = 3) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    quick = "--quick" in sys.argv
    _CLASS_CACHE.clear()
    t = time.perf_counter()
    cls = bk.registry.get(str(DATA / "ward.brdf"))
    print(f"load + compile ward.brdf: {time.perf_counter() - t:.3f} s (first GL use included)")
    file_model = cls(kd=0.3, ks=0.2, alpha_x=0.15, alpha_y=0.4)
    ours = bk.model("ward", kd=0.3, ks=0.2, alpha_x=0.15, alpha_y=0.4)
    print(f"{'pairs':>9} {'.brdf (GLSL) pairs/s':>22} {'numpy ward pairs/s':>20} {'ratio':>7}")
    for n in (1_000, 100_000, 1_000_000):
        wi, wo = _pairs(n)
        file_model.eval(wi, wo)  # warm
        tg = _best(lambda: file_model.eval(wi, wo))
        tn = _best(lambda: ours.eval(wi, wo))
        print(f"{n:>9} {n / tg:>22.3g} {n / tn:>20.3g} {tn / tg:>7.2f}")
    sources = [("microfacet gold", bk.model("microfacet", alpha=0.2)), ("ward", bk.model("ward"))]
    if not quick:
        sources.append(("merl/gold-metallic-paint", bk.material("merl/gold-metallic-paint")))
    print(f"\n{'source':<26} {'format':<10} {'method':<7} {'rel. error':>10} {'seconds':>8}")
    with tempfile.TemporaryDirectory() as tmp:
        for label, m in sources:
            for fmt, ext in (("mitsuba", "xml"), ("materialx", "mtlx"), ("gltf", "glb")):
                t = time.perf_counter()
                r = bk.export(m, fmt, Path(tmp) / f"x.{ext}")
                dt = time.perf_counter() - t
                err = "exact" if r.exact else f"{100 * r.relative_error:.1f} %"
                print(f"{label:<26} {fmt:<10} {r.method:<7} {err:>10} {dt:8.2f}")


if __name__ == "__main__":
    main()
