"""Measured files wherever a model is taken (issue 28): RGL ``.bsdf`` (isotropic, anisotropic) and
UTIA ``.bin`` through the real command line, in-process (:func:`brdfkit.cli.main`): ``eval``,
``check``, ``plot``, ``render``, ``export``, ``fit`` and the batch fit over a folder; and bad files
as one line, exit status 2, at every one of those commands.

The files are written by brdfkit itself from known analytic models (small tables, for speed), so
every result can be checked against the source model: the fits recover its parameters, ``check``
finds its albedo, ``eval`` gives the reader's value.
"""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.measured import utia

ISO = dict(name="microfacet", alpha=0.3)
ANISO = dict(name="ward", kd=[0.3, 0.2, 0.1], ks=[0.1, 0.1, 0.1], alpha_x=0.2, alpha_y=0.5)


def _model(spec):
    spec = dict(spec)
    return bk.model(spec.pop("name"), **spec)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """``iso.bsdf`` (GGX), ``aniso.bsdf`` (anisotropic Ward) and ``ward.bin`` (the same Ward, UTIA)."""
    d = tmp_path_factory.mktemp("formats")
    out = {"iso": str(d / "iso.bsdf"), "aniso": str(d / "aniso.bsdf"), "utia": str(d / "ward.bin")}
    r = bk.tabulate(_model(ISO), out["iso"], format="rgl", resolution=16, n_theta=8, ndf_resolution=32,
                     error_pairs=500)
    assert r.error < 0.05, r.error
    r = bk.tabulate(_model(ANISO), out["aniso"], format="rgl", resolution=16, n_theta=6, n_phi=4,
                     ndf_resolution=32, error_pairs=500)
    assert r.error < 0.1 and r.shape["isotropic"] is False, (r.error, r.shape)
    utia.write_utia_table(utia.tabulate_utia(_model(ANISO)), out["utia"])
    return out


def _one_error_line(r, *words):
    assert r.returncode == 2, (r.returncode, r.stdout[-300:], r.stderr[-600:])
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("brdfkit: error: "), r.stderr
    for w in words:
        assert w in lines[0], (w, lines[0])
    assert "Traceback" not in r.stderr + r.stdout


def _vec(theta_deg, phi_deg):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


# ----------------------------------------------------------------- eval, check
@pytest.mark.parametrize("kind", ["iso", "aniso", "utia"])
def test_eval(files, kind, cli):
    r = cli("eval", files[kind], "--wi", "30,20", "--wo", "50,200", "--json")
    assert r.returncode == 0, r.stderr
    got = np.array(json.loads(r.stdout)["value"])
    want = bk.model(files[kind]).eval(_vec(30, 20), _vec(50, 200))
    np.testing.assert_allclose(got, want, rtol=1e-9)
    assert (got > 0).all()


@pytest.mark.parametrize("kind, source, tol", [("iso", ISO, 0.03), ("utia", ANISO, 0.05)])
def test_check_finds_the_source_models_albedo(files, kind, source, tol, cli):
    """``brdfkit check FILE``: the albedo it reports at θ <= 60° is the source model's, to the tabulation error
    (UTIA: its 15° grid, extrapolated above 75°, gives up to 4 % at 55-60°)."""
    from brdfkit.analysis.albedo import albedo

    r = cli("check", files[kind], "--level", "fast", "--json")
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    th = np.array(res["albedo"]["theta_deg"])
    got = np.array(res["albedo"]["rgb"])[th <= 60]
    want = albedo(_model(source), np.radians(th[th <= 60]), level="fast")
    np.testing.assert_allclose(got, want, rtol=tol)
    assert isinstance(res["reciprocal"], bool)


# ----------------------------------------------------------------- plot, render
@pytest.mark.parametrize("kind", ["iso", "aniso", "utia"])
@pytest.mark.parametrize("plot", ["polar", "sphere"])
def test_plot(files, kind, plot, cli, tmp_path):
    import matplotlib.image as mpimg

    out = tmp_path / f"{kind}-{plot}.png"
    r = cli("plot", files[kind], "--kind", plot, "--size", "48", "-o", str(out))
    assert r.returncode == 0, r.stderr
    img = mpimg.imread(out)
    assert img.shape[0] > 40 and img[..., :3].std() > 0.01  # a picture, not a blank page


@pytest.mark.parametrize("kind", ["iso", "aniso", "utia"])
def test_render(files, kind, cli, tmp_path):
    out = tmp_path / f"{kind}.npy"
    r = cli("render", "-m", files[kind], "--size", "32x32", "-o", str(out), "--env", "none", "--json")
    assert r.returncode == 0, r.stderr
    img = np.load(out)
    lit = img[..., 3] > 0.5
    assert lit.sum() > 50 and np.isfinite(img).all() and img[lit, :3].max() > 0.01


@pytest.mark.parametrize("kind", ["aniso", "utia"])
def test_anisotropic_files_render_on_glsl(files, kind, cli, tmp_path):
    """An anisotropic RGL or UTIA file renders through its GLSL twin (``rgl.glsl``, ``utia.glsl``) when
    asked; that the picture is the numpy backend's is test_render_tables_glsl's job (1e-4, no AA)."""
    out = tmp_path / f"{kind}.npy"
    r = cli("render", "-m", files[kind], "--size", "32x32", "-o", str(out), "--env", "none", "--backend", "glsl")
    assert r.returncode == 0, r.stderr
    img = np.load(out)
    lit = img[..., 3] > 0.5
    assert lit.sum() > 50 and np.isfinite(img).all() and img[lit, :3].max() > 0.01


# ----------------------------------------------------------------- export
@pytest.mark.parametrize("kind, target, suffix", [
    ("iso", "mitsuba", ".xml"), ("aniso", "mitsuba", ".json"), ("utia", "mitsuba", ".xml"),
    ("iso", "materialx", ".mtlx"), ("aniso", "gltf", ".glb"), ("utia", "gltf", ".glb"),
])
def test_export(files, kind, target, suffix, cli, tmp_path):
    out = tmp_path / f"{kind}{suffix}"
    r = cli("export", files[kind], "--to", target, "-o", str(out), "--json")
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert out.is_file() and out.stat().st_size > 50
    if target == "mitsuba" and kind != "utia":  # Mitsuba 3 reads RGL files itself: exact
        assert res["exact"] and res["target"] == "measured" and res["error"] is None
    else:  # fitted, with its error stated
        assert not res["exact"] and 0 < res["relative_error"] < 0.2, res


def test_mitsuba_export_of_an_rgl_file_is_the_file(files, mi, tmp_path):
    """The exported XML, loaded by Mitsuba 3, evaluates as brdfkit's reader of the file."""
    from brdfkit.interchange.export import export, mitsuba_eval

    rng = np.random.default_rng(3)
    wi, wo = (_vec(rng.uniform(5, 70, 200), rng.uniform(0, 360, 200)).T for _ in range(2))
    for kind in ("iso", "aniso"):
        m = bk.model(files[kind])
        res = export(m, "mitsuba", tmp_path / f"{kind}.xml")
        got = mitsuba_eval(mi.load_file(res.path), wi, wo)
        np.testing.assert_allclose(got, m.eval(wi, wo), rtol=1e-4, atol=1e-6)


# ----------------------------------------------------------------- fit
@pytest.mark.parametrize("kind, model, want, rel", [
    ("iso", "microfacet", {"alpha": 0.3}, 0.05),
    ("aniso", "ward", {"alpha_x": 0.2, "alpha_y": 0.5}, 0.15),
    ("utia", "ward", {"alpha_x": 0.2, "alpha_y": 0.5}, 0.15),
])
def test_fit_recovers_the_source_model(files, kind, model, want, rel, cli):
    """Mitsuba users' workflow: an analytic model fitted to an RGL (or UTIA) file finds the model it came from."""
    r = cli("fit", files[kind], "-m", model, "--samples", "1500", "--starts", "2", "--json")
    assert r.returncode == 0, r.stderr
    params = json.loads(r.stdout)["params"]
    for k, v in want.items():
        assert params[k] == pytest.approx(v, rel=rel), (k, params[k])


def test_bk_fit_takes_an_rgl_path(files):
    r = bk.fit("ward", files["aniso"], samples=1000, starts=2)
    assert r.params["alpha_x"] == pytest.approx(0.2, rel=0.15)
    assert r.params["alpha_y"] == pytest.approx(0.5, rel=0.15)


# ----------------------------------------------------------------- the batch over a folder
@pytest.fixture(scope="module")
def folder(files, tmp_path_factory):
    """A folder of every measured format: RGL, UTIA, MERL (.binary), plus files the batch must skip."""
    d = tmp_path_factory.mktemp("batch") / "mats"
    d.mkdir()
    for kind in ("iso", "utia"):
        os.link(files[kind], d / os.path.basename(files[kind]))
    bk.save_merl(bk.model("lambert", kd=[0.5, 0.4, 0.3]), d / "grey.binary")
    (d / "notes.txt").write_text("not a material")
    (d / ".half-written.bsdf").write_bytes(b"tensor")
    return d


def test_batch_fit_over_a_folder_of_every_format(folder, cli, tmp_path):
    out = tmp_path / "out"
    r = cli("fit", "--all-measured", "--set", str(folder), "-m", "lambert", "-m", "ward", "--samples", "400",
            "--starts", "1", "--workers", "1", "--out", str(out), "--json")
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert res["fitted"] == 6
    rows = (out / "fit_errors.csv").read_text().strip().splitlines()
    assert rows[0] == "material,lambert,ward"
    assert sorted(row.split(",")[0] for row in rows[1:]) == sorted(
        str(folder / n) for n in ("grey.binary", "iso.bsdf", "ward.bin"))
    by = {(x["source"], x["column"]): x for x in res["results"]}
    grey = by[("grey", "lambert")]
    np.testing.assert_allclose(grey["params"]["kd"], [0.5, 0.4, 0.3], rtol=1e-3)  # the table's own model
    assert by[("ward", "ward")]["error"] < by[("ward", "lambert")]["error"]


def test_batch_refuses_a_bad_file_before_any_fit(folder, cli, tmp_path):
    bad = tmp_path / "mats"
    bad.mkdir()
    for n in os.listdir(folder):
        os.link(folder / n, bad / n)
    (bad / "broken.bsdf").write_bytes(b"tensor_file\0\x02\x00" + b"\0" * 40)
    out = tmp_path / "out"
    r = cli("fit", "--all-measured", "--set", str(bad), "-m", "lambert", "--out", str(out), "--workers", "1")
    _one_error_line(r, "broken.bsdf", "version 2.0")
    assert not out.exists()


def test_batch_folder_errors(cli, tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "a.txt").write_text("x")
    _one_error_line(cli("fit", "--all-measured", "--set", str(empty), "-m", "lambert", "--out", str(tmp_path / "o")),
                    "no measured files", ".bsdf")
    _one_error_line(cli("fit", str(empty), "-m", "lambert"), "is a folder", "--all-measured --set")
    _one_error_line(cli("fit", "--all-measured", "--set", str(tmp_path / "nope"), "-m", "lambert",
                        "--out", str(tmp_path / "o")), "unknown measured set", "folder")


# ----------------------------------------------------------------- bad files at every command
@pytest.fixture(scope="module")
def bad(files, tmp_path_factory):
    from brdfkit.measured.tensor_file import read_tensor_file, tensor_file_bytes

    d = tmp_path_factory.mktemp("bad")
    raw = open(files["iso"], "rb").read()
    fields = {k: np.array(v) for k, v in read_tensor_file(files["iso"]).items()}
    fields["vndf"][0, 1, 2, 3] = np.nan
    table = np.fromfile(files["utia"], dtype="<f8")
    table[12345] = np.inf
    out = {
        "magic": (b"tensor_fi1e\0" + raw[12:], "not a tensor_file"),
        "rgl-nan": (tensor_file_bytes(fields), "'vndf' holds NaN"),
        "utia-short": (table.tobytes()[:-8], "UTIA"),
        "utia-inf": (table.tobytes(), "infinite"),
    }
    paths = {}
    for name, (data, words) in out.items():
        p = d / (name + (".bin" if name.startswith("utia") else ".bsdf"))
        p.write_bytes(data)
        paths[name] = (str(p), words)
    return paths


COMMANDS = {
    "eval": lambda f, d: ("eval", f, "--wi", "30,0", "--wo", "30,180"),
    "check": lambda f, d: ("check", f, "--level", "fast"),
    "plot": lambda f, d: ("plot", f, "-o", str(d / "p.png")),
    "render": lambda f, d: ("render", "-m", f, "--size", "16x16", "-o", str(d / "r.png")),
    "render-measured": lambda f, d: ("render", "--measured", f, "--size", "16x16", "-o", str(d / "r.png")),
    "export": lambda f, d: ("export", f, "--to", "gltf", "-o", str(d / "e.glb")),
    "fit": lambda f, d: ("fit", f, "-m", "lambert", "--samples", "100"),
    "tabulate": lambda f, d: ("tabulate", f, "-o", str(d / "t.binary")),
    "info": lambda f, d: ("info", f),
}


@pytest.mark.parametrize("which", ["magic", "rgl-nan", "utia-short", "utia-inf"])
@pytest.mark.parametrize("command", list(COMMANDS))
def test_bad_file_is_one_line_at_every_command(bad, which, command, cli, tmp_path):
    path, words = bad[which]
    r = cli(*COMMANDS[command](path, tmp_path))
    _one_error_line(r, os.path.basename(path), words)
    assert not any(tmp_path.iterdir())  # nothing written


# ----------------------------------------------------------------- bk.tabulate(..., format="utia")
def test_tabulate_writes_utia(files, tmp_path, cli):
    """``format="utia"`` (or a ``.bin`` path) writes the model at the UTIA grid: the same bytes as
    ``tabulate_utia`` + ``write_utia_table``, read back as UTIA, with its tabulation error."""
    p = tmp_path / "w.bin"
    r = bk.tabulate(_model(ANISO), p, error_pairs=4000)
    assert r.format == "utia" and r.bytes == utia.FILE_BYTES
    assert p.read_bytes() == open(files["utia"], "rb").read()
    assert isinstance(bk.model(str(p)), utia.UTIABRDF)
    assert 0 < r.error < 0.05, r.error  # this anisotropic Ward on the 15°/7.5° grid: 3.3 %
    with pytest.raises(ValueError, match="applies to format 'rgl' only"):
        bk.tabulate("lambert", tmp_path / "l.bin", resolution=16)
    with pytest.raises(ValueError, match="must end in .bin"):
        bk.tabulate("lambert", tmp_path / "l.bsdf", format="utia")
    c = cli("tabulate", "lambert", "-p", "kd=0.5", "--format", "utia", "-o", str(tmp_path / "l.bin"), "--json")
    assert c.returncode == 0, c.stderr
    res = json.loads(c.stdout)
    assert res["format"] == "utia" and res["error"] < 1e-12  # a constant is exact on any grid
    np.testing.assert_allclose(bk.model(str(tmp_path / "l.bin")).eval(_vec(30, 10), _vec(70, 100)), 0.5 / np.pi)


# ----------------------------------------------------------------- scenes
@pytest.mark.parametrize("key", ["merl", "measured"])
def test_scene_file_takes_measured_files_beside_it(files, key, cli, tmp_path):
    """A scene's material may be an RGL or UTIA file, relative to the scene file's folder."""
    for kind in ("aniso", "utia"):
        name = os.path.basename(files[kind])
        os.link(files[kind], tmp_path / name)
        scene = tmp_path / f"{kind}.json"
        scene.write_text(json.dumps({"material": {key: name}, "size": [24, 24], "mesh": "sphere"}))
        out = tmp_path / f"{kind}-{key}.npy"
        r = cli("render", "--scene", str(scene), "-o", str(out), "--env", "none")
        assert r.returncode == 0, r.stderr
        assert (np.load(out)[..., 3] > 0.5).sum() > 50
