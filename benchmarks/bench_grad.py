"""Throughput of ``m.eval_grad`` beside ``m.eval`` (issue 31), compiled engine, in one run.

    .venv/bin/python benchmarks/bench_grad.py                    # the default cases, 2^20 pairs
    .venv/bin/python benchmarks/bench_grad.py --log2n 18 --repeat 5 --json

Per case (a model at fixed parameters) and dtype (float32, float64), on the same random direction
pairs: ``m.eval``, ``m.eval_grad`` (every continuous parameter) and ``m.eval_grad(wrt=ROUGHNESS)``
(the one parameter a roughness fit moves most), each the best of ``--repeat`` calls after an untimed
warm-up (which loads or compiles the driver), in millions of pairs per second, and the ratios
gradient/eval. ``outputs`` is the number of nonzero derivative values per pair (at the first pair: 3
channels × the parameter components that reach that channel): a gradient call writes that many numbers where ``eval``
writes 3, so its memory traffic alone bounds the ratio. ``bound`` measures that bound for the layout
eval_grad returns (SPEC.md: an RGB parameter's derivative is ``(..., 3, 3)``, zeros included, and
``alpha`` beside ``alpha_x``/``alpha_y``): eval's time over the time a compiled parallel loop takes to
write as many values per pair into freshly allocated arrays, as eval_grad does; no gradient of every
parameter in that layout can be faster than that fraction of eval.

Alternating rounds (eval, grad, grad-wrt, eval, ...) so that a load change on the shared machine
touches all three alike; the load average is printed. Nothing is asserted.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from bench_eval import _load, _stderr_console, directions

#: (label, registry name, parameters, the parameter of the ``wrt`` column)
CASES = (
    ("ggx conductor", "microfacet", {"distribution": "ggx", "fresnel": "conductor", "alpha": 0.3}, "alpha"),
    ("ggx schlick", "microfacet", {"distribution": "ggx", "fresnel": "schlick", "alpha": 0.3}, "alpha"),
    ("beckmann conductor", "microfacet", {"distribution": "beckmann", "alpha": 0.3}, "alpha"),
    ("cook-torrance", "cook-torrance", {}, "m"),
    ("ward", "ward", {}, "alpha_x"),
    ("blinn-phong", "blinn-phong", {}, "shininess"),
    ("ashikhmin-shirley", "ashikhmin-shirley", {}, "nu"),
    ("oren-nayar", "oren-nayar", {}, "sigma"),
)


def _best(fn, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


_FILL = None


def _write_time(values_per_pair: int, wi: np.ndarray, repeat: int) -> float:
    """Best time to write ``values_per_pair`` values of ``wi``'s dtype per pair into a fresh (n, k) array
    with a compiled parallel loop (each value a cheap function of the pair's direction)."""
    global _FILL
    if _FILL is None:
        import numba

        @numba.njit(parallel=True)
        def fill(w, out):
            for j in numba.prange(out.shape[0]):
                s = w[j, 0] + w[j, 1] + w[j, 2]
                for k in range(out.shape[1]):
                    out[j, k] = s

        _FILL = fill
    _FILL(wi, np.empty((wi.shape[0], values_per_pair), wi.dtype))  # compile
    return _best(lambda: _FILL(wi, np.empty((wi.shape[0], values_per_pair), wi.dtype)), repeat)


def run(n: int, repeat: int, cases=CASES, progress: bool = True) -> list[dict]:
    import brdfkit as bk
    from rich.progress import Progress

    bk.set_engine("compiled")
    wi64, wo64 = directions(n)
    rows = []
    with Progress(transient=True, disable=not progress, console=_stderr_console()) as bar:
        task = bar.add_task("benchmarking", total=2 * len(cases))
        for label, name, params, wrt in cases:
            m = bk.model(name, **params)
            if wrt not in m.params:
                raise SystemExit(f"{label}: {name} has no parameter {wrt!r}")
            for dt in (np.float32, np.float64):
                bar.update(task, description=f"{label} {dt.__name__}")
                wi, wo = wi64.astype(dt), wo64.astype(dt)
                calls = {"eval": lambda: m.eval(wi, wo), "grad": lambda: m.eval_grad(wi, wo),
                         "grad_wrt": lambda: m.eval_grad(wi, wo, wrt=wrt)}
                for fn in calls.values():  # warm-up: load or compile, and touch the output memory once
                    fn()
                best = {k: float("inf") for k in calls}
                for _ in range(repeat):
                    for k, fn in calls.items():
                        best[k] = min(best[k], _best(fn, 1))
                _, g = m.eval_grad(wi[:1], wo[:1])  # a generic pair: structural zeros are the only zeros
                outputs = int(sum(np.count_nonzero(v) for k, v in g.items() if not (k == "alpha" and "alpha_x" in g)))
                returned = int(sum(v[0].size for v in g.values()))  # every value the call writes per pair
                write = _write_time(returned, wi, repeat)
                rows.append({"case": label, "dtype": dt.__name__, "n": n, "wrt": wrt, "outputs_per_pair": outputs,
                             **{f"{k}_mpairs_per_s": n / t / 1e6 for k, t in best.items()},
                             "grad_vs_eval": best["eval"] / best["grad"],
                             "grad_wrt_vs_eval": best["eval"] / best["grad_wrt"],
                             "returned_per_pair": returned, "write_bound_vs_eval": best["eval"] / write})
                bar.advance(task)
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--log2n", type=int, default=20, help="number of direction pairs is 2^LOG2N (default 20)")
    ap.add_argument("--repeat", type=int, default=5, help="alternating rounds; the best call counts")
    ap.add_argument("--json", action="store_true", help="print a JSON list instead of the table")
    args = ap.parse_args(argv)
    rows = run(1 << args.log2n, args.repeat)
    if args.json:
        json.dump(rows, sys.stdout, indent=1)
        print()
        return 0
    from rich.console import Console
    from rich.table import Table

    t = Table(title=f"eval_grad beside eval, 2^{args.log2n} pairs, compiled engine (load average {_load()})")
    for col in ("case", "dtype", "outputs/pair", "eval M/s", "grad M/s", "grad/eval", "bound", "wrt",
                "grad(wrt) M/s", "grad(wrt)/eval"):
        t.add_column(col, justify="left" if col in ("case", "dtype", "wrt") else "right")
    for r in rows:
        t.add_row(r["case"], r["dtype"], str(r["outputs_per_pair"]), f"{r['eval_mpairs_per_s']:.1f}",
                  f"{r['grad_mpairs_per_s']:.2f}", f"{r['grad_vs_eval']:.3f}",
                  f"{r['write_bound_vs_eval']:.2f} ({r['returned_per_pair']})", r["wrt"],
                  f"{r['grad_wrt_mpairs_per_s']:.2f}", f"{r['grad_wrt_vs_eval']:.3f}")
    Console(width=150).print(t)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
