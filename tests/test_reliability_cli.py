"""Numbers that overflow, and the small things a new user hit (issue 14).

* one number parser (:func:`brdfkit.params.to_float`): ``10**400`` and
  ``"1e400"`` are the usual one-line ``ValueError`` in ``bk.model``, ``-p`` and
  ``/api/eval`` (before: ``OverflowError`` with a traceback, status 500);
* ``brdfkit --version``; ``brdfkit info merl/chrome``; measured materials
  labelled by name in ``check`` and ``plot``; a repeated ``-p`` is an error;
  ``--phi-d 400`` is an error; ``project.license`` is an SPDX string.
"""

from __future__ import annotations

import json
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.cli import main
from brdfkit.params import to_float

HUGE = 10**400


def _run(capsys, argv):
    rc = main(argv)
    out = capsys.readouterr()
    return rc, out.out, out.err


@pytest.mark.parametrize(
    "value",
    [HUGE, -HUGE, "1e400", "-1e400", "1" + "0" * 400, float("inf"), float("nan"), "nan", "inf", None, True, "x", b"1", [1.0]],
)
def test_to_float_turns_every_bad_number_into_one_line_value_error(value):
    with pytest.raises(ValueError) as e:
        to_float(value, "thing")
    msg = str(e.value)
    assert msg.startswith("thing") and "\n" not in msg and len(msg) < 200


def test_to_float_accepts_ordinary_numbers():
    assert to_float(3, "x") == 3.0
    assert to_float(np.float32(0.5), "x") == 0.5
    assert to_float(" 2.5e-3 ", "x") == 2.5e-3
    assert to_float(5e-324, "x") == 5e-324  # the smallest positive float is a number like any other
    assert to_float(10**300, "x") == 1e300
    assert to_float(float("inf"), "x", finite=False) == float("inf")


@pytest.mark.parametrize("name", bk.models())
def test_every_scalar_and_rgb_parameter_refuses_huge_integers(name):
    info = bk.model_info(name)
    for p in info["params"]:
        if p["kind"] not in ("scalar", "rgb", "int"):
            continue
        for bad in (HUGE, -HUGE, [HUGE, 0.1, 0.1] if p["kind"] == "rgb" else HUGE):
            with pytest.raises(ValueError, match=p["name"]):
                bk.model(name, **{p["name"]: bad})


def test_cli_overflow_and_repeated_p_are_exit_2(capsys):
    for argv in (
        ["eval", "ward", "-p", "alpha_x=1e400", "--wi", "30,0", "--wo", "30,180"],
        ["eval", "ward", "-p", "alpha_x=1" + "0" * 400, "--wi", "30,0", "--wo", "30,180"],
        ["eval", "ward", "-p", "kd=0.1,1e400,0.1", "--wi", "30,0", "--wo", "30,180"],
        ["eval", "ward", "-p", "alpha_x=0.1", "-p", "alpha_x=0.2", "--wi", "30,0", "--wo", "30,180"],
    ):
        rc, out, err = _run(capsys, argv)
        assert rc == 2 and err.startswith("brdfkit: error:") and err.count("\n") == 1, err
    rc, _, err = _run(capsys, ["eval", "ward", "-p", "alpha_x=0.1", "-p", "alpha_x=0.2", "--wi", "30,0", "--wo", "30,180"])
    assert "given twice" in err


def test_api_eval_overflow_is_400():
    from brdfkit.web.server import BadRequest, eval_payload

    for q in (
        {"model": ["ward"], "params": ['{"alpha_x": 1' + "0" * 400 + "}"], "wi": ["0,0,1"], "wo": ["0,0,1"]},
        {"model": ["ward"], "params": ['{"kd": [1' + "0" * 400 + ", 0, 0]}"], "wi": ["0,0,1"], "wo": ["0,0,1"]},
        {"model": ["ward"], "params": ["{}"], "wi": ["[1" + "0" * 400 + ", 0, 1]"], "wo": ["0,0,1"]},
    ):
        with pytest.raises(BadRequest):
            eval_payload(q)


def test_version(capsys):
    rc, out, err = _run(capsys, ["--version"])
    assert rc == 0 and out.strip() == f"brdfkit {bk.__version__}"


def test_info_of_a_measured_material(capsys):
    rc, out, err = _run(capsys, ["info", "merl/chrome"])
    assert rc == 0, err
    assert out.startswith("merl/chrome:") and "no parameters" in out
    rc, out, err = _run(capsys, ["info", "merl/chrome", "--json"])
    data = json.loads(out)
    assert data["name"] == "merl/chrome" and data["params"] == []
    rc, out, err = _run(capsys, ["info", "no-such-thing"])
    assert rc == 2 and "unknown model" in err


def test_measured_materials_are_labelled_by_name(capsys):
    from brdfkit.analysis.plots import label

    assert label(bk.material("merl/chrome")) == "merl/chrome"
    assert label(bk.model("lambert")).startswith("lambert(")
    rc, out, err = _run(capsys, ["check", "merl/chrome", "--level", "fast"])
    assert rc == 0, err
    assert out.splitlines()[0] == "merl/chrome"


def test_plot_angles_are_range_checked(capsys, tmp_path):
    for argv in (
        ["plot", "lambert", "--kind", "slice", "--phi-d", "400", "-o", str(tmp_path / "a.png")],
        ["plot", "lambert", "--kind", "slice", "--phi-d", "-1", "-o", str(tmp_path / "a.png")],
        ["plot", "lambert", "--kind", "polar", "--theta-i", "120", "-o", str(tmp_path / "a.png")],
    ):
        rc, _, err = _run(capsys, argv)
        assert rc == 2 and err.startswith("brdfkit: error: plot:"), err
    assert list(tmp_path.iterdir()) == []


def test_license_is_an_spdx_string():
    data = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())
    assert data["project"]["license"] == "MIT"


def test_readme_scene_example_points_at_a_shipped_file():
    root = Path(__file__).resolve().parents[1]
    readme = (root / "README.md").read_text()
    assert "--scene example" in readme  # the scene shipped in the package (brdfkit.examples), found from any folder
    assert (root / "src" / "brdfkit" / "examples" / "scene.json").is_file()
    assert (root / "docs" / "scene.json").is_file()  # in a clone, a link to that file


def test_integer_options_too_large_for_c_are_exit_2(capsys):
    rc, _, err = _run(capsys, ["check", "--all", "--jobs", "1" + "0" * 23])
    assert rc == 2 and "--jobs" in err, err
