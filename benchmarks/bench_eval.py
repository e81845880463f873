"""Evaluation throughput of every registered model: the compiled engine beside the reference.

    .venv/bin/python benchmarks/bench_eval.py            # rich table
    .venv/bin/python benchmarks/bench_eval.py --json     # JSON list on stdout
    .venv/bin/python benchmarks/bench_eval.py --models ward,phong --log2n 18 --repeat 5

Per model, at default parameters, on the same random direction pairs (uniform over
the upper hemisphere):

* compiled engine (``bk.set_engine("compiled")``, numba, all cores), float64 and
  float32: one batched ``m.eval(wi, wo)`` on 2^20 pairs (``--log2n``), best of
  ``--repeat`` timed calls after a warm-up call (which also loads or compiles the
  kernel), in millions of evaluations per second (wall clock);
* one-pair latency of the compiled engine: the median over 2000 calls of
  ``m.eval(wi[0], wo[0])`` (float64, shape (3,)), in microseconds — the whole
  Python call, argument checks included;
* reference engine (``bk.set_engine("reference")``: the same kernel source run
  uncompiled, pair by pair in Python), float64, on 2^10 pairs (``--ref-log2n``);
* the ratio compiled/reference, and the ratio to the numpy implementation that
  preceded the engine (its float64/float32 figures measured with this script on
  2026-11-22, kept in :data:`NUMPY_BEFORE`).

The float64 CPU rate (evaluations per CPU second of the process, all threads) counts, on
numba's TBB threading layer, the moment its workers spin after a call before they sleep: it
reads lower than on workqueue for the same kernel (docs/speed.md, "Threads").

The machine's load average is printed with the table: on the shared 2-core
development machine figures vary by ±30 % from run to run, and those taken on a
busy machine are lower bounds.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time

import numpy as np

#: Meval/s of the numpy implementation before the engine (float64, float32), 2^20 pairs,
#: best of 3, measured 2026-11-22 on the development machine while quiet (load 0.0-0.4).
NUMPY_BEFORE = {
    "lambert": (96.16, 106.25),
    "phong": (16.73, 32.05),
    "blinn-phong": (11.24, 15.32),
    "microfacet": (2.52, 3.54),
    "cook-torrance": (3.37, 3.90),
    "oren-nayar": (8.13, 15.10),
    "ward": (8.05, 10.38),
    "schlick": (6.42, 8.11),
    "htsg": (0.36, 0.44),
    "ashikhmin-shirley": (5.73, 7.74),
}


def directions(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    from brdfkit.geometry import random_unit_vectors

    rng = np.random.default_rng(seed)
    return random_unit_vectors(n, rng), random_unit_vectors(n, rng)


def _timed(m, wi, wo) -> tuple[float, float]:
    w0, c0 = time.perf_counter(), time.process_time()
    m.eval(wi, wo)
    return time.perf_counter() - w0, time.process_time() - c0


def time_eval(m, wi, wo, repeat: int, budget_s: float = 5.0, warm: bool = True) -> tuple[float, float]:
    """Best wall time and best CPU time (this process) of up to ``repeat`` calls after an untimed warm-up.

    The warm-up loads (or compiles) the kernel; at least one timed call is made,
    more until ``repeat`` or ``budget_s`` seconds of timed calls.
    """
    if warm:
        m.eval(wi[:64], wo[:64])
        m.eval(wi, wo)
    best_wall = best_cpu = float("inf")
    spent = 0.0
    for _ in range(repeat):
        wall, cpu = _timed(m, wi, wo)
        best_wall, best_cpu = min(best_wall, wall), min(best_cpu, cpu)
        spent += wall
        if spent > budget_s:
            break
    return best_wall, best_cpu


def one_pair_us(m, wi, wo, calls: int = 2000) -> float:
    """Median wall time of one ``m.eval`` of a single pair, microseconds."""
    a, b = wi[0].copy(), wo[0].copy()
    m.eval(a, b)
    ts = []
    for _ in range(calls):
        t0 = time.perf_counter()
        m.eval(a, b)
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts) * 1e6


def run(models: list[str], n: int, repeat: int, n_ref: int = 1024, progress: bool = True) -> list[dict]:
    import brdfkit as bk

    wi64, wo64 = directions(n)
    wi32, wo32 = wi64.astype(np.float32), wo64.astype(np.float32)
    rows = []
    from rich.progress import Progress

    old = bk.engine()
    try:
        with Progress(transient=True, disable=not progress, console=_stderr_console()) as bar:
            task = bar.add_task("benchmarking", total=4 * len(models))
            for name in models:
                m = bk.model(name)
                row = {"model": name, "n": n, "n_reference": n_ref}
                bk.set_engine("compiled")
                for tag, (wi, wo) in (("float64", (wi64, wo64)), ("float32", (wi32, wo32))):
                    bar.update(task, description=f"{name} compiled {tag}")
                    wall, cpu = time_eval(m, wi, wo, repeat)
                    row[f"{tag}_seconds"] = wall
                    row[f"{tag}_evals_per_s"] = n / wall
                    row[f"{tag}_cpu_seconds"] = cpu
                    row[f"{tag}_evals_per_cpu_s"] = n / cpu if cpu > 0 else None
                    before = NUMPY_BEFORE.get(name)
                    k = 0 if tag == "float64" else 1
                    row[f"{tag}_vs_numpy_before"] = (n / wall / 1e6 / before[k]) if before else None
                    bar.advance(task)
                bar.update(task, description=f"{name} one pair")
                row["one_pair_us"] = one_pair_us(m, wi64, wo64)
                bar.advance(task)
                bk.set_engine("reference")
                bar.update(task, description=f"{name} reference")
                m.eval(wi64[:8], wo64[:8])  # warm-up: the reference's own one-time setup (rebuilt functions, the unit check)
                wall, _ = time_eval(m, wi64[:n_ref], wo64[:n_ref], 1, budget_s=0.0, warm=False)
                row["reference_float64_evals_per_s"] = n_ref / wall
                row["compiled_vs_reference_float64"] = row["float64_evals_per_s"] / row["reference_float64_evals_per_s"]
                bar.advance(task)
                rows.append(row)
    finally:
        bk.set_engine(old)
    return rows


def _load() -> str:
    try:
        return ", ".join(f"{x:.1f}" for x in os.getloadavg())
    except OSError:
        return "n/a"


def _stderr_console():
    from rich.console import Console

    return Console(stderr=True)


def main(argv: list[str] | None = None) -> int:
    import brdfkit as bk

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--log2n", type=int, default=20, help="number of direction pairs is 2^LOG2N (default 20)")
    ap.add_argument("--repeat", type=int, default=3, help="timed calls per model and dtype; the best counts")
    ap.add_argument("--models", default="", help="comma-separated registry names (default: every model)")
    ap.add_argument("--ref-log2n", type=int, default=10, help="pairs for the (slow) reference engine: 2^N (default 10)")
    ap.add_argument("--json", action="store_true", help="print a JSON list instead of the table")
    a = ap.parse_args(argv)
    if not 4 <= a.log2n <= 26:
        ap.error("--log2n must lie in [4, 26]")
    if a.repeat < 1:
        ap.error("--repeat must be >= 1")
    names = [s.strip() for s in a.models.split(",") if s.strip()] or bk.models()
    for s in names:
        if s not in bk.models():
            ap.error(f"unknown model {s!r}; valid models: {', '.join(bk.models())}")

    if not 4 <= a.ref_log2n <= 20:
        ap.error("--ref-log2n must lie in [4, 20]")
    rows = run(names, 2**a.log2n, a.repeat, n_ref=2**a.ref_log2n, progress=not a.json)
    if a.json:
        print(json.dumps(rows, indent=2))
        return 0

    from rich.console import Console
    from rich.table import Table

    import numba

    t = Table(
        title=f"brdfkit eval throughput: compiled engine on 2^{a.log2n} pairs (best of {a.repeat}), "
        f"reference on 2^{a.ref_log2n}, default parameters, Meval/s",
        title_justify="left",
        caption=f"numpy {np.__version__}, numba {numba.__version__} ({numba.get_num_threads()} threads), "
        f"Python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} CPUs, load average {_load()}; "
        "x numpy = compiled / the numpy implementation before the engine (NUMPY_BEFORE)",
        caption_justify="left",
    )
    for col in ("model", "compiled f64", "compiled f32", "one pair µs", "reference f64",
                "compiled/ref", "f64 x numpy", "f32 x numpy", "f64 CPU Meval/s"):
        t.add_column(col, justify="left" if col == "model" else "right", no_wrap=True)

    def mev(x):
        return "n/a" if x is None else f"{x / 1e6:.3g}"

    def ratio(x):
        return "n/a" if x is None else f"{x:.3g}x"

    for r in rows:
        t.add_row(
            r["model"],
            mev(r["float64_evals_per_s"]),
            mev(r["float32_evals_per_s"]),
            f"{r['one_pair_us']:.1f}",
            mev(r["reference_float64_evals_per_s"]),
            ratio(r["compiled_vs_reference_float64"]),
            ratio(r["float64_vs_numpy_before"]),
            ratio(r["float32_vs_numpy_before"]),
            mev(r["float64_evals_per_cpu_s"]),
        )
    Console(width=max(150, Console().width)).print(t)
    return 0


if __name__ == "__main__":
    sys.exit(main())
