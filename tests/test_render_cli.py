"""``brdfkit render`` and ``brdfkit gallery`` on the command line."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest
from PIL import Image

from brdfkit.cli import main


def test_render_flags(tmp_path, capsys):
    out = tmp_path / "ct.png"
    rc = main(["render", "--model", "cook-torrance", "-p", "m=0.3", "--shading", "phong", "--size", "80x60",
               "--mesh", "sphere", "-o", str(out), "--json"])
    assert rc == 0
    info = json.loads(capsys.readouterr().out)
    assert info["material"] == "cook-torrance" and info["shading"] == "phong" and info["srgb"] is True
    img = np.asarray(Image.open(out))
    assert img.shape == (60, 80, 3)
    assert img.max() > 200 and img[0, 0].max() == 0  # a lit object on the black background


def test_render_scene_file(tmp_path, capsys):
    import trimesh

    from brdfkit.render import meshes

    s = meshes.sphere(12, 6)
    trimesh.Trimesh(vertices=s.positions, faces=s.faces, process=False).export(tmp_path / "ball.obj")
    scene = {
        "mesh": "ball.obj",  # relative to the scene file
        "camera": {"eye": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 35},
        "size": [48, 40],
        "lights": [{"position": [1, 1, 2, 1], "diffuse": [1, 1, 1], "spot_cutoff": 30,
                    "spot_direction": [-0.3, -0.3, -1]}],
        "light_model": {"ambient": [0.1, 0.1, 0.1], "local_viewer": True},
        "material": {"opengl": {"ambient": [0.1, 0, 0], "diffuse": [0.7, 0.1, 0.1], "specular": [1, 1, 1],
                                "emission": [0, 0, 0], "shininess": 40}},
        "shading": "gouraud",
        "background": [0, 0, 1, 1],
        "antialias": False,
    }
    (tmp_path / "scene.json").write_text(json.dumps(scene))
    rc = main(["render", "--scene", str(tmp_path / "scene.json"), "-o", str(tmp_path / "out.png")])
    assert rc == 0
    img = np.asarray(Image.open(tmp_path / "out.png"))
    assert img.shape == (40, 48, 3)
    assert tuple(img[0, 0]) == (0, 0, 255)  # the background colour, unencoded
    # flags override the scene file
    rc = main(["render", "--scene", str(tmp_path / "scene.json"), "--size", "20x20", "-o", str(tmp_path / "o.exr")])
    assert rc == 0
    from brdfkit.render.image import read_exr

    assert read_exr(tmp_path / "o.exr").shape == (20, 20, 4)


@pytest.mark.parametrize(
    "args, fragment",
    [
        (["--model", "nope"], "unknown model"),
        (["--model", "ward", "-p", "alpha_x=5"], "alpha_x"),
        (["--opengl", "gold", "--model", "ward"], "only one of"),
        (["--opengl", "gold", "--shading", "toon"], "shading"),
        (["--opengl", "gold", "--size", "0x4"], "--size"),
        (["--scene", "/nonexistent/scene.json"], "not found"),
        (["--mesh", "/nonexistent/x.obj"], "not found"),
        (["--opengl", "gold", "--tonemap", "filmic"], "tonemap"),
    ],
)
def test_render_errors_are_one_line(tmp_path, capsys, args, fragment):
    rc = main(["render", *args, "-o", str(tmp_path / "x.png")])
    err = capsys.readouterr().err
    assert rc != 0
    assert fragment in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_render_bad_output_suffix(tmp_path, capsys):
    rc = main(["render", "--opengl", "gold", "-o", str(tmp_path / "x.jpg")])
    assert rc != 0 and ".png" in capsys.readouterr().err


def test_gallery(tmp_path, capsys):
    rc = main(["gallery", "-o", str(tmp_path / "g"), "--size", "48", "--only", "materials",
               "--only", "gouraud-vs-phong", "--json"])
    assert rc == 0
    files = json.loads(capsys.readouterr().out)
    assert [p.rsplit("/", 1)[-1] for p in files] == ["materials.png", "gouraud-vs-phong.png"]
    img = np.asarray(Image.open(files[0]))
    assert img.shape[1] > 6 * 48 and img.shape[0] > 2 * 48  # 6 x 2 labelled panels
    rc = main(["gallery", "--only", "nope", "-o", str(tmp_path / "g")])
    assert rc != 0 and "unknown figure" in capsys.readouterr().err


def test_render_measured_material(tmp_path, capsys):
    rc = main(["render", "--measured", "merl/aluminium", "--mesh", "sphere", "--size", "32", "-o",
               str(tmp_path / "al.png"), "--json"])
    assert rc == 0
    assert json.loads(capsys.readouterr().out)["size"] == [32, 32]
    assert np.asarray(Image.open(tmp_path / "al.png")).max() > 50


# --- default lighting (issue 30): a BRDF given no lighting is lit by the studio environment ------


def _luminance(path):
    return (np.asarray(Image.open(path).convert("RGB")).astype(float) / 255) @ [0.2126, 0.7152, 0.0722]


def test_default_lighting_shows_a_mirror_as_one(tmp_path, capsys):
    """``brdfkit render --measured merl/chrome`` was a black ball (one speck of the single light):
    object mean 0.013, 0.4 % of its pixels above 0.3 at 64 px; in the studio: 0.093 and 10 %."""
    assert main(["render", "--opengl", "gold", "--mesh", "sphere", "--size", "64", "-o", str(tmp_path / "m.png")]) == 0
    obj = _luminance(tmp_path / "m.png") > 0  # the sphere's pixels (gold with OpenGL's ambient is never black)
    capsys.readouterr()
    out = tmp_path / "chrome.png"
    assert main(["render", "--measured", "merl/chrome", "--mesh", "sphere", "--size", "64", "-o", str(out), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["environment"] == "studio" and info["samples"] == 64
    lum = _luminance(out)
    assert lum[~obj].max() == 0  # the environment is not drawn: the background stays black
    assert lum[obj].mean() > 0.05 and lum[obj].max() > 0.6 and (lum[obj] > 0.3).mean() > 0.03
    # --env none: the point light as before, the black ball
    assert main(["render", "--measured", "merl/chrome", "--mesh", "sphere", "--size", "64", "--env", "none",
                 "-o", str(out), "--json"]) == 0
    assert "environment" not in json.loads(capsys.readouterr().out)
    assert _luminance(out)[obj].mean() < 0.03


def test_default_lighting_leaves_opengl_scenes_and_flat_shading_alone(tmp_path, capsys):
    for args in (["--opengl", "gold"], ["--model", "cook-torrance", "--shading", "gouraud"]):
        assert main(["render", *args, "--mesh", "sphere", "--size", "16", "-o", str(tmp_path / "a.png"), "--json"]) == 0
        assert "environment" not in json.loads(capsys.readouterr().out)
    # a scene file's lights win
    scene = {"mesh": "sphere", "size": [16, 16], "material": {"model": "lambert"},
             "lights": [{"position": [0, 0, 1, 0], "diffuse": [1, 1, 1]}]}
    (tmp_path / "s.json").write_text(json.dumps(scene))
    assert main(["render", "--scene", str(tmp_path / "s.json"), "-o", str(tmp_path / "b.png"), "--json"]) == 0
    assert "environment" not in json.loads(capsys.readouterr().out)


def test_samples_apply_to_the_default_environment(tmp_path, capsys):
    rc = main(["render", "--model", "lambert", "--mesh", "sphere", "--size", "16", "--samples", "8",
               "-o", str(tmp_path / "a.png"), "--json"])
    assert rc == 0 and json.loads(capsys.readouterr().out)["samples"] == 8
    rc = main(["render", "--opengl", "gold", "--samples", "8", "-o", str(tmp_path / "b.png")])
    err = capsys.readouterr().err
    assert rc == 2 and "--samples needs environment lighting" in err and not (tmp_path / "b.png").exists()


def test_example_scene_is_found_from_any_folder(tmp_path, capsys, monkeypatch):
    from brdfkit import examples

    monkeypatch.chdir(tmp_path)
    assert main(["render", "--scene", "example", "--size", "24", "-o", "scene.png", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["material"] == "cook-torrance" and (tmp_path / "scene.png").is_file()
    assert examples.path("scene.json").is_file() and examples.path("ggx.brdf").is_file()
    with pytest.raises(ValueError, match="unknown example"):
        examples.path("nope.json")


def test_default_environment_only_on_the_glsl_backend(tmp_path):
    """The numpy backend's environment lighting is the reference quadrature (minutes): never a default."""
    from brdfkit.render import scene as sc
    from brdfkit.render.lighting import uses_default_environment

    parsed, _ = sc.scene_from_json({"material": {"model": "cook-torrance"}, "size": [8, 8]})
    assert uses_default_environment(parsed, lights_given=False)
    assert not uses_default_environment(parsed, lights_given=False, glsl=False)
    assert not uses_default_environment(parsed, lights_given=True)


def test_gallery_skips_a_plot_figure_that_cannot_run_here(tmp_path, capsys, monkeypatch):
    """Where Mitsuba's llvm variant is missing the default gallery names the skipped figure on stderr
    and makes the rest; asking for it explicitly is a one-line error (exit 1, nothing written)."""
    from brdfkit.render import gallery

    monkeypatch.setattr(gallery.FIGURES["microsurfaces"], "unavailable", lambda: "no Mitsuba here")
    names = gallery.gallery_names(None, notify=lambda m: print(m, file=sys.stderr))
    assert "microsurfaces" not in names and "materials" in names
    assert "skipped figure 'microsurfaces': no Mitsuba here" in capsys.readouterr().err
    rc = main(["gallery", "--only", "microsurfaces", "-o", str(tmp_path / "g")])
    err = capsys.readouterr().err
    assert rc != 0 and "cannot be made here: no Mitsuba here" in err and "Traceback" not in err
    assert not (tmp_path / "g").exists()
