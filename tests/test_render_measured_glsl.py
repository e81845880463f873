"""Measured BRDFs through real OpenGL: the MERL table as a 3D texture in GLSL (shaders/measured.glsl).

* parity: ``glsl.eval_glsl`` of a MERL model equals its numpy ``eval`` (nearest
  lookup) at many direction pairs. To see *which* bin the shader read, one table
  stores its own bin indices (R = θh bin, G = θd bin, B = φd bin, some bins
  missing): any indexing error shows. A pair may fall into the neighbouring bin
  only when float32 puts its angles within float32 reach of a bin boundary; the
  distance to the nearest boundary is measured independently, in float64;
* tables written by ``save_merl`` from an analytic model and from a built-in
  Neural-BRDF material, nearest and trilinear;
* a 64×64 sphere through the ``glsl`` backend equals the ``numpy`` backend;
* the shader compiles as GLSL ES 3.00 and 3.30 core (driver and glslangValidator);
* ``brdfkit render --measured FILE`` uses the GLSL path.
"""

from __future__ import annotations

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.measured.merl import MERLBRDF, symmetric_half_diff, tabulate, write_merl_table
from brdfkit.render import glsl
from _numeric_helpers import peak_pairs

HALF_PI = np.pi / 2


def _pairs(n=150_000, seed=7):
    """Uniform pairs, pairs near the mirror direction (fine θh bins) and the shared special pairs."""
    wi, wo = peak_pairs(n, seed)
    pv = glsl.parity_vectors()
    wi = np.concatenate([wi, pv["wi"].astype(np.float32)])
    wo = np.concatenate([wo, pv["wo"].astype(np.float32)])
    return wi, wo


def _boundary_distance(wi, wo):
    """Distance (in bin-index units, float64) of each pair's angles to the nearest MERL bin boundary."""
    th, td, pd = symmetric_half_diff(wi, wo)
    uh = np.sqrt(th / HALF_PI) * 90
    ud = td / HALF_PI * 90
    up = pd / np.pi * 180
    return np.minimum.reduce(
        [np.abs(uh - np.round(uh)), np.abs(ud - np.round(ud)), np.abs(up - np.round(up)), up, 180 - up]
    )


@pytest.fixture(scope="module")
def id_model(tmp_path_factory):
    """A MERL file whose bins hold their own indices (+1), 5 % of them missing."""
    i, j, k = np.meshgrid(np.arange(90), np.arange(90), np.arange(180), indexing="ij")
    table = np.stack([i + 1.0, j + 1.0, k + 1.0]) * 0.01
    missing = np.random.default_rng(3).random((90, 90, 180)) < 0.05
    table[:, missing] = -1.0
    path = tmp_path_factory.mktemp("merl") / "ids.binary"
    write_merl_table(table, path)
    return bk.load_merl(path)


@pytest.mark.parametrize("version", glsl.VERSIONS)
def test_nearest_reads_the_same_bin_as_numpy(id_model, version):
    wi, wo = _pairs()
    f_gl = glsl.eval_glsl(id_model, wi, wo, version=version)
    f_np = id_model.eval(wi, wo)
    assert f_gl.dtype == np.float32 and f_gl.shape == f_np.shape
    assert np.isfinite(f_gl).all() and (f_gl >= 0).all()
    same = np.isclose(f_gl, f_np, rtol=1e-6, atol=0).all(axis=-1)
    frac = 1.0 - same.mean()
    # measured on llvmpipe: 8 of 225 826 pairs (3.5e-5), all within 6.1e-6 bin of a boundary
    assert frac < 5e-3, frac
    if not same.all():
        dist = _boundary_distance(wi[~same], wo[~same])
        assert dist.max() < 1e-4, dist.max()  # only where float32 cannot tell the bins apart
    # missing bins read 0, measured bins their value: both occur
    assert (f_np == 0).all(axis=-1).mean() > 0.01 and (f_np > 0).all(axis=-1).mean() > 0.5
    # below / at the horizon: 0
    below = (wi[:, 2] <= 0) | (wo[:, 2] <= 0)
    assert below.any() and (f_gl[below] == 0).all()


def test_nearest_is_exactly_reciprocal(id_model):
    wi, wo = _pairs(40_000, seed=11)
    np.testing.assert_array_equal(glsl.eval_glsl(id_model, wi, wo), glsl.eval_glsl(id_model, wo, wi))


def test_trilinear_matches_numpy(id_model):
    m = id_model.with_params(interpolation="trilinear")
    wi, wo = _pairs(60_000, seed=5)
    f_gl = glsl.eval_glsl(m, wi, wo)
    f_np = m.eval(wi, wo)
    # continuous in the angles except where a missing corner's weight switches on/off
    close = np.isclose(f_gl, f_np, rtol=1e-4, atol=1e-6).all(axis=-1)
    assert close.mean() > 0.995, close.mean()


def _check_parity(model, wi, wo):
    f_gl = glsl.eval_glsl(model, wi, wo)
    f_np = model.eval(wi, wo)
    same = np.isclose(f_gl, f_np, rtol=1e-6, atol=0).all(axis=-1)
    assert 1.0 - same.mean() < 5e-3
    if not same.all():
        assert _boundary_distance(wi[~same], wo[~same]).max() < 1e-4
    return f_gl


def test_saved_analytic_model(tmp_path):
    src = bk.model("cook-torrance", m=0.25)
    bk.save_merl(src, tmp_path / "ct.binary")
    m = bk.load_merl(tmp_path / "ct.binary")
    wi, wo = _pairs(60_000, seed=2)
    f = _check_parity(m, wi, wo)
    assert f.max() > 1.0  # a real specular peak was looked up
    # and the trilinear GLSL is close to the analytic model away from the peak
    mt = m.with_params(interpolation="trilinear")
    g = glsl.eval_glsl(mt, wi, wo)
    np.testing.assert_allclose(g, mt.eval(wi, wo), rtol=1e-4, atol=1e-6)


def test_builtin_material_via_merl_tabulation(tmp_path):
    nb = bk.material("merl/gold-metallic-paint")
    bk.save_merl(nb, tmp_path / "gold.binary")
    m = bk.load_merl(tmp_path / "gold.binary")
    wi, wo = _pairs(60_000, seed=9)
    f_file = _check_parity(m, wi, wo)
    # the Neural-BRDF model itself renders through its MERL tabulation: the same texels
    f_nb = glsl.eval_glsl(nb, wi, wo)
    same = np.isclose(f_nb, f_file, rtol=1e-6, atol=0).all(axis=-1)
    assert same.mean() > 0.999
    # the table approximates the network (nearest bins of a smooth function): median error small
    f_net = nb.eval(wi, wo)
    ok = f_net.max(axis=-1) > 1e-3
    rel = np.abs(f_nb[ok] - f_net[ok]).max(axis=-1) / f_net[ok].max(axis=-1)
    assert np.median(rel) < 0.05, np.median(rel)


def test_texels_layout(id_model):
    t = glsl.table_texels(id_model)
    assert t.shape == (90, 90, 180, 4) and t.dtype == np.float32
    tab = id_model.table
    np.testing.assert_array_equal(t[5, 7, 11, :3], np.maximum(tab[:, 5, 7, 11], 0).astype(np.float32))
    np.testing.assert_array_equal(t[..., 3] == 1, (tab >= 0).all(axis=0))
    with pytest.raises(ValueError, match="measured"):
        glsl.table_texels(bk.model("lambert"))


@pytest.mark.parametrize("version", glsl.VERSIONS)
def test_shader_compiles(version):
    assert glsl.has_shader(MERLBRDF) and glsl.shader_path(MERLBRDF).name == "measured.glsl"
    glsl.compile_check(MERLBRDF, version)
    assert glsl.declared_uniforms(glsl.shader_source(MERLBRDF))["u_table"] == "sampler3D"


@pytest.mark.skipif(not glsl.glslang_available(), reason="glslangValidator not installed (glslang-tools)")
@pytest.mark.parametrize("version", glsl.VERSIONS)
def test_shader_glslang(version):
    glsl.glslang_validate(MERLBRDF, version)


def _sphere_scene(material, shading, antialias=False):
    from brdfkit.render import make_scene

    return make_scene(
        mesh={"builtin": "sphere", "segments": 48, "rings": 24},
        material=material,
        shading=shading,
        size=(64, 64),
        antialias=antialias,
    )


@pytest.mark.parametrize("shading", ["phong", "gouraud"])
def test_render_glsl_equals_numpy(shading):
    from brdfkit.render import render_linear
    from brdfkit.render.renderer import has_glsl

    m = MERLBRDF(tabulate(bk.material("merl/blue-metallic-paint")), label="blue")
    assert has_glsl(m)  # auto picks the GLSL path
    scene = _sphere_scene(m, shading)
    a = render_linear(scene, "glsl")
    b = render_linear(scene, "numpy")
    np.testing.assert_array_equal(a[..., 3], b[..., 3])
    inside = a[..., 3] == 1
    assert inside.sum() > 1500
    d = np.abs(a[..., :3] - b[..., :3]).max(axis=-1)[inside]
    scale = np.maximum(b[..., :3].max(axis=-1)[inside], 1e-3)
    # measured: ≤ 2e-7 absolute; allow a few pixels on a bin boundary
    assert np.mean(d / scale > 1e-4) < 5e-3
    assert a[..., :3].max() > 0.3  # lit


def test_cli_render_measured_file_uses_glsl(tmp_path, capsys, monkeypatch):
    from PIL import Image

    from brdfkit.cli import main
    from brdfkit.render.renderer import Renderer

    src = bk.model("cook-torrance", m=0.3)
    bk.save_merl(src, tmp_path / "ct.binary")
    outs = {}
    original = Renderer._render_numpy
    for backend in ("auto", "numpy"):
        if backend == "auto":  # the default must not fall back to the numpy backend
            monkeypatch.setattr(Renderer, "_render_numpy", lambda self, scene: 1 / 0)
        else:
            monkeypatch.setattr(Renderer, "_render_numpy", original)
        out = tmp_path / f"{backend}.npy"
        # --env none: the two backends under the same point lights (the default environment is the GLSL backend's)
        rc = main(["render", "--measured", str(tmp_path / "ct.binary"), "--mesh", "sphere", "--size", "48",
                   "--no-antialias", "--backend", backend, "--env", "none", "-o", str(out)])
        assert rc == 0
        outs[backend] = np.load(out)
    capsys.readouterr()
    a, b = outs["auto"], outs["numpy"]
    inside = (a[..., 3] == 1) & (b[..., 3] == 1)
    assert inside.sum() > 500
    np.testing.assert_allclose(a[inside][:, :3], b[inside][:, :3], rtol=1e-4, atol=1e-5)
    rc = main(["render", "--measured", str(tmp_path / "ct.binary"), "--mesh", "sphere", "--size", "48",
               "--backend", "glsl", "-o", str(tmp_path / "x.png")])
    assert rc == 0 and np.asarray(Image.open(tmp_path / "x.png")).max() > 100
