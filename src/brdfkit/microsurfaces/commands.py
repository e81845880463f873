"""``brdfkit measure``: a whole BRDF table measured on an explicit microsurface, written as a file.

    brdfkit measure beckmann -p alpha=0.5 --format merl -o beckmann.binary --samples 200000
    brdfkit measure ggx -p alpha=0.3 -p fresnel=conductor -o ggx.bsdf --n-theta 32 --json

The surface is traced from ``--n-theta`` incident angles, ``--samples`` paths each, binned (see
:mod:`brdfkit.microsurfaces.table`) and written with ``bk.tabulate`` (MERL ``.binary`` or RGL
``.bsdf``), so every command that reads those files takes the result.
"""

from __future__ import annotations

import time
from typing import Any, List, Optional

import typer

from ..cli_common import print_json

#: -p names that are the surface's own (the rest are microfacet's facet/roughness parameters)
_OWN = {"angle": float, "resolution": int, "seed": int, "engine": str, "max_bounces": int}


def parse_surface_params(items: List[str]) -> dict[str, Any]:
    """``-p name=value`` strings: the surface's own names, ``fresnel=white``, else microfacet's table."""
    from ..models.microfacet import Microfacet
    from ..params import parse_assignments

    own: dict[str, Any] = {}
    rest: list[str] = []
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep:
            raise ValueError(f"-p {item!r}: expected name=value")
        if name in _OWN:
            try:
                own[name] = _OWN[name](value.strip())
            except ValueError:
                raise ValueError(f"-p {item!r}: {name} must be {_OWN[name].__name__}") from None
        elif name == "fresnel" and value.strip() == "white":
            own["fresnel"] = "white"
        else:
            rest.append(item)
    facet = parse_assignments("microsurface", Microfacet.spec, rest)
    return {**facet, **own}


def _measure_cmd(kind, param, fmt, out, samples, n_theta, bounces, as_json) -> None:
    from ..fileio import check_output_path
    from ..measured.progress import fit_progress
    from ..measured.tabulation import FORMATS, _format_of, tabulate
    from . import microsurface

    if out is None:
        raise ValueError("missing -o PATH: the file to write (.binary for merl, .bsdf for rgl)")
    fmt = _format_of(out, fmt)
    check_output_path(out, what=f"{fmt.upper()} file", suffixes=(FORMATS[fmt],))
    surface = microsurface(kind, **parse_surface_params(param))
    t0 = time.perf_counter()
    with fit_progress(not as_json, f"measure {kind}", n_theta, unit="incident angles") as step:
        table = surface.table(n_theta=n_theta, samples=samples, bounces=bounces, progress=step)
    res = tabulate(kind, out, fmt, model=table, progress=not as_json)
    if as_json:
        print_json(dict(res.to_json(), samples=samples, n_theta=n_theta))
        return
    typer.echo(f"wrote {res.path} ({res.format}, {res.bytes / 1e6:.2f} MB) from {n_theta} x {samples} traced paths "
               f"in {time.perf_counter() - t0:.1f} s")
    if res.error is not None:
        typer.echo(f"  tabulation error {100 * res.error:.3g} % ({res.error_measure}, {res.error_pairs} pairs)")


def register(app: typer.Typer) -> None:
    @app.command("measure")
    def measure_cmd(
        kind: str = typer.Argument(..., help="v-groove, beckmann or ggx (only isotropic surfaces tabulate)"),
        param: List[str] = typer.Option([], "--param", "-p",
                                        help="alpha, fresnel (white|conductor|dielectric|schlick), eta, k, f0, "
                                             "resolution, seed, engine: name=value (repeatable)"),
        fmt: Optional[str] = typer.Option(None, "--format", "-f", help="merl or rgl (default: told by the suffix of -o)"),
        out: Optional[str] = typer.Option(None, "--out", "-o", help="the file to write: .binary (merl) or .bsdf (rgl)"),
        samples: int = typer.Option(200000, "--samples", help="traced paths per incident angle"),
        n_theta: int = typer.Option(24, "--n-theta", help="incident angles, uniform in θ on [0, 89°]"),
        bounces: Optional[int] = typer.Option(None, "--bounces", help="only paths with exactly this many reflections"),
        as_json: bool = typer.Option(False, "--json", help="print a JSON summary (path, format, sizes, error)"),
    ) -> None:
        """Measure a BRDF on an explicit microsurface (traced with Mitsuba 3) and write it as a MERL/RGL file."""
        _measure_cmd(kind, param, fmt, out, samples, n_theta, bounces, as_json)
