"""Plots: every kind writes a non-blank file in each format; the CLI parses --vs groups."""

from __future__ import annotations

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.analysis.commands import parse_model_groups
from brdfkit.analysis.plots import save_figure, sphere_image
from brdfkit.cli import main


def _png_pixels(path):
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB"), dtype=np.float64)


@pytest.mark.parametrize("kind", ["polar", "lobe", "albedo", "slice", "sphere"])
def test_each_kind_png(kind, tmp_path, capsys):
    out = tmp_path / f"{kind}.png"
    argv = ["plot", "phong", "-p", "shininess=20", "--vs", "lambert", "-p", "kd=0.3", "--kind", kind, "-o", str(out)]
    if kind == "sphere":
        argv += ["--size", "64"]
    assert main(argv) == 0, capsys.readouterr().err
    px = _png_pixels(out)
    assert px.shape[0] > 200 and px.shape[1] > 200
    assert px.std() > 5.0  # not blank


@pytest.mark.parametrize("ext, magic", [(".svg", b"<?xml"), (".pdf", b"%PDF")])
def test_vector_formats(ext, magic, tmp_path):
    out = tmp_path / f"p{ext}"
    assert main(["plot", "ward", "--kind", "polar", "--log", "-o", str(out)]) == 0
    assert out.read_bytes()[:5].startswith(magic[:4])


def test_parse_model_groups():
    g = parse_model_groups(["phong", "-p", "a=1", "-pb=2", "--vs", "ward", "--param=c=3", "--vs", "lambert"])
    assert g == [("phong", ["a=1", "b=2"]), ("ward", ["c=3"]), ("lambert", [])]
    for bad in (["-p", "a=1"], ["phong", "--vs"], ["phong", "ward"], ["phong", "--what"], []):
        with pytest.raises(ValueError):
            parse_model_groups(bad)


@pytest.mark.parametrize(
    "argv, msg",
    [
        (["plot", "phong", "-o", "x.gif"], "must end in"),
        (["plot", "phong", "--kind", "pie"], "--kind"),
        (["plot", "phong", "-p", "shininess=-1"], "out of range"),
        (["plot", "phong", "--theta-i", "95"], "theta"),
        (["plot", "nope"], "unknown model"),
    ],
)
def test_plot_errors(argv, msg, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) != 0
    err = capsys.readouterr().err
    assert msg in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_sphere_image_is_lambert_cosine():
    """For Lambert the sphere radiance is kd/π · max(0, n·L): check pixels against that."""
    kd = 0.6
    img = sphere_image(bk.model("lambert", kd=kd), 30.0, 0.0, size=65)
    c = (np.arange(65) + 0.5) / 65 * 2 - 1
    Y, X = np.meshgrid(-c, c, indexing="ij")
    inside = X**2 + Y**2 < 1
    Z = np.sqrt(np.clip(1 - X**2 - Y**2, 0, 1))
    L = np.array([np.sin(np.radians(30)), 0.0, np.cos(np.radians(30))])
    expect = kd / np.pi * np.maximum(0, X * L[0] + Y * L[1] + Z * L[2])
    lit = inside & (expect > 1e-3)  # the BRDF is 0 where the viewer sees the surface edge-on
    np.testing.assert_allclose(img[..., 0][lit], expect[lit], rtol=1e-9, atol=1e-12)
    assert np.all(np.isnan(img[~inside]))


def test_save_figure_rejects_unknown_extension(tmp_path):
    from matplotlib.figure import Figure

    with pytest.raises(ValueError, match="must end in"):
        save_figure(Figure(), tmp_path / "x.jpg")
