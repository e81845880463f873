"""Wall time of one-shot `brdfkit` commands beside the floor of the tools they run on.

    .venv/bin/python benchmarks/bench_cli.py [--rounds 7]

Issue 9 asks for `brdfkit eval` < 1 s and one `brdfkit fit merl/gold-metallic-paint --model
microfacet` < 1 s wall. A fresh process pays the interpreter, numpy, numba (its import and, at the
first call of a compiled function, its target's initialisation, even for a function loaded from its
disk cache) and, for a fit, ``scipy.optimize`` before any of brdfkit's work. This script times, each
in its own fresh process, the rounds alternating:

* ``python -c pass``, ``import numpy``;
* ``numba floor``: ``import numba`` and one call of a trivial ``@njit(cache=True)`` function loaded from
  its disk cache (the least a process that runs one compiled kernel pays), with numba's BLAS probe
  held back as the ``brdfkit`` command holds it back (``engine.skip_blas_probe``), and as numba does
  by default (the probe imports all of ``scipy.linalg``);
* ``numba + scipy.optimize floor``: the same and ``import scipy.optimize`` (the least a fit paid while
  ``scipy.optimize.least_squares`` solved every fit; a fit with a model's exact Jacobian is now solved by
  ``brdfkit.measured.trust_region`` and imports no scipy, a fit without one, of a ``.brdf`` file's GLSL,
  still does);
* the commands: ``brdfkit eval``, ``brdfkit fit`` (both with brdfkit's numba cache and Python's
  bytecode cache warm: each command runs once before the rounds, without ``PYTHONDONTWRITEBYTECODE``).

It prints the medians and each command's time above its floor (what brdfkit's own imports and work
cost): the fit's above both floors, the numba one (what it pays now) and the numba + scipy.optimize
one (issue 31's goal is stated against it). Tests never assert on time; on a shared machine read the medians of the same run side by side.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

NUMBA_FLOOR = """
import numba
{probe}
@numba.njit(cache=True)
def one(x):
    return x + 1.0

one(1.0)
"""

#: what ``brdfkit.engine.skip_blas_probe`` does for the console script (numba's BLAS probe would import
#: all of scipy.linalg at the first compiled call), without importing brdfkit
SKIP_PROBE = """
import sys
sys.modules["scipy.linalg"] = None
import numba.np.arraymath
del sys.modules["scipy.linalg"]
"""


def _brdfkit() -> list[str]:
    exe = Path(sys.executable).with_name("brdfkit")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "brdfkit"]


def _wall(cmd: list[str], env: dict[str, str]) -> float:
    t = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    dt = time.perf_counter() - t
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: exit {p.returncode}: {p.stderr.strip()[-200:]}")
    return dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=7, help="fresh processes per row (default 7)")
    args = ap.parse_args()
    if args.rounds < 1:
        raise SystemExit("--rounds must be at least 1")
    with tempfile.TemporaryDirectory(prefix="bench_cli_") as tmp:
        floor = Path(tmp) / "numba_floor.py"
        floor.write_text(NUMBA_FLOOR.format(probe=SKIP_PROBE))
        floor_probe = Path(tmp) / "numba_probe_floor.py"
        floor_probe.write_text(NUMBA_FLOOR.format(probe=""))
        floor_scipy = Path(tmp) / "numba_scipy_floor.py"
        floor_scipy.write_text(NUMBA_FLOOR.format(probe="") + "import scipy.optimize\n")
        # as an installed package runs: with its modules' bytecode cached (pip writes it at install; an
        # editable install writes it at the first import). A machine that sets PYTHONDONTWRITEBYTECODE
        # (this project's development host does) would otherwise compile brdfkit's sources in every
        # process, 50-60 ms of each command here; the warm-up below writes the cache.
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env_floor = dict(env, NUMBA_CACHE_DIR=str(Path(tmp) / "numba-cache"))
        py = sys.executable
        bk = _brdfkit()
        floor_name = "numba floor (BLAS probe skipped, as brdfkit's command does)"
        fit_floor_name = "numba + scipy.optimize floor"
        rows = [
            ("python -c pass", [py, "-c", "pass"], env, None),
            ("import numpy", [py, "-c", "import numpy"], env, None),
            (floor_name, [py, str(floor)], env_floor, None),
            ("numba floor (numba's default: its BLAS probe)", [py, str(floor_probe)], env_floor, None),
            (fit_floor_name, [py, str(floor_scipy)], env_floor, None),
            ("brdfkit eval microfacet --wi 30,0 --wo 30,180", bk + ["eval", "microfacet", "--wi", "30,0", "--wo", "30,180"],
             env, floor_name),
            ("brdfkit fit merl/gold-metallic-paint --model microfacet",
             bk + ["fit", "merl/gold-metallic-paint", "--model", "microfacet"], env, (floor_name, fit_floor_name)),
        ]
        for _, cmd, e, _ in rows:  # warm-up: numba caches (the floor's and brdfkit's), the OS's file cache
            _wall(cmd, e)
        times: dict[str, list[float]] = {name: [] for name, *_ in rows}
        load0 = os.getloadavg()[0]
        for _ in range(args.rounds):
            for name, cmd, e, _ in rows:
                times[name].append(_wall(cmd, e))
        load1 = os.getloadavg()[0]
    print(f"{args.rounds} rounds, fresh processes, alternating; load average {load0:.2f} before, {load1:.2f} after; "
          f"{os.cpu_count()} CPUs visible")
    print(f"{'command':<66} {'median s':>9} {'min s':>7} {'max s':>7}  above its floor")
    med = {name: statistics.median(t) for name, t in times.items()}
    for name, _, _, base in rows:
        t = times[name]
        bases = (base,) if isinstance(base, str) else base or ()
        above = ", ".join(f"{med[name] - med[b]:+.2f} s" + (f" ({b.split(' (')[0]})" if len(bases) > 1 else "")
                          for b in bases)
        print(f"{name:<66} {med[name]:9.2f} {min(t):7.2f} {max(t):7.2f}  {above}")


if __name__ == "__main__":
    main()
