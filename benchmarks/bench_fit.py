"""Benchmark: fitting analytic models to measured materials.

    .venv/bin/python benchmarks/bench_fit.py            # one material × five models (a table)
    .venv/bin/python benchmarks/bench_fit.py --batch    # also the whole MERL batch (100 × 5), timed

Prints wall time per fit (default settings of ``brdfkit fit``: 3000 samples,
4 starts, metric ngan), the error, and the evaluations used. Target: one
material with one model in under 30 s on two cores.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import brdfkit as bk
from brdfkit.measured import fit as F

MODELS = (
    ("blinn-phong", {}),
    ("ward", {}),
    ("cook-torrance", {}),
    ("ashikhmin-shirley", {}),
    ("microfacet", {"distribution": "ggx", "fresnel": "schlick"}),
)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--material", default="merl/gold-metallic-paint")
    ap.add_argument("--batch", action="store_true", help="also time the full MERL batch (100 materials × 5 models)")
    ap.add_argument("--out", default="/tmp/brdfkit-bench-batch")
    args = ap.parse_args()

    print(f"cpus available: {len(os.sched_getaffinity(0))}, load average: {os.getloadavg()[0]:.2f}")
    t0 = time.perf_counter()
    data = F.sample(args.material, n=3000)
    print(f"sampling {args.material}: {time.perf_counter() - t0:.2f} s")
    print(f"{'model':<20}{'free values':>12}{'wall s':>9}{'cpu s':>9}{'evals':>8}{'error':>12}")
    for name, fixed in MODELS:
        if name not in bk.models():
            print(f"{name:<20}  (not registered)")
            continue
        w0, c0 = time.perf_counter(), time.process_time()
        r = F.fit(name, args.material, fixed=fixed, data=data)
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        nfree = r.n_free
        print(f"{name:<20}{nfree:>12}{wall:>9.2f}{cpu:>9.2f}{r.nfev:>8}{r.error:>12.5g}")
    if args.batch:
        from brdfkit.measured.commands import measured_names, write_batch

        names = [n for n, _ in MODELS]
        sources = measured_names("merl")
        w0 = time.perf_counter()
        res = F.fit_batch(names, sources, fixed={n: f for n, f in MODELS}, progress=sys.stderr.isatty())
        wall = time.perf_counter() - w0
        write_batch(res, names, sources, args.out, "ngan", wall)
        print(f"MERL batch: {len(sources)} materials × {len(names)} models in {wall:.0f} s "
              f"({wall / (len(sources) * len(names)):.2f} s per fit); tables in {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
