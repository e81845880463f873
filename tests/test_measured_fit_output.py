"""What a fit reports (issue 30): ``brdfkit fit``'s text output starts with its first line, and a
subnormal fitted value (4.94e-324) is reported as 0 in the result, its JSON and the text."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from brdfkit.measured import fit as F

SUBNORMAL = 5e-324  # the smallest positive float, as a kd pressed against its bound of 0 can end


def test_text_output_starts_with_the_result_line(cli):
    rc, out, err = cli("fit", "merl/blue-acrylic", "-m", "lambert", "--samples", "300", "--starts", "1")
    assert rc == 0, err
    assert out.startswith("lambert fitted to merl/blue-acrylic: error "), repr(out[:80])
    assert out.splitlines()[1].startswith("  kd=")


@pytest.mark.parametrize("value, flushed", [(SUBNORMAL, 0.0), (-2e-310, 0.0), (2.3e-308, 2.3e-308), (0.0, 0.0),
                                            (1e-300, 1e-300), (math.inf, math.inf), (0.25, 0.25)])
def test_flush_subnormal_floats(value, flushed):
    assert F.flush_subnormal(value) == flushed
    assert F.flush_subnormal(np.float64(value)) == flushed


def test_flush_subnormal_arrays_and_dicts():
    rgb = np.array([SUBNORMAL, 0.5, 1e-20])
    rgb.setflags(write=False)
    out = F.flush_subnormal({"kd": rgb, "mode": "a", "n": 3, "ok": np.array([0.1, 0.2, 0.3])})
    assert out["kd"].tolist() == [0.0, 0.5, 1e-20] and not out["kd"].flags.writeable
    assert rgb[0] == SUBNORMAL  # the input is left alone
    assert out["mode"] == "a" and out["n"] == 3 and out["ok"].tolist() == [0.1, 0.2, 0.3]


@pytest.mark.parametrize("name", ["lambert", "ward"])  # nothing free / a fit with free values
def test_a_subnormal_value_is_reported_as_zero(name):
    r = F.fit(name, "merl/blue-acrylic", fixed={"kd": SUBNORMAL}, samples=300, starts=1)
    assert r.params["kd"].tolist() == [0.0, 0.0, 0.0]
    assert r.to_json()["params"]["kd"] == [0.0, 0.0, 0.0]
    if name == "ward":  # the result's model is the reported one
        assert r.model.params["kd"].tolist() == [0.0, 0.0, 0.0]


def test_cli_prints_a_subnormal_value_as_zero(cli):
    rc, out, err = cli("fit", "merl/blue-acrylic", "-m", "ward", "-p", f"kd={SUBNORMAL!r}", "--samples", "300",
                       "--starts", "1")
    assert rc == 0, err
    assert " kd=0,0,0 " in out and "e-324" not in out
    rc, out, err = cli("fit", "merl/blue-acrylic", "-m", "ward", "-p", f"kd={SUBNORMAL!r}", "--samples", "300",
                       "--starts", "1", "--json")
    assert json.loads(out)["params"]["kd"] == [0.0, 0.0, 0.0]
