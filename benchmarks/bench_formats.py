"""Measured formats side by side: read time and eval throughput of an RGL ``.bsdf`` material beside
the same material as a MERL ``.binary``, and beside Mitsuba 3's own ``measured`` plugin on the same
``.bsdf`` file, in one run.

    .venv/bin/python benchmarks/bench_formats.py                 # table with the ratios
    .venv/bin/python benchmarks/bench_formats.py --log2n 18 --json

The files are written first (``bk.tabulate``, default resolution, into a temporary folder):
``merl/gold-metallic-paint`` as MERL, that MERL file as an isotropic RGL file (1 x 32 incident
directions, 64^2 samples), and ``ward`` (anisotropic) as RGL (11 x 32). Timed (median of
``--calls`` calls after one warm-up call):

* read: ``bk.load_measured(path)`` (brdfkit: the reader with every check, the float64 working
  copies) and Mitsuba's ``load_dict({"type": "measured", ...})`` of the same file;
* eval: ``model.eval(wi, wo)`` on ``2^log2n`` pairs uniform over the hemispheres (numpy in and
  out): brdfkit's RGL evaluator (numpy, one thread), brdfkit's MERL lookup (compiled, every core),
  and Mitsuba's ``measured`` ``eval`` in ``llvm_ad_rgb`` (float32, JIT-compiled, every core) on
  Dr.Jit arrays already built (kernel) and with numpy in and out.

Mitsuba's LLVM variant needs ``libLLVM`` >= 16 (``DRJIT_LIBLLVM_PATH`` is pointed at the newest
system one, as ``bench_vs_mitsuba.py`` does); without it the Mitsuba columns are skipped.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_vs_mitsuba import MIN_LLVM, directions, newest_libllvm  # noqa: E402


def _median(fn, calls: int) -> float:
    fn()
    ts = []
    for _ in range(calls):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def _mitsuba(paths: dict, wi: np.ndarray, wo: np.ndarray, calls: int) -> dict | None:
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        lib, version = newest_libllvm()
        if version < MIN_LLVM:
            return None
        os.environ["DRJIT_LIBLLVM_PATH"] = lib
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    ctx = mi.BSDFContext()
    n = len(wi)
    wi32, wo32 = wi.astype(np.float32), wo.astype(np.float32)

    def to_dr(a):
        return mi.Vector3f(a[:, 0], a[:, 1], a[:, 2])

    out = {}
    for key, path in paths.items():
        bsdf = mi.load_dict({"type": "measured", "filename": path})
        out[f"{key}_read_s"] = _median(lambda: mi.load_dict({"type": "measured", "filename": path}), calls)
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = to_dr(wo32)  # Mitsuba's wi is brdfkit's wo (toward the viewer)
        light = to_dr(wi32)
        dr.eval(si, light)
        dr.sync_thread()

        def kernel():
            v = bsdf.eval(ctx, si, light)
            dr.eval(v)
            dr.sync_thread()

        def from_numpy():
            s = dr.zeros(mi.SurfaceInteraction3f, n)
            s.wi = to_dr(wo32)
            return np.array(bsdf.eval(ctx, s, to_dr(wi32)))

        out[f"{key}_kernel_s"] = _median(kernel, calls)
        out[f"{key}_numpy_s"] = _median(from_numpy, calls)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--log2n", type=int, default=18)
    ap.add_argument("--calls", type=int, default=5)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    import brdfkit as bk

    n = 1 << args.log2n
    wi, wo = directions(n)
    with tempfile.TemporaryDirectory() as d:
        merl = bk.tabulate("merl/gold-metallic-paint", os.path.join(d, "gold.binary"), error_pairs=0)
        rgl = bk.tabulate(merl.path, os.path.join(d, "gold.bsdf"), error_pairs=0)
        aniso = bk.tabulate("ward", os.path.join(d, "ward.bsdf"), error_pairs=0)
        res = {"pairs": n, "sizes_MB": {k: round(r.bytes / 1e6, 2) for k, r in
                                        (("merl", merl), ("rgl", rgl), ("rgl_aniso", aniso))}}
        models = {}
        for key, path in (("merl", merl.path), ("rgl", rgl.path), ("rgl_aniso", aniso.path)):
            res[f"brdfkit_{key}_read_s"] = _median(lambda: bk.load_measured(path), args.calls)
            models[key] = bk.load_measured(path)
        for key, m in models.items():
            res[f"brdfkit_{key}_eval_s"] = _median(lambda: m.eval(wi, wo), args.calls)
        ms = _mitsuba({"rgl": rgl.path, "rgl_aniso": aniso.path}, wi, wo, args.calls)
    if ms:
        res.update({f"mitsuba_{k}": v for k, v in ms.items()})
    rate = {k[:-2]: n / v / 1e6 for k, v in res.items() if k.endswith("_eval_s") or k.endswith("kernel_s")
            or k.endswith("numpy_s")}
    if args.json:
        print(json.dumps({"results": res, "M_evals_per_s": rate}, indent=2))
        return 0
    print(f"measured formats, {n} pairs, sizes (MB): {res['sizes_MB']}")
    print("read (median s)")
    for key in ("merl", "rgl", "rgl_aniso"):
        line = f"  {key:10s} brdfkit {res[f'brdfkit_{key}_read_s']:.4f}"
        if ms and f"{key}_read_s" in ms:
            line += f"   mitsuba {ms[f'{key}_read_s']:.4f}   brdfkit/mitsuba time {res[f'brdfkit_{key}_read_s'] / ms[f'{key}_read_s']:.2f}x"
        print(line)
    print("eval (M evals/s)")
    for key in ("merl", "rgl", "rgl_aniso"):
        line = f"  {key:10s} brdfkit {rate[f'brdfkit_{key}_eval']:8.2f}"
        if ms and f"{key}_kernel_s" in ms:
            k, nn = rate[f"mitsuba_{key}_kernel"], rate[f"mitsuba_{key}_numpy"]
            line += (f"   mitsuba kernel {k:8.2f}, numpy in/out {nn:8.2f}   brdfkit/mitsuba "
                     f"{rate[f'brdfkit_{key}_eval'] / k:.3f}x (kernel), {rate[f'brdfkit_{key}_eval'] / nn:.3f}x (numpy)")
        print(line)
    print(f"  brdfkit RGL / brdfkit MERL throughput {rate['brdfkit_rgl_eval'] / rate['brdfkit_merl_eval']:.3f}x, "
          f"read time RGL / MERL {res['brdfkit_rgl_read_s'] / res['brdfkit_merl_read_s']:.2f}x")
    if not ms:
        print("  (Mitsuba's llvm_ad_rgb needs libLLVM >= %d: skipped)" % MIN_LLVM)
    return 0


if __name__ == "__main__":
    sys.exit(main())
