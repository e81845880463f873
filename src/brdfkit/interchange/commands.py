"""``brdfkit export``: a model, a measured material or a fit's result as a Mitsuba / MaterialX / glTF material.

    brdfkit export microfacet -p alpha=0.3 --to mitsuba -o gold.xml
    brdfkit export merl/gold-metallic-paint --to gltf -o gold.glb
    brdfkit fit merl/chrome --model microfacet --json > fit.json
    brdfkit export fit.json --to materialx -o chrome.mtlx --json
"""

from __future__ import annotations

from typing import List

import typer

from ..cli_common import print_json


def source_model(source: str, items: List[str] | None = None):
    """SOURCE of ``brdfkit export``: anything :mod:`brdfkit.sources` resolves (a model name or ``.brdf``
    file, a measured material / MERL file, or a fit's JSON, whose parameters ``-p`` overrides)."""
    from ..sources import from_cli

    return from_cli(source, items)


def register(app: typer.Typer) -> None:
    @app.command("export")
    def export_cmd(
        source: str = typer.Argument(..., help="model name, .brdf file, measured material or file (.binary, .bin, .bsdf), or a fit's JSON"),
        param: List[str] = typer.Option([], "--param", "-p", help="set a parameter: name=value (repeatable)"),
        to: str = typer.Option(..., "--to", help="mitsuba, materialx or gltf"),
        output: str = typer.Option(..., "--output", "-o", help="file to write: .xml/.json (mitsuba), .mtlx, .glb"),
        metric: str = typer.Option("ngan", "--metric", help="error metric of fitted exports: ngan, l2, log, cbrt"),
        as_json: bool = typer.Option(False, "--json", help="print the result as JSON (with --to mitsuba: and the mi.load_dict dict)"),
    ) -> None:
        """Write a material for Mitsuba 3, MaterialX (OpenPBR) or glTF; fitted where the target can't express it."""
        from .export import FORMATS, _check_path, export

        if to not in FORMATS:
            raise ValueError(f"unknown --to {to!r}; valid formats: {', '.join(FORMATS)}")
        _check_path(output, to)  # before any (possibly long) work
        model = source_model(source, param)
        r = export(model, to, output, metric=metric, name=getattr(model, "label", None) or source)
        if as_json:
            out = r.to_json()
            if to == "mitsuba":
                out["mitsuba_dict"] = r.params
            print_json(out)
            return
        how = "exact" if r.exact else f"{r.method}: error {r.error:.4g} ({r.metric}), {100 * r.relative_error:.2f} % relative"
        typer.echo(f"wrote {r.path}: {r.target} ({how})")
        if r.note:
            typer.echo(f"  {r.note}")
