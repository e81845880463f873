"""brdfkit's compiled engine against Mitsuba 3's LLVM JIT: GGX conductor, 2^20 direction pairs.

    .venv/bin/python benchmarks/bench_vs_mitsuba.py                  # table with the ratios
    .venv/bin/python benchmarks/bench_vs_mitsuba.py --rounds 7 --log2n 20 --json
    .venv/bin/python benchmarks/bench_vs_mitsuba.py --grad             # derivatives: Dr.Jit AD vs eval_grad

The same BRDF on both sides: GGX (width alpha), the separable Smith shadowing
G1(wi)·G1(wo), conductor Fresnel, no diffuse part — brdfkit's
``microfacet(distribution="ggx", shadowing="smith", fresnel="conductor", kd=0, ks=1)``
and Mitsuba's ``roughconductor`` (``distribution="ggx"``). Conventions: brdfkit's ``wi``
points to the light and ``wo`` to the viewer (pbrt); Mitsuba names them the other way
round (its ``si.wi`` is our ``wo``) and its ``eval`` includes the cosine of the light
direction, so ``f_brdfkit(wi, wo) = mitsuba.eval(si.wi = wo, wo = wi) / wi.z``. The script
checks that the two agree (printed: the median relative difference; the Fresnel forms
differ slightly, Mitsuba uses a cheaper approximation of the conductor term).

Timed, per process, the median of ``--calls`` calls after warm-up calls (which
include Dr.Jit's kernel compilation and numba's cache load):

* ``mitsuba kernel``: ``bsdf.eval`` on data already in Dr.Jit arrays, forced with
  ``dr.eval`` and ``dr.sync_thread`` (the time of the JIT-compiled kernel, cached);
* ``mitsuba numpy``: numpy arrays in, Dr.Jit arrays built, eval, numpy array out;
* ``brdfkit``: ``m.eval(wi, wo)`` on numpy arrays (the compiled engine), float32 and float64, on
  ``(n, 3)`` arrays in rows (C order) and with each component contiguous (Fortran order: the
  layout of Dr.Jit's arrays, which brdfkit's structure-of-arrays driver reads in place).

Each measurement runs in its own fresh process, the Mitsuba and brdfkit processes
alternating for ``--rounds`` rounds; the figure is the median over rounds. Mitsuba from
PyPI ships float32 variants only (``llvm_ad_rgb``); brdfkit's float64 figure is therefore
set against the same float32 Mitsuba kernel. Both use every core (Dr.Jit's thread pool,
numba's ``prange``), or ``--threads N`` on both sides (``--threads 1``: the code generated per
core, without the thread pools). Besides the medians the script prints the ratio of the fastest
single calls of all rounds, the figure least disturbed by other jobs on a shared host (there the
spread between a side's median and fastest call can differ between the two sides). On a shared
machine read the ratios, taken side by side, rather than
the absolute rates.

``--grad`` (issue 31, the choice between its two routes to gradients: brdfkit's forward twins of the
scalar source, or Dr.Jit's automatic differentiation): per-pair derivatives of the same BRDF, float32,
in alternating processes. Mitsuba: ``bsdf.eval`` and, per derivative, one ``dr.forward`` pass from the
parameter (``alpha``; ``eta`` and ``k`` as RGB colours, whose channel ``c`` reaches only ``f_c``, so one
pass each gives the three ``∂f_c/∂eta_c``), numpy in and numpy out on both sides, Dr.Jit's kernels
cached after the warm-up calls. brdfkit: ``m.eval``, ``m.eval_grad(wrt="alpha")``, ``wrt="eta"`` and
``wrt=["alpha", "eta", "k"]`` (the seven derivatives). It prints each side's rates, its
gradient/eval ratio, and brdfkit's gradient rate over Mitsuba's for the same derivatives.

Dr.Jit (1.5, with Mitsuba 3.9) emits LLVM's ``fmaximum``, which LLVM 14/15 — Debian 12's
default ``libLLVM`` — cannot compile ("LLVM ERROR: Cannot select: fmaximum"); the script
points ``DRJIT_LIBLLVM_PATH`` at the newest system ``libLLVM`` it finds (install one with
``apt-get install libllvm19``) unless that variable is already set.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np

ALPHA = 0.3
ETA = (0.2, 0.9, 1.1)  # a gold-like conductor, per RGB channel
K = (3.9, 2.4, 1.8)


def directions(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``n`` pairs uniform over the upper hemisphere (float64)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(2):
        u = rng.random((n, 2))
        z = u[:, 0]
        r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
        phi = 2.0 * np.pi * u[:, 1]
        out.append(np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1))
    return out[0], out[1]


def _times(fn, calls: int, warm: int = 2) -> tuple[float, float]:
    """(median, fastest) seconds of ``calls`` calls of ``fn`` after ``warm`` untimed ones."""
    for _ in range(warm):
        fn()
    ts = []
    for _ in range(calls):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts), min(ts)


# --------------------------------------------------------------------------- workers (one per process)
def _mitsuba(threads: int):
    """``(mi, dr, bsdf, to_dr)``: Mitsuba's ``llvm_ad_rgb`` variant, its GGX ``roughconductor`` at the
    benchmark's parameters, and a numpy ``(n, 3)`` array as a Dr.Jit vector."""
    import drjit as dr
    import mitsuba as mi

    if threads:
        dr.set_thread_count(threads)
    mi.set_variant("llvm_ad_rgb")
    bsdf = mi.load_dict({"type": "roughconductor", "distribution": "ggx", "alpha": ALPHA,
                         "eta": {"type": "rgb", "value": list(ETA)}, "k": {"type": "rgb", "value": list(K)}})

    def to_dr(a):
        return mi.Vector3f(a[:, 0], a[:, 1], a[:, 2])

    return mi, dr, bsdf, to_dr


def _brdfkit_model():
    """brdfkit's model of the same BRDF (module docstring), on the compiled engine."""
    import brdfkit as bk
    from brdfkit import engine

    engine.set_engine("compiled")
    return bk.model("microfacet", distribution="ggx", shadowing="smith", fresnel="conductor",
                    alpha=ALPHA, eta=ETA, k=K, kd=0.0, ks=1.0)


def _eval_numpy(mi, dr, bsdf, to_dr, ctx, wi32: np.ndarray, wo32: np.ndarray):
    """Mitsuba's ``bsdf.eval`` of numpy directions (brdfkit's ``wi`` is Mitsuba's light direction, its
    ``wo`` Mitsuba's ``wi``, toward the viewer), the Dr.Jit result unevaluated."""
    s = dr.zeros(mi.SurfaceInteraction3f, len(wi32))
    s.wi = to_dr(wo32)
    return bsdf.eval(ctx, s, to_dr(wi32))


def _rows(a) -> np.ndarray:
    """A Dr.Jit colour array as numpy ``(n, 3)`` (it converts to ``(3, n)`` or ``(n, 3)`` by version)."""
    a = np.asarray(a)
    return a.T if a.shape[0] == 3 and a.shape[-1] != 3 else a


def worker_mitsuba(n: int, calls: int, threads: int = 0) -> dict:
    mi, dr, bsdf, to_dr = _mitsuba(threads)
    wi, wo = directions(n)
    wi32, wo32 = wi.astype(np.float32), wo.astype(np.float32)
    ctx = mi.BSDFContext()
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = to_dr(wo32)  # Mitsuba's wi is our wo (toward the viewer)
    d_light = to_dr(wi32)
    dr.eval(si, d_light)
    dr.sync_thread()

    def kernel():
        v = bsdf.eval(ctx, si, d_light)
        dr.eval(v)
        dr.sync_thread()
        return v

    def from_numpy():
        return np.array(_eval_numpy(mi, dr, bsdf, to_dr, ctx, wi32, wo32))

    t_kernel, b_kernel = _times(kernel, calls)
    t_numpy, b_numpy = _times(from_numpy, calls)
    f = _rows(from_numpy()) / wi32[:, 2:3]  # remove the cosine of the light direction
    return {"kernel_s": t_kernel, "numpy_s": t_numpy, "kernel_best_s": b_kernel, "numpy_best_s": b_numpy,
            "sample": f[:4096].astype(np.float64).tolist()}


def worker_brdfkit(n: int, calls: int, threads: int = 0) -> dict:
    m = _brdfkit_model()
    wi, wo = directions(n)
    out = {}
    for name, dt, order in (("f32_s", np.float32, "C"), ("f64_s", np.float64, "C"),
                            ("f32F_s", np.float32, "F"), ("f64F_s", np.float64, "F")):
        a, b = wi.astype(dt, order=order), wo.astype(dt, order=order)
        out[name], out[name.replace("_s", "_best_s")] = _times(lambda: m.eval(a, b), calls)
    out["sample"] = m.eval(wi.astype(np.float32), wo.astype(np.float32))[:4096].astype(np.float64).tolist()
    return out


def worker_mitsuba_grad(n: int, calls: int, threads: int = 0) -> dict:
    """Mitsuba's eval and its forward-mode derivatives (``--grad``), numpy in and out."""
    mi, dr, bsdf, to_dr = _mitsuba(threads)
    params = mi.traverse(bsdf)
    keys = ("alpha.value", "eta.value", "k.value")
    wi, wo = directions(n)
    wi32, wo32 = wi.astype(np.float32), wo.astype(np.float32)
    ctx = mi.BSDFContext()

    def evaluate():
        return _eval_numpy(mi, dr, bsdf, to_dr, ctx, wi32, wo32)

    def value():
        return np.array(evaluate())

    def grads(which):
        out = []
        for key in which:
            dr.enable_grad(params[key])
            params.update()
            v = evaluate()
            dr.forward(params[key])
            out.append(np.array(dr.grad(v)))
            dr.disable_grad(params[key])
            params.update()
        return np.array(v), out

    t_eval, b_eval = _times(value, calls)
    t_one, b_one = _times(lambda: grads(keys[:1]), calls)
    t_rgb, b_rgb = _times(lambda: grads(keys[1:2]), calls)
    t_all, b_all = _times(lambda: grads(keys), calls)
    _, (g,) = grads(keys[:1])
    g = _rows(g)
    return {"eval_s": t_eval, "one_s": t_one, "rgb_s": t_rgb, "all_s": t_all, "eval_best_s": b_eval,
            "one_best_s": b_one, "rgb_best_s": b_rgb, "all_best_s": b_all, "sample": (g / wi32[:, 2:3])[:4096].astype(np.float64).tolist()}


def worker_brdfkit_grad(n: int, calls: int, threads: int = 0) -> dict:
    """brdfkit's eval and eval_grad of the same BRDF (``--grad``), float32."""
    m = _brdfkit_model()
    wi, wo = (w.astype(np.float32) for w in directions(n))
    out = {}
    for name, fn in (("eval", lambda: m.eval(wi, wo)), ("one", lambda: m.eval_grad(wi, wo, wrt="alpha")),
                     ("rgb", lambda: m.eval_grad(wi, wo, wrt="eta")),
                     ("all", lambda: m.eval_grad(wi, wo, wrt=["alpha", "eta", "k"]))):
        out[name + "_s"], out[name + "_best_s"] = _times(fn, calls)
    out["sample"] = m.eval_grad(wi, wo, wrt="alpha")[1]["alpha"][:4096].astype(np.float64).tolist()
    return out


def grad_main(args, n: int) -> int:
    """``--grad``: the two routes to per-pair derivatives, side by side (module docstring)."""
    mits, bks = [], []
    for _ in range(args.rounds):
        mits.append(_run_worker("mitsuba-grad", n, args.calls, args.threads))
        bks.append(_run_worker("brdfkit-grad", n, args.calls, args.threads))
    med = statistics.median
    rate = lambda t: n / t / 1e6  # noqa: E731
    a, b = np.array(mits[0]["sample"]), np.array(bks[0]["sample"])
    ok = np.abs(b) > 1e-3 * np.abs(b).max()
    res = {"pairs": n, "rounds": args.rounds, "threads": args.threads or "all",
           "load_average": os.getloadavg()[0] if hasattr(os, "getloadavg") else None,
           "median_rel_difference_dalpha": float(np.median(np.abs(a[ok] - b[ok]) / np.abs(b[ok])))}
    for side, rows in (("mitsuba", mits), ("brdfkit", bks)):
        for k in ("eval", "one", "rgb", "all"):
            res[f"{side}_{k}_M_s"] = rate(med(r[k + "_s"] for r in rows))
            res[f"{side}_{k}_fastest_M_s"] = rate(min(r[k + "_best_s"] for r in rows))
    if args.json:
        print(json.dumps(res, indent=2))
        return 0
    print(f"GGX conductor float32, {n} pairs, per-pair derivatives, {args.rounds} alternating process rounds x "
          f"{args.calls} calls (load average {res['load_average']:.2f}, threads: {res['threads']}); M pairs/s, "
          f"median (fastest call)")
    print(f"{'':34}{'mitsuba (Dr.Jit AD)':>24}{'brdfkit (forward twin)':>26}{'brdfkit / mitsuba':>20}")
    for k, label in (("eval", "eval"), ("one", "d/d alpha"), ("rgb", "d/d eta (3 values)"),
                     ("all", "d/d alpha, eta, k (7 values)")):
        m_, b_ = res[f"mitsuba_{k}_M_s"], res[f"brdfkit_{k}_M_s"]
        mf, bf = res[f"mitsuba_{k}_fastest_M_s"], res[f"brdfkit_{k}_fastest_M_s"]
        print(f"{label:<34}{m_:>13.1f} ({mf:7.1f}){b_:>15.1f} ({bf:7.1f}){b_ / m_:>12.2f}x ({bf / mf:.2f}x)")
    for side in ("mitsuba", "brdfkit"):
        e = res[f"{side}_eval_M_s"]
        print(f"  {side}: gradient / eval throughput: d/d alpha {res[f'{side}_one_M_s'] / e:.3f}, "
              f"d/d eta {res[f'{side}_rgb_M_s'] / e:.3f}, all seven {res[f'{side}_all_M_s'] / e:.3f}")
    print(f"  d/d alpha agrees to a median relative difference of {res['median_rel_difference_dalpha']:.2g} "
          f"(Mitsuba's Fresnel form differs slightly)")
    return 0


# --------------------------------------------------------------------------- driver
WORKERS = {"mitsuba": worker_mitsuba, "brdfkit": worker_brdfkit, "mitsuba-grad": worker_mitsuba_grad,
           "brdfkit-grad": worker_brdfkit_grad}

#: the oldest LLVM that compiles the ``fmaximum`` Dr.Jit 1.5 emits
MIN_LLVM = 16


def newest_libllvm() -> tuple[str | None, int]:
    """The newest system ``libLLVM`` and its major version (``(None, 0)`` if none). Dr.Jit needs
    LLVM >= :data:`MIN_LLVM` for the ``fmaximum`` it emits; with Debian 12's default LLVM 14/15
    the kernel fails with "Cannot select: fmaximum"."""
    import glob
    import re

    best, best_v = None, 0
    for f in glob.glob("/usr/lib/*/libLLVM*.so*") + glob.glob("/usr/lib/llvm-*/lib/libLLVM*.so*"):
        m = re.search(r"libLLVM[-.](?:so\.)?(\d+)", os.path.basename(f))
        if m and int(m.group(1)) > best_v:
            best, best_v = f, int(m.group(1))
    return best, best_v


def _run_worker(kind: str, n: int, calls: int, threads: int = 0) -> dict:
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", kind, "--log2n", str(int(np.log2(n))),
           "--calls", str(calls), "--threads", str(threads)]
    env = dict(os.environ)
    if threads:
        env["NUMBA_NUM_THREADS"] = str(threads)  # numba's pool is sized at import, in the worker
    if kind.startswith("mitsuba") and "DRJIT_LIBLLVM_PATH" not in env:
        lib, version = newest_libllvm()
        if version < MIN_LLVM:  # Dr.Jit would abort inside LLVM with a page of "Cannot select" output
            raise SystemExit(f"bench_vs_mitsuba: Mitsuba's LLVM variant needs libLLVM >= {MIN_LLVM}, the newest here is "
                             f"{version or 'none'} (apt-get install libllvm19, or set DRJIT_LIBLLVM_PATH)")
        env["DRJIT_LIBLLVM_PATH"] = lib
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=900, env=env)
    if res.returncode != 0:
        raise SystemExit(f"bench_vs_mitsuba: {kind} worker failed:\n{res.stderr[-2000:]}")
    return json.loads(res.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--log2n", type=int, default=20)
    ap.add_argument("--rounds", type=int, default=5, help="alternating Mitsuba/brdfkit process pairs")
    ap.add_argument("--calls", type=int, default=7, help="timed calls per process (median)")
    ap.add_argument("--threads", type=int, default=0,
                    help="threads on both sides (Dr.Jit's pool, numba's); default: every core")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--grad", action="store_true", help="per-pair derivatives: Dr.Jit's AD against eval_grad")
    ap.add_argument("--worker", choices=tuple(WORKERS), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    n = 1 << args.log2n
    if args.worker:
        print(json.dumps(WORKERS[args.worker](n, args.calls, args.threads)))
        return 0
    if args.grad:
        return grad_main(args, n)

    mits, bks = [], []
    for _ in range(args.rounds):
        mits.append(_run_worker("mitsuba", n, args.calls, args.threads))
        bks.append(_run_worker("brdfkit", n, args.calls, args.threads))
    med = statistics.median
    tk = med(r["kernel_s"] for r in mits)
    tn = med(r["numpy_s"] for r in mits)
    t32 = med(r["f32_s"] for r in bks)
    t64 = med(r["f64_s"] for r in bks)
    t32f = med(r["f32F_s"] for r in bks)
    t64f = med(r["f64F_s"] for r in bks)
    fastest = {k: min(r[k] for r in rows) for rows, ks in ((mits, ("kernel_best_s", "numpy_best_s")),
                                                           (bks, ("f32_best_s", "f64_best_s", "f32F_best_s", "f64F_best_s")))
               for k in ks}
    a = np.array(mits[0]["sample"])
    b = np.array(bks[0]["sample"])
    ok = b > 1e-6
    agree = float(np.median(np.abs(a[ok] - b[ok]) / b[ok]))
    rate = lambda t: n / t / 1e6  # noqa: E731
    res = {
        "pairs": n,
        "rounds": args.rounds,
        "calls_per_process": args.calls,
        "mitsuba_variant": "llvm_ad_rgb (float32)",
        "libllvm": os.environ.get("DRJIT_LIBLLVM_PATH") or newest_libllvm()[0],
        "mitsuba_kernel_Meval_s": rate(tk),
        "mitsuba_numpy_Meval_s": rate(tn),
        "brdfkit_f32_Meval_s": rate(t32),
        "brdfkit_f64_Meval_s": rate(t64),
        "brdfkit_f32_fortran_Meval_s": rate(t32f),
        "brdfkit_f64_fortran_Meval_s": rate(t64f),
        "ratio_f32_vs_mitsuba_kernel": tk / t32,
        "ratio_f32_fortran_vs_mitsuba_kernel": tk / t32f,
        "ratio_f64_fortran_vs_mitsuba_kernel": tk / t64f,
        "ratio_f64_vs_mitsuba_kernel": tk / t64,
        "ratio_f32_vs_mitsuba_numpy": tn / t32,
        "ratio_f64_vs_mitsuba_numpy": tn / t64,
        "fastest_call_Meval_s": {k.replace("_best_s", ""): rate(v) for k, v in fastest.items()},
        "fastest_ratio_f32_vs_mitsuba_kernel": fastest["kernel_best_s"] / fastest["f32_best_s"],
        "fastest_ratio_f64_vs_mitsuba_kernel": fastest["kernel_best_s"] / fastest["f64_best_s"],
        "fastest_ratio_f32_fortran_vs_mitsuba_kernel": fastest["kernel_best_s"] / fastest["f32F_best_s"],
        "threads": args.threads or "all",
        "median_rel_difference": agree,
        "load_average": os.getloadavg()[0] if hasattr(os, "getloadavg") else None,
        "cpus": os.cpu_count(),
    }
    if args.json:
        print(json.dumps(res, indent=2))
        return 0
    print(f"GGX conductor, {n} pairs, {args.rounds} alternating process rounds x {args.calls} calls "
          f"(load average {res['load_average']:.2f}, {res['cpus']} CPUs, threads: {res['threads']})")
    print(f"  (Dr.Jit's LLVM: {res['libllvm']})")
    print(f"  mitsuba llvm_ad_rgb kernel (Dr.Jit arrays)  {res['mitsuba_kernel_Meval_s']:8.1f} M evals/s")
    print(f"  mitsuba llvm_ad_rgb numpy in/out            {res['mitsuba_numpy_Meval_s']:8.1f} M evals/s")
    print(f"  brdfkit compiled float32                    {res['brdfkit_f32_Meval_s']:8.1f} M evals/s")
    print(f"  brdfkit compiled float64                    {res['brdfkit_f64_Meval_s']:8.1f} M evals/s")
    print(f"  brdfkit float32, Fortran-ordered (n, 3)     {res['brdfkit_f32_fortran_Meval_s']:8.1f} M evals/s")
    print(f"  brdfkit float64, Fortran-ordered (n, 3)     {res['brdfkit_f64_fortran_Meval_s']:8.1f} M evals/s")
    print(f"  ratio brdfkit/mitsuba-kernel: float32 {res['ratio_f32_vs_mitsuba_kernel']:.2f}x, "
          f"float64 {res['ratio_f64_vs_mitsuba_kernel']:.2f}x")
    print(f"  ratio with components contiguous (Fortran order, like Dr.Jit's arrays): float32 "
          f"{res['ratio_f32_fortran_vs_mitsuba_kernel']:.2f}x, float64 {res['ratio_f64_fortran_vs_mitsuba_kernel']:.2f}x")
    print(f"  ratio brdfkit/mitsuba-numpy:  float32 {res['ratio_f32_vs_mitsuba_numpy']:.2f}x, "
          f"float64 {res['ratio_f64_vs_mitsuba_numpy']:.2f}x")
    print(f"  fastest single calls, the ratio: float32 {res['fastest_ratio_f32_vs_mitsuba_kernel']:.2f}x, "
          f"float64 {res['fastest_ratio_f64_vs_mitsuba_kernel']:.2f}x, float32 Fortran-ordered "
          f"{res['fastest_ratio_f32_fortran_vs_mitsuba_kernel']:.2f}x (the least disturbed by other jobs)")
    print(f"  values agree to a median relative difference of {agree:.2g} (Fresnel forms differ)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
