"""Jupyter display: a model shows a lit sphere and its lobe (PNG / HTML), a fit result its report."""

from __future__ import annotations

import base64
import io
import math
import re
from pathlib import Path

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.interchange import notebook

DATA = Path(__file__).parent / "data"


def _decode(png: bytes) -> np.ndarray:
    from matplotlib.image import imread

    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    return imread(io.BytesIO(png), format="png")[..., :3]


def _srgb(x: float) -> float:
    return 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1 / 2.4) - 0.055


def test_model_png_shows_a_correctly_lit_sphere_and_a_lobe():
    kd = 0.6
    img = _decode(bk.model("lambert", kd=kd)._repr_png_())
    h, w, _ = img.shape
    assert w > 1.5 * h  # two panels side by side
    s = max(notebook.SPHERE_SIZE, int(h * 0.8))
    top = (h - s) // 2
    # the sphere's centre faces the viewer; the light is 45° off the view axis:
    # radiance = kd/π · cos 45°, sRGB-encoded
    centre = img[top + s // 2, s // 2]
    want = _srgb(kd / math.pi * math.cos(math.radians(45)))
    np.testing.assert_allclose(centre, want, atol=2.5 / 255)
    # the corner of the sphere tile is background (0.15 grey), the lobe panel has colour
    np.testing.assert_allclose(img[top + 2, 2], 0.15, atol=2 / 255)
    lobe = img[:, s + 8 :]
    assert np.ptp(lobe, axis=-1).max() > 0.3  # viridis colours, not grey


def test_model_html_has_name_parameters_and_image():
    m = bk.model("ward", kd=0.2, ks=0.05)
    h = m._repr_html_()
    assert "ward" in h and "alpha_x" in h and "0.05" in h
    (b64,) = re.findall(r"base64,([A-Za-z0-9+/=]+)", h)
    _decode(base64.b64decode(b64))


def test_brdf_file_model_displays():
    img = _decode(bk.load_brdf(DATA / "ggx.brdf")._repr_png_())
    assert img.shape[0] > 100 and np.isfinite(img).all()


def test_fit_result_shows_its_report():
    r = bk.fit("ward", "merl/gold-metallic-paint", samples=600, starts=1)
    h = r._repr_html_()
    assert "merl/gold-metallic-paint" in h and f"{r.error:.5g}" in h and "alpha_x" in h
    assert "<figcaption>measured</figcaption>" in h and "<figcaption>fitted</figcaption>" in h
    pics = [_decode(base64.b64decode(b)) for b in re.findall(r"base64,([A-Za-z0-9+/=]+)", h)]
    assert len(pics) == 2 and all(p.mean() > 0.01 for p in pics)
    # the two spheres resemble each other (a fit, not a different material)
    assert np.abs(pics[0] - pics[1]).mean() < 0.1


@pytest.mark.parametrize("name", ["lambert", "microfacet"])
def test_png_is_deterministic(name):
    m = bk.model(name)
    assert m._repr_png_() == m._repr_png_()


def test_ipython_display_formatter_shows_model_and_fit():
    """IPython's own display machinery (what a Jupyter cell uses) finds the PNG and the HTML."""
    IPython = pytest.importorskip("IPython")
    from IPython.core.formatters import DisplayFormatter

    fmt = DisplayFormatter()
    data, _ = fmt.format(bk.model("microfacet", alpha=0.3))
    assert {"image/png", "text/html", "text/plain"} <= set(data)
    assert data["image/png"][:8] == b"\x89PNG\r\n\x1a\n" and "<img" in data["text/html"]
    r = bk.fit("lambert", bk.model("oren-nayar", kd=0.5, sigma=0.2), samples=300, starts=1)
    data, _ = fmt.format(r)
    assert "text/html" in data and "fit of lambert" in data["text/html"]
    assert IPython.version_info >= (8,)


def test_model_png_sphere_has_a_margin_in_its_tile():
    """The sphere does not touch its tile's edges (the left one is the picture's edge): on the
    centre row and column, the first and last pixels of the tile are background grey."""
    img = _decode(bk.model("lambert", kd=0.8)._repr_png_())
    h = img.shape[0]
    s = max(notebook.SPHERE_SIZE, int(h * 0.8))
    top = (h - s) // 2
    tile = img[top : top + s, :s]
    m = int(round(notebook.SPHERE_MARGIN * s))
    assert m >= 2
    row, col = tile[s // 2], tile[:, s // 2]
    for line in (row, col):
        np.testing.assert_allclose(line[:m], 0.15, atol=2 / 255)
        np.testing.assert_allclose(line[-m:], 0.15, atol=2 / 255)
    # the light (φ = 135°) is at the upper left: the left and top limbs are lit right after the margin
    assert tile[s // 2, m + 1].mean() > 0.3 and tile[m + 1, s // 2].mean() > 0.3


def test_models_package_does_not_import_interchange():
    """Jupyter display is attached by brdfkit/__init__.py; brdfkit.models.base has no import of interchange."""
    import ast
    import inspect

    from brdfkit.models import base

    tree = ast.parse(inspect.getsource(base))
    mods = [n.module or "" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
    mods += [a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names]
    assert not [m for m in mods if "interchange" in m], mods
    assert callable(bk.BRDF._repr_png_) and callable(bk.BRDF._repr_html_)
