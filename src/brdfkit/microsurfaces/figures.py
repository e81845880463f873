"""The lecture's three microfacet pictures, made from simulation (issue 29).

* :func:`cross_section` — a cut through a rough surface with light paths traced through it,
  coloured by their number of reflections (masking, shadowing and inter-reflection seen directly).
  The surface is a Gaussian *profile* (heights vary along x only), so that paths arriving in the
  xz-plane stay in it and the cut shows them whole.
* :func:`masking_curves` — simulated G1(θo) of the Beckmann and GGX heightfields beside Smith's
  G1, and of the V-groove surface beside the V-groove formula.
* :func:`albedo_split` — the white surfaces' simulated directional albedo split into single and
  multiple scattering, beside the single-scattering microfacet albedo E(μ) and the Kulla-Conty
  compensation 1 − E(μ) (height-correlated Smith tables of :mod:`brdfkit.terms.multiscatter`).

``python -m brdfkit.microsurfaces.figures OUTDIR`` writes the three PNGs (used in docs/).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ..analysis.plots import save_figure
from ..fileio import check_output_path
from . import microsurface
from .engines import make_engine
from .surfaces import Scales, grid_tile
from .tracer import trace

_COLOURS = {1: "#1f77b4", 2: "#ff7f0e", 3: "#d62728"}
_NAMES = {"beckmann": "Beckmann", "ggx": "GGX"}


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def gaussian_profile(n: int = 4096, corr_cells: float = 10.0, seed: int = 2):
    """A periodic surface constant along y whose x-slopes are normal with variance 1/2 (α = 1)."""
    rng = np.random.default_rng(seed)
    k = 2.0 * np.pi * np.fft.fftfreq(n)
    h = np.real(np.fft.ifft(np.fft.fft(rng.standard_normal(n)) * np.exp(-(k**2) * corr_cells**2 / 8.0)))
    v = np.mean((np.roll(h, -1) - h) ** 2)
    return grid_tile((h - h.mean())[:, None], np.sqrt(2.0 * v), 1.0)


def cross_section(path, alpha: float = 0.9, theta_deg: float = 60.0, rays: int = 70, window_corr: float = 16.0,
                  seed: int = 1) -> Path:
    """PNG: a profile of roughness ``alpha`` and ``rays`` paths arriving from ``theta_deg``."""
    path = check_output_path(path, what="figure", suffixes=(".png",))
    plt = _plt()
    corr = 10.0
    tile = gaussian_profile(corr_cells=corr)
    lx, _ = tile.size
    window = window_corr * corr * tile.dx  # a few correlation lengths
    x0 = 0.5 * lx - 0.5 * window
    eng = make_engine(tile, "mitsuba-llvm")
    rng = np.random.default_rng(seed)
    th = np.radians(theta_deg)
    wi = np.array([np.sin(th), 0.0, np.cos(th)])
    # rays aimed at the window's middle half: start on the top plane, back along -wi
    zt = tile.zmax
    xs = x0 + window * (0.2 + 0.6 * rng.random(rays)) + zt * alpha * np.tan(th)
    o = np.stack([xs, np.full(rays, 0.5), np.full(rays, zt)], -1)
    sc = Scales(np.ones(rays), np.full(rays, alpha))
    p = trace(eng, tile, sc, o, np.broadcast_to(-wi, (rays, 3)), lambda c: np.ones((len(c), 3)), 16, record=True)
    fig, ax = plt.subplots(figsize=(9, 3.6), dpi=130)
    xg = np.arange(tile.heights.shape[0] + 1) * tile.dx
    zg = np.append(tile.heights[:, 0], tile.heights[0, 0]) * alpha
    sel = (xg >= x0 - 5) & (xg <= x0 + window + 5)
    ax.fill_between(xg[sel], zg[sel], zg[sel].min() - 0.1 * window, color="0.82", lw=0)
    ax.plot(xg[sel], zg[sel], color="0.25", lw=1.0)
    shown = {1: 0, 2: 0, 3: 0}
    for r in range(rays):
        q = p.points[r]
        if p.status[r] != 0 or np.any(np.abs(np.diff(q[:, 0])) > 0.5 * lx):
            continue  # lost, or wrapped around the tile: not drawn
        xy = np.column_stack([q[:, 0], q[:, 2] * alpha])
        reach = 0.3 * window
        out = np.array([p.wo[r, 0], p.wo[r, 2]]) / max(np.hypot(p.wo[r, 0], p.wo[r, 2]), 1e-9)
        xy = np.vstack([xy[:1] + reach * np.array([wi[0], wi[2]]), xy, xy[-1] + reach * out])
        b = int(min(p.bounces[r], 3))
        shown[b] += 1
        ax.plot(xy[:, 0], xy[:, 1], color=_COLOURS[b], lw=0.9, alpha=0.85)
    for b, lab in ((1, "1 reflection"), (2, "2 reflections"), (3, "3 or more")):
        ax.plot([], [], color=_COLOURS[b], label=f"{lab} ({shown[b]})")
    ax.set_xlim(x0, x0 + window)
    ax.set_ylim(zg[sel].min() - 0.05 * window, zt * alpha + 0.3 * window)
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("height")
    ax.set_title(f"Light from θi = {theta_deg:g}° on a Gaussian profile (Beckmann α = {alpha:g}, white facets), "
                 "traced with Mitsuba 3", fontsize=9)
    ax.legend(loc="upper right", fontsize=8, frameon=False)
    fig.tight_layout()
    save_figure(fig, path, dpi="figure", bbox_inches="tight")  # the equal-aspect cut leaves wide margins otherwise
    plt.close(fig)
    return path


def masking_curves(path, samples: int = 20000) -> Path:
    """PNG: simulated G1(θo) (points, ±2 standard errors) against Smith's and the V-groove formula."""
    from ..terms.shadowing import smith_g1, v_groove

    path = check_output_path(path, what="figure", suffixes=(".png",))
    plt = _plt()
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.8), dpi=120)
    th = np.radians(np.arange(0.0, 89.0, 1.0))
    ths = np.radians([0.0, 20.0, 40.0, 55.0, 65.0, 72.0, 78.0, 82.0, 85.0, 88.0])

    def dirs(t):
        return np.stack([np.sin(t), 0.0 * t, np.cos(t)], -1)

    for ax, kind in zip(axes[:2], ("beckmann", "ggx")):
        for a, col in zip((0.2, 0.5, 1.0), ("#1f77b4", "#2ca02c", "#d62728")):
            ax.plot(np.degrees(th), smith_g1(dirs(th), a, None, distribution=kind), color=col, lw=1.2,
                    label=f"Smith, α = {a:g}")
            est = microsurface(kind, alpha=a).masking(dirs(ths), samples=samples)
            ax.errorbar(np.degrees(ths), est.value, yerr=2 * est.stderr, fmt="o", ms=3.5, color=col, capsize=2)
        ax.set_title(f"{_NAMES[kind]}: traced G1 (dots, ±2 s.e.) vs Smith (lines)", fontsize=9)
    for ang, col in zip((20.0, 40.0), ("#9467bd", "#8c564b")):
        a = np.radians(ang)
        h = np.array([np.sin(a), 0.0, np.cos(a)])
        w = dirs(th)
        c = w @ h
        axes[2].plot(np.degrees(th), v_groove(np.full(len(th), h[2]), w[:, 2], w[:, 2], c, c), color=col, lw=1.2,
                     label=f"V-groove formula, {ang:g}° facets")
        est = microsurface("v-groove", angle=ang).masking(dirs(ths), samples=samples)
        axes[2].errorbar(np.degrees(ths), est.value, yerr=2 * est.stderr, fmt="o", ms=3.5, color=col, capsize=2)
    axes[2].set_title("V-grooves (Torrance-Sparrow): traced vs formula", fontsize=9)
    for ax in axes:
        ax.set_xlabel("θo (degrees), across the grooves")
        ax.set_ylabel("G1")
        ax.set_ylim(0, 1.03)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="lower left", frameon=False)
    fig.tight_layout()
    save_figure(fig, path, dpi="figure")
    plt.close(fig)
    return path


def albedo_split(path, samples: int = 40000) -> Path:
    """PNG: simulated single / multiple scattering albedo of white surfaces vs E(μ) and 1 − E(μ)."""
    from ..terms.multiscatter import albedo_lookup, albedo_row, table

    path = check_output_path(path, what="figure", suffixes=(".png",))
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(13, 3.8), dpi=120)
    th = np.radians(np.arange(0.0, 88.0, 1.0))
    ths = np.radians([0.0, 30.0, 50.0, 65.0, 75.0, 82.0])
    for ax, kind in zip(axes, ("beckmann", "ggx")):
        for a, col in zip((0.5, 1.0), ("#1f77b4", "#d62728")):
            e = albedo_lookup(albedo_row(table(kind, "smith-correlated"), a), np.cos(th))
            ax.plot(np.degrees(th), e, color=col, lw=1.2)
            ax.plot(np.degrees(th), 1 - e, color=col, lw=1.2, ls="--")
            s = microsurface(kind, alpha=a)
            res = [s.albedo(np.array([np.sin(t), 0.0, np.cos(t)]), bounces=1, samples=samples) for t in ths]
            single = np.array([r.by_bounce[0, 0] for r in res])
            multi = np.array([r.by_bounce[1, 0] for r in res])
            ax.plot(np.degrees(ths), single, "o", ms=4, color=col)
            ax.plot(np.degrees(ths), multi, "s", ms=4, mfc="none", color=col)
        for a, col in zip((0.5, 1.0), ("#1f77b4", "#d62728")):
            ax.plot([], [], color=col, lw=6, label=f"α = {a:g}")
        ax.plot([], [], color="0.3", lw=1.2, label="E(μ): microfacet single scattering")
        ax.plot([], [], color="0.3", lw=1.2, ls="--", label="1 − E(μ): Kulla-Conty lobe's albedo")
        ax.plot([], [], "o", color="0.3", label="traced, 1 reflection")
        ax.plot([], [], "s", mfc="none", color="0.3", label="traced, 2 or more")
        ax.set_title(f"White {_NAMES[kind]} surface: albedo by number of reflections", fontsize=9)
        ax.set_xlabel("θi (degrees)")
        ax.set_ylabel("directional albedo")
        ax.set_ylim(0, 1.03)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6.5, loc="upper left", bbox_to_anchor=(1.0, 1.0), frameon=False)
    fig.tight_layout()
    save_figure(fig, path, dpi="figure")
    plt.close(fig)
    return path


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0] if args else "docs/img")
    cross_section(out / "microsurface_paths.png")
    masking_curves(out / "microsurface_masking.png")
    albedo_split(out / "microsurface_albedo.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
