"""``brdfkit check`` and ``brdfkit plot``."""

from __future__ import annotations

import math
import os
from typing import Any, List, Optional

import typer

from ..cli_common import model_from_cli, print_json


def _run_all(level: str, jobs: int, quiet: bool) -> list[dict[str, Any]]:
    """check_all, in ``jobs`` processes, with a rich progress bar on stderr."""
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from .verdict import run_checks, stress_jobs

    work = stress_jobs()
    console = Console(stderr=True)
    with Progress(
        TextColumn("checking {task.description:<32}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TimeElapsedColumn(),
        console=console,
        disable=quiet or not console.is_terminal,
        transient=True,
    ) as prog:
        task = prog.add_task("", total=len(work))
        return run_checks(
            work, level=level, jobs=jobs, progress=lambda n, s, r: prog.update(task, advance=1, description=n)
        )


def _table(results: list[dict[str, Any]]) -> None:
    from rich.console import Console
    from rich.table import Table

    from .plots import setting_text, where_text

    t = Table(title="brdfkit check --all: reciprocity and energy conservation", show_lines=False)
    for col, just in (
        ("model", "left"),
        ("setting", "left"),
        ("reciprocal", "center"),
        ("asymmetry", "right"),
        ("energy", "center"),
        ("max albedo", "right"),
        ("at θ", "right"),
        ("± err", "right"),
    ):
        t.add_column(col, justify=just, overflow="fold")
    for r in results:
        t.add_row(
            r["model"],
            setting_text(r.get("changed", {})),
            "yes" if r["reciprocal"] else "NO",
            f"{r['reciprocity_error']:.1e}",
            "yes" if r["energy_conserving"] else "NO",
            f"{r['max_albedo']:.4f}",
            where_text(r),
            f"{r['integration_error']:.0e}",
        )
    Console(width=max(150, int(os.environ.get("COLUMNS", "0") or 0))).print(t)


def _note(message: str) -> None:
    """Tell the user (stderr) what was done on their behalf, e.g. a created output folder."""
    typer.echo(f"brdfkit: {message}", err=True)


def register(app: typer.Typer) -> None:
    @app.command("check")
    def check_cmd(
        model: Optional[str] = typer.Argument(None, help="a model (see `brdfkit list`), a built-in measured material or a file (.bsdf, .bin, .binary, .brdf, fit .json)"),
        param: List[str] = typer.Option([], "-p", "--param", help="parameter name=value (repeatable)"),
        all_models: bool = typer.Option(False, "--all", help="every model at its defaults and stress settings"),
        json_out: bool = typer.Option(False, "--json", help="print JSON (a list with --all)"),
        level: Optional[str] = typer.Option(
            None, "--level", help="quadrature level: fast | normal | fine (default: normal, fast with --all)"
        ),
        jobs: int = typer.Option(
            min(2, os.cpu_count() or 1), "--jobs", "-j", help="worker processes for --all"
        ),
        plot_path: Optional[str] = typer.Option(
            None, "--plot", help="--all: also save the verdict table as a figure (.png, .svg, .pdf)"
        ),
    ) -> None:
        """Reciprocity and energy conservation (albedo, white furnace) of a model."""
        from .albedo import LEVELS
        from .verdict import check

        if level is not None and level not in LEVELS:
            raise ValueError(f"check: --level must be one of {', '.join(LEVELS)}, got {level!r}")
        if not 1 <= jobs <= 256:
            raise ValueError(f"check: --jobs must lie in [1, 256], got {jobs}")
        if all_models:
            if model is not None or param:
                raise ValueError("check: give either MODEL [-p ...] or --all, not both")
        elif plot_path is not None:
            raise ValueError("check: --plot goes with --all")
        if all_models:
            if plot_path is not None:  # before the work: a bad path must not cost the whole run
                from ..fileio import check_output_path
                from .plots import FORMATS

                check_output_path(plot_path, what="check --plot", suffixes=FORMATS, notify=_note)
            results = _run_all(level or "fast", jobs, quiet=json_out)
            if plot_path is not None:
                from .plots import save_figure, verdict_table_figure

                save_figure(verdict_table_figure(results), plot_path)
            if json_out:
                print_json(results)
            else:
                _table(results)
            return
        if model is None:
            raise ValueError("check: give a MODEL (see `brdfkit list`) or --all")
        m = model_from_cli(model, param)
        r = check(m, level=level or "normal")
        if json_out:
            print_json(r)
            return
        from .plots import label

        typer.echo(label(m))
        w = r["reciprocity_worst"]
        typer.echo(
            f"  reciprocal:        {'yes' if r['reciprocal'] else 'NO'} (largest relative asymmetry "
            f"{r['reciprocity_error']:.2e}"
            + ("" if r["reciprocal"] else f" at wi={w['wi_deg']}°, wo={w['wo_deg']}°")
            + f"; tolerance {r['reciprocity_tolerance']:.1e}, {r['reciprocity_precision']} evaluation)"
        )
        typer.echo(
            f"  energy conserving: {'yes' if r['energy_conserving'] else 'NO'} (max albedo {r['max_albedo']:.6f} "
            f"± {r['integration_error']:.1e} at θ={r['max_albedo_theta_deg']:g}°"
            + (", light-incidence reflectance" if r["max_albedo_curve"] == "albedo_light" else "")
            + ")"
        )
        typer.echo(f"  white furnace:     {r['white_furnace']}")
        a = r["albedo"]
        cells = [f"{t:g}°:{max(v):.4f}" for t, v in zip(a["theta_deg"], a["rgb"])]
        typer.echo("  albedo a(θo):      " + "  ".join(cells))

    @app.command(
        "plot",
        context_settings={"ignore_unknown_options": True, "allow_extra_args": True},
    )
    def plot_cmd(
        spec: List[str] = typer.Argument(
            ...,
            metavar="MODEL [-p k=v ...] [--vs MODEL [-p k=v ...]] ...",
            help="the model, its parameters, and models to overlay with --vs (each with its own -p)",
        ),
        kind: str = typer.Option("polar", "--kind", "-k", help="polar | lobe | albedo | slice | sphere"),
        output: str = typer.Option("brdf.png", "--output", "-o", help="output file: .png, .svg or .pdf"),
        theta_i: float = typer.Option(45.0, "--theta-i", help="light polar angle in degrees (polar, lobe, sphere)"),
        phi_i: Optional[float] = typer.Option(
            None, "--phi-i", help="light azimuth in degrees (default 0; sphere: 135, the upper left)"
        ),
        log: bool = typer.Option(False, "--log", help="log scale (polar radius, lobe, albedo axis, sphere tone map; the slice is always log)"),
        no_cos: bool = typer.Option(False, "--no-cos", help="polar: plot f_r instead of f_r·cos θo"),
        phi_d: float = typer.Option(90.0, "--phi-d", help="slice: φd in degrees"),
        exposure: float = typer.Option(1.0, "--exposure", help="sphere: radiance scale"),
        size: int = typer.Option(256, "--size", help="sphere: image size in pixels"),
        level: str = typer.Option("fast", "--level", help="albedo: quadrature level fast | normal | fine"),
    ) -> None:
        """Plot one or more models: in-plane polar slice, 3D lobe, albedo curves, θh×θd slice, lit sphere.

        Example: brdfkit plot phong -p shininess=50 --vs blinn-phong -p shininess=200 --kind polar -o cmp.png
        """
        from .plots import KINDS, plot, save_figure

        if kind not in KINDS:
            raise ValueError(f"plot: --kind must be one of {', '.join(KINDS)}, got {kind!r}")
        for what, v in (("--theta-i", theta_i), ("--phi-i", phi_i or 0.0), ("--phi-d", phi_d), ("--exposure", exposure)):
            if not math.isfinite(v):
                raise ValueError(f"plot: {what} must be finite, got {v!r}")
        if not exposure > 0:
            raise ValueError(f"plot: --exposure must be positive, got {exposure:g}")
        if not 16 <= size <= 4096:
            raise ValueError(f"plot: --size must lie in [16, 4096], got {size}")
        if not 0.0 <= phi_d <= 360.0:
            raise ValueError(f"plot: --phi-d must lie in [0, 360] degrees, got {phi_d:g}")
        if kind in ("polar", "lobe") and not 0.0 <= theta_i <= 90.0:
            raise ValueError(f"plot: --theta-i must lie in [0, 90] degrees, got {theta_i:g}")
        models = [model_from_cli(n, items) for n, items in parse_model_groups(spec)]
        from ..fileio import check_output_path
        from .plots import FORMATS

        check_output_path(output, what="plot", suffixes=FORMATS, notify=_note)
        opts: dict[str, Any] = {"log": log}
        if kind == "polar":
            opts.update(theta_i_deg=theta_i, phi_i_deg=phi_i or 0.0, cosine=not no_cos)
        elif kind == "lobe":
            opts.update(theta_i_deg=theta_i, phi_i_deg=phi_i or 0.0)
        elif kind == "albedo":
            opts.update(level=level)
        elif kind == "slice":
            opts.update(phi_d_deg=phi_d, log=True)  # f spans decades: always a log colour scale
        elif kind == "sphere":
            if not 0.0 <= theta_i < 90.0:
                raise ValueError(f"plot: --theta-i must lie in [0, 90) degrees, got {theta_i:g}")
            opts.update(
                light_theta_deg=theta_i, light_phi_deg=135.0 if phi_i is None else phi_i, exposure=exposure, size=size
            )
        fig = plot(kind, models, **opts)
        path = save_figure(fig, output)
        typer.echo(f"wrote {path}")


def parse_model_groups(tokens: list[str]) -> list[tuple[str, list[str]]]:
    """``MODEL -p a=1 --vs M2 -p b=2`` -> ``[("MODEL", ["a=1"]), ("M2", ["b=2"])]``."""
    groups: list[tuple[str, list[str]]] = []
    i = 0
    toks = list(tokens)
    while i < len(toks):
        t = toks[i]
        if t in ("-p", "--param"):
            if not groups:
                raise ValueError("plot: -p must follow a MODEL")
            if i + 1 >= len(toks):
                raise ValueError("plot: -p needs a name=value")
            groups[-1][1].append(toks[i + 1])
            i += 2
        elif t.startswith("--param="):
            if not groups:
                raise ValueError("plot: -p must follow a MODEL")
            groups[-1][1].append(t.split("=", 1)[1])
            i += 1
        elif t.startswith("-p") and len(t) > 2:
            if not groups:
                raise ValueError("plot: -p must follow a MODEL")
            groups[-1][1].append(t[2:])
            i += 1
        elif t == "--vs":
            if not groups:
                raise ValueError("plot: --vs must follow a MODEL")
            if i + 1 >= len(toks) or toks[i + 1].startswith("-"):
                raise ValueError("plot: --vs needs a MODEL name")
            groups.append((toks[i + 1], []))
            i += 2
        elif t.startswith("-"):
            raise ValueError(f"plot: unknown option {t!r}; see `brdfkit plot --help`")
        else:
            if groups:
                raise ValueError(f"plot: unexpected {t!r}; overlay further models with --vs MODEL")
            groups.append((t, []))
            i += 1
    if not groups:
        raise ValueError("plot: give a MODEL (see `brdfkit list`)")
    if len(groups) > 9:
        raise ValueError("plot: at most 9 models per plot")
    return groups
