"""Evaluation throughput of every registered model, float64 and float32.

    .venv/bin/python benchmarks/bench_eval.py            # rich table
    .venv/bin/python benchmarks/bench_eval.py --json     # JSON list on stdout
    .venv/bin/python benchmarks/bench_eval.py --models ward,phong --log2n 18 --repeat 5

Each model is evaluated at its default parameters on the same 2^20 (by
default) random direction pairs, uniform over the upper hemisphere, in one
batched ``m.eval(wi, wo)`` call; the figure is pairs per second of the best of
``--repeat`` timed calls after one warm-up call (a model whose warm-up call
takes more than 5 s is timed by that call alone). Wall-clock throughput is the
headline; throughput per second of this process's CPU time (user + system) is
shown too, since it is less disturbed by other processes on a shared machine.
Plain numpy, no threads beyond what numpy itself uses. The machine's load
average is printed with the table: figures taken on a busy machine are lower
bounds.

Measured 2026-11-22 on the development machine while quiet (2 vCPUs AMD EPYC, numpy 2.4.6,
Python 3.11.7, load average 0.0-0.4), 2^20 pairs, best of 3, millions of evaluations per second:

    model               float64  float32
    lambert               96.16   106.25
    phong                 16.73    32.05
    blinn-phong           11.24    15.32
    microfacet             2.52     3.54
    cook-torrance          3.37     3.90
    oren-nayar             8.13    15.10
    ward                   8.05    10.38
    schlick                6.42     8.11
    htsg                   0.36     0.44
    ashikhmin-shirley      5.73     7.74
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time

import numpy as np


def directions(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    from brdfkit.geometry import random_unit_vectors

    rng = np.random.default_rng(seed)
    return random_unit_vectors(n, rng), random_unit_vectors(n, rng)


def _timed(m, wi, wo) -> tuple[float, float]:
    w0, c0 = time.perf_counter(), time.process_time()
    m.eval(wi, wo)
    return time.perf_counter() - w0, time.process_time() - c0


def time_eval(m, wi, wo, repeat: int, budget_s: float = 5.0) -> tuple[float, float]:
    """Best wall time and best CPU time (this process) of up to ``repeat`` calls after a warm-up.

    A slow model (a warm-up call longer than ``budget_s``) is not repeated: its
    warm-up call is the measurement, so the whole benchmark stays within minutes.
    """
    wall, cpu = _timed(m, wi, wo)
    if wall > budget_s:
        return wall, cpu
    best_wall = best_cpu = float("inf")
    spent = 0.0
    for _ in range(repeat):
        wall, cpu = _timed(m, wi, wo)
        best_wall, best_cpu = min(best_wall, wall), min(best_cpu, cpu)
        spent += wall
        if spent > budget_s:
            break
    return best_wall, best_cpu


def run(models: list[str], n: int, repeat: int, progress: bool = True) -> list[dict]:
    import brdfkit as bk

    wi64, wo64 = directions(n)
    wi32, wo32 = wi64.astype(np.float32), wo64.astype(np.float32)
    rows = []
    from rich.progress import Progress

    with Progress(transient=True, disable=not progress, console=_stderr_console()) as bar:
        task = bar.add_task("benchmarking", total=2 * len(models))
        for name in models:
            m = bk.model(name)
            row = {"model": name, "n": n}
            for tag, (wi, wo) in (("float64", (wi64, wo64)), ("float32", (wi32, wo32))):
                bar.update(task, description=f"{name} {tag}")
                wall, cpu = time_eval(m, wi, wo, repeat)
                row[f"{tag}_seconds"] = wall
                row[f"{tag}_evals_per_s"] = n / wall
                row[f"{tag}_cpu_seconds"] = cpu
                row[f"{tag}_evals_per_cpu_s"] = n / cpu if cpu > 0 else None
                bar.advance(task)
            rows.append(row)
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

    rows = run(names, 2**a.log2n, a.repeat, progress=not a.json)
    if a.json:
        print(json.dumps(rows, indent=2))
        return 0

    from rich.console import Console
    from rich.table import Table

    t = Table(
        title=f"brdfkit eval throughput: 2^{a.log2n} direction pairs, default parameters, best of {a.repeat}",
        title_justify="left",
        caption=f"numpy {np.__version__}, Python {platform.python_version()}, {platform.machine()}, "
        f"{os.cpu_count()} CPUs, load average {_load()}",
        caption_justify="left",
    )
    t.add_column("model", no_wrap=True)
    t.add_column("float64 Meval/s", justify="right")
    t.add_column("float32 Meval/s", justify="right")
    t.add_column("float64 ms/call", justify="right")
    t.add_column("float32 ms/call", justify="right")
    t.add_column("float64 CPU Meval/s", justify="right")
    t.add_column("float32 CPU Meval/s", justify="right")

    def mev(x):
        return "n/a" if x is None else f"{x / 1e6:.2f}"

    def ms(seconds):
        v = seconds * 1e3
        return f"{v:.0f}" if v >= 10 else f"{v:.3g}"

    for r in rows:
        t.add_row(
            r["model"],
            mev(r["float64_evals_per_s"]),
            mev(r["float32_evals_per_s"]),
            ms(r["float64_seconds"]),
            ms(r["float32_seconds"]),
            mev(r["float64_evals_per_cpu_s"]),
            mev(r["float32_evals_per_cpu_s"]),
        )
    Console(width=max(150, Console().width)).print(t)
    return 0


if __name__ == "__main__":
    sys.exit(main())
