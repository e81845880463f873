"""Image-based lighting in the headless renderer: white furnace, agreement with a brute-force numpy
reference, the environments (built-ins, files, cache), the scene file and the command line."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.analysis.albedo import albedo
from brdfkit.render import environment as E
from brdfkit.render import ibl
from brdfkit.render.renderer import default_renderer
from brdfkit.render.scene import make_scene, scene_from_json


@pytest.fixture(autouse=True)
def _cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("BRDFKIT_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "cache"))


def _scene(material, env, size=48, samples=256, eye=(0.0, 0.0, 3.0)):
    s = make_scene(mesh={"builtin": "sphere", "segments": 64, "rings": 32}, material=material, size=(size, size),
                   antialias=False, camera={"eye": list(eye), "target": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 40})
    s.environment = env
    s.samples = samples
    return s


def _facing(scene, min_cos=0.2):
    """Covered pixels whose normal faces the viewer by at least ``min_cos``, and the cosines."""
    pos, nrm, _ = default_renderer().gbuffer(scene)
    n = nrm[..., :3] / np.maximum(np.linalg.norm(nrm[..., :3], axis=-1, keepdims=True), 1e-12)
    v = -pos[..., :3] / np.maximum(np.linalg.norm(pos[..., :3], axis=-1, keepdims=True), 1e-12)
    c = (n * v).sum(-1)
    mask = (pos[..., 3] > 0) & (c > min_cos)
    return mask, c


def furnace():
    return E.environment_from_spec({"name": "furnace", "visible": False})[0]


def test_lambert_white_furnace_is_one():
    s = _scene(bk.model("lambert", kd=1.0), furnace(), samples=256)
    img = default_renderer().render_linear(s, "glsl")
    mask, _ = _facing(s, 0.05)
    vals = img[mask][:, :3]
    assert mask.sum() > 1000
    assert abs(vals.mean() - 1.0) < 0.01  # the image: 1 within 1 %
    assert np.percentile(np.abs(vals - 1), 95) < 0.06  # each pixel: Monte Carlo noise of 256 samples


@pytest.mark.parametrize("params", [dict(alpha=0.5, fresnel="none"),
                                    dict(alpha=0.3, distribution="beckmann", fresnel="none"),
                                    dict(alpha=1.0, fresnel="none", multiscatter=True),
                                    dict(alpha=0.2)])
def test_microfacet_white_furnace_matches_albedo(params):
    """In a uniform white environment a pixel's radiance is the directional albedo at its viewing angle."""
    m = bk.model("microfacet", **params)
    s = _scene(m, furnace(), samples=256)
    img = default_renderer().render_linear(s, "glsl")
    mask, c = _facing(s, 0.2)
    th = np.arccos(np.clip(c[mask], 0, 1))
    grid = np.radians(np.linspace(0, 80, 33))
    ref = np.stack([np.interp(th, grid, albedo(m, grid)[:, k]) for k in range(3)], -1)
    got = img[mask][:, :3]
    ratio = got.mean(0) / ref.mean(0)
    assert np.all(np.abs(ratio - 1) < 0.02), ratio
    # angle by angle too: bins of 10° averaged
    for lo in range(0, 80, 10):
        sel = (th >= math.radians(lo)) & (th < math.radians(lo + 10))
        if sel.sum() > 30:
            r = got[sel].mean(0) / ref[sel].mean(0)
            assert np.all(np.abs(r - 1) < 0.03), (lo, r)


def _small_sky():
    sky = E.builtin_map("sky")
    return E.Environment("sky-16x32", sky.reshape(16, 32, 32, 32, 3).mean((1, 3)), rotation_deg=30.0, visible=False)


@pytest.mark.parametrize("material", [
    dict(model="microfacet", params=dict(alpha=0.35)),
    dict(model="phong", params=dict(shininess=30, kd=0.3, ks=0.4)),
    dict(model="oren-nayar", params=dict(sigma=0.5, kd=0.8)),  # no sampler: cosine only
])
def test_converged_render_matches_numpy_reference(material):
    """GL Monte Carlo (2048 samples per pixel) vs the numpy brute force over every environment texel
    (3 × 3 cells each) on the same G-buffer: the image mean within 1 %, the mean per-pixel error
    within 3 % (the noise of 2048 samples is about 1.5 %)."""
    env = _small_sky()
    s = _scene(bk.model(material["model"], **material["params"]), env, size=24, samples=2048, eye=(0.0, 1.2, 2.8))
    r = default_renderer()
    gl = r.render_linear(s, "glsl")
    ref = r.render_linear(s, "numpy")  # antialias off: the same pixel centres
    mask, _ = _facing(s, 0.1)
    a, b = gl[mask][:, :3].astype(np.float64), ref[mask][:, :3].astype(np.float64)
    assert mask.sum() > 150
    assert np.all(np.abs(a.mean(0) / b.mean(0) - 1) < 0.01), (a.mean(0), b.mean(0))
    assert np.abs(a - b).mean() / b.mean() < 0.03


def test_sampler_uniforms_follow_sampler_for():
    u = ibl.sampler_uniforms(bk.model("lambert"))
    assert u["bki_lobe"] == ibl.LOBES["none"] and u["bki_diffuse_prob"] == 1.0
    u = ibl.sampler_uniforms(bk.model("microfacet", alpha_x=0.1, alpha_y=0.3, kd=0.2))
    assert u["bki_lobe"] == ibl.LOBES["ggx-visible"] and u["bki_lobe_params"] == (0.1, 0.3)
    assert 0 < u["bki_diffuse_prob"] < 0.5
    assert ibl.sampler_uniforms(bk.model("microfacet", distribution="beckmann"))["bki_lobe"] == ibl.LOBES["beckmann-h"]
    assert ibl.sampler_uniforms(bk.model("phong", shininess=40))["bki_lobe_params"] == (40.0, 0.0)
    assert ibl.sampler_uniforms(bk.model("blinn-phong"))["bki_lobe"] == ibl.LOBES["blinn"]


def test_environment_sampling_pdf_integrates_to_one():
    env = E.environment_from_spec("studio")[0]
    h, w = env.shape
    d = E.texel_directions(h, w)
    total = (env.pdf(d.reshape(-1, 3)).reshape(h, w) * E.row_solid_angles(h, w)[:, None]).sum()
    assert total == pytest.approx(1.0, rel=1e-6)
    # brighter texels are more likely, in proportion to their luminance
    lum = env.rgb @ E.LUMA
    i, j = np.unravel_index(np.argmax(lum), lum.shape)
    k, l = np.unravel_index(np.argmin(lum), lum.shape)
    p = env.pdf(d[[i, k], [j, l]])
    assert p[0] / p[1] == pytest.approx((lum[i, j] + 0.01 * lum.mean()) / (lum[k, l] + 0.01 * lum.mean()), rel=1e-4)


def test_sky_is_normalised_and_sun_is_brightest():
    env = E.environment_from_spec("sky")[0]
    h, w = env.shape
    d = E.texel_directions(h, w)
    om = E.row_solid_angles(h, w)[:, None]
    e_up = ((env.rgb @ E.LUMA) * np.maximum(d[..., 1], 0) * om).sum()
    assert e_up == pytest.approx(math.pi, rel=1e-3)  # a white horizontal Lambert surface: radiance 1
    lum = env.rgb @ E.LUMA
    i, j = np.unravel_index(np.argmax(lum), lum.shape)
    assert d[i, j, 1] == pytest.approx(math.sin(math.radians(35)), abs=0.02)  # the sun, 35° up
    sky = lum[: h // 2]
    assert sky[h // 4, :].min() > 0 and np.all(env.rgb >= 0)
    # Preetham: the sky is bluer than the sun; the sun is yellower than white after the atmosphere
    assert env.rgb[h // 8, 0, 2] > env.rgb[h // 8, 0, 0]
    assert env.rgb[i, j, 0] > env.rgb[i, j, 2]


def test_builtins_are_cached_atomically(tmp_path, monkeypatch):
    monkeypatch.setenv("BRDFKIT_CACHE_DIR", str(tmp_path))
    a = E.builtin_map("studio")
    files = list((tmp_path / "env").iterdir())
    assert [f.suffix for f in files] == [".npy"]  # no temporary file left behind
    files[0].write_bytes(b"garbage")  # a damaged cache is rebuilt, not trusted
    np.testing.assert_array_equal(E.builtin_map("studio"), a)
    np.testing.assert_array_equal(np.load(files[0]), a)


def test_hdr_round_trip_and_errors(tmp_path):
    rng = np.random.default_rng(0)
    img = (rng.random((8, 16, 3)) * 5).astype(np.float32)
    p = tmp_path / "x.hdr"
    E.write_hdr(p, img)
    back = E.read_hdr(p)
    # RGBE keeps 8 bits of mantissa under an exponent shared by the pixel's three channels
    assert np.all(np.abs(back - img) <= img.max(-1, keepdims=True) * 2.0**-7)
    env, n = E.environment_from_spec({"path": str(p), "samples": 16})
    assert n == 16 and env.shape == (8, 16)
    bad = tmp_path / "bad.hdr"
    bad.write_bytes(b"not an hdr")
    with pytest.raises(ValueError, match="Radiance"):
        E.read_map(bad)
    with pytest.raises(ValueError, match="must end in"):
        E.read_map(__file__)
    with pytest.raises(ValueError, match="unknown environment"):
        E.environment_from_spec({"name": "moon"})
    with pytest.raises(ValueError, match="unknown field"):
        E.environment_from_spec({"name": "sky", "exposure": 2})
    with pytest.raises(ValueError, match="finite and non-negative"):
        E.Environment("x", -np.ones((4, 8, 3)))
    with pytest.raises(ValueError, match="samples"):
        E.environment_from_spec({"name": "sky", "samples": 0})


def test_exr_environment(tmp_path):
    from brdfkit.render.image import save_exr

    img = np.ones((8, 16, 4), np.float32) * np.array([0.5, 1.0, 2.0, 1.0], np.float32)
    p = tmp_path / "e.exr"
    save_exr(p, img)
    env = E.environment_from_spec(str(p))[0]
    np.testing.assert_allclose(env.rgb[0, 0], [0.5, 1.0, 2.0])


def test_scene_file_environment_and_background(tmp_path):
    scene, _ = scene_from_json({"mesh": {"builtin": "sphere", "segments": 32, "rings": 16}, "size": [32, 32],
                                "material": {"model": "lambert", "params": {"kd": 0.5}},
                                "environment": {"name": "furnace", "samples": 16}})
    assert scene.environment.name == "furnace" and scene.samples == 16
    img = default_renderer().render_linear(scene)
    assert np.all(img[..., 3] == 1.0)  # the environment fills the background
    assert img[0, 0, :3] == pytest.approx([1.0, 1.0, 1.0])
    assert abs(img[16, 16, 0] - 0.5) < 0.1
    with pytest.raises(ValueError, match="BRDF material"):
        scene_from_json({"material": {"opengl": "gold"}, "environment": "sky"})
    with pytest.raises(ValueError, match="phong"):
        scene_from_json({"material": {"model": "lambert"}, "shading": "gouraud", "environment": "furnace"})


def test_cli(tmp_path, capsys):
    from brdfkit.cli import main

    assert main(["render", "--list-envs", "--json"]) == 0
    names = [e["name"] for e in json.loads(capsys.readouterr().out)]
    assert names == list(E.BUILTINS)
    out = tmp_path / "r.png"
    assert main(["render", "--model", "microfacet", "-p", "multiscatter=true", "--mesh", "sphere", "--size", "32",
                 "--env", "studio", "--samples", "8", "-o", str(out), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["environment"] == "studio" and info["samples"] == 8 and out.is_file()
    rc = main(["render", "--model", "lambert", "--env", "studio", "--samples", "0", "-o", str(out)])
    assert rc == 2 and "brdfkit: error: samples must be an integer" in capsys.readouterr().err
    rc = main(["render", "--model", "lambert", "--env", str(tmp_path / "none.exr"), "-o", str(out)])
    assert rc == 2 and "not found" in capsys.readouterr().err
    rc = main(["render", "--opengl", "gold", "--env", "sky", "-o", str(out)])
    assert rc == 2 and "BRDF material" in capsys.readouterr().err


def test_ibl_shaders_are_glsl_es():
    """The IBL shaders compile as GLSL ES 3.00 (for the explorer) with glslangValidator."""
    import shutil
    import subprocess

    from brdfkit.render import glsl

    exe = shutil.which("glslangValidator")
    if exe is None:
        pytest.skip("glslangValidator not installed")
    src = "#version 300 es\n#define BKR_IBL\n" + glsl.shader_source("microfacet") + "".join(
        glsl.shader_file(n) for n in ("pipeline_lights.glsl", "ibl_sampling.glsl", "ibl.glsl", "pipeline_fragment.glsl"))
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        f = Path(tmp) / "ibl.frag"
        f.write_text(src)
        r = subprocess.run([exe, str(f)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


def test_measured_material_under_an_environment():
    """A measured near-mirror (chrome-steel) gets a narrow sampling lobe; its IBL render is finite,
    non-negative and shows the soft boxes (it was black but for one highlight under a point light)."""
    m = bk.material("merl/chrome-steel")
    a, pd = ibl.measured_lobe(m)
    assert a < 0.05 and 0.1 <= pd <= 0.9
    env = E.environment_from_spec({"name": "studio", "visible": False})[0]
    s = _scene(m, env, size=32, samples=16)
    img = default_renderer().render_linear(s, "glsl")
    assert np.all(np.isfinite(img)) and img.min() >= 0
    mask, _ = _facing(s, 0.1)
    assert np.percentile(img[mask][:, :3].max(-1), 99) > 0.5  # bright reflections of the boxes
