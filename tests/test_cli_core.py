"""The core command line: ``brdfkit list``, ``info``, ``eval`` and its error handling.

Most tests run the CLI in-process through :func:`brdfkit.cli.main` (capturing
stdout/stderr); a few run the installed console script and ``python -m brdfkit``
in a real subprocess, to prove that no traceback ever reaches stderr.
"""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.cli import main

MODELS = bk.models()


def run_cli(capsys, *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(autouse=True)
def _wide_terminal(monkeypatch):
    monkeypatch.setenv("COLUMNS", "200")  # rich tables: no wrapping of names in the checks below


def _text(value) -> str:
    """A parameter value as it is typed after ``-p name=``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple, np.ndarray)):
        return ",".join(repr(float(v)) for v in value)
    return repr(value) if isinstance(value, float) else str(value)


def _valid_other_value(p):
    """A valid value different from the default when possible (for -p parsing round trips)."""
    if p.kind == "bool":
        return not bool(p.default)
    if p.kind == "choice":
        others = [c for c in p.choices if c != p.default]
        return others[0] if others else p.default
    lo, hi = p.range
    if p.open_lo:
        lo = lo + 1e-3 * (1 if math.isinf(hi) else hi - lo)
    if math.isinf(hi):
        hi = lo + 10.0
    elif p.open_hi:
        hi = hi - 1e-3 * (hi - lo)
    v = lo + 0.37 * (hi - lo)
    if p.kind == "int":
        return int(round(v))
    if p.kind == "rgb":
        return [lo + 0.2 * (hi - lo), v, lo + 0.9 * (hi - lo)]
    return v


# ---------------------------------------------------------------------------
# list / info
# ---------------------------------------------------------------------------


def test_list_table_names_every_model(capsys):
    code, out, err = run_cli(capsys, "list")
    assert code == 0 and err == ""
    for name in MODELS:
        assert name in out
        info = bk.model_info(name)
        assert ("isotropic" if info["isotropic"] else "anisotropic") in out


def test_list_json(capsys):
    code, out, err = run_cli(capsys, "list", "--json")
    assert code == 0 and err == ""
    rows = json.loads(out)
    assert [r["name"] for r in rows] == MODELS
    for r in rows:
        info = bk.model_info(r["name"])
        assert r["isotropic"] is info["isotropic"]
        assert r["title"] == info["title"] and r["reference"] == info["reference"]
        assert r["params"] == [p["name"] for p in info["params"]]


@pytest.mark.parametrize("name", MODELS)
def test_info_table(capsys, name):
    code, out, err = run_cli(capsys, "info", name)
    assert code == 0 and err == ""
    info = bk.model_info(name)
    assert info["reference"] in out
    for row in info["params"]:
        assert f"│ {row['name']} " in out  # a row starts with the parameter's name
        for word in row["range"].split(" | ") if row["kind"] == "choice" else [row["range"]]:
            assert word in out, word


@pytest.mark.parametrize("name", MODELS)
def test_info_json_is_model_info(capsys, name):
    code, out, err = run_cli(capsys, "info", name, "--json")
    assert code == 0 and err == ""
    data = json.loads(out)
    expected = json.loads(json.dumps(bk.model_info(name), default=lambda o: np.asarray(o).tolist()))
    assert data == expected
    for row in data["params"]:
        assert set(row) >= {"name", "kind", "default", "range", "unit", "doc"}


# ---------------------------------------------------------------------------
# eval
# ---------------------------------------------------------------------------


def test_eval_lambert_value_and_angles(capsys):
    code, out, err = run_cli(
        capsys, "eval", "lambert", "-p", "kd=0.1,0.2,0.3", "--wi", "30,0", "--wo", "60,90", "--json"
    )
    assert code == 0 and err == ""
    r = json.loads(out)
    assert r["model"] == "lambert"
    np.testing.assert_allclose(r["value"], [0.1 / math.pi, 0.2 / math.pi, 0.3 / math.pi], rtol=1e-14)
    np.testing.assert_allclose(r["wi"], [0.5, 0.0, math.sqrt(3) / 2], atol=1e-15)
    np.testing.assert_allclose(r["wo"], [0.0, math.sqrt(3) / 2, 0.5], atol=1e-15)
    assert r["params"] == {"kd": [0.1, 0.2, 0.3]}


def test_eval_vectors_are_normalised_and_horizon_is_zero(capsys):
    code, out, _ = run_cli(capsys, "eval", "lambert", "--wi-vec", "0,0,5", "--wo-vec", "3,0,4", "--json")
    assert code == 0
    r = json.loads(out)
    assert r["wi"] == [0.0, 0.0, 1.0]
    np.testing.assert_allclose(r["wo"], [0.6, 0.0, 0.8], rtol=1e-15)
    code, out, _ = run_cli(capsys, "eval", "lambert", "--wi", "90,0", "--wo", "0,0", "--json")
    assert code == 0 and json.loads(out)["value"] == [0.0, 0.0, 0.0]
    code, out, _ = run_cli(capsys, "eval", "lambert", "--wi-vec", "1,1,-1", "--wo", "0,0", "--json")
    assert code == 0 and json.loads(out)["value"] == [0.0, 0.0, 0.0]


def test_eval_text_output(capsys):
    code, out, err = run_cli(capsys, "eval", "lambert", "-p", "kd=0.5", "--wi", "0,0", "--wo", "0,0")
    assert code == 0 and err == ""
    assert f"{0.5 / math.pi:.7g}" in out and "1/sr" in out


@pytest.mark.parametrize("name", MODELS)
def test_eval_every_model_at_defaults(capsys, name):
    code, out, err = run_cli(capsys, "eval", name, "--wi", "40,10", "--wo", "35,200", "--json")
    assert code == 0 and err == ""
    r = json.loads(out)
    m = bk.model(name)
    wi = bk.geometry.spherical_to_vector(math.radians(40), math.radians(10))
    wo = bk.geometry.spherical_to_vector(math.radians(35), math.radians(200))
    np.testing.assert_allclose(r["value"], m.eval(wi, wo), rtol=1e-12, atol=0)
    assert r["params"] == json.loads(json.dumps(m.params_json()))
    assert set(r["params"]) == {p.name for p in type(m).spec}


@pytest.mark.parametrize("name", MODELS)
def test_eval_parses_every_parameter(capsys, name):
    """Each parameter typed with -p (number, r,g,b, true/false, choice) reaches the model."""
    spec = bk.registry.get(name).spec
    given = {p.name: _valid_other_value(p) for p in spec}
    args = ["eval", name, "--wi-vec", "0.3,-0.2,0.9", "--wo-vec", "-0.1,0.4,0.8", "--json"]
    for k, v in given.items():
        args += ["-p", f"{k}={_text(v)}"]
    code, out, err = run_cli(capsys, *args)
    assert code == 0, err
    r = json.loads(out)
    m = bk.model(name, **given)
    assert r["params"] == json.loads(json.dumps(m.params_json()))
    wi = np.array([0.3, -0.2, 0.9]) / np.linalg.norm([0.3, -0.2, 0.9])
    wo = np.array([-0.1, 0.4, 0.8]) / np.linalg.norm([-0.1, 0.4, 0.8])
    np.testing.assert_allclose(r["value"], m.eval(wi, wo), rtol=1e-12, atol=0)


def test_help_for_each_core_command(capsys):
    for args in ([], ["--help"], ["list", "--help"], ["info", "--help"], ["eval", "--help"]):
        code, out, err = run_cli(capsys, *args)
        assert code == 0, args
        assert "Usage" in out


# ---------------------------------------------------------------------------
# errors: one line on stderr, non-zero status, no traceback
# ---------------------------------------------------------------------------

_W = ["--wi", "30,0", "--wo", "30,180"]


def _first_with(kind):
    for name in MODELS:
        for p in bk.registry.get(name).spec:
            if p.kind == kind:
                return name, p
    return None, None


def _error_cases():
    cases = [
        (["eval", "no-such-model", *_W], "valid models"),
        (["info", "no-such-model"], "no-such-model"),
        (["eval", "lambert", "-p", "roughness=1", *_W], "roughness"),
        (["eval", "lambert", "-p", "kd=1.5", *_W], "out of range"),
        (["eval", "lambert", "-p", "kd=-0.01", *_W], "out of range"),
        (["eval", "lambert", "-p", "kd=nan", *_W], "finite"),
        (["eval", "lambert", "-p", "kd=inf", *_W], "finite"),
        (["eval", "lambert", "-p", "kd=0.1,0.2", *_W], "kd"),
        (["eval", "lambert", "-p", "kd=abc", *_W], "kd"),
        (["eval", "lambert", "-p", "kd", *_W], "name=value"),
        (["eval", "lambert", "--wi", "30", "--wo", "0,0"], "--wi"),
        (["eval", "lambert", "--wi", "a,b", "--wo", "0,0"], "--wi"),
        (["eval", "lambert", "--wi", "30,0,0", "--wo", "0,0"], "--wi"),
        (["eval", "lambert", "--wi", "nan,0", "--wo", "0,0"], "finite"),
        (["eval", "lambert", "--wi", "190,0", "--wo", "0,0"], "theta"),
        (["eval", "lambert", "--wi", "30,0"], "--wo"),
        (["eval", "lambert", "--wo", "30,0"], "--wi"),
        (["eval", "lambert", "--wi-vec", "0,0,0", "--wo", "0,0"], "non-zero"),
        (["eval", "lambert", "--wi-vec", "0,1", "--wo", "0,0"], "--wi-vec"),
        (["eval", "lambert", "--wi", "0,0", "--wi-vec", "0,0,1", "--wo", "0,0"], "not both"),
        (["eval"], "MODEL"),
        (["eval", "lambert", *_W, "--bogus"], "--bogus"),
        (["no-such-command"], "no-such-command"),
    ]
    name, p = _first_with("choice")
    if name is not None:
        cases.append((["eval", name, "-p", f"{p.name}=not-a-choice", *_W], p.choices[0]))
    name, p = _first_with("bool")
    if name is not None:
        cases.append((["eval", name, "-p", f"{p.name}=maybe", *_W], p.name))
    return [pytest.param(a, s, id=" ".join(a)) for a, s in cases]


@pytest.mark.parametrize("args,needle", _error_cases())
def test_errors_are_one_line(capsys, args, needle):
    code, out, err = run_cli(capsys, *args)
    assert code != 0
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("brdfkit: error: ")
    assert needle.lower() in lines[0].lower(), lines[0]
    assert "Traceback" not in err


def test_wrong_choice_via_cli(capsys):
    name, p = _first_with("choice")
    if name is None:
        pytest.skip("no registered model has a choice parameter yet")
    code, _, err = run_cli(capsys, "eval", name, "-p", f"{p.name}=not-a-choice", *_W)
    assert code != 0 and all(c in err for c in p.choices)


# ---------------------------------------------------------------------------
# real processes: the console script and python -m brdfkit
# ---------------------------------------------------------------------------


def _console_script() -> list[str]:
    exe = Path(sys.executable).parent / "brdfkit"
    if exe.exists():
        return [str(exe)]
    found = shutil.which("brdfkit")
    return [found] if found else [sys.executable, "-m", "brdfkit"]


@pytest.mark.parametrize("launcher", ["script", "module"])
def test_subprocess_no_traceback(launcher):
    cmd = _console_script() if launcher == "script" else [sys.executable, "-m", "brdfkit"]
    ok = subprocess.run(
        [*cmd, "eval", "lambert", "-p", "kd=0.2", "--wi", "0,0", "--wo", "45,0", "--json"],
        capture_output=True, text=True, timeout=120,
    )
    assert ok.returncode == 0, ok.stderr
    np.testing.assert_allclose(json.loads(ok.stdout)["value"], [0.2 / math.pi] * 3, rtol=1e-14)
    for bad in (
        ["eval", "lambert", "-p", "kd=nan", "--wi", "0,0", "--wo", "0,0"],
        ["eval", "lambert", "--wi", "0,0"],
        ["eval", "lambert", "--wi", "0,0", "--wo", "0,0", "--nope"],
    ):
        r = subprocess.run([*cmd, *bad], capture_output=True, text=True, timeout=120)
        assert r.returncode == 2, (bad, r.returncode, r.stderr)
        assert "Traceback" not in r.stderr
        assert len(r.stderr.strip().splitlines()) == 1 and r.stderr.startswith("brdfkit: error: "), r.stderr
        assert r.stdout == ""


# ---------------------------------------------------------------------------
# cli_common helpers
# ---------------------------------------------------------------------------


def test_direction_helpers():
    from brdfkit.cli_common import direction_from_degrees, direction_from_vector, parse_pair

    np.testing.assert_allclose(direction_from_degrees("90,90", "--wi"), [0.0, 1.0, 0.0], atol=0)
    np.testing.assert_allclose(direction_from_degrees("180,0", "--wi"), [0.0, 0.0, -1.0], atol=0)
    np.testing.assert_allclose(direction_from_degrees("60, -90", "--wi"), [0.0, -math.sqrt(3) / 2, 0.5], atol=1e-15)
    np.testing.assert_allclose(direction_from_vector("0,-3,4", "--wo-vec"), [0.0, -0.6, 0.8], rtol=1e-15)
    assert parse_pair(" 1.5 , 2e1", "--x") == (1.5, 20.0)
    for bad in ("1", "1,2,3", "x,1", "inf,1", ""):
        with pytest.raises(ValueError, match="--x"):
            parse_pair(bad, "--x")
    with pytest.raises(ValueError, match="non-zero"):
        direction_from_vector("0,0,0", "--wo-vec")


def test_model_from_cli_parses_with_the_spec():
    from brdfkit.cli_common import model_from_cli

    m = model_from_cli("lambert", ["kd=0.25,0.5,1"])
    assert m.params["kd"].tolist() == [0.25, 0.5, 1.0]
    assert model_from_cli("lambert", None).params["kd"].tolist() == [0.5, 0.5, 0.5]
    with pytest.raises(ValueError, match="valid models"):
        model_from_cli("nope", [])


def test_to_json_compact_rows_and_round_trip():
    from brdfkit.cli_common import to_json

    obj = {"v": np.array([0.5, 1.0, 2.0]), "n": np.float32(1.5), "rows": [{"a": (1, 2)}], "s": "[1,2]", "e": []}
    text = to_json(obj)
    assert '"v": [0.5, 1.0, 2.0]' in text  # a row of numbers stays on one line
    assert json.loads(text) == {"v": [0.5, 1.0, 2.0], "n": 1.5, "rows": [{"a": [1, 2]}], "s": "[1,2]", "e": []}
    assert json.loads(to_json(obj, indent=None)) == json.loads(text)
    with pytest.raises(ValueError):
        to_json({"x": float("nan")})


def test_unexpected_exception_is_one_line_unless_debug(capsys, monkeypatch):
    import brdfkit.cli_core as core

    def boom(*a, **k):
        raise RuntimeError("no GL driver\nsecond line")

    monkeypatch.setattr(core, "eval_result", boom)
    monkeypatch.delenv("BRDFKIT_DEBUG", raising=False)
    code, out, err = run_cli(capsys, "eval", "lambert", "--wi", "0,0", "--wo", "0,0")
    assert code == 1 and out == ""
    assert err.strip() == (
        "brdfkit: internal error: RuntimeError: no GL driver (set BRDFKIT_DEBUG=1 for the traceback)"
    )
    monkeypatch.setenv("BRDFKIT_DEBUG", "1")
    with pytest.raises(RuntimeError, match="no GL driver"):
        main(["eval", "lambert", "--wi", "0,0", "--wo", "0,0"])


def test_the_command_table_names_what_each_plugin_registers():
    """cli.COMMANDS (which plugin a run imports for its command) matches what the plugins register."""
    import importlib

    import typer

    from brdfkit import cli

    found = {}
    for mod in cli._PLUGINS:
        sub = typer.Typer()
        importlib.import_module(mod).register(sub)
        for c in sub.registered_commands:
            found[c.name or c.callback.__name__] = mod
    assert found == cli.COMMANDS


def test_a_command_imports_only_its_own_plugin_and_help_lists_all(capsys):
    code = (
        "import sys\n"
        "from brdfkit.cli import main\n"
        "rc = main(['eval', 'lambert', '--wi', '10,0', '--wo', '20,90'])\n"
        "print(rc, sorted(m for m in sys.modules if m.startswith(('brdfkit.render', 'brdfkit.web', "
        "'brdfkit.measured.commands', 'brdfkit.analysis.commands', 'brdfkit.interchange'))))\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.strip().splitlines()[-1] == "0 []", r.stdout
    from brdfkit import cli

    rc, out, _ = run_cli(capsys, "--help")
    assert rc == 0
    for name in cli.COMMANDS:
        assert name in out, name
    rc, _, err = run_cli(capsys, "evl")  # a misspelt command: every plugin loaded, click's one-line error
    assert rc == 2 and "No such command" in err
