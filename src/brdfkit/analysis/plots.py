"""Pictures of BRDFs with matplotlib (Agg, no display needed).

Kinds (as in Disney's BRDF Explorer, plus the albedo curve):

``polar``   in-plane slice: f_r(wi, wo) cos θo for wo in the plane of incidence, the light at
            a chosen θi; several models overlaid.
``lobe``    3D lobe: the surface r(wo) = f_r(wi, wo) cos θo · wo over the hemisphere.
``albedo``  directional albedo a(θ) = ∫ f cos θi dωi (the white furnace), per model; for
            non-reciprocal models also ρ(θ) = ∫ f cos θo dωo (light from θ), dotted.
``slice``   the Rusinkiewicz θh × θd image of f_r at φd = 90° (log colour scale).
``sphere``  a sphere lit by one directional light, shaded in numpy (orthographic view).

Every function returns a :class:`matplotlib.figure.Figure`; :func:`save_figure`
writes PNG, SVG or PDF by the file's extension.
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..geometry import spherical_to_vector

KINDS = ("polar", "lobe", "albedo", "slice", "sphere")
FORMATS = (".png", ".svg", ".pdf")
_STYLES = ("-", "--", "-.", ":")
_COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#7f7f7f")


def _figure(w: float, h: float):
    from matplotlib.figure import Figure

    return Figure(figsize=(w, h), layout="constrained")


def _fmt_value(v: Any) -> str:
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if isinstance(v, (list, tuple)):
        if len(set(v)) == 1:
            return _fmt_value(v[0])
        return "(" + ",".join(_fmt_value(x) for x in v) + ")"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:.4g}".replace("e+0", "e").replace("e+", "e").replace("e-0", "e-")
    return str(v)


def label(model: Any, width: int | None = None) -> str:
    """``name(k=v, ...)`` with every parameter in effect (:meth:`BRDF.active_params`), for legends and titles."""
    active = getattr(model, "active_params", None)
    params = active() if callable(active) else (getattr(model, "params", {}) or {})
    own = getattr(model, "label", None)  # measured data: its material name ("merl/chrome"), not "nbrdf()"
    if isinstance(own, str) and own and not params:
        text = own
    else:
        text = f"{getattr(model, 'name', type(model).__name__)}(" + ", ".join(
            f"{k}={_fmt_value(v)}" for k, v in params.items()
        ) + ")"
    if width:
        text = "\n".join(textwrap.wrap(text, width, subsequent_indent="  "))
    return text


def setting_text(changed: dict[str, Any]) -> str:
    """A ``check --all`` result's ``changed`` parameters as ``k=v, ...`` (``defaults`` when none)."""
    if not changed:
        return "defaults"
    return ", ".join(f"{k}={_fmt_value(v)}" for k, v in changed.items())


def where_text(result: dict[str, Any]) -> str:
    """Where a :func:`~brdfkit.analysis.check` result's max albedo lies: ``θ°``, ``(light)`` if on ρ."""
    light = result.get("max_albedo_curve") == "albedo_light"
    return f"{result['max_albedo_theta_deg']:g}°" + (" (light)" if light else "")


def _light_dir(theta_i_deg: float, phi_i_deg: float) -> np.ndarray:
    """The light direction wi (3,) of the polar and lobe plots; θi must lie in [0°, 90°)."""
    if not 0.0 <= theta_i_deg < 90.0:
        raise ValueError(f"plot: the light's theta must lie in [0, 90) degrees, got {theta_i_deg:g}")
    return spherical_to_vector(math.radians(theta_i_deg), math.radians(phi_i_deg))


def _luminance(rgb: np.ndarray) -> np.ndarray:
    return rgb @ np.array([0.2126, 0.7152, 0.0722])


def _check_models(models: Sequence[Any]) -> list[Any]:
    models = list(models)
    if not models:
        raise ValueError("plot: at least one model is needed")
    return models


def _log_radius(v: np.ndarray, vmax: float, decades: float) -> np.ndarray:
    with np.errstate(divide="ignore"):
        r = np.log10(np.maximum(v, 1e-300) / vmax) + decades
    return np.clip(r, 0.0, decades)


# ---------------------------------------------------------------------------------------------
def polar_plot(
    models: Sequence[Any],
    theta_i_deg: float = 45.0,
    phi_i_deg: float = 0.0,
    *,
    log: bool = False,
    decades: float = 4.0,
    cosine: bool = True,
    n: int = 721,
):
    """In-plane polar plot of f_r·cos θo (``cosine=False``: f_r) with the light at θi.

    ``theta_i_deg`` in [0, 90), ``phi_i_deg``: the light's direction in degrees.
    ``log``: the radius is log10 of the value, spanning ``decades`` decades below
    the largest value; ``n``: sample count of θo over (−90°, 90°).
    """
    models = _check_models(models)
    wi = _light_dir(theta_i_deg, phi_i_deg)
    # plotting angle a in (−90°, 90°): a > 0 is the mirror side (azimuth φi + 180°)
    a = np.radians(np.linspace(-89.9, 89.9, n))
    wo = spherical_to_vector(np.abs(a), np.where(a >= 0, math.radians(phi_i_deg) + math.pi, math.radians(phi_i_deg)))
    curves = []
    for m in models:
        f = np.asarray(m.eval(wi, wo), dtype=np.float64)
        v = _luminance(f) * (wo[:, 2] if cosine else 1.0)
        curves.append(v)
    vmax = max(float(c.max()) for c in curves)
    if not vmax > 0:
        vmax = 1.0
    fig = _figure(8.0, 5.0)
    ax = fig.add_subplot(projection="polar")
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)
    ax.set_thetamin(-90)
    ax.set_thetamax(90)
    for k, (m, v) in enumerate(zip(models, curves)):
        r = _log_radius(v, vmax, decades) if log else v
        ax.plot(a, r, color=_COLORS[k % len(_COLORS)], ls=_STYLES[k % len(_STYLES)], lw=2, label=label(m, 60))
    rmax = decades if log else vmax * 1.08
    ax.set_rmax(rmax)
    ax.set_rmin(0)
    from matplotlib.ticker import MaxNLocator

    ax.yaxis.set_major_locator(MaxNLocator(4))
    ax.tick_params(axis="y", labelsize=8)
    ti = math.radians(theta_i_deg)
    ax.annotate(
        "",
        xy=(-ti, 0.0),
        xytext=(-ti, rmax * 0.9),
        arrowprops=dict(arrowstyle="->", color="#444444", lw=1.5),
    )
    ax.text(-ti, rmax * 0.93, f"light\nθi={theta_i_deg:g}°", ha="center", va="bottom", fontsize=8, color="#444444")
    ax.plot([ti, ti], [0, rmax * 0.9], ls=":", color="#888888", lw=1)
    ax.text(ti, rmax * 0.93, "mirror", ha="center", va="bottom", fontsize=8, color="#666666")
    if log:
        ticks = np.arange(0, decades + 0.5, 1.0)
        ax.set_rticks(ticks)
        ax.set_yticklabels([f"{vmax * 10 ** (t - decades):.0e}" for t in ticks], fontsize=8)
    quantity = "luminance of f_r·cos θo [1/sr]" if cosine else "luminance of f_r [1/sr]"
    ax.set_title(
        f"In-plane slice, light at θi={theta_i_deg:g}°, φi={phi_i_deg:g}°\n"
        f"{quantity}{' (log radius)' if log else ''}; right: mirror side",
        fontsize=11,
    )
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.02), fontsize=8, frameon=False)
    return fig


# ---------------------------------------------------------------------------------------------
def lobe_plot(
    models: Sequence[Any],
    theta_i_deg: float = 45.0,
    phi_i_deg: float = 0.0,
    *,
    log: bool = False,
    decades: float = 4.0,
    n_theta: int = 60,
    n_phi: int = 120,
):
    """3D lobe r(wo) = f_r(wi, wo) cos θo along wo (one panel per model).

    Light direction and ``log``/``decades`` as :func:`polar_plot`; each panel is
    normalised to its own maximum; ``n_theta`` × ``n_phi`` grid over the hemisphere.
    """
    from matplotlib import cm

    models = _check_models(models)
    wi = _light_dir(theta_i_deg, phi_i_deg)
    # a regular (θo, φo) grid, θo up to 89.5° (the lobe's rim at the horizon)
    T, P = np.meshgrid(np.radians(np.linspace(0, 89.5, n_theta)), np.linspace(0, 2 * math.pi, n_phi), indexing="ij")
    wo = spherical_to_vector(T, P)
    fig = _figure(5.8 * len(models), 5.6)
    for k, m in enumerate(models):
        v = _luminance(np.asarray(m.eval(wi, wo), dtype=np.float64)) * wo[..., 2]
        vmax = float(v.max()) or 1.0
        r = _log_radius(v, vmax, decades) / decades if log else v / vmax
        X, Y, Z = (r[..., None] * wo).transpose(2, 0, 1)
        ax = fig.add_subplot(1, len(models), k + 1, projection="3d")
        ax.plot_surface(X, Y, Z, facecolors=cm.viridis(r), rstride=1, cstride=1, linewidth=0, antialiased=False, shade=False)
        L = 1.1 * wi
        ax.plot([0, L[0]], [0, L[1]], [0, L[2]], color="#d62728", lw=2)
        ax.text(L[0], L[1], L[2], "light", color="#d62728", fontsize=9)
        ax.set_xlim(-1, 1)
        ax.set_ylim(-1, 1)
        ax.set_zlim(0, 1)
        ax.set_box_aspect((2, 2, 1))
        ax.set_xlabel("x (tangent)")
        ax.set_ylabel("y")
        ax.set_zlabel("z (normal)")
        ax.view_init(elev=22, azim=-60)
        scale = f"log, {decades:g} decades" if log else "linear"
        ax.set_title(f"{label(m, 44)}\nf_r·cos θo, normalised to max {vmax:.3g} ({scale})", fontsize=9)
    fig.suptitle(f"3D lobe, light at θi={theta_i_deg:g}°, φi={phi_i_deg:g}°", fontsize=11)
    return fig


# ---------------------------------------------------------------------------------------------
def albedo_plot(
    models: Sequence[Any],
    *,
    log: bool = False,
    level: str = "fast",
    theta_deg: Sequence[float] | None = None,
    phi_deg: float = 0.0,
    title: str | None = None,
    labels: Sequence[str] | None = None,
    show_light: bool = True,
):
    """Albedo curves a(θ) (solid) and, for non-reciprocal models, ρ(θ) (dotted).

    ``theta_deg``: the polar angles in degrees (default 0° to 89.5°), ``phi_deg``
    the azimuth of the scan; ``level`` the quadrature level of
    :func:`~brdfkit.analysis.albedo.albedo`; ``labels`` replace the legend entries;
    ``show_light=False`` omits the ρ curves.
    """
    from .albedo import albedo_result
    from .reciprocity import reciprocity_error, RECIPROCITY_TOL

    models = _check_models(models)
    th = np.asarray(theta_deg if theta_deg is not None else np.r_[0:88:2, 88, 89, 89.5], dtype=np.float64)
    fig = _figure(8.2, 5.2)
    ax = fig.add_subplot()
    ax.axhline(1.0, color="black", lw=1, ls="--", label="1 (energy limit)")
    ymax = 1.05
    for k, m in enumerate(models):
        color = _COLORS[k % len(_COLORS)]
        name = labels[k] if labels is not None else label(m, 90)
        curves = [("wi", "-", "")]
        if show_light and reciprocity_error(m) > RECIPROCITY_TOL:
            curves.append(("wo", ":", " — light from θ (not reciprocal)"))
        for over, ls, extra in curves:
            r = albedo_result(m, np.radians(th), math.radians(phi_deg), over=over, level=level)
            v = r.value
            top = v.max(axis=-1)
            ax.plot(th, top, color=color, ls=ls, lw=2, label=name + extra)
            if not np.allclose(v, v[:, :1], rtol=1e-9, atol=1e-12):
                ax.fill_between(th, v.min(axis=-1), top, color=color, alpha=0.15, lw=0)
            ymax = max(ymax, float(v.max()) * 1.05)
    ax.set_xlim(0, 90)
    if log:
        ax.set_yscale("log")
    else:
        ax.set_ylim(0, min(ymax, 50.0))
    ax.set_xlabel("θ (degrees from the normal)")
    ax.set_ylabel("directional albedo")
    ax.grid(True, alpha=0.3)
    ax.set_title(
        title
        or "Directional albedo a(θo) = ∫ f_r cos θi dωi (white furnace)\n"
        "largest RGB channel; shaded band: range over R, G, B",
        fontsize=11,
    )
    ax.legend(fontsize=7.5, loc="best")
    return fig


# ---------------------------------------------------------------------------------------------
def slice_plot(models: Sequence[Any], *, phi_d_deg: float = 90.0, log: bool = True, n: int = 256):
    """Rusinkiewicz image slice: f_r over θh (x) × θd (y), ``n`` × ``n`` pixels over [0°, 90°]², at φd in degrees."""
    from matplotlib.colors import LogNorm, Normalize

    from ..geometry import from_rusinkiewicz

    models = _check_models(models)
    g = np.radians((np.arange(n) + 0.5) * 90.0 / n)
    TD, TH = np.meshgrid(g, g, indexing="ij")  # rows: θd, columns: θh
    wi, wo = from_rusinkiewicz(TH, 0.0, TD, math.radians(phi_d_deg))
    valid = (wi[..., 2] > 0) & (wo[..., 2] > 0)
    fig = _figure(5.0 * len(models), 5.6)
    for k, m in enumerate(models):
        f = _luminance(np.asarray(m.eval(wi, wo), dtype=np.float64))
        img = np.where(valid, f, np.nan)
        ax = fig.add_subplot(1, len(models), k + 1)
        pos = img[np.isfinite(img) & (img > 0)]
        extend = "neither"
        if log and pos.size:
            # the 99.5th percentile, so that a grazing singularity (1/(n·l n·v)) does not
            # push everything else into black; 5 decades below it
            hi = float(np.percentile(pos, 99.5))
            extend = "max" if float(pos.max()) > hi * (1 + 1e-9) else "neither"
            lo = max(float(pos.min()), hi * 1e-5)
            if not lo < hi:
                lo = hi / 10
            norm = LogNorm(vmin=lo, vmax=hi)
            img = np.where(img > 0, img, norm.vmin)
        else:
            norm = Normalize(vmin=0, vmax=float(np.nanmax(img)) if np.isfinite(img).any() else 1.0)
        cmap = __import__("matplotlib").colormaps["viridis"].with_extremes(bad="#bbbbbb")
        im = ax.imshow(img, origin="lower", extent=(0, 90, 0, 90), cmap=cmap, norm=norm, aspect="equal")
        fig.colorbar(im, ax=ax, shrink=0.85, extend=extend, label="luminance of f_r [1/sr]")
        ax.set_xlabel("θh (degrees)")
        ax.set_ylabel("θd (degrees)")
        ax.set_title(f"{label(m, 54)}\nφd = {phi_d_deg:g}° (grey: below horizon)", fontsize=8.5)
    return fig


# ---------------------------------------------------------------------------------------------
def sphere_image(
    model: Any,
    light_theta_deg: float = 45.0,
    light_phi_deg: float = 135.0,
    *,
    size: int = 256,
    exposure: float = 1.0,
) -> np.ndarray:
    """Linear-RGB radiance image (size, size, 3) of a unit sphere under a directional light.

    Orthographic camera on +z looking at the sphere (pixel centres sample
    [−1, 1]², +y up), light of unit irradiance from (θ, φ) in camera space, in
    degrees (θ from the view axis, φ from +x toward +y). At each pixel the BRDF
    frame has the sphere normal as n and the surface direction of the projected
    +x axis as tangent. Radiance = f_r(wi, wo) cos θi · exposure; background NaN.
    """
    from ..geometry import to_local

    c = (np.arange(size) + 0.5) / size * 2 - 1
    Y, X = np.meshgrid(-c, c, indexing="ij")
    r2 = X**2 + Y**2
    inside = r2 < 1
    Z = np.sqrt(np.clip(1 - r2, 0, 1))
    nrm = np.stack([X, Y, Z], -1)[inside]
    t = np.array([1.0, 0.0, 0.0]) - nrm[:, :1] * nrm
    tl = np.linalg.norm(t, axis=-1, keepdims=True)
    t = np.where(tl > 1e-9, t / np.where(tl > 0, tl, 1), np.array([0.0, 1.0, 0.0]))
    b = np.cross(nrm, t)
    L = spherical_to_vector(math.radians(light_theta_deg), math.radians(light_phi_deg))
    V = np.array([0.0, 0.0, 1.0])
    wi = to_local(np.broadcast_to(L, nrm.shape), t, b, nrm)
    wo = to_local(np.broadcast_to(V, nrm.shape), t, b, nrm)
    f = np.asarray(model.eval(wi, wo), dtype=np.float64)
    rad = f * np.maximum(wi[:, 2:3], 0) * exposure
    img = np.full((size, size, 3), np.nan)
    img[inside] = rad
    return img


def sphere_plot(
    models: Sequence[Any],
    light_theta_deg: float = 45.0,
    light_phi_deg: float = 135.0,
    *,
    size: int = 256,
    exposure: float = 1.0,
    log: bool = False,
):
    """Lit spheres side by side (sRGB, clipped at 1; ``log``: log-compressed tone map).

    Light (θ, φ) in degrees from the view axis, ``size`` pixels, ``exposure`` a
    radiance scale: see :func:`sphere_image`.
    """
    from ..render.image import srgb_encode  # numpy only (no OpenGL at import time)

    models = _check_models(models)
    fig = _figure(3.6 * len(models), 4.0)
    for k, m in enumerate(models):
        img = sphere_image(m, light_theta_deg, light_phi_deg, size=size, exposure=exposure)
        bg = ~np.isfinite(img[..., 0])
        lin = np.nan_to_num(img)
        if log:
            lin = np.log1p(lin * 100.0) / math.log1p(100.0 * max(float(lin.max()), 1e-12))
        out = srgb_encode(lin)
        out[bg] = 0.15
        ax = fig.add_subplot(1, len(models), k + 1)
        ax.imshow(out, interpolation="nearest")
        ax.set_axis_off()
        ax.set_title(label(m, 36), fontsize=8)
    fig.suptitle(
        f"Sphere, directional light at θ={light_theta_deg:g}°, φ={light_phi_deg:g}° from the view axis"
        f"\nradiance = f_r cos θi × {exposure:g}{', log tone map' if log else ', clipped at 1'}",
        fontsize=10,
    )
    return fig


# ---------------------------------------------------------------------------------------------
def verdict_table_figure(results: Sequence[dict[str, Any]], title: str | None = None):
    """The ``check --all`` verdicts as a table image (green: passes, red: fails)."""
    rows = []
    colors = []
    good, bad, plain = "#d9f2d9", "#f8d0d0", "#ffffff"
    for r in results:
        setting = "\n".join(textwrap.wrap(setting_text(r.get("changed", {})), 46))
        where = where_text(r)
        rows.append(
            [
                r["model"],
                setting,
                "yes" if r["reciprocal"] else "NO",
                f"{r['reciprocity_error']:.1e}",
                "yes" if r["energy_conserving"] else "NO",
                f"{r['max_albedo']:.4f}",
                where,
            ]
        )
        colors.append(
            [plain, plain, good if r["reciprocal"] else bad, plain, good if r["energy_conserving"] else bad, plain, plain]
        )
    heights = [1 + row[1].count("\n") for row in rows]
    fig = _figure(11.5, 0.8 + 0.2 * (sum(heights) + 2))
    ax = fig.add_subplot()
    ax.set_axis_off()
    cols = ["model", "setting", "reciprocal", "asymmetry", "energy\nconserving", "max albedo", "at θ"]
    tab = ax.table(
        cellText=rows,
        cellColours=colors,
        colLabels=cols,
        colWidths=[0.13, 0.4, 0.08, 0.09, 0.09, 0.09, 0.1],
        loc="upper center",
        cellLoc="center",
    )
    tab.auto_set_font_size(False)
    tab.set_fontsize(7.5)
    unit = 1.0 / (sum(heights) + 2)
    for (i, j), cell in tab.get_celld().items():
        h = 2 if i == 0 else heights[i - 1]
        cell.set_height(unit * h)
        if j in (0, 1):
            cell.set_text_props(ha="left")
            cell.PAD = 0.02
        if i == 0:
            cell.set_text_props(weight="bold")
            cell.set_facecolor("#e8e8e8")
    ax.set_title(
        title or "brdfkit check --all: Helmholtz reciprocity and energy conservation (white furnace)",
        fontsize=11,
    )
    return fig


# ---------------------------------------------------------------------------------------------
def plot(kind: str, models: Sequence[Any], **options: Any):
    """Dispatch on ``kind`` (one of :data:`KINDS`)."""
    funcs = {"polar": polar_plot, "lobe": lobe_plot, "albedo": albedo_plot, "slice": slice_plot, "sphere": sphere_plot}
    if kind not in funcs:
        raise ValueError(f"plot: unknown kind {kind!r}; valid kinds: {', '.join(KINDS)}")
    return funcs[kind](models, **options)


def save_figure(fig, path: str | Path, dpi: float | str = 150, bbox_inches: str | None = None) -> Path:
    """Write ``fig`` as PNG, SVG or PDF (by extension), atomically (a killed write leaves the previous file).

    ``dpi`` ``"figure"`` keeps the figure's own; ``bbox_inches="tight"`` crops the margins to the content.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    p = Path(path)
    ext = p.suffix.lower()
    if ext not in FORMATS:
        raise ValueError(f"plot: output must end in {', '.join(FORMATS)}, got {p.name!r}")
    from ..fileio import atomic_path

    if not p.parent.is_dir():
        raise OSError(f"plot: output folder does not exist: {str(p.parent)!r}")
    FigureCanvasAgg(fig)
    with atomic_path(p) as tmp:  # a killed write leaves the previous file whole
        fig.savefig(tmp, dpi=dpi, format=ext[1:], bbox_inches=bbox_inches)
    return p


__all__ = [
    "KINDS",
    "label",
    "polar_plot",
    "lobe_plot",
    "albedo_plot",
    "slice_plot",
    "sphere_plot",
    "sphere_image",
    "verdict_table_figure",
    "plot",
    "save_figure",
]
