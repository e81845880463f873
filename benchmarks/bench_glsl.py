"""GLSL vs numpy: evaluation throughput and agreement of every model, default parameters.

    .venv/bin/python benchmarks/bench_glsl.py [N]

For N random direction pairs over the upper hemisphere (default 1e6), times
``brdfkit.render.glsl.eval_glsl`` (headless OpenGL, transform feedback; the
first call, which compiles, is timed separately) and ``model.eval`` on float32
input, and prints the largest relative difference of the GLSL result from
numpy float32 and from numpy float64 (same float32 inputs) where |f| > 1e-6.
"""

from __future__ import annotations

import sys
import time

import numpy as np

import brdfkit as bk
from brdfkit.geometry import random_unit_vectors
from brdfkit.render import glsl


def main(n: int = 1_000_000) -> None:
    rng = np.random.default_rng(1)
    wi = random_unit_vectors(n, rng).astype(np.float32)
    wo = random_unit_vectors(n, rng).astype(np.float32)
    print(f"N = {n:,} pairs; GL: {glsl.gl_info()['GL_RENDERER']}")
    head = f"{'model':20s} {'compile+1st (s)':>15s} {'GLSL (s)':>9s} {'GLSL Mpairs/s':>13s} {'numpy32 (s)':>11s} {'rel vs np32':>11s} {'rel vs np64':>11s}"
    print(head)
    print("-" * len(head))
    for name in bk.models():
        if not glsl.has_shader(name):
            print(f"{name:20s} (no GLSL)")
            continue
        m = bk.model(name)
        t0 = time.perf_counter()
        glsl.eval_glsl(m, wi[:16], wo[:16])
        t_first = time.perf_counter() - t0
        t0 = time.perf_counter()
        g = glsl.eval_glsl(m, wi, wo)
        t_gl = time.perf_counter() - t0
        t0 = time.perf_counter()
        f = m.eval(wi, wo)
        t_np = time.perf_counter() - t0
        f64 = m.eval(wi.astype(np.float64), wo.astype(np.float64))
        big = np.abs(f64) > 1e-6
        rel32 = np.max(np.abs(g[big] - f[big]) / np.abs(f64[big])) if big.any() else 0.0
        rel64 = np.max(np.abs(g[big] - f64[big]) / np.abs(f64[big])) if big.any() else 0.0
        print(f"{name:20s} {t_first:15.3f} {t_gl:9.3f} {n / t_gl / 1e6:13.1f} {t_np:11.3f} {rel32:11.2e} {rel64:11.2e}")


if __name__ == "__main__":
    main(int(float(sys.argv[1])) if len(sys.argv) > 1 else 1_000_000)
