"""Regenerate the figures of docs/physics.md and the README.

    python -m brdfkit.analysis.figures [OUTDIR]      (default docs/img)

Writes ``verdict_table.png``, ``albedo_curves.png``, ``polar_example.png``,
``lobe_example.png``, ``slice_example.png`` and ``sphere_example.png``, and prints the
verdict table as markdown.
"""

from __future__ import annotations

import sys
from pathlib import Path

from .. import sources

from . import plots


def albedo_models():
    """The README comparison: Phong, normalised Phong, Blinn-Phong, Cook-Torrance 1982, microfacet."""
    return [
        (sources.model("phong", kd=0.0, ks=1.0, shininess=10.0, normalized=False), "Phong 1975 as a BRDF, (r·v)^10/cos θi"),
        (sources.model("phong", kd=0.0, ks=1.0, shininess=10.0, normalized=True), "Phong normalised (Lewis 1994), s=10"),
        (
            sources.model("blinn-phong", kd=0.0, ks=1.0, shininess=40.0, normalized=True),
            "Blinn-Phong normalised, (s+8)/(8π)(n·h)^40",
        ),
        (sources.model("cook-torrance", kd=0.0, ks=1.0, m=0.3, ior=10.0), "Cook-Torrance 1982, m=0.3, ior=10"),
        (
            sources.model(
                "microfacet", distribution="beckmann", alpha=0.3, shadowing="v-groove",
                fresnel="dielectric", eta=10.0, k=0.0, kd=0.0, ks=1.0,
            ),
            "same, modern 1/(4 n·l n·v) form (Walter 2007)",
        ),
        (
            sources.model("microfacet", distribution="ggx", alpha=0.3, shadowing="smith", fresnel="none", kd=0.0, ks=1.0),
            "microfacet GGX α=0.3, Smith G, no Fresnel",
        ),
    ]


def markdown_table(results) -> str:
    lines = [
        "| model | setting | reciprocal | asymmetry | energy conserving | max albedo | at θ |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in results:
        lines.append(
            f"| {r['model']} | {plots.setting_text(r.get('changed', {}))} | "
            f"{'yes' if r['reciprocal'] else '**no**'} | {r['reciprocity_error']:.1e} | "
            f"{'yes' if r['energy_conserving'] else '**no**'} | "
            f"{r['max_albedo']:.4f} ± {r['integration_error']:.0e} | {plots.where_text(r)} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    out = Path(argv[0] if argv else "docs/img")
    out.mkdir(parents=True, exist_ok=True)
    from .verdict import check_all

    results = check_all(level="fast", jobs=2)
    plots.save_figure(plots.verdict_table_figure(results), out / "verdict_table.png")
    pairs = albedo_models()
    fig = plots.albedo_plot(
        [m for m, _ in pairs],
        labels=[t for _, t in pairs],
        level="normal",
        title="White-furnace albedo a(θo) = ∫ f_r cos θi dωi, kd = 0, ks = 1\n"
        "dotted: ρ(θi) = ∫ f_r cos θo dωo for the non-reciprocal form",
    )
    fig.axes[0].set_ylim(0, 4.5)
    plots.save_figure(fig, out / "albedo_curves.png")
    cmp = [
        sources.model("phong", kd=0.1, ks=0.9, shininess=30.0),
        sources.model("blinn-phong", kd=0.1, ks=0.9, shininess=120.0),
        sources.model("microfacet", distribution="ggx", alpha=0.25, fresnel="none", kd=0.1, ks=0.9),
        sources.model("cook-torrance", kd=0.1, ks=0.9, m=0.25, ior=1.5),
    ]
    plots.save_figure(plots.polar_plot(cmp, 60.0, log=True), out / "polar_example.png")
    plots.save_figure(
        plots.lobe_plot([sources.model("ward", kd=0.1, ks=0.4, alpha_x=0.08, alpha_y=0.3), cmp[2]], 50.0),
        out / "lobe_example.png",
    )
    plots.save_figure(plots.slice_plot([cmp[3], cmp[2]]), out / "slice_example.png")
    plots.save_figure(
        plots.sphere_plot(
            [
                sources.model("lambert", kd=0.7),
                sources.model("oren-nayar", kd=0.7, sigma=1.0),
                cmp[0],
                sources.model("ward", kd=0.3, ks=0.3, alpha_x=0.05, alpha_y=0.3),
                sources.model("microfacet", alpha=0.2),
            ],
            size=200,
        ),
        out / "sphere_example.png",
    )
    print(markdown_table(results))


if __name__ == "__main__":
    main()
