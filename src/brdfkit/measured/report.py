"""The fit report (``brdfkit fit ... --report DIR``): measured vs fitted, side by side.

Writes into DIR

* ``slices.png``: f_r in the plane of incidence for three incidence angles,
  measured (solid) and fitted (dashed), per RGB channel, log scale;
* ``spheres.png``: a sphere lit by a directional key light and a weaker fill
  light, shaded with the measured and with the fitted BRDF (same exposure);
* ``fit.json`` (the fit result) and ``index.md`` tying them together.

The spheres are shaded in numpy by :func:`brdfkit.analysis.plots.sphere_image`
(orthographic camera on +z, radiance ``Σ f_r(wi, wo) · cos θi · E`` summed over
the :data:`LIGHTS`), exposed so that the measured image's 99.5th percentile
maps to 1 and encoded with the sRGB transfer curve
(:func:`brdfkit.render.image.srgb_encode`).
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

from ..fileio import atomic_path, write_json, write_text
from ..geometry import spherical_to_vector, vector_to_spherical

SLICE_THETA_I_DEG = (20.0, 45.0, 70.0)
#: (direction in camera space (+z toward the viewer), irradiance): a key light and a weaker fill
LIGHTS = ((np.array([-0.55, 0.45, 0.70]), 1.0), (np.array([0.7, -0.2, 0.5]), 0.25))


def plane_slice(model, theta_i_deg: float, n: int = 361) -> tuple[np.ndarray, np.ndarray]:
    """``(θo in degrees, signed; f (n, 3))`` with the light at φ = 180° and θo > 0 on the mirror side."""
    t = np.radians(np.linspace(-89.5, 89.5, n))
    wi = spherical_to_vector(np.radians(theta_i_deg), np.pi)
    wo = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)
    return np.degrees(t), np.asarray(model.eval(np.broadcast_to(wi, wo.shape), wo), np.float64)


def shade_sphere(model, size: int = 160) -> np.ndarray:
    """Linear radiance image ``(size, size, 3)`` of a unit sphere under :data:`LIGHTS` (black background)."""
    from ..analysis.plots import sphere_image

    img = np.zeros((size, size, 3))
    for direction, power in LIGHTS:
        theta, phi = vector_to_spherical(direction)
        one = sphere_image(model, math.degrees(theta), math.degrees(phi), size=size, exposure=power)
        img += np.nan_to_num(one)  # background NaN -> black
    return img


def write_report(result, measured, out_dir: str) -> dict[str, Any]:
    """Write the report of a :class:`~brdfkit.measured.result.FitResult`; returns the file paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..render.image import srgb_encode

    os.makedirs(out_dir, exist_ok=True)
    fitted = result.model
    colors = ("tab:red", "tab:green", "tab:blue")

    # -- in-plane slices ---------------------------------------------------------
    fig, axes = plt.subplots(1, len(SLICE_THETA_I_DEG), figsize=(4.2 * len(SLICE_THETA_I_DEG), 3.8), dpi=100)
    for ax, ti in zip(np.atleast_1d(axes), SLICE_THETA_I_DEG):
        th, fm = plane_slice(measured, ti)
        _, ff = plane_slice(fitted, ti)
        for c in range(3):
            ax.plot(th, np.maximum(fm[:, c], 1e-4), color=colors[c], lw=1.5)
            ax.plot(th, np.maximum(ff[:, c], 1e-4), color=colors[c], lw=1.2, ls="--")
        ax.axvline(ti, color="0.6", lw=0.8, ls=":")
        ax.set_yscale("log")
        ax.set_xlim(-90, 90)
        ax.set_xlabel("θo in the plane of incidence (°)")
        ax.set_title(f"θi = {ti:g}°")
        ax.grid(True, which="both", alpha=0.25)
    np.atleast_1d(axes)[0].set_ylabel("f_r (1/sr)")
    fig.suptitle(f"{result.source}: measured (solid) vs {fitted.name} fit (dashed), error {result.error:.4g} ({result.metric})")
    fig.tight_layout()
    slices = os.path.join(out_dir, "slices.png")
    with atomic_path(slices) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)

    # -- spheres ---------------------------------------------------------------------
    im_m = shade_sphere(measured)
    im_f = shade_sphere(fitted)
    lit = im_m[im_m.sum(axis=-1) > 0]
    ref = float(np.percentile(lit.max(axis=-1), 99.5)) if lit.size else 1.0
    exposure = 1.0 / ref if ref > 0 else 1.0
    fig, axes = plt.subplots(1, 2, figsize=(7, 3.8), dpi=100)
    for ax, im, title in zip(axes, (im_m, im_f), ("measured: " + result.source, f"fitted: {fitted.name}")):
        ax.imshow(srgb_encode(im * exposure), interpolation="nearest")
        ax.set_title(title, fontsize=10)
        ax.axis("off")
    fig.tight_layout()
    spheres = os.path.join(out_dir, "spheres.png")
    with atomic_path(spheres) as tmp:
        fig.savefig(tmp, format="png", facecolor="white")
    plt.close(fig)

    js = os.path.join(out_dir, "fit.json")
    write_json(js, result.to_json(), indent=2)
    index = os.path.join(out_dir, "index.md")
    params = result.to_json()["params"]
    lines = [f"# Fit of `{fitted.name}` to `{result.source}`", "",
             f"Error {result.error:.6g} (metric `{result.metric}`), {result.samples} samples, "
             f"{result.starts} starts, {result.seconds:.1f} s.", ""]
    if getattr(result, "at_bound", None):
        lines += ["At a fitting bound: " + ", ".join(result.at_bound) + ".", ""]
    lines += ["| parameter | value |", "|---|---|"]
    for k, v in params.items():
        if isinstance(v, list):
            v = ", ".join(f"{x:.4g}" for x in v)
        elif isinstance(v, float):
            v = f"{v:.4g}"
        lines.append(f"| {k} | {v} |")
    lines += ["", "![in-plane slices](slices.png)", "", "![spheres](spheres.png)"]
    write_text(index, "\n".join(lines) + "\n")
    return {"index": index, "slices": slices, "spheres": spheres, "json": js}
