"""Core commands: ``brdfkit list``, ``brdfkit info MODEL``, ``brdfkit eval MODEL``.

Everything here is generic over the registry: the model list, the parameter
tables and the parsing of ``-p name=value`` all come from the models'
:class:`brdfkit.params.Param` specs, so a newly registered model appears in
every command without touching this file.

Conventions (SPEC.md): ``wi`` points toward the light, ``wo`` toward the
viewer, normal ``+z``, tangent ``+x``; ``eval`` prints f_r in 1/sr (no cosine).
``--wi THETA,PHI`` / ``--wo THETA,PHI`` take degrees (theta from the normal,
phi from the tangent ``+x`` toward ``+y``); ``--wi-vec`` / ``--wo-vec`` take
vectors, normalised here.
"""

from __future__ import annotations

from typing import Any, List, Optional

import numpy as np
import typer

from . import registry
from .cli_common import (
    direction_from_degrees,
    direction_from_vector,
    model_from_cli,
    print_json,
)


def _console():
    """A rich console; 120 columns when the output is not a terminal (pipes, files)."""
    from rich.console import Console

    con = Console(highlight=False)
    if not con.is_terminal:
        con = Console(highlight=False, width=120)
    return con


def _fmt_default(value: Any, brackets: bool = False) -> str:
    """A parameter value for display (4 significant digits; an RGB triple of equal values as one number)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple, np.ndarray)):
        vals = [float(v) for v in value]
        if len(set(vals)) == 1:
            return f"{vals[0]:.4g}"
        text = ", ".join(f"{v:.4g}" for v in vals)
        return f"[{text}]" if brackets else text
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def _cli_text(value: Any) -> str:
    """A parameter value as typed after ``-p name=`` (full precision, no spaces)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple, np.ndarray)):
        vals = [float(v) for v in value]
        return f"{vals[0]:g}" if len(set(vals)) == 1 else ",".join(f"{v:g}" for v in vals)
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def _direction(angles: Optional[str], vec: Optional[str], name: str) -> np.ndarray:
    if angles is not None and vec is not None:
        raise ValueError(f"give either --{name} THETA,PHI or --{name}-vec x,y,z, not both")
    if angles is not None:
        return direction_from_degrees(angles, f"--{name}")
    if vec is not None:
        return direction_from_vector(vec, f"--{name}-vec")
    raise ValueError(f"missing --{name}: give --{name} THETA,PHI (degrees) or --{name}-vec x,y,z")


def list_rows() -> list[dict[str, Any]]:
    """One row per registered model: name, title, reference, isotropic, parameter names."""

    rows = []
    for name in registry.names():
        info = registry.get(name).info()
        rows.append(
            {
                "name": info["name"],
                "isotropic": bool(info["isotropic"]),
                "title": info["title"],
                "reference": info["reference"],
                "params": [p["name"] for p in info["params"]],
            }
        )
    return rows


def eval_result(m: Any, wi: np.ndarray, wo: np.ndarray) -> dict[str, Any]:
    """What ``brdfkit eval --json`` prints for the model ``m`` at unit directions ``wi``, ``wo`` (3,)."""
    f = m.eval(wi, wo)
    return {
        "model": getattr(m, "label", None) or m.name,
        "params": m.params_json(),
        "wi": [float(x) for x in wi],
        "wo": [float(x) for x in wo],
        "value": [float(x) for x in np.asarray(f).reshape(3)],
    }


def measured_info(name: str, m: Any) -> dict[str, Any]:
    """What ``brdfkit info`` shows for a measured material (a built-in name or a MERL file)."""
    kind = type(m).__name__
    title = {
        "NeuralBRDF": "built-in measured material (Neural-BRDF network trained on the measurement)",
        "MERLBRDF": "measured material from a MERL .binary table (90 x 90 x 180 bins)",
        "UTIABRDF": "measured material from a UTIA .bin table (6 x 48 x 6 x 48, Filip & Vavra 2014)",
    }.get(kind, "measured material")
    return {
        "name": getattr(m, "label", None) or name,
        "title": title,
        "kind": kind,
        "source": getattr(m, "source", "") or getattr(m, "label", None) or name,
        "isotropic": bool(getattr(m, "isotropic", True)),
        "params": [],
    }


def _measured_info(name: str, m: Any, json_: bool) -> None:
    data = measured_info(name, m)
    if json_:
        print_json(data)
        return
    con = _console()
    iso = "isotropic" if data["isotropic"] else "anisotropic"
    con.print(f"{data['name']}: {data['title']} ({iso})", markup=False, soft_wrap=True)
    if data["source"] != data["name"]:
        con.print(f"Source: {data['source']}", markup=False, soft_wrap=True)
    con.print(
        f"Measured data has no parameters. Use it wherever a model is taken, e.g. "
        f"brdfkit eval {name} --wi 30,0 --wo 30,180; brdfkit list --measured lists the built-in ones.",
        markup=False,
        soft_wrap=True,
    )


def register(app: typer.Typer) -> None:
    @app.command("list")
    def list_models(
        json_: bool = typer.Option(False, "--json", help="Print a JSON list instead of a table."),
        measured: bool = typer.Option(False, "--measured", help="List the built-in measured materials instead."),
    ) -> None:
        """List the registered reflectance models."""
        if measured:
            from .measured.commands import list_measured

            return list_measured(json_)
        rows = list_rows()
        if json_:
            print_json(rows)
            return
        from rich.table import Table
        from rich.text import Text

        t = Table(title=f"brdfkit models ({len(rows)})", title_justify="left")
        t.add_column("name", style="bold", no_wrap=True)
        t.add_column("symmetry", no_wrap=True)
        t.add_column("description")
        t.add_column("reference")
        for r in rows:
            t.add_row(*map(Text, (r["name"], "isotropic" if r["isotropic"] else "anisotropic", r["title"], r["reference"])))
        _console().print(t)

    @app.command("info")
    def info(
        model: str = typer.Argument(..., metavar="MODEL", help="Registry name (see `brdfkit list`)."),
        json_: bool = typer.Option(False, "--json", help="Print the model info as JSON."),
    ) -> None:
        """Show a model's title, reference and parameter table (or what a measured material is)."""
        from .sources import identify

        src = identify(model)
        if src.is_measured:
            return _measured_info(model, src.build(), json_)
        data = src.model_class().info()
        if json_:
            print_json(data)
            return
        from rich.markup import escape
        from rich.table import Table
        from rich.text import Text

        con = _console()
        sym = "isotropic" if data["isotropic"] else "anisotropic"
        con.print(f"[bold]{escape(data['name'])}[/bold]: {escape(data['title'])} ({sym})", soft_wrap=True)
        con.print(f"Reference: {data['reference']}", soft_wrap=True, markup=False)
        t = Table(title_justify="left")
        for col in ("name", "kind", "default", "range", "unit", "doc"):
            t.add_column(col, no_wrap=col in ("name", "kind"), overflow="fold")
        for p in data["params"]:
            cells = (p["name"], p["kind"], _fmt_default(p["default"]), p["range"], p["unit"], p["doc"])
            t.add_row(*(Text(str(c)) for c in cells))
        con.print(t)
        if data["params"]:
            p0 = data["params"][0]
            con.print(
                f"Set parameters with -p name=value, e.g. brdfkit eval {data['name']} "
                f"-p {p0['name']}={_cli_text(p0['default'])} --wi 30,0 --wo 30,180",
                markup=False,
                soft_wrap=True,
            )

    @app.command("eval")
    def eval_cmd(
        model: str = typer.Argument(..., metavar="MODEL", help="Registry name (see `brdfkit list`)."),
        param: List[str] = typer.Option(
            [], "-p", "--param", metavar="NAME=VALUE", help="Parameter as name=value (number, r,g,b, true/false, choice). Repeatable."
        ),
        wi: Optional[str] = typer.Option(None, "--wi", metavar="THETA,PHI", help="Light direction THETA,PHI in degrees."),
        wo: Optional[str] = typer.Option(None, "--wo", metavar="THETA,PHI", help="View direction THETA,PHI in degrees."),
        wi_vec: Optional[str] = typer.Option(None, "--wi-vec", metavar="X,Y,Z", help="Light direction as a vector x,y,z (normalised)."),
        wo_vec: Optional[str] = typer.Option(None, "--wo-vec", metavar="X,Y,Z", help="View direction as a vector x,y,z (normalised)."),
        json_: bool = typer.Option(False, "--json", help="Print model, params, wi, wo and value as JSON."),
    ) -> None:
        """Evaluate f_r(wi, wo) in 1/sr (RGB, without the cosine factor).

        wi points toward the light, wo toward the viewer; the normal is +z and
        the tangent +x. Example: brdfkit eval ward -p alpha_x=0.1 --wi 30,0 --wo 30,180
        """
        m = model_from_cli(model, param)  # an unknown model or bad -p first: the clearest message
        v_in = _direction(wi, wi_vec, "wi")
        v_out = _direction(wo, wo_vec, "wo")
        res = eval_result(m, v_in, v_out)
        if json_:
            print_json(res)
            return
        con = _console()
        args = ", ".join(f"{k}={_fmt_default(v, brackets=True)}" for k, v in res["params"].items())
        con.print(f"{res['model']}({args})", markup=False)
        con.print(
            "wi = ({:.6g}, {:.6g}, {:.6g})  wo = ({:.6g}, {:.6g}, {:.6g})".format(*res["wi"], *res["wo"]),
            markup=False,
        )
        r, g, b = res["value"]
        con.print(f"f_r = {r:.7g} {g:.7g} {b:.7g}  [1/sr, RGB]", markup=False)
