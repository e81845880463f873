"""Evaluations per second of the HTSG model, against `microfacet` (and `lambert` as the floor).

    .venv/bin/python benchmarks/bench_htsg.py [--n 200000] [--repeat 5] [--threads N]

Random direction pairs, uniform over the upper hemisphere, float64, one RGB value per pair
(HTSG: three wavelengths, three series). Each configuration is timed `repeat` times,
interleaved with the microfacet reference so that load on a shared machine affects both
alike; the best time counts. The ratio column is HTSG time / microfacet time for the
same batch (the issue's bound: at most 20). ``--threads`` sets numba's thread count (default:
numba's); with ``--threads 1`` the process's CPU time is timed instead of the wall clock, which
other load on a shared machine disturbs much less.
"""

from __future__ import annotations

import argparse
import time

import numba
import numpy as np
from rich.console import Console
from rich.table import Table

import brdfkit as bk
from brdfkit.geometry import random_unit_vectors

CONFIGS = [
    ("htsg aluminium σ0=0.18 τ=3 (default)", "htsg", {}),
    ("htsg σ0=0.38 τ=3", "htsg", {"sigma0": 0.38}),
    ("htsg σ0=0.8 τ=3", "htsg", {"sigma0": 0.8}),
    ("htsg σ0=2 τ=10 (large g: asymptotic form)", "htsg", {"sigma0": 2.0, "tau": 10.0}),
    ("htsg dielectric n=1.5 σ0=0.18 kd=0.5", "htsg", {"eta": 1.5, "k": 0.0, "kd": 0.5}),
]
REFERENCE = ("microfacet beckmann/smith/conductor", "microfacet", {"distribution": "beckmann", "fresnel": "conductor"})
FLOOR = ("lambert", "lambert", {})


_clock = time.perf_counter


def _best(model, wi, wo, repeat):
    best = np.inf
    for _ in range(repeat):
        t0 = _clock()
        model.eval(wi, wo)
        best = min(best, _clock() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200_000, help="direction pairs per batch")
    ap.add_argument("--repeat", type=int, default=5, help="timed repetitions (best counts)")
    ap.add_argument("--threads", type=int, default=0, help="numba threads (0: numba's default)")
    args = ap.parse_args()
    global _clock
    if args.threads > 0:
        numba.set_num_threads(args.threads)
    if numba.get_num_threads() == 1:
        _clock = time.process_time
    rng = np.random.default_rng(0)
    wi = random_unit_vectors(args.n, rng)
    wo = random_unit_vectors(args.n, rng)
    ref = bk.model(REFERENCE[1], **REFERENCE[2])
    ref.eval(wi[:100], wo[:100])  # warm up

    title = f"evaluations per second, {args.n} random pairs, float64, best of {args.repeat}, {numba.get_num_threads()} threads" + (
        ", CPU time" if _clock is time.process_time else ""
    )
    table = Table(title=title)
    table.add_column("model")
    table.add_column("evals/s", justify="right")
    table.add_column("µs/eval", justify="right")
    table.add_column("× microfacet time", justify="right")
    for label, name, params in [FLOOR, REFERENCE, *CONFIGS]:
        m = bk.model(name, **params)
        m.eval(wi[:100], wo[:100])
        t_model, t_ref = np.inf, np.inf
        for _ in range(args.repeat):  # interleave with the reference
            t_model = min(t_model, _best(m, wi, wo, 1))
            t_ref = min(t_ref, _best(ref, wi, wo, 1))
        table.add_row(label, f"{args.n / t_model:,.0f}", f"{1e6 * t_model / args.n:.3f}", f"{t_model / t_ref:.1f}")
    Console().print(table)


if __name__ == "__main__":
    main()
