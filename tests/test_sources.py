"""The one resolver (:mod:`brdfkit.sources`): every kind of source, every place that takes one.

Each kind (a registered name, a built-in measured material, a ``.brdf`` file, a fit's JSON, a
MERL file) is resolved once and the same way by ``bk.model``, ``bk.fit``, the CLI commands,
scenes and the web API; unknown names and missing files give one line that says what works.
"""

from __future__ import annotations

import ast
import json
from pathlib import Path

import numpy as np
import pytest

import brdfkit as bk
from brdfkit import sources
from brdfkit.cli import main
from brdfkit.measured.merl import write_merl_table

DATA = Path(__file__).parent / "data"
GGX = DATA / "ggx.brdf"
SRC = Path(bk.__file__).parent


@pytest.fixture(scope="module")
def merl_file(tmp_path_factory):
    """A MERL file holding a constant 0.25/sr in red, 0.5 in green, 0.75 in blue."""
    p = tmp_path_factory.mktemp("merl") / "flat.binary"
    table = np.empty((3, 90, 90, 180))
    table[0], table[1], table[2] = 0.25, 0.5, 0.75
    write_merl_table(table, p)
    return p


@pytest.fixture()
def fit_json(tmp_path):
    p = tmp_path / "fit.json"
    p.write_text(json.dumps({"model": "ward", "source": "merl/chrome",
                             "params": {"kd": [0.1, 0.2, 0.3], "ks": [0.4, 0.4, 0.4], "alpha_x": 0.07, "alpha_y": 0.07},
                             "error": 0.1, "metric": "ngan"}))
    return p


WI = np.array([0.3, 0.1, np.sqrt(1 - 0.1)])
WO = np.array([-0.2, 0.2, np.sqrt(1 - 0.08)])


def test_each_kind_is_identified(merl_file, fit_json):
    assert sources.identify("ward").kind == "model"
    assert sources.identify("merl/chrome") == sources.Source("material", "merl/chrome")
    assert sources.identify("chrome") == sources.Source("material", "merl/chrome")  # a unique bare name
    assert sources.identify(str(GGX)).kind == "brdf"
    assert sources.identify(fit_json).kind == "fit"
    assert sources.identify(str(merl_file)).kind == "merl"
    m = bk.model("lambert")
    assert sources.identify(m).kind == "instance" and sources.resolve(m) is m


def test_every_kind_builds_the_model_it_names(merl_file, fit_json):
    np.testing.assert_allclose(bk.model("merl/chrome").eval(WI, WO), bk.material("merl/chrome").eval(WI, WO))
    np.testing.assert_allclose(bk.model(str(merl_file)).eval(WI, WO), [0.25, 0.5, 0.75], rtol=1e-12)
    fitted = bk.model(str(fit_json))
    assert fitted.name == "ward" and fitted.params["alpha_x"] == 0.07
    assert fitted.label == "ward fitted to merl/chrome"
    np.testing.assert_allclose(fitted.params["kd"], [0.1, 0.2, 0.3])
    # a fit's parameters can be overridden, like a model's
    assert bk.model(str(fit_json), alpha_x=0.2).params["alpha_x"] == 0.2
    g = bk.model(str(GGX), alpha=0.2)
    assert g.params["alpha"] == pytest.approx(0.2)
    assert bk.model_info(str(GGX))["params"]


@pytest.mark.parametrize("bad, words", [
    ("nope", "unknown model 'nope'"),
    ("chrme", "did you mean chrome"),
    ("merl/nope", "unknown measured material 'merl/nope'"),
    ("./missing.binary", "no such MERL file"),
    ("missing.brdf", "no such .brdf file"),
    ("missing.json", "no such file (a fit's JSON"),
    ("some/where/else", "no such file"),
])
def test_unknown_sources_get_one_line_saying_what_works(bad, words):
    with pytest.raises(ValueError) as e:
        bk.model(bad)
    msg = str(e.value)
    assert words in msg and "\n" not in msg


def test_measured_data_takes_no_parameters(merl_file):
    with pytest.raises(ValueError, match="measured data takes no parameters"):
        bk.model("merl/chrome", kd=0.5)
    with pytest.raises(ValueError, match="measured data takes no parameters; drop -p kd=1"):
        sources.from_cli(str(merl_file), ["kd=1"])


def test_kinds_can_be_restricted():
    with pytest.raises(ValueError, match="ward: expected a built-in measured material or a MERL .binary file or a MERL or UTIA .bin file or an RGL .bsdf file, got a registered model"):
        sources.resolve("ward", kinds=sources.MEASURED)


def test_files_false_refuses_paths_from_text_alone(tmp_path, monkeypatch, merl_file):
    """The web's mode: a path is refused before anything on disk is looked at."""
    import os

    looked = []
    for fn in ("isfile", "exists"):
        real = getattr(os.path, fn)
        monkeypatch.setattr(os.path, fn, lambda p, _r=real, _f=fn: looked.append((_f, p)) or _r(p))
    for path in (str(merl_file), str(GGX), "/etc/passwd", "x.json", "../../secret"):
        with pytest.raises(ValueError, match="file paths are not accepted"):
            sources.resolve(path, files=False)
    with pytest.raises(ValueError, match="unknown model 'nope'"):
        sources.resolve("nope", files=False)
    assert looked == []
    assert sources.resolve("merl/chrome", files=False).material == "merl/chrome"


def test_load_measured_reads_measured_files_only(merl_file, fit_json):
    np.testing.assert_allclose(bk.load_measured(merl_file).eval(WI, WO), [0.25, 0.5, 0.75], rtol=1e-12)
    with pytest.raises(ValueError, match="not a measured-data file"):
        bk.load_measured(fit_json)
    with pytest.raises(ValueError, match="no such file"):
        bk.load_measured(merl_file.parent / "nope.binary")


# -- every place that takes a model takes every kind, through the resolver --------------------------
def _cli(capsys, argv):
    rc = main(argv)
    out = capsys.readouterr()
    return rc, out.out, out.err


def test_cli_commands_take_a_fits_json(capsys, fit_json, tmp_path):
    rc, out, err = _cli(capsys, ["eval", str(fit_json), "--wi", "30,0", "--wo", "30,180", "--json"])
    assert rc == 0, err
    want = bk.model(str(fit_json)).eval(
        bk.geometry.spherical_to_vector(np.radians(30), 0.0), bk.geometry.spherical_to_vector(np.radians(30), np.pi))
    np.testing.assert_allclose(json.loads(out)["value"], want, rtol=1e-9)
    rc, out, err = _cli(capsys, ["info", str(fit_json), "--json"])
    assert rc == 0 and json.loads(out)["name"] == "ward", err


def test_cli_refuses_unknown_sources_the_same_everywhere(capsys, tmp_path):
    for argv in (["eval", "nope", "--wi", "0,0", "--wo", "0,0"], ["check", "nope"], ["info", "nope"],
                 ["export", "nope", "--to", "gltf", "-o", str(tmp_path / "x.glb")]):
        rc, out, err = _cli(capsys, argv)
        assert rc != 0 and "unknown model 'nope'" in err and "Traceback" not in err, argv


def test_scene_materials_resolve_through_sources(merl_file, fit_json):
    from brdfkit.render.scene import material_from_spec

    assert material_from_spec({"model": str(fit_json)}).params["alpha_x"] == 0.07
    assert material_from_spec({"measured": "chrome"}).material == "merl/chrome"
    np.testing.assert_allclose(material_from_spec({"merl": str(merl_file)}).eval(WI, WO), [0.25, 0.5, 0.75], rtol=1e-12)
    with pytest.raises(ValueError, match="expected a built-in measured material"):
        material_from_spec({"measured": "ward"})


def test_fit_takes_any_source(fit_json):
    """The fitter's source is resolved by the same function: a fit's JSON is data to fit to."""
    from brdfkit.measured.fit import resolve_source

    assert resolve_source(str(fit_json)).params["alpha_x"] == 0.07
    assert resolve_source("chrome").material == "merl/chrome"


def test_no_other_module_decides_what_a_name_is():
    """Reading a model file or looking up a material by a user's text happens in sources.py only.

    The readers themselves (``load_merl``, ``material``, ``load_brdf`` and their classes) are
    defined elsewhere; any other module calling them on a user's text would be a seventh place.
    """
    readers = {"load_merl", "load_brdf", "load_brdf_class", "_measured_from_cli", "model_from_fit_json"}
    allowed = {"sources.py", "__init__.py", "measured/merl.py", "interchange/brdf_explorer.py"}
    offenders = []
    for path in SRC.rglob("*.py"):
        rel = path.relative_to(SRC).as_posix()
        if rel in allowed:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call):
                f = node.func
                name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", None)
                if name in readers:
                    offenders.append(f"{rel}:{node.lineno} {name}")
    assert offenders == []
