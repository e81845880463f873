"""``brdfkit export``: a model, a measured material or a fit's result as a Mitsuba / MaterialX / glTF material.

    brdfkit export microfacet -p alpha=0.3 --to mitsuba -o gold.xml
    brdfkit export merl/gold-metallic-paint --to gltf -o gold.glb
    brdfkit fit merl/chrome --model microfacet --json > fit.json
    brdfkit export fit.json --to materialx -o chrome.mtlx --json
"""

from __future__ import annotations

import json
import os
from typing import Any, List

import numpy as np
import typer

from ..cli_common import print_json


def model_from_fit_json(path: str, items: List[str] | None = None):
    """The fitted model of a ``brdfkit fit ... --json`` file (``-p`` items override its parameters)."""
    import brdfkit as bk
    from brdfkit.params import parse_assignments
    from brdfkit.registry import get

    try:
        with open(path, encoding="utf-8") as fh:
            obj = json.load(fh)
    except OSError as e:
        raise ValueError(f"{path}: cannot read: {e.strerror or e}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise ValueError(f"{path}: not valid JSON ({e})") from None
    if isinstance(obj, list) and len(obj) == 1:
        obj = obj[0]
    if not isinstance(obj, dict) or not isinstance(obj.get("model"), str) or not isinstance(obj.get("params"), dict):
        raise ValueError(f"{path}: expected the JSON of 'brdfkit fit ... --json' (an object with 'model' and 'params')")
    name = obj["model"]
    cls = get(name)
    params: dict[str, Any] = {k: (np.asarray(v, dtype=np.float64) if isinstance(v, list) else v)
                              for k, v in obj["params"].items() if v is not None}
    params.update(parse_assignments(name, cls.spec, items or ()))
    model = bk.model(name, **params)
    src = obj.get("source")
    try:
        model.label = f"{name} fitted to {src}" if src else name
    except AttributeError:  # pragma: no cover
        pass
    return model


def source_model(source: str, items: List[str] | None = None):
    """SOURCE of ``brdfkit export``: a model name or ``.brdf`` file, a measured material / MERL file,
    or a fit's JSON (``brdfkit fit ... --json > fit.json``)."""
    from ..cli_common import model_from_cli

    if source.lower().endswith(".json"):
        if not os.path.isfile(source):
            raise ValueError(f"{source}: no such file (a fit's JSON: brdfkit fit ... --json > {source})")
        return model_from_fit_json(source, items)
    return model_from_cli(source, items)


def register(app: typer.Typer) -> None:
    @app.command("export")
    def export_cmd(
        source: str = typer.Argument(..., help="model name, .brdf file, measured material / MERL file, or a fit's JSON"),
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
