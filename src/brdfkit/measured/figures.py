"""The formats picture of ``docs/measured.md``: one material from MERL, from RGL and from its fit.

    python -m brdfkit.measured.figures [OUT.png] [--material merl/gold-metallic-paint]

Writes (default ``docs/img/formats_example.png``): the built-in material tabulated to a MERL
file (``bk.tabulate``), that MERL file tabulated to an RGL file, and the microfacet model (GGX,
Smith, Schlick, Lambert) fitted to the MERL file; top row, each lit as a sphere (directional
light at 45°, the same exposure, log tone map); bottom, the incidence plane at θi = 45°,
``f_r cos θi`` of the three against θo (log scale), with each file's tabulation error and the
fit's error in the legend. Everything is recomputed (about 15 s).
"""

from __future__ import annotations

import math
import os
import sys
import tempfile

import numpy as np

DEFAULT_OUT = os.path.join("docs", "img", "formats_example.png")


def _in_plane(model, theta_i_deg: float, theta_o: np.ndarray) -> np.ndarray:
    """``f_r cos θi`` luminance in the incidence plane (φo = 180°: positive θo is the mirror side)."""
    ti = math.radians(theta_i_deg)
    wi = np.array([math.sin(ti), 0.0, math.cos(ti)])
    to = np.radians(theta_o)
    wo = np.stack([-np.sin(to), np.zeros_like(to), np.cos(to)], axis=1)
    f = np.asarray(model.eval(np.broadcast_to(wi, wo.shape), wo), dtype=np.float64)
    return f @ np.array([0.2126, 0.7152, 0.0722]) * math.cos(ti)


def formats_figure(material: str = "merl/gold-metallic-paint"):
    """The figure (module docstring) and a dict of the figures it shows."""
    from ..analysis.plots import _figure, sphere_image
    from ..render.image import srgb_encode
    from ..sources import load_measured, resolve
    from .optimise import fit
    from .tabulation import tabulate, tabulation_error

    with tempfile.TemporaryDirectory() as d:
        merl = tabulate(material, os.path.join(d, "m.binary"))
        rgl = tabulate(merl.path, os.path.join(d, "m.bsdf"))
        m_merl, m_rgl = load_measured(merl.path), load_measured(rgl.path)
        res = fit("microfacet", m_merl, fixed={"fresnel": "schlick"}, starts=2, seed=0)
        fit_err = tabulation_error(m_merl, res.model)
        source = resolve(material)
    panels = [(f"MERL .binary ({merl.bytes / 1e6:.0f} MB)\nerror against the network {100 * merl.error:.1f} %", m_merl),
              (f"RGL .bsdf from the MERL file ({rgl.bytes / 1e6:.1f} MB)\nerror against it {100 * rgl.error:.1f} %",
               m_rgl),
              (f"microfacet fitted to the MERL file\n(GGX, Smith, Schlick, Lambert): {100 * fit_err:.1f} %",
               res.model)]
    fig = _figure(11.0, 7.6)
    grid = fig.add_gridspec(2, 3, height_ratios=[1.0, 0.9])
    images = [sphere_image(m, 45.0, 135.0, size=220) for _, m in panels]
    peak = max(float(np.nanmax(im)) for im in images)
    for k, ((title, _), img) in enumerate(zip(panels, images)):
        ax = fig.add_subplot(grid[0, k])
        bg = ~np.isfinite(img[..., 0])
        lin = np.log1p(np.nan_to_num(img) * 100.0) / math.log1p(100.0 * peak)
        out = srgb_encode(lin)
        out[bg] = 0.15
        ax.imshow(out, interpolation="nearest")
        ax.set_axis_off()
        ax.set_title(title, fontsize=9)
    ax = fig.add_subplot(grid[1, :])
    theta_o = np.linspace(-89.0, 89.0, 713)
    ax.semilogy(theta_o, _in_plane(source, 45.0, theta_o), color="0.6", lw=4, alpha=0.6,
                label=f"{material} (the built-in network, the source)")
    for (title, m), style in zip(panels, ("-", "--", ":")):
        ax.semilogy(theta_o, _in_plane(m, 45.0, theta_o), style, lw=1.4, label=title.replace("\n", ": "))
    ax.set_xlabel("θo in the incidence plane (degrees; positive: the mirror side)")
    ax.set_ylabel("f_r cos θi (luminance, 1/sr)")
    ax.set_title("incidence plane, θi = 45°", fontsize=9)
    ax.legend(fontsize=7.5, loc="upper left")
    ax.grid(alpha=0.3, which="both")
    fig.suptitle(f"{material}: the same material as MERL, as RGL and as a fitted model\n"
                 "spheres: light at θ = 45°, same exposure, log tone map; errors: relative RMS of f_r cos θi cos θo "
                 "against the previous stage", fontsize=9.5)
    return fig, {"merl_error": merl.error, "rgl_error": rgl.error, "fit_error": fit_err,
                 "merl_bytes": merl.bytes, "rgl_bytes": rgl.bytes}


def write_formats_figure(out: str = DEFAULT_OUT, material: str = "merl/gold-metallic-paint") -> dict:
    """Write the figure to ``out`` (PNG, atomically, the path checked first); returns its figures."""
    from ..fileio import atomic_path, check_output_path

    check_output_path(out, what="figure", suffixes=(".png",))
    fig, info = formats_figure(material)
    with atomic_path(out) as tmp:
        fig.savefig(tmp, format="png", dpi=110, facecolor="white")
    return info


def main(argv: list[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    material = "merl/gold-metallic-paint"
    if "--material" in args:
        i = args.index("--material")
        material = args[i + 1]
        del args[i:i + 2]
    out = args[0] if args else DEFAULT_OUT
    try:
        info = write_formats_figure(out, material)
    except ValueError as e:
        print(f"brdfkit.measured.figures: error: {e}", file=sys.stderr)
        return 2
    print(f"wrote {out}: " + ", ".join(f"{k} {v:.4g}" for k, v in info.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
