"""Exports of oren-nayar variant="eon" (exact in MaterialX and glTF), and two interchange fixes:
a microfacet without diffuse exported to Mitsuba is not "clamped", save_merl says what to give."""

from __future__ import annotations

import numpy as np
import pytest

import brdfkit as bk
from _classic_helpers import random_upper
from brdfkit.interchange.targets import GltfPBR, OpenPBRSurface

KD = [0.2, 0.5, 0.8]


@pytest.mark.parametrize("sigma,r", [(0.6, 0.6), (1.3, 1.0)])
def test_materialx_eon_is_exact(tmp_path, sigma, r):
    mx = pytest.importorskip("MaterialX")
    m = bk.model("oren-nayar", kd=KD, sigma=sigma, variant="eon")
    path = tmp_path / "eon.mtlx"
    res = bk.export(m, "materialx", path)
    assert res.exact and res.error is None and "oren_nayar_diffuse_bsdf" in res.target
    assert res.params["base_diffuse_roughness"] == pytest.approx(r) and res.params["specular_weight"] == 0
    # the OpenPBR formula with these parameters is the model itself
    wi, wo = random_upper(2000, 51), random_upper(2000, 52)
    np.testing.assert_allclose(OpenPBRSurface(**res.params).eval(wi, wo), m.eval(wi, wo), rtol=1e-12)
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(path))
    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    doc.importLibrary(lib)
    assert doc.validate()[0]
    (bsdf,) = [n for n in doc.getNodes() if n.getCategory() == "oren_nayar_diffuse_bsdf"]
    assert bsdf.getInputValue("energy_compensation") is True
    assert bsdf.getInputValue("roughness") == pytest.approx(r)
    assert list(bsdf.getInputValue("color").asTuple()) == pytest.approx(KD)
    (opbr,) = [n for n in doc.getNodes() if n.getCategory() == "open_pbr_surface"]
    assert opbr.getInputValue("base_diffuse_roughness") == pytest.approx(r)
    assert {m.getName() for m in doc.getMaterialNodes()} >= {"M_oren_nayar_eon", "M_oren_nayar_openpbr"}


def test_materialx_other_models_do_not_write_diffuse_roughness(tmp_path):
    pytest.importorskip("MaterialX")
    bk.export(bk.model("lambert", kd=0.5), "materialx", tmp_path / "l.mtlx")
    text = (tmp_path / "l.mtlx").read_text()
    assert "diffuse_roughness" not in text and "oren_nayar" not in text


def test_gltf_eon_is_exact(tmp_path):
    pygltflib = pytest.importorskip("pygltflib")
    m = bk.model("oren-nayar", kd=KD, sigma=0.45, variant="eon")
    path = tmp_path / "eon.glb"
    res = bk.export(m, "gltf", path)
    assert res.exact and "KHR_materials_diffuse_roughness" in res.target
    g = pygltflib.GLTF2().load_binary(str(path))
    mat = g.materials[0]
    assert mat.extensions["KHR_materials_diffuse_roughness"] == {"diffuseRoughnessFactor": pytest.approx(0.45)}
    assert mat.extensions["KHR_materials_specular"]["specularFactor"] == 0.0
    assert "KHR_materials_diffuse_roughness" in g.extensionsUsed
    np.testing.assert_allclose(mat.pbrMetallicRoughness.baseColorFactor[:3], KD)
    wi, wo = random_upper(2000, 53), random_upper(2000, 54)
    np.testing.assert_allclose(GltfPBR(**res.params).eval(wi, wo), m.eval(wi, wo), rtol=1e-12)


def test_targets_at_zero_diffuse_roughness_are_lambert_diffuse():
    wi, wo = random_upper(500, 55), random_upper(500, 56)
    lam = bk.model("lambert", kd=KD).eval(wi, wo)
    np.testing.assert_allclose(GltfPBR(base_color=KD, specular=0.0).eval(wi, wo), lam, rtol=1e-15)
    np.testing.assert_allclose(OpenPBRSurface(base_color=KD, specular_weight=0.0).eval(wi, wo), lam, rtol=1e-15)


def test_mitsuba_export_of_a_microfacet_without_diffuse_is_not_clamped(tmp_path):
    """microfacet fresnel=schlick (kd = 0, ks = 1) is fitted as a conductor: with kd held at 0 the
    result is a plain roughconductor, not a blend whose 'kd + ks > 1' had to be clamped."""
    pytest.importorskip("mitsuba")
    m = bk.model("microfacet", fresnel="schlick")
    assert np.all(m.params["kd"] == 0) and np.all(m.params["ks"] == 1)
    res = bk.export(m, "mitsuba", tmp_path / "m.json")
    assert "clamped" not in res.note, res.note
    assert res.target == "roughconductor"
    assert res.extra["fit"]["params"]["kd"] == [0.0, 0.0, 0.0]
    assert res.relative_error < 0.05


@pytest.mark.parametrize("params,says", [
    (dict(name="ward", alpha_x=0.2, alpha_y=0.2), ["alpha_x = alpha_y", "no isotropic parameter", "alpha="]),
    (dict(name="ashikhmin-shirley", nu=50.0, nv=50.0), ["nu = nv", "alpha="]),
    (dict(name="microfacet", alpha_x=0.1, alpha_y=0.3), ["give one roughness, alpha=", "instead of alpha_x and alpha_y"]),
])
def test_save_merl_refusal_says_what_to_do(tmp_path, params, says):
    name = params.pop("name")
    with pytest.raises(ValueError) as e:
        bk.save_merl(bk.model(name, **params), tmp_path / "x.binary")
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith(f"{name}: the MERL format stores isotropic BRDFs only")
    for s in says:
        assert s in msg, msg
    assert not (tmp_path / "x.binary").exists()
