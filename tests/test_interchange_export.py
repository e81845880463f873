"""Export to Mitsuba 3, MaterialX (OpenPBR) and glTF, checked by loading the files back with the
targets' own libraries.

* Mitsuba: the written XML (``mi.load_file``) and JSON dict (``mi.load_dict``) are
  evaluated by Mitsuba 3 itself (``scalar_rgb``, float32) on random pairs, with
  Mitsuba's naming (its ``si.wi`` is our ``wo``) and its cosine (``eval``
  includes cos θ of our ``wi``) undone: 1e-4 relative where the mapping is
  exact; where it is not, the error the export states is recomputed here from
  Mitsuba's values on the fitter's samples.
* MaterialX: the written document, read back, passes ``Document.validate``
  against the standard libraries; the OpenPBR values are checked against the
  model (F0 from eta, k by the closed form at normal incidence).
* glTF: the ``.glb`` loads back with pygltflib and with trimesh with the
  intended material values and a closed unit sphere.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.interchange import approx
from brdfkit.interchange.targets import F82_MU, GltfPBR, OpenPBRSurface, f82_tint_fresnel

DATA = Path(__file__).parent / "data"


@pytest.fixture(scope="module")
def mi():
    mitsuba = pytest.importorskip("mitsuba")
    old = mitsuba.variant()
    mitsuba.set_variant("scalar_rgb")
    yield mitsuba
    if old:
        mitsuba.set_variant(old)


def _pairs(n=400, seed=5, zmin=0.02):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(2):
        v = rng.normal(size=(n, 3))
        v[:, 2] = np.abs(v[:, 2])
        v /= np.linalg.norm(v, axis=1, keepdims=True)
        v = v[v[:, 2] > zmin][: n // 2]
        out.append(v)
    m = min(len(out[0]), len(out[1]))
    return out[0][:m], out[1][:m]


def _mitsuba_f(mi, bsdf, wi, wo):
    """f_r in OUR convention from a loaded Mitsuba BSDF (independent of brdfkit's own helper)."""
    ctx = mi.BSDFContext()
    si = mi.SurfaceInteraction3f()
    si.sh_frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))
    out = np.empty((len(wi), 3))
    for j, (a, b) in enumerate(zip(wi, wo)):
        si.wi = mi.Vector3f(*map(float, b))  # Mitsuba's wi: toward the viewer = our wo
        v = bsdf.eval(ctx, si, mi.Vector3f(*map(float, a)))  # includes cos θ of our wi
        out[j] = [v[0] / a[2], v[1] / a[2], v[2] / a[2]]
    return out


EXACT_MITSUBA = [
    ("lambert", {"kd": [0.2, 0.5, 0.8]}, "diffuse"),
    ("microfacet", {"alpha_x": 0.15, "alpha_y": 0.4, "eta": [0.2, 0.9, 1.6], "k": [3.9, 2.4, 1.2]}, "roughconductor"),
    ("microfacet", {"alpha": 0.3, "ks": [0.5, 0.4, 0.3], "kd": [0.1, 0.2, 0.3]}, "blendbsdf(diffuse, roughconductor)"),
    ("microfacet", {"alpha": 0.05, "ks": 0.4, "kd": 0.6}, "blendbsdf(diffuse, roughconductor)"),  # ks + kd = 1
]


@pytest.mark.parametrize("name,params,target", EXACT_MITSUBA, ids=[f"{c[0]}-{c[2]}-{i}" for i, c in enumerate(EXACT_MITSUBA)])
def test_mitsuba_round_trip_exact(mi, tmp_path, name, params, target):
    m = bk.model(name, **params)
    wi, wo = _pairs()
    ours = m.eval(wi, wo)
    for suffix in (".xml", ".json"):
        path = tmp_path / f"m{suffix}"
        r = bk.export(m, "mitsuba", path)
        assert r.exact and r.error is None and r.target == target and float(r) == 0.0
        if suffix == ".xml":
            bsdf = mi.load_file(str(path))
        else:
            bsdf = mi.load_dict(json.loads(path.read_text()))
        theirs = _mitsuba_f(mi, bsdf, wi, wo)
        # Mitsuba's scalar_rgb computes in float32
        np.testing.assert_allclose(theirs, ours, rtol=1e-4, atol=1e-7)


def test_mitsuba_round_trip_detects_a_wrong_mapping(mi, tmp_path):
    """The round trip is sharp: the same file with alpha_u and alpha_v swapped fails it."""
    m = bk.model("microfacet", alpha_x=0.15, alpha_y=0.4)
    path = tmp_path / "m.xml"
    bk.export(m, "mitsuba", path)
    text = path.read_text().replace('"alpha_u"', '"tmp"').replace('"alpha_v"', '"alpha_u"').replace('"tmp"', '"alpha_v"')
    path.write_text(text)
    wi, wo = _pairs()
    theirs = _mitsuba_f(mi, mi.load_file(str(path)), wi, wo)
    assert np.max(np.abs(theirs - m.eval(wi, wo)) / (np.abs(m.eval(wi, wo)) + 1e-7)) > 0.1


APPROX_MITSUBA = [
    ("microfacet", {"distribution": "beckmann", "alpha": 0.2}, "roughconductor", "direct"),
    ("microfacet", {"fresnel": "dielectric", "eta": 1.5, "kd": 0.5, "alpha": 0.3}, "roughplastic", "direct"),
    ("ward", {"kd": 0.2, "ks": 0.3, "alpha_x": 0.3, "alpha_y": 0.1}, "blendbsdf(diffuse, roughconductor)", "fit"),
    ("oren-nayar", {"kd": 0.6, "sigma": 0.3}, None, "fit"),
    # kd + ks > 1: Mitsuba takes reflectances in [0, 1] only, so they are clamped
    ("microfacet", {"alpha": 0.05, "ks": 0.9, "kd": 0.6}, "blendbsdf(diffuse, roughconductor)", "direct"),
]


@pytest.mark.parametrize("name,params,target,method", APPROX_MITSUBA, ids=[f"{c[0]}-{c[3]}-{i}" for i, c in enumerate(APPROX_MITSUBA)])
def test_mitsuba_stated_error_is_what_mitsuba_gives(mi, tmp_path, name, params, target, method):
    m = bk.model(name, **params)
    path = tmp_path / "m.xml"
    r = bk.export(m, "mitsuba", path)
    assert not r.exact and r.method == method and r.error > 0 and 0 < r.relative_error < 1
    if target:
        assert r.target == target
    # recompute the error from Mitsuba's own values on the fitter's samples (seed 0)
    from brdfkit.measured.fit import sample

    data = sample(approx._AsSamplable(m), n=3000, seed=0)
    theirs = _mitsuba_f(mi, mi.load_file(str(path)), data.wi, data.wo)
    d = (theirs - data.f) * data.wi[:, 2:3]
    err = math.sqrt(np.mean(data.w[:, None] * d * d))
    assert err == pytest.approx(r.error, rel=2e-3)


def test_mitsuba_fit_source_from_fit_json(tmp_path):
    fit_json = tmp_path / "fit.json"
    fit = bk.fit("blinn-phong", bk.model("oren-nayar", kd=0.5, sigma=0.4), samples=1000, starts=1)
    fit_json.write_text(json.dumps(fit.to_json()))
    from brdfkit.interchange.commands import source_model

    m = source_model(str(fit_json))
    assert type(m).name == "blinn-phong"
    for k, v in fit.params.items():
        assert np.allclose(m.params[k], v) if not isinstance(v, str) else m.params[k] == v


# --------------------------------------------------------------------------- MaterialX


def _read_validated(path):
    import MaterialX as mx

    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(path))
    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    doc.importLibrary(lib)
    ok, msg = doc.validate()
    assert ok, msg
    nodes = {n.getCategory(): n for n in doc.getNodes()}
    assert {"open_pbr_surface", "standard_surface", "surfacematerial"} <= set(nodes)
    return doc, nodes


def _inputs(node):
    out = {}
    for i in node.getInputs():
        v = i.getValue()
        out[i.getName()] = [float(x) for x in v.asTuple()] if hasattr(v, "asTuple") else float(v)
    return out


def test_materialx_lambert_exact_and_valid(tmp_path):
    path = tmp_path / "lambert.mtlx"
    r = bk.export(bk.model("lambert", kd=[0.2, 0.4, 0.6]), "materialx", path)
    assert r.exact and r.error is None
    _, nodes = _read_validated(path)
    o = _inputs(nodes["open_pbr_surface"])
    np.testing.assert_allclose(o["base_color"], [0.2, 0.4, 0.6], rtol=1e-5)
    assert o["specular_weight"] == 0.0 and o["base_metalness"] == 0.0
    s = _inputs(nodes["standard_surface"])
    np.testing.assert_allclose(s["base_color"], [0.2, 0.4, 0.6], rtol=1e-5)
    assert s["specular"] == 0.0
    # the OpenPBR formula with these values is Lambert
    wi, wo = _pairs(200)
    np.testing.assert_allclose(OpenPBRSurface(**r.params).eval(wi, wo), bk.model("lambert", kd=[0.2, 0.4, 0.6]).eval(wi, wo), rtol=1e-12)


def test_materialx_conductor_f0_from_eta_k(tmp_path):
    eta, k = np.array([0.143, 0.375, 1.442]), np.array([3.983, 2.386, 1.603])
    m = bk.model("microfacet", alpha=0.25, eta=eta, k=k)
    path = tmp_path / "gold.mtlx"
    r = bk.export(m, "materialx", path)
    _, nodes = _read_validated(path)
    o = _inputs(nodes["open_pbr_surface"])
    f0 = ((eta - 1) ** 2 + k**2) / ((eta + 1) ** 2 + k**2)  # normal-incidence conductor reflectance
    assert o["base_metalness"] == pytest.approx(1.0, abs=1e-3)
    assert r.method in ("direct", "fit") and not r.exact and 0 < r.relative_error < 0.05
    if r.method == "direct":
        np.testing.assert_allclose(o["base_color"], f0, rtol=1e-5)
        assert o["specular_roughness"] == pytest.approx(math.sqrt(0.25), rel=1e-5)
    # whatever the method, the direct mapping's values are F0 and the F82 tint
    f0_map, tint = approx.conductor_f0_f82(eta, k)
    np.testing.assert_allclose(f0_map, f0, rtol=1e-12)
    from brdfkit.terms.fresnel import fresnel_conductor

    # at the F82 angle the F82-tint Fresnel equals the conductor's, in every channel whose tint
    # needs no clamping to [0, 1] (gold's blue would need a tint > 1)
    ok = tint < 1
    assert ok.sum() >= 2
    f82 = np.asarray(fresnel_conductor(np.full(3, F82_MU), eta, k))
    np.testing.assert_allclose(f82_tint_fresnel(np.full(3, F82_MU), f0_map, tint)[ok], f82[ok], rtol=1e-9)
    assert (f82_tint_fresnel(np.full(3, F82_MU), f0_map, tint)[~ok] < f82[~ok]).all()
    # the stated error is the OpenPBR formula's error at the written values
    data = approx._samples(m)
    err, _ = approx._errors(OpenPBRSurface(**r.params).eval(data.wi, data.wo), data, "ngan")
    assert err == pytest.approx(r.error, rel=1e-9)


def test_materialx_fitted_model(tmp_path):
    m = bk.model("blinn-phong", kd=0.4, ks=0.2, shininess=60, normalized=True)
    r = bk.export(m, "materialx", tmp_path / "bp.mtlx")
    assert r.method == "fit" and not r.exact and r.relative_error < 0.5
    _read_validated(tmp_path / "bp.mtlx")
    data = approx._samples(m)
    err, _ = approx._errors(OpenPBRSurface(**r.params).eval(data.wi, data.wo), data, "ngan")
    assert err == pytest.approx(r.error, rel=1e-9)


# --------------------------------------------------------------------------- glTF


def _load_glb(path):
    import pygltflib
    import trimesh

    g = pygltflib.GLTF2().load_binary(str(path))
    scene = trimesh.load(str(path))
    geoms = list(scene.geometry.values())
    assert len(geoms) == 1
    return g, geoms[0]


def test_gltf_lambert_exact(tmp_path):
    path = tmp_path / "l.glb"
    r = bk.export(bk.model("lambert", kd=[0.2, 0.4, 0.6]), "gltf", path)
    assert r.exact
    g, mesh = _load_glb(path)
    mat = g.materials[0]
    np.testing.assert_allclose(mat.pbrMetallicRoughness.baseColorFactor, [0.2, 0.4, 0.6, 1.0])
    assert mat.pbrMetallicRoughness.metallicFactor == 0.0
    assert mat.extensions["KHR_materials_specular"]["specularFactor"] == 0.0
    assert "KHR_materials_specular" in g.extensionsUsed
    tm = mesh.visual.material
    np.testing.assert_allclose(np.asarray(tm.baseColorFactor[:3], float) / 255, [0.2, 0.4, 0.6], atol=1 / 255)
    # a closed unit sphere with outward normals
    assert mesh.is_watertight
    np.testing.assert_allclose(np.linalg.norm(mesh.vertices, axis=1), 1.0, atol=1e-6)
    assert (np.einsum("ij,ij->i", mesh.face_normals, mesh.triangles_center) > 0).all()
    wi, wo = _pairs(200)
    np.testing.assert_allclose(GltfPBR(**r.params).eval(wi, wo), bk.model("lambert", kd=[0.2, 0.4, 0.6]).eval(wi, wo), rtol=1e-12)


def test_gltf_schlick_metal_exact(tmp_path):
    m = bk.model("microfacet", alpha=0.16, fresnel="schlick", f0=[0.9, 0.6, 0.3])
    path = tmp_path / "metal.glb"
    r = bk.export(m, "gltf", path)
    assert r.exact and r.target == "pbrMetallicRoughness"
    g, mesh = _load_glb(path)
    pbr = g.materials[0].pbrMetallicRoughness
    np.testing.assert_allclose(pbr.baseColorFactor, [0.9, 0.6, 0.3, 1.0])
    assert pbr.metallicFactor == 1.0 and pbr.roughnessFactor == pytest.approx(0.4)
    assert not g.materials[0].extensions  # the defaults: no extension needed
    tm = mesh.visual.material
    assert tm.metallicFactor == 1.0 and tm.roughnessFactor == pytest.approx(0.4)
    wi, wo = _pairs(400)
    np.testing.assert_allclose(GltfPBR(**r.params).eval(wi, wo), m.eval(wi, wo), rtol=1e-9)


def test_gltf_fitted_and_stated_error(tmp_path):
    m = bk.model("ward", kd=0.3, ks=0.15, alpha_x=0.2, alpha_y=0.2)
    path = tmp_path / "w.glb"
    r = bk.export(m, "gltf", path)
    assert r.method == "fit" and not r.exact and 0 < r.relative_error < 1
    g, mesh = _load_glb(path)
    pbr = g.materials[0].pbrMetallicRoughness
    np.testing.assert_allclose(pbr.baseColorFactor[:3], r.params["base_color"])
    assert pbr.metallicFactor == pytest.approx(r.params["metallic"]) and pbr.roughnessFactor == pytest.approx(r.params["roughness"])
    data = approx._samples(m)
    err, _ = approx._errors(GltfPBR(**r.params).eval(data.wi, data.wo), data, "ngan")
    assert err == pytest.approx(r.error, rel=1e-9)


def test_gltf_brdf_explorer_source(tmp_path):
    """A .brdf file (GLSL through OpenGL) is a valid export source; its GGX is glTF's metal."""
    m = bk.load_brdf(DATA / "ggx.brdf", alpha=0.25, f0=[0.9, 0.6, 0.3], useDiffuse=False)
    r = bk.export(m, "gltf", tmp_path / "b.glb")
    assert r.method == "fit" and r.relative_error < 1e-3
    np.testing.assert_allclose(r.params["base_color"], [0.9, 0.6, 0.3], atol=2e-3)
    assert r.params["roughness"] == pytest.approx(0.5, abs=2e-3) and r.params["metallic"] == pytest.approx(1, abs=2e-3)


# --------------------------------------------------------------------------- CLI


def _cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "brdfkit", *args], capture_output=True, text=True, timeout=300, cwd=cwd)


def test_cli_export_json_and_errors(tmp_path):
    out = tmp_path / "g.xml"
    r = _cli("export", "microfacet", "-p", "alpha=0.3", "--to", "mitsuba", "-o", str(out), "--json")
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert res["exact"] is True and res["target"] == "roughconductor" and out.is_file()
    assert res["mitsuba_dict"]["type"] == "roughconductor" and res["mitsuba_dict"]["alpha_u"] == 0.3
    for args, needle in [
        (("ward", "--to", "obj", "-o", str(tmp_path / "x.obj")), "unknown --to 'obj'"),
        (("ward", "--to", "gltf", "-o", str(tmp_path / "x.xml")), "must end in .glb"),
        (("ward", "--to", "gltf", "-o", str(tmp_path / "a" / "b" / "x.glb")), "does not exist"),
        (("nosuchmodel", "--to", "gltf", "-o", str(tmp_path / "x.glb")), "unknown model"),
        ((str(tmp_path / "nofit.json"), "--to", "gltf", "-o", str(tmp_path / "x.glb")), "no such file"),
        (("ward", "-p", "kd=7", "--to", "gltf", "-o", str(tmp_path / "x.glb")), "out of range"),
    ]:
        r = _cli("export", *args)
        assert r.returncode == 2, (args, r.stdout, r.stderr)
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("brdfkit: error:") and needle in lines[0], r.stderr
    bad = tmp_path / "bad.json"
    bad.write_text('{"not": "a fit"}')
    r = _cli("export", str(bad), "--to", "gltf", "-o", str(tmp_path / "x.glb"))
    assert r.returncode == 2 and "expected the JSON of 'brdfkit fit" in r.stderr
    assert not (tmp_path / "x.glb").exists()


@pytest.mark.parametrize(
    "cls,params",
    [
        (GltfPBR, {}),
        (GltfPBR, {"metallic": 1.0, "roughness": 0.0, "base_color": 1.0}),
        (GltfPBR, {"metallic": 0.3, "roughness": 0.05, "ior": 5.0, "specular": 0.5, "specular_color": [1, 0, 0.5]}),
        (OpenPBRSurface, {}),
        (OpenPBRSurface, {"base_metalness": 1.0, "specular_roughness": 0.0, "specular_color": 0.0}),
        (OpenPBRSurface, {"base_metalness": 0.5, "specular_roughness_anisotropy": 1.0, "specular_ior": 5.0}),
    ],
)
def test_target_formulas_keep_the_contract(cls, params):
    """The targets' formulas (used for fitting and errors) are BRDFs: finite, >= 0, 0 below the horizon."""
    from brdfkit.render.glsl import parity_vectors

    v = parity_vectors()
    f = cls(**params).eval(v["wi"].astype(float), v["wo"].astype(float))
    assert np.isfinite(f).all() and (f >= 0).all()
    below = (v["wi"][:, 2] <= 0) | (v["wo"][:, 2] <= 0)
    assert (f[below] == 0).all() and f[~below].max() > 0


def test_gltf_formula_independent_point():
    """GltfPBR at one pair, against the formula written out by hand (glTF 2.0 Appendix B)."""
    wi = np.array([0.6, 0.0, 0.8])
    wo = np.array([-0.28, 0.0, 0.96])
    base, metallic, rough, ior = np.array([0.5, 0.4, 0.3]), 0.25, 0.5, 1.5
    a = rough**2
    h = (wi + wo) / np.linalg.norm(wi + wo)
    nh, nl, nv, vh = h[2], wi[2], wo[2], wo @ h
    D = a * a / (math.pi * (nh * nh * (a * a - 1) + 1) ** 2)
    V = 1 / ((nl + math.sqrt(a * a + (1 - a * a) * nl * nl)) * (nv + math.sqrt(a * a + (1 - a * a) * nv * nv)))
    f0 = ((ior - 1) / (ior + 1)) ** 2
    F0 = f0 + (base - f0) * metallic
    F = F0 + (1 - F0) * (1 - vh) ** 5
    want = (1 - metallic) * (1 - F) * base / math.pi + F * D * V
    got = GltfPBR(base_color=base, metallic=metallic, roughness=rough, ior=ior).eval(wi, wo)
    np.testing.assert_allclose(got, want, rtol=1e-12)


def test_export_takes_a_fit_result(tmp_path):
    fit = bk.fit("lambert", bk.model("oren-nayar", kd=0.5, sigma=0.2), samples=300, starts=1)
    r = bk.export(fit, "gltf", tmp_path / "f.glb")
    assert r.exact and r.params["base_color"] == pytest.approx(list(fit.params["kd"]))
    with pytest.raises(ValueError, match="expected a model"):
        bk.export("lambert", "gltf", tmp_path / "g.glb")
    with pytest.raises(ValueError, match="unknown export format 'obj'"):
        bk.export(fit.model, "obj", tmp_path / "g.obj")
