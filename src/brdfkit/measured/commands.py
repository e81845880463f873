"""``brdfkit fit``: fit analytic models to measured materials (one, or all of them).

    brdfkit fit merl/gold-metallic-paint --model ward --json
    brdfkit fit my.binary --model microfacet -p distribution=ggx -p fresnel=schlick --report out/
    brdfkit fit --all-measured --set merl --model blinn-phong --model ward --out docs/measured
"""

from __future__ import annotations

import json
import os
import time
from typing import Any, List, Optional

import numpy as np
import typer

from ..cli_common import print_json


def measured_names(set_name: str | None = None) -> list[str]:
    """The built-in measured materials (``set/name``), optionally of one set (merl, rgl, nielsen)."""
    from .nbrdf import SETS, materials

    if set_name in (None, "", "all"):
        return list(materials())
    if set_name not in SETS:
        raise ValueError(f"unknown measured set {set_name!r}; valid sets: {', '.join(SETS)}, all")
    return [n for n in materials() if n.split("/", 1)[0] == set_name]


def _fixed_for(model_name: str, items: List[str], strict: bool) -> dict[str, Any]:
    """Parse ``-p name=value``; with ``strict=False`` skip names the model lacks."""
    from .. import registry
    from ..params import parse_assignments

    cls = registry.get(model_name)
    if strict:
        return parse_assignments(model_name, cls.spec, items)
    names = {p.name for p in cls.spec}
    keep = [it for it in items if it.partition("=")[0].strip() in names]
    return parse_assignments(model_name, cls.spec, keep)


def _fmt_params(params: dict[str, Any]) -> str:
    parts = []
    for k, v in params.items():
        if isinstance(v, np.ndarray):
            parts.append(f"{k}=" + ",".join(f"{x:.4g}" for x in v))
        elif isinstance(v, float):
            parts.append(f"{k}={v:.4g}")
        else:
            parts.append(f"{k}={v}")
    return " ".join(parts)


# --------------------------------------------------------------------------- batch output
def write_batch(results, models: list[str], sources: list[str], out_dir: str, metric: str, seconds: float) -> dict[str, str]:
    """CSV, Markdown, sorted-error PNG and parameters JSON of a batch; returns the paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(out_dir, exist_ok=True)
    table = {(r.source, r.model.name): r for r in results}
    csv_path = os.path.join(out_dir, "fit_errors.csv")
    with open(csv_path, "w") as fh:
        fh.write("material," + ",".join(models) + "\n")
        for s in sources:
            fh.write(s + "," + ",".join(f"{table[(s, m)].error:.6g}" for m in models) + "\n")
    md_path = os.path.join(out_dir, "fit_errors.md")
    errs = np.array([[table[(s, m)].error for m in models] for s in sources])
    best = errs.argmin(axis=1)
    with open(md_path, "w") as fh:
        fh.write(f"Fitting error per material and model; metric: {metric}. Best per row in bold.\n\n")
        fh.write("| material | " + " | ".join(models) + " |\n")
        fh.write("|---|" + "---:|" * len(models) + "\n")
        for i, s in enumerate(sources):
            cells = [f"**{e:.4g}**" if j == best[i] else f"{e:.4g}" for j, e in enumerate(errs[i])]
            fh.write(f"| {s} | " + " | ".join(cells) + " |\n")
        fh.write("| **median** | " + " | ".join(f"{np.median(errs[:, j]):.4g}" for j in range(len(models))) + " |\n")
        fh.write("| **mean** | " + " | ".join(f"{np.mean(errs[:, j]):.4g}" for j in range(len(models))) + " |\n")
        fh.write("| **best on** | " + " | ".join(str(int((best == j).sum())) for j in range(len(models))) + " |\n")
        fh.write(f"\n{len(sources)} materials × {len(models)} models fitted in {seconds:.0f} s.\n")
    png_path = os.path.join(out_dir, "fit_errors_sorted.png")
    fig, ax = plt.subplots(figsize=(8, 4.8), dpi=110)
    for j, m in enumerate(models):
        ax.plot(np.arange(1, len(sources) + 1), np.sort(errs[:, j]), label=m, lw=1.6)
    ax.set_yscale("log")
    ax.set_xlabel("materials, sorted by error (per model)")
    ax.set_ylabel(f"fitting error ({metric})")
    ax.set_title(f"Fit of {len(models)} analytic models to {len(sources)} measured materials")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(png_path)
    plt.close(fig)
    json_path = os.path.join(out_dir, "fit_params.json")
    with open(json_path, "w") as fh:
        json.dump([r.to_json() for r in results], fh, indent=1)
    return {"csv": csv_path, "markdown": md_path, "plot": png_path, "params": json_path}


def register(app: typer.Typer) -> None:
    @app.command("fit")
    def fit_cmd(
        source: Optional[str] = typer.Argument(
            None, help="a MERL .binary file or a built-in material (e.g. merl/gold-metallic-paint)"
        ),
        model: List[str] = typer.Option([], "--model", "-m", help="analytic model to fit (repeat with --all-measured)"),
        param: List[str] = typer.Option([], "--param", "-p", help="hold a parameter fixed: name=value (repeatable)"),
        metric: str = typer.Option("ngan", "--metric", help="ngan (cosine-weighted RMS), l2, log or cbrt"),
        starts: int = typer.Option(4, "--starts", help="local optimisations (multi-start)"),
        samples: int = typer.Option(3000, "--samples", help="measured samples used for fitting"),
        seed: int = typer.Option(0, "--seed", help="random seed of the sampling and the starts"),
        as_json: bool = typer.Option(False, "--json", help="print the result as JSON"),
        report: Optional[str] = typer.Option(None, "--report", help="write a report (slices, spheres) into DIR"),
        all_measured: bool = typer.Option(False, "--all-measured", help="fit every built-in material"),
        set_name: str = typer.Option("all", "--set", help="with --all-measured: merl, rgl, nielsen or all"),
        limit: int = typer.Option(0, "--limit", help="with --all-measured: only the first N materials"),
        out: str = typer.Option("fit-results", "--out", "-o", help="with --all-measured: output folder"),
    ) -> None:
        """Fit an analytic model to a measured material (MERL file or built-in); or a whole batch."""
        from .. import registry
        from .fit import METRICS

        if metric not in METRICS:
            raise ValueError(f"unknown metric {metric!r}; valid metrics: {', '.join(METRICS)}")
        if not model:
            raise ValueError("missing --model NAME; valid models: " + ", ".join(registry.names()))
        for m in model:
            registry.get(m)
        if all_measured:
            if source is not None:
                raise ValueError("give either SOURCE or --all-measured, not both")
            _batch(model, param, metric, starts, samples, seed, set_name, limit, out, as_json)
            return
        if source is None:
            raise ValueError("missing SOURCE: a MERL .binary file or a built-in material (see brdfkit list --measured)")
        if len(model) != 1:
            raise ValueError("fit one --model at a time for a single SOURCE (several models need --all-measured)")
        _single(source, model[0], param, metric, starts, samples, seed, as_json, report)


def _single(source, model_name, param, metric, starts, samples, seed, as_json, report) -> None:
    from .fit import fit, resolve_source

    fixed = _fixed_for(model_name, param, strict=True)
    measured = resolve_source(source)
    res = fit(model_name, measured, fixed=fixed, metric=metric, starts=starts, samples=samples, seed=seed,
              progress=not as_json)
    out = res.to_json()
    if report:
        from .report import write_report

        out["report"] = write_report(res, measured, report)
    if as_json:
        print_json(out)
        return
    typer.echo(f"{model_name} fitted to {res.source}: error {res.error:.6g} ({metric}), "
               f"{res.samples} samples, {res.starts} starts, {res.seconds:.1f} s")
    typer.echo("  " + _fmt_params(res.params))
    if report:
        typer.echo(f"  report: {out['report']['index']}")


def _batch(models, param, metric, starts, samples, seed, set_name, limit, out, as_json) -> None:
    from .fit import fit_batch

    sources = measured_names(set_name)
    if limit < 0:
        raise ValueError(f"--limit must be >= 0, got {limit}")
    if limit:
        sources = sources[:limit]
    fixed = {m: _fixed_for(m, param, strict=False) for m in models}
    used = {k for f in fixed.values() for k in f}
    for item in param:
        if item.partition("=")[0].strip() not in used:
            raise ValueError(f"parameter assignment {item!r} matches none of the models {', '.join(models)}")
    t0 = time.perf_counter()
    results = fit_batch(models, sources, metric=metric, fixed=fixed, progress=not as_json,
                        starts=starts, samples=samples, seed=seed)
    seconds = time.perf_counter() - t0
    paths = write_batch(results, list(models), sources, out, metric, seconds)
    if as_json:
        print_json({"metric": metric, "seconds": round(seconds, 2), "files": paths,
                    "results": [r.to_json() for r in results]})
        return
    typer.echo(f"fitted {len(models)} model(s) to {len(sources)} material(s) in {seconds:.1f} s")
    for k, v in paths.items():
        typer.echo(f"  {k}: {v}")


def list_measured(as_json: bool = False) -> None:
    """What ``brdfkit list --measured`` prints: the built-in measured materials."""
    names = measured_names()
    if as_json:
        print_json(names)
        return
    from .nbrdf import SETS

    for s in SETS:
        sub = [n for n in names if n.startswith(s + "/")]
        typer.echo(f"{s} ({len(sub)}):")
        for n in sub:
            typer.echo(f"  {n}")
