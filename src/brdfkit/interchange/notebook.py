"""How a model and a fit result show themselves in Jupyter.

``BRDF._repr_png_`` / ``_repr_html_`` (:func:`model_png`, :func:`model_html`) and
``FitResult._repr_html_`` (:func:`fit_html`) delegate here. The two model methods are attached
to :class:`~brdfkit.models.base.BRDF` from outside, when :mod:`brdfkit` is imported (its
``_attach_notebook_display``), so that ``brdfkit.models`` never imports this package; they
import this module on the first display only, which keeps ``import brdfkit`` (and every CLI
command that does not need it) free of ``brdfkit.interchange``.

* a model: a PNG with a lit sphere (:func:`brdfkit.analysis.plots.sphere_image`,
  a directional light at 45° from the view axis, sRGB) and its 3D lobe for light
  at 45° (:func:`brdfkit.analysis.plots.lobe_plot`), side by side; the HTML adds
  the model's name and its parameter table;
* a fit result: its report -- source, model, error and metric, the fitted
  parameters, and the measured and fitted spheres under the fit report's lights
  (:func:`brdfkit.measured.report.shade_sphere`, same exposure).

Every picture is made with matplotlib's Agg backend in memory; nothing is written to disk.
"""

from __future__ import annotations

import base64
import html
import io
import math
from typing import Any

import numpy as np

SPHERE_SIZE = 160
#: background margin around the sphere inside its tile, as a fraction of the tile (each side):
#: the disk would otherwise touch the tile's edges, the picture's left edge among them
SPHERE_MARGIN = 0.05
LIGHT_THETA_DEG = 45.0
LIGHT_PHI_DEG = 135.0
DPI = 72


def _agg():
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def _fig_rgb(fig) -> np.ndarray:
    """The figure's pixels (H, W, 3) uint8, and close it."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig.set_dpi(DPI)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    rgba = np.asarray(canvas.buffer_rgba())[..., :3].copy()
    _agg().close(fig)
    return rgba


def _png(rgb: np.ndarray) -> bytes:
    from matplotlib.image import imsave

    buf = io.BytesIO()
    imsave(buf, rgb, format="png")
    return buf.getvalue()


def _hstack(images: list[np.ndarray], pad: int = 8) -> np.ndarray:
    h = max(im.shape[0] for im in images)
    parts = []
    for k, im in enumerate(images):
        if im.shape[0] < h:  # centre vertically on white
            top = (h - im.shape[0]) // 2
            canvas = np.full((h, im.shape[1], 3), 255, np.uint8)
            canvas[top : top + im.shape[0]] = im
            im = canvas
        parts.append(im)
        if k < len(images) - 1:
            parts.append(np.full((h, pad, 3), 255, np.uint8))
    return np.concatenate(parts, axis=1)


def _sphere_rgb(model: Any, size: int = SPHERE_SIZE) -> np.ndarray:
    """A ``size`` × ``size`` tile: the lit sphere, centred, on 0.15 grey with a margin of
    :data:`SPHERE_MARGIN` on every side (the sphere's centre stays at pixel ``size // 2``)."""
    from ..analysis.plots import sphere_image
    from ..render.image import srgb_encode

    margin = max(2, int(round(SPHERE_MARGIN * size)))
    img = sphere_image(model, LIGHT_THETA_DEG, LIGHT_PHI_DEG, size=size - 2 * margin)
    bg = ~np.isfinite(img[..., 0])
    disk = srgb_encode(np.clip(np.nan_to_num(img), 0, 1))
    disk[bg] = 0.15
    out = np.full((size, size, 3), 0.15)
    out[margin : size - margin, margin : size - margin] = disk
    return (np.clip(out, 0, 1) * 255 + 0.5).astype(np.uint8)


def model_png(model: Any) -> bytes:
    """PNG bytes: the lit sphere and the 3D lobe of ``model``."""
    from ..analysis.plots import lobe_plot

    lobe = _fig_rgb(lobe_plot([model], theta_i_deg=45.0))
    # the sphere about as tall as the lobe's figure (~400 px at 72 dpi)
    sphere = _sphere_rgb(model, size=max(SPHERE_SIZE, int(lobe.shape[0] * 0.8)))
    return _png(_hstack([sphere, lobe]))


def _value_text(v: Any) -> str:
    if isinstance(v, np.ndarray):
        return ", ".join(f"{x:.4g}" for x in v.tolist())
    if isinstance(v, (list, tuple)):
        return ", ".join(f"{x:.4g}" if isinstance(x, float) else str(x) for x in v)
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def _table(params: dict[str, Any]) -> str:
    rows = "".join(
        f"<tr><td style='text-align:left'><code>{html.escape(str(k))}</code></td>"
        f"<td style='text-align:left'>{html.escape(_value_text(v))}</td></tr>"
        for k, v in params.items()
    )
    return f"<table><tr><th>parameter</th><th>value</th></tr>{rows}</table>"


def _img(png: bytes, alt: str) -> str:
    return f"<img alt='{html.escape(alt)}' src='data:image/png;base64,{base64.b64encode(png).decode()}'/>"


def model_html(model: Any) -> str:
    """HTML: the model's name, reference and parameters, and :func:`model_png`."""
    cls = type(model)
    title = html.escape(f"{cls.name or cls.__name__} — {cls.title}".strip(" —"))
    ref = html.escape(cls.reference or "")
    params = model.params or {}
    return (
        f"<div class='brdfkit-model'><b>{title}</b><br/><small>{ref}</small>"
        f"<div style='display:flex;gap:1em;align-items:flex-start'>{_table(params)}"
        f"{_img(model_png(model), 'lit sphere and 3D lobe')}</div></div>"
    )


def _measured_for(result: Any):
    """The fit's measured source as a model, if it can be found again (a material name or a file)."""
    try:
        from ..sources import resolve

        return resolve(result.source)
    except Exception:  # noqa: BLE001 - the report shows the fitted side alone then
        return None


def fit_html(result: Any) -> str:
    """HTML report of a :class:`brdfkit.measured.fit.FitResult`."""
    from ..measured.metrics import METRIC_TITLES
    from ..measured.report import shade_sphere
    from ..render.image import srgb_encode

    fitted = result.model
    measured = _measured_for(result)
    imgs = [("fitted", shade_sphere(fitted))]
    if measured is not None:
        imgs.insert(0, ("measured", shade_sphere(measured)))
    ref = imgs[0][1]
    finite = ref[np.isfinite(ref)]
    exposure = 1.0 / max(float(np.percentile(finite, 99.5)) if finite.size else 1.0, 1e-12)
    tiles = []
    for name, lin in imgs:
        rgb = (np.clip(srgb_encode(np.clip(lin * exposure, 0, 1)), 0, 1) * 255 + 0.5).astype(np.uint8)
        tiles.append(f"<figure style='margin:0'>{_img(_png(rgb), name)}<figcaption>{name}</figcaption></figure>")
    metric = html.escape(f"{result.metric} ({METRIC_TITLES.get(result.metric, '')})")
    head = html.escape(f"fit of {fitted.name} to {result.source}")
    err = result.error if math.isfinite(result.error) else float("nan")
    return (
        f"<div class='brdfkit-fit'><b>{head}</b><br/>error {err:.5g}, metric {metric}; "
        f"{result.samples} samples, {result.starts} starts, {result.seconds:.2f} s"
        f"<div style='display:flex;gap:1em;align-items:flex-start'>{_table(result.params)}{''.join(tiles)}</div></div>"
    )


__all__ = ["model_png", "model_html", "fit_html"]
