"""``brdfkit fit``: fit analytic models to measured materials (one, or all of them).

    brdfkit fit merl/gold-metallic-paint --model ward --json
    brdfkit fit my.binary --model microfacet -p distribution=ggx -p fresnel=schlick --report out/
    brdfkit fit --all-measured --set merl --model blinn-phong --model ward --out docs/measured

``brdfkit tabulate``: write any model as a measured file (MERL ``.binary``, RGL ``.bsdf``).

    brdfkit tabulate microfacet -p alpha=0.2 --format rgl -o ggx.bsdf
    brdfkit tabulate merl/gold-metallic-paint -o gold.binary --json
"""

from __future__ import annotations

import os
import time
from typing import Any, List, Optional

import numpy as np
import typer

from ..cli_common import print_json


def measured_names(set_name: str | None = None) -> list[str]:
    """The built-in measured materials (``set/name``), optionally of one set (merl, rgl, nielsen);
    or, when ``set_name`` is a folder, its measured files (:func:`measured_files`)."""
    from .nbrdf import SETS, materials

    if set_name in (None, "", "all"):
        return list(materials())
    if set_name not in SETS:
        if os.path.isdir(set_name):
            return measured_files(set_name)
        raise ValueError(f"unknown measured set {set_name!r}; valid sets: {', '.join(SETS)}, all, "
                         "or a folder of measured files")
    return [n for n in materials() if n.split("/", 1)[0] == set_name]


def measured_files(folder: str) -> list[str]:
    """The measured-data files directly in ``folder`` (every suffix :mod:`brdfkit.sources` reads as
    measured data: MERL ``.binary``, MERL/UTIA ``.bin``, RGL ``.bsdf``), sorted by name; hidden files
    (an atomic write in flight) are skipped. A folder with none is a one-line ``ValueError``."""
    from ..sources import FILE_KINDS, MEASURED

    suffixes = sorted(s for s, k in FILE_KINDS.items() if k in MEASURED)
    try:
        names = sorted(os.listdir(folder))
    except OSError as e:
        raise ValueError(f"{folder}: cannot list the folder: {e.strerror or e}") from None
    found = [os.path.join(folder, n) for n in names
             if not n.startswith(".") and os.path.splitext(n)[1].lower() in suffixes
             and os.path.isfile(os.path.join(folder, n))]
    if not found:
        raise ValueError(f"{folder}: no measured files in this folder (looked for {', '.join(suffixes)})")
    return found


def _fixed_for(model_name: str, items: List[str], strict: bool) -> dict[str, Any]:
    """Parse ``-p name=value``; with ``strict=False`` skip names the model lacks."""
    from ..params import parse_assignments
    from ..sources import model_class

    cls = model_class(model_name)
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


def parse_samples(text: str) -> int | str:
    """``--samples``: a number (at least 16) or ``table`` (every measured bin)."""
    t = str(text).strip().lower()
    if t == "table":
        return "table"
    try:
        n = int(t)
    except ValueError:
        raise ValueError(f"--samples must be a number of samples or 'table', got {text!r}") from None
    if n < 16:
        raise ValueError(f"--samples must be at least 16 (or 'table'), got {n}")
    return n


def parse_model_spec(text: str) -> tuple[str, str, list[str]]:
    """``--model NAME[:k=v[:k=v...]]`` -> (column label, registry name, ``k=v`` items).

    The same model can so appear twice with different options, e.g. ``ward`` and
    ``ward:normalization=dur`` (Ngan et al.'s Ward and Ward-Dür); the label is the text given."""
    from ..sources import model_class

    name, *items = [x.strip() for x in text.split(":")]
    model_class(name)
    for it in items:
        if "=" not in it:
            raise ValueError(f"--model {text!r}: expected NAME:name=value, got {it!r}")
    return text, name, items


def register(app: typer.Typer) -> None:
    _register_tabulate(app)

    @app.command("fit")
    def fit_cmd(
        source: Optional[str] = typer.Argument(
            None, help="a measured file (MERL .binary, UTIA .bin, RGL .bsdf), a built-in material "
                       "(e.g. merl/gold-metallic-paint) or any model"
        ),
        model: List[str] = typer.Option([], "--model", "-m",
                                        help="analytic model to fit; with --all-measured repeatable, "
                                             "and NAME:k=v[:k=v] fixes options of that column"),
        param: List[str] = typer.Option([], "--param", "-p", help="hold a parameter fixed: name=value (repeatable)"),
        metric: str = typer.Option("ngan", "--metric", help="ngan (cosine-weighted RMS), l2, log or cbrt"),
        starts: int = typer.Option(4, "--starts", help="local optimisations (multi-start; more where their minima disagree, and one per log-scale value)"),
        samples: str = typer.Option("3000", "--samples", help="measured samples used for fitting, or 'table' (every bin)"),
        lobes: int = typer.Option(1, "--lobes", help="1, or 2 for a second specular lobe (Ngan et al. 2005)"),
        seed: int = typer.Option(0, "--seed", help="random seed of the sampling and the starts"),
        as_json: bool = typer.Option(False, "--json", help="print the result as JSON"),
        report: Optional[str] = typer.Option(None, "--report", help="write a report (slices, spheres) into DIR"),
        all_measured: bool = typer.Option(False, "--all-measured", help="fit every built-in material"),
        set_name: str = typer.Option("all", "--set", help="with --all-measured: merl, rgl, nielsen, all, "
                                            "or a folder of measured files (.binary, .bin, .bsdf)"),
        limit: int = typer.Option(0, "--limit", help="with --all-measured: only the first N materials"),
        out: str = typer.Option("fit-results", "--out", "-o", help="with --all-measured: output folder"),
        scheduler: Optional[str] = typer.Option(None, "--scheduler",
                                                help="with --all-measured: a Dask scheduler, tcp://HOST:PORT"),
        workers: int = typer.Option(0, "--workers", help="with --all-measured, no --scheduler: local processes (0: one per CPU)"),
        resume: bool = typer.Option(False, "--resume", help="with --all-measured: keep the fits already in --out"),
    ) -> None:
        """Fit an analytic model to a measured material (a file or a built-in one); or a whole batch."""
        from .. import registry
        from .metrics import METRICS

        if metric not in METRICS:
            raise ValueError(f"unknown metric {metric!r}; valid metrics: {', '.join(METRICS)}")
        if not model:
            raise ValueError("missing --model NAME; valid models: " + ", ".join(registry.names()))
        n_samples = parse_samples(samples)
        if lobes not in (1, 2):
            raise ValueError(f"--lobes must be 1 or 2, got {lobes}")
        if all_measured:
            if source is not None:
                raise ValueError("give either SOURCE or --all-measured, not both")
            _batch(model, param, metric, starts, n_samples, seed, set_name, limit, out, as_json, lobes,
                   scheduler, workers, resume)
            return
        for flag, given in (("--scheduler", scheduler is not None), ("--resume", resume), ("--workers", workers != 0)):
            if given:
                raise ValueError(f"{flag} needs --all-measured")
        if source is None:
            raise ValueError("missing SOURCE: a measured file (.binary, .bin, .bsdf) or a built-in material "
                             "(see brdfkit list --measured)")
        if os.path.isdir(source):
            raise ValueError(f"{source} is a folder: fit every measured file in it with "
                             f"--all-measured --set {source} --out DIR")
        if len(model) != 1:
            raise ValueError("fit one --model at a time for a single SOURCE (several models need --all-measured)")
        _, name, items = parse_model_spec(model[0])
        _single(source, name, list(items) + list(param), metric, starts, n_samples, seed, as_json, report, lobes)


def _tabulate_cmd(source, param, fmt, out, as_json, resolution, n_theta, n_phi, ndf_resolution, description):
    from ..sources import from_cli
    from .tabulation import tabulate

    if out is None:
        raise ValueError("missing -o PATH: the file to write (.bsdf for rgl, .binary for merl, .bin for utia)")
    kw = dict(resolution=resolution, n_theta=n_theta, n_phi=n_phi, ndf_resolution=ndf_resolution,
              description=description)
    # the request (format, options, output path) is checked before the source is read
    from .tabulation import FORMATS, _format_of, _rgl_options
    from ..fileio import check_output_path

    fmt = _format_of(out, fmt)
    _rgl_options(fmt, dict(kw, isotropic=None))
    check_output_path(out, what=f"{fmt.upper()} file", suffixes=(FORMATS[fmt],))
    model = from_cli(source, param)
    res = tabulate(source, out, fmt, model=model, progress=not as_json, **kw)
    if as_json:
        print_json(res.to_json())
        return
    sh = res.shape
    size = {"rgl": lambda: f"{sh['n_phi']} x {sh['n_theta']} incident directions, {sh['resolution']}^2 samples each",
            "utia": lambda: "6 x 48 x 6 x 48 angles", "merl": lambda: "90 x 90 x 180 bins"}[res.format]()
    typer.echo(f"wrote {res.path} ({res.format}, {res.bytes / 1e6:.2f} MB, {size}) in {res.seconds:.1f} s")
    if res.error is not None:
        typer.echo(f"  tabulation error {100 * res.error:.3g} % ({res.error_measure}, {res.error_pairs} pairs)")


def _single(source, model_name, param, metric, starts, samples, seed, as_json, report, lobes=1) -> None:
    from .optimise import fit
    from .samples import resolve_source

    fixed = _fixed_for(model_name, param, strict=True)
    if report:
        from ..fileio import check_output_path

        check_output_path(report, what="report", is_dir=True)
    measured = resolve_source(source)
    res = fit(model_name, measured, fixed=fixed, metric=metric, starts=starts, samples=samples, seed=seed,
              lobes=lobes, progress=not as_json)
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
    if res.at_bound:
        typer.echo("  at a fitting bound: " + ", ".join(res.at_bound))
    if report:
        typer.echo(f"  report: {out['report']['index']}")


def _register_tabulate(app: typer.Typer) -> None:
    @app.command("tabulate")
    def tabulate_cmd(
        source: str = typer.Argument(..., help="any model: a name (brdfkit list), a built-in material, "
                                               "a .brdf, a fit's .json, a MERL .binary or an RGL .bsdf file"),
        param: List[str] = typer.Option([], "--param", "-p", help="a parameter of the model: name=value (repeatable)"),
        fmt: Optional[str] = typer.Option(None, "--format", "-f", help="merl, rgl or utia (default: told by the suffix of -o)"),
        out: Optional[str] = typer.Option(None, "--out", "-o", help="the file to write: .binary (merl), .bsdf (rgl) or .bin (utia)"),
        as_json: bool = typer.Option(False, "--json", help="print a JSON summary (path, format, sizes, error)"),
        resolution: Optional[int] = typer.Option(None, "--resolution", help="rgl: samples per side of each table (64)"),
        n_theta: Optional[int] = typer.Option(None, "--n-theta", help="rgl: incident elevations (32)"),
        n_phi: Optional[int] = typer.Option(None, "--n-phi",
                                            help="rgl: incident azimuths of an anisotropic model (10 per quarter turn)"),
        ndf_resolution: Optional[int] = typer.Option(None, "--ndf-resolution", help="rgl: NDF nodes per side (64)"),
        description: Optional[str] = typer.Option(None, "--description", help="rgl: the file's description text"),
    ) -> None:
        """Write any model as a measured file: MERL .binary, RGL .bsdf (Mitsuba 3's `measured`) or UTIA .bin."""
        _tabulate_cmd(source, param, fmt, out, as_json, resolution, n_theta, n_phi, ndf_resolution, description)


def _batch(models, param, metric, starts, samples, seed, set_name, limit, out, as_json, lobes=1,
           scheduler=None, workers=0, resume=False) -> None:
    import sys

    from ..fileio import check_output_path
    from .batch import run_batch

    sources = measured_names(set_name)
    if limit < 0:
        raise ValueError(f"--limit must be >= 0, got {limit}")
    if workers < 0:
        raise ValueError(f"--workers must be >= 0, got {workers}")
    if limit:
        sources = sources[:limit]
    if os.path.isdir(set_name):  # read every file once before any fit: a bad one is one line, not a dead batch
        from ..sources import MEASURED, resolve

        for path in sources:
            resolve(path, kinds=MEASURED)
    specs = [parse_model_spec(m) for m in models]
    labels = [lab for lab, _, _ in specs]
    if len(set(labels)) != len(labels):
        raise ValueError("a --model is given twice")
    fixed, used = {}, set()
    names = {}
    for lab, name, items in specs:
        fixed[lab] = dict(_fixed_for(name, param, strict=False), **_fixed_for(name, items, strict=True))
        used |= set(_fixed_for(name, param, strict=False))
        names[lab] = name
    for item in param:
        if item.partition("=")[0].strip() not in used:
            raise ValueError(f"parameter assignment {item!r} matches none of the models {', '.join(models)}")
    check_output_path(out, what="batch output", is_dir=True)
    show = not as_json
    t0 = time.perf_counter()

    def progress(done, total, rec):
        if show:
            print(f"[{done}/{total}] {rec['source']} {rec['column']}: {rec['error']:.4g} "
                  f"({time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)

    try:
        res = run_batch(labels, sources, out, names=names, fixed=fixed, metric=metric, samples=samples,
                        starts=starts, seed=seed, lobes=lobes, scheduler=scheduler, workers=workers or None,
                        resume=resume, progress=progress)
    except KeyboardInterrupt:
        print(f"brdfkit: interrupted; finished fits are kept in {os.path.join(out, 'fits')} "
              "(run again with --resume)", file=sys.stderr, flush=True)
        raise
    paths = res.files
    if as_json:
        print_json({"metric": metric, "seconds": round(res.seconds, 2), "files": paths, "fitted": res.fitted,
                    "skipped": res.skipped, "at_bound": res.at_bound, "results": [r for r in res.records if r]})
        return
    typer.echo(f"fitted {res.fitted} and kept {res.skipped} of {len(res.jobs)} fits "
               f"({len(labels)} model(s) × {len(sources)} material(s)) in {res.seconds:.1f} s")
    if res.at_bound:
        typer.echo(f"  {len(res.at_bound)} fit(s) ended on a fitting bound (listed in fit_errors.md)")
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
