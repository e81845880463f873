"""The GLSL twins of the RGL and UTIA readers (shaders/rgl.glsl, shaders/utia.glsl) through real OpenGL.

* parity: ``glsl.eval_glsl`` of a model read from a small RGL ``.bsdf`` (isotropic, and
  anisotropic with reduction 4, written by ``bk.tabulate`` at low resolution) and from a
  UTIA ``.bin`` (``tabulate_utia`` + ``write_utia_table``) equals the Python reader's
  ``eval`` to 1e-4 relative (plus 1e-6 of the peak, the analytic models' tolerance) on
  random and near-mirror direction pairs, as GLSL 3.30 core and GLSL ES 3.00;
* the texture layout of :mod:`brdfkit.render.tables` (what each texel holds), and its
  transfer format (``pack`` / ``unpack``) round trip;
* a sphere rendered through the ``glsl`` backend equals the ``numpy`` backend.
"""

from __future__ import annotations

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.measured.utia import tabulate_utia, write_utia_table
from brdfkit.memo import Held
from brdfkit.render import glsl, tables
from _numeric_helpers import peak_pairs

RGL_OPTS = {"resolution": 16, "n_theta": 4, "ndf_resolution": 16}


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("tables")
    iso = bk.model("microfacet", alpha=0.3, fresnel="schlick", f0=[0.9, 0.5, 0.2], kd=0.05)
    aniso = bk.model("ward", alpha_x=0.1, alpha_y=0.4, kd=0.1, ks=[0.3, 0.2, 0.1])
    bk.tabulate(iso, d / "iso.bsdf", format="rgl", **RGL_OPTS)
    bk.tabulate(aniso, d / "aniso.bsdf", format="rgl", n_phi=5, **RGL_OPTS)
    write_utia_table(tabulate_utia(aniso), d / "ward.bin")
    return {"iso": d / "iso.bsdf", "aniso": d / "aniso.bsdf", "utia": d / "ward.bin"}


def _assert_parity(model, wi, wo, version):
    got = glsl.eval_glsl(model, wi, wo, version=version)
    ref = model.eval(wi.astype(np.float64), wo.astype(np.float64))
    assert got.shape == ref.shape and np.isfinite(got).all() and (got >= 0).all()
    tol = 1e-4 * np.abs(ref) + 1e-6 * np.abs(ref).max()
    bad = (np.abs(got - ref) > tol).any(axis=1)
    assert not bad.any(), f"{bad.sum()} of {len(ref)} pairs differ, e.g. {got[bad][0]} vs {ref[bad][0]}"
    return ref


@pytest.mark.parametrize("which", ["iso", "aniso", "utia"])
@pytest.mark.parametrize("version", glsl.VERSIONS)
def test_glsl_twin_equals_the_python_reader(files, which, version):
    m = bk.model(str(files[which]))
    assert glsl.has_shader(m) and glsl.shader_path(m).name == ("utia.glsl" if which == "utia" else "rgl.glsl")
    n = 60_000 if version == "330 core" else 6_000
    wi, wo = peak_pairs(n, seed=len(which) + len(version))
    ref = _assert_parity(m, wi, wo, version)
    assert ref.max() > (1.0 if which == "iso" else 0.2)  # a real peak was looked up
    if which != "iso":  # anisotropic: rotating both directions about the normal changes the value
        c, s = np.cos(0.9), np.sin(0.9)
        rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], dtype=np.float32)
        g0 = glsl.eval_glsl(m, wi[:2000], wo[:2000])
        g1 = glsl.eval_glsl(m, wi[:2000] @ rot.T, wo[:2000] @ rot.T)
        assert np.abs(g0 - g1).max() > 0.05 * g0.max()
    # below the horizon: 0
    below = np.array([[0.3, 0.1, -0.2], [0.0, 0.6, 0.8]], dtype=np.float32)
    assert (glsl.eval_glsl(m, below, below[::-1]) == 0).all()


def test_rgl_texture_layout(files):
    m = bk.model(str(files["aniso"]))
    ts = tables.table_set(m)
    warp, rgb, ndf, sigma, axes = (t.data for t in ts.textures)
    n_phi, n_theta, h, w = m.resolution
    assert ts.ints == {"u_rgl_n_phi": n_phi, "u_rgl_n_theta": n_theta, "u_rgl_isotropic": 0,
                       "u_rgl_reduction": 4, "u_rgl_jacobian": 1}
    assert warp.shape[:1] == rgb.shape[:1] == (n_phi * n_theta,) and rgb.shape[1:] == (h, w, 4)
    # r: each slice integrates to 1 over its bilinear interpolant (trapezoids in x, then y)
    vndf = warp[..., 0].astype(np.float64)
    hv, wv = vndf.shape[1:]
    rows = (0.5 * (vndf[:, :, :-1] + vndf[:, :, 1:])).sum(axis=2) / (wv - 1)
    np.testing.assert_allclose((0.5 * (rows[:, :-1] + rows[:, 1:])).sum(axis=1) / (hv - 1), 1.0, rtol=1e-5)
    # g: the running integral along x (its last column is the row's total); b: the marginal CDF
    np.testing.assert_allclose(warp[:, :, wv - 2, 1], rows, rtol=1e-5)
    np.testing.assert_allclose(warp[:, hv - 2, 0, 2], 1.0, rtol=1e-5)
    # rgb: the file's own samples (slice = i_phi · n_theta + i_theta)
    f = bk.measured.rgl.read_rgl(files["aniso"])
    np.testing.assert_array_equal(rgb[2 * n_theta + 1, ..., :3], np.moveaxis(f["rgb"][2, 1], 0, -1))
    np.testing.assert_array_equal(ndf[..., 0], f["ndf"])
    np.testing.assert_array_equal(sigma[..., 0], f["sigma"])
    np.testing.assert_array_equal(axes[0, :n_phi, 0], f["phi_i"])
    np.testing.assert_array_equal(axes[1, :n_theta, 0], f["theta_i"])


def test_utia_texture_layout_and_pack_round_trip(files):
    m = bk.model(str(files["utia"]))
    ts = tables.table_set(m)
    (tex,) = ts.textures
    assert tex.size == (48, 6, 288) and tex.components == 4
    # texel (φv, θv, θi·48 + φi) holds table[:, θi, φi, θv, φv]
    np.testing.assert_array_equal(tex.data[3 * 48 + 17, 4, 29, :3], m.table[:, 3, 17, 4, 29].astype(np.float32))
    head, arrays = tables.unpack(tables.pack(ts, name="ward"))
    assert head["format"] == "utia" and head["shader"] == "utia.glsl" and head["name"] == "ward"
    assert head["textures"][0]["unit"] == tables.FIRST_UNIT and head["bytes"] == tex.data.nbytes
    np.testing.assert_array_equal(arrays[0], tex.data)
    with pytest.raises(ValueError, match="only RGL"):
        tables.table_set(bk.model("lambert"))


def test_table_set_is_built_once_and_read_only(files):
    m = bk.model(str(files["aniso"]))
    ts = tables.table_set(m)
    assert tables.table_set(m) is ts
    assert tables.table_set(bk.model(str(files["aniso"]))) is ts  # the same file: the same (digest) key
    assert all(not t.data.flags.writeable for t in ts.textures)
    with pytest.raises(ValueError, match="read-only"):
        ts.textures[0].data[0, 0, 0, 0] = 1.0
    fresh = tables.rgl_tables(m)  # the builder itself: a new, writable set equal to the held one
    assert all(t.data.flags.writeable and np.array_equal(t.data, h.data) for t, h in zip(fresh.textures, ts.textures))
    tables.table_set(bk.model(str(files["iso"])))
    tables.table_set(bk.model(str(files["utia"])))
    assert tables.table_set(m) is not ts  # two other sets asked for since: this one was dropped and rebuilt


def test_held_keeps_the_last_ones_by_key():
    held, built = Held(2), []

    def build(v):
        return lambda: built.append(v) or v

    assert held.get("a", build(1)) == 1 and held.get("b", build(2)) == 2
    assert held.get("a", build(10)) == 1 and built == [1, 2]  # held: not built again
    held.get("c", build(3))  # "b" is the least recently used
    assert len(held) == 2 and held.get("b", build(20)) == 20 and held.get("a", build(30)) == 30
    assert built == [1, 2, 3, 20, 30]


@pytest.mark.parametrize("which", ["aniso", "utia"])
def test_render_glsl_equals_numpy(files, which):
    from brdfkit.render import make_scene, render_linear
    from brdfkit.render.renderer import has_glsl

    m = bk.model(str(files[which]))
    assert has_glsl(m)
    scene = make_scene(mesh={"builtin": "sphere", "segments": 48, "rings": 24}, material=m, shading="phong",
                       size=(48, 48), antialias=False)
    a, b = render_linear(scene, "glsl"), render_linear(scene, "numpy")
    inside = (a[..., 3] == 1) & (b[..., 3] == 1)
    assert inside.sum() > 800
    np.testing.assert_allclose(a[inside][:, :3], b[inside][:, :3], rtol=1e-4, atol=1e-5 * b[..., :3].max())
    assert a[..., :3].max() > 0.05


@pytest.mark.skipif(not glsl.glslang_available(), reason="glslangValidator not installed (glslang-tools)")
@pytest.mark.parametrize("shader", ["rgl.glsl", "utia.glsl"])
@pytest.mark.parametrize("version", glsl.VERSIONS)
def test_shaders_pass_the_reference_compiler(shader, version):
    glsl.glslang_validate_source(glsl.common_source() + glsl.shader_file(shader), version)
