"""Regenerate the published table in this folder: 159 materials × 9 columns.

    nice python docs/measured/regenerate.py --out DIR [--workers N] [--resume] [--only LABEL ...] [--publish]

The same batch as ``brdfkit fit --all-measured -m blinn-phong -m ward -m ward:normalization=dur
-m lafortune -m cook-torrance -m ashikhmin-shirley -m ashikhmin-shirley:variant=ngan -m htsg
-m microfacet:distribution=ggx:fresnel=schlick --samples 2000 --starts 4``, with the table's
short column labels. The stored fits go to ``DIR/fits/``; ``--resume`` keeps those with the
same settings (``--only`` re-fits some columns and keeps the others). ``--publish`` copies the
tables and plots (not the per-fit files) into this folder.
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

#: label -> (registry model, fixed parameters)
COLUMNS = {
    "blinn-phong": ("blinn-phong", {}),
    "ward": ("ward", {}),
    "ward-dür": ("ward", {"normalization": "dur"}),
    "lafortune": ("lafortune", {}),
    "cook-torrance": ("cook-torrance", {}),
    "ashikhmin-shirley (paper)": ("ashikhmin-shirley", {}),
    "ashikhmin-shirley (ngan)": ("ashikhmin-shirley", {"variant": "ngan"}),
    "he (htsg)": ("htsg", {}),
    "microfacet ggx": ("microfacet", {"distribution": "ggx", "fresnel": "schlick"}),
}
HERE = Path(__file__).resolve().parent
PUBLISHED = ("fit_errors.csv", "fit_errors.md", "fit_errors_sorted.png", "fit_errors_by_material.png", "fit_params.json")


def main() -> int:
    from brdfkit.measured.batch import make_jobs, run_batch
    from brdfkit.measured.commands import measured_names

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="output folder (the per-fit files go to OUT/fits)")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--resume", action="store_true")
    ap.add_argument("--only", action="append", choices=list(COLUMNS), help="re-fit only this column")
    ap.add_argument("--publish", action="store_true", help="copy the tables and plots into docs/measured")
    args = ap.parse_args()
    sources = measured_names("all")
    labels = list(COLUMNS)
    names = {k: v[0] for k, v in COLUMNS.items()}
    fixed = {k: v[1] for k, v in COLUMNS.items()}
    settings = dict(samples=2000, starts=4)
    out = Path(args.out)
    if args.only:  # drop the stored fits of those columns, keep the rest
        for j in make_jobs(args.only, sources, fixed, names, **settings):
            (out / "fits" / j.file_name()).unlink(missing_ok=True)

    def progress(done, total, rec):
        print(f"[{done}/{total}] {rec['source']} {rec['column']}: {rec['error']:.4g} ({rec['seconds']:.1f} s)",
              file=sys.stderr, flush=True)

    res = run_batch(labels, sources, out, names=names, fixed=fixed, workers=args.workers,
                    resume=args.resume or bool(args.only), progress=progress, **settings)
    print(f"{res.fitted} fitted, {res.skipped} kept, {res.seconds:.0f} s; complete: {res.complete}")
    if args.publish and res.complete and out.resolve() != HERE:
        from brdfkit.fileio import atomic_path

        for f in PUBLISHED:
            with atomic_path(HERE / f) as tmp:
                shutil.copyfile(out / f, tmp)
    return 0 if res.complete else 1


if __name__ == "__main__":
    raise SystemExit(main())
