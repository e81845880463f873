"""Time `brdfkit check`: one check per model, and `check --all` (the table) with 1 and 2 workers.

    .venv/bin/python benchmarks/bench_check.py [--quick]

Prints wall-clock seconds, the CPU seconds of the run (user + system, all its processes; less
disturbed by other load on a shared machine than the wall clock) and the load average before each run. The target (issue 9) is
`check --all --json --jobs 2` under 3 s wall with a warm numba cache; each `check --all`
configuration runs twice, so that the second run is warm. `--quick` skips the single-worker run
and the per-model timings.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import brdfkit as bk
from brdfkit.analysis import check, stress_settings


def per_model() -> None:
    """One check per model at level normal, timed, and their sum."""
    print(f"{'model':<20} {'level':<7} {'seconds':>8} {'max albedo':>11} {'±err':>8}")
    total = 0.0
    for name in bk.models():
        t = time.perf_counter()
        r = check(bk.model(name), level="normal")
        dt = time.perf_counter() - t
        total += dt
        print(f"{name:<20} {'normal':<7} {dt:8.2f} {r['max_albedo']:11.5f} {r['integration_error']:8.0e}")
    print(f"{'(sum)':<20} {'':<7} {total:8.2f}")


def main() -> None:
    quick = "--quick" in sys.argv
    if not quick:
        per_model()
    n_checks = sum(len(stress_settings(n)) for n in bk.models())
    exe = Path(sys.executable).with_name("brdfkit")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "brdfkit"]
    print()
    print(f"check --all: {n_checks} checks (defaults + stress), {os.cpu_count()} CPUs visible")
    for jobs in ([2] if quick else [1, 2]):
        for _ in range(2):
            load = os.getloadavg()[0]
            t = time.perf_counter()
            r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            p = subprocess.run(cmd + ["check", "--all", "--json", "--jobs", str(jobs)], capture_output=True, text=True)
            dt = time.perf_counter() - t
            r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
            status = "ok" if p.returncode == 0 else f"exit {p.returncode}: {p.stderr.strip()[:80]}"
            print(f"  --jobs {jobs}: {dt:6.2f} s wall, {cpu:5.2f} s CPU  (load {load:.2f} before; {status})")


if __name__ == "__main__":
    main()
