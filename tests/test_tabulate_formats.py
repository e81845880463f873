"""``bk.tabulate`` / ``brdfkit tabulate``: the MERL format, round trips between MERL and RGL,
the CLI, and bad input (one-line ``ValueError`` before any work; exit status 2, no traceback).

Round trip MERL -> RGL -> MERL of a measured material (merl/gold-metallic-paint: its MERL table,
written to RGL at the default resolution, tabulated back to MERL): the relative RMS of
``f_r cos θi cos θo`` between the first and the last MERL file, on 20000 pairs uniform over the
hemispheres, is printed and at most 3 % (measured 2.1 %).
"""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.measured import rgl_writer
from brdfkit.measured import tabulation as tab
from brdfkit.measured.merl import read_merl_table, tabulate as merl_table
from brdfkit.models.base import BRDF


@pytest.fixture(scope="module")
def gold_merl(tmp_path_factory):
    """merl/gold-metallic-paint as a MERL file, written by bk.tabulate."""
    d = tmp_path_factory.mktemp("formats")
    res = bk.tabulate("merl/gold-metallic-paint", d / "gold.binary")
    return d, res


def test_merl_through_tabulate_is_save_merl(gold_merl, tmp_path):
    d, res = gold_merl
    assert res.format == "merl" and res.bytes == 12 + 3 * 90 * 90 * 180 * 8
    assert res.shape == {"theta_h": 90, "theta_d": 90, "phi_d": 180}
    np.testing.assert_allclose(read_merl_table(res.path), merl_table(bk.material("merl/gold-metallic-paint")), rtol=1e-15)
    print(f"\nmerl/gold-metallic-paint -> MERL: tabulation error {100 * res.error:.2f} % (nearest bins)")
    assert res.error < 0.05
    # a MERL file tabulated to MERL again is the same table, bit for bit
    again = bk.tabulate(res.path, tmp_path / "again.binary", "merl")
    assert open(again.path, "rb").read() == open(res.path, "rb").read()
    assert again.error == 0.0


def test_merl_to_rgl_to_merl_round_trip(gold_merl):
    d, first = gold_merl
    rgl = bk.tabulate(first.path, d / "gold.bsdf", "rgl")
    back = bk.tabulate(rgl.path, d / "gold-back.binary", "merl")
    a, b = bk.load_measured(first.path), bk.load_measured(back.path)
    err = tab.tabulation_error(a, b)
    print(f"\nMERL -> RGL -> MERL (gold-metallic-paint): MERL -> RGL {100 * rgl.error:.2f} %, "
          f"RGL -> MERL {100 * back.error:.2f} %, round trip {100 * err:.2f} % (relative RMS of f cos cos)")
    assert err <= 0.03
    assert rgl.shape["isotropic"] and rgl.bytes < 3e6


def test_rgl_to_rgl_keeps_the_material(gold_merl, tmp_path):
    """An RGL file is a source like any other: tabulated again it stays within the tabulation error."""
    d, _ = gold_merl
    src = d / "gold.bsdf"
    if not src.exists():
        bk.tabulate(d / "gold.binary", src)
    res = bk.tabulate(src, tmp_path / "again.bsdf", resolution=32, n_theta=16)
    assert res.error < 0.03


def test_fit_json_and_brdf_file_sources(tmp_path):
    fit = tmp_path / "fit.json"
    fit.write_text(json.dumps({"model": "ward", "source": "merl/chrome", "params": {
        "kd": [0.1, 0.2, 0.3], "ks": [0.4, 0.4, 0.4], "alpha_x": 0.1, "alpha_y": 0.1}}))
    res = bk.tabulate(fit, tmp_path / "fit.bsdf", resolution=24, n_theta=12, n_phi=5, ndf_resolution=24)
    assert res.shape["n_phi"] == 5 and res.error < 0.05
    here = os.path.dirname(__file__)
    res = bk.tabulate(os.path.join(here, "data", "lambert.brdf"), tmp_path / "lambert.bsdf", resolution=16,
                      n_theta=8, n_phi=5, ndf_resolution=16)
    assert res.error < 0.05  # 16^2 samples: coarse on purpose (fast); at the defaults 0.7 %


def test_progress_callback_sees_every_incident_direction(tmp_path):
    seen = []
    bk.tabulate("microfacet", tmp_path / "g.bsdf", params={"alpha": 0.3}, resolution=8, n_theta=6,
                ndf_resolution=8, progress=lambda done, total: seen.append((done, total)), error_pairs=0)
    assert seen == [(k, 6) for k in range(1, 7)]


# ----------------------------------------------------------------- bad input
BAD = [
    (dict(format="xyz"), "g.bsdf", "unknown format 'xyz'"),
    (dict(format="rgl"), "g.binary", "must end in .bsdf"),
    (dict(format="merl"), "g.bsdf", "must end in .binary"),
    (dict(), "g.dat", "cannot tell the format"),
    (dict(resolution=2), "g.bsdf", "resolution must lie in"),
    (dict(resolution=True), "g.bsdf", "resolution must be a whole number"),
    (dict(resolution=16.5), "g.bsdf", "resolution must be a whole number"),
    (dict(n_theta=1), "g.bsdf", "n_theta must lie in"),
    (dict(n_phi=2), "g.bsdf", "n_phi must lie in"),
    (dict(ndf_resolution=1000), "g.bsdf", "ndf_resolution must lie in"),
    (dict(isotropic="yes"), "g.bsdf", "isotropic must be true or false"),
    (dict(description=5), "g.bsdf", "description must be text"),
    (dict(resolution=512, n_theta=256), "g.bsdf", "more than the reader's limit"),
    (dict(resolution=32), "g.binary", "applies to format 'rgl' only"),
    (dict(params={"alpha": -1.0}), "g.bsdf", "alpha"),
    (dict(params={"nosuch": 1.0}), "g.bsdf", "unknown parameter"),
    (dict(error_pairs=-1), "g.bsdf", "error_pairs"),
]


@pytest.mark.parametrize("kw,name,match", BAD, ids=[m for _, _, m in BAD])
def test_bad_requests_are_one_line_errors_before_any_work(tmp_path, monkeypatch, kw, name, match):
    def no_work(*a, **k):
        raise AssertionError("the work started")

    monkeypatch.setattr(rgl_writer, "rgl_tables", no_work)
    with pytest.raises(ValueError, match=match) as e:
        bk.tabulate("microfacet", tmp_path / name, **kw)
    assert "\n" not in str(e.value)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("where,match", [
    ("folder", "is a folder"), ("under-a-file", "is not a folder"), ("missing-tree", "does not exist")])
def test_unwritable_outputs(tmp_path, monkeypatch, where, match):
    monkeypatch.setattr(rgl_writer, "rgl_tables", lambda *a, **k: (_ for _ in ()).throw(AssertionError("work")))
    if where == "folder":
        (tmp_path / "x.bsdf").mkdir()
        out = tmp_path / "x.bsdf"
    elif where == "under-a-file":
        (tmp_path / "file").write_text("x")
        out = tmp_path / "file" / "x.bsdf"
    else:
        out = tmp_path / "a" / "b" / "x.bsdf"
    with pytest.raises(ValueError, match=match):
        bk.tabulate("ward", out)


def test_bad_sources(tmp_path):
    with pytest.raises(ValueError, match="unknown model"):
        bk.tabulate("nosuchmodel", tmp_path / "x.bsdf")
    with pytest.raises(ValueError, match="MERL format stores isotropic BRDFs only"):
        bk.tabulate("ward", tmp_path / "x.binary")
    with pytest.raises(ValueError, match="no such"):
        bk.tabulate(tmp_path / "missing.bsdf", tmp_path / "x.binary")


class _Black(BRDF):
    name = "black-test"

    def _eval(self, wi, wo, p):
        return np.zeros(np.broadcast_shapes(wi.shape, wo.shape))


def test_a_model_without_backscattering_is_refused(tmp_path):
    with pytest.raises(ValueError, match="backscattering is 0"):
        bk.tabulate(_Black(), tmp_path / "x.bsdf")


class _Failing(BRDF):
    """Fails at its 5th evaluation: the tabulation dies half-way."""

    name = "failing-test"

    def __init__(self):
        self.calls = 0
        super().__init__()

    def _eval(self, wi, wo, p):
        self.calls += 1
        if self.calls == 5:
            raise RuntimeError("died")
        return np.full(np.broadcast_shapes(wi.shape, wo.shape), 0.2)


def test_a_failed_tabulation_leaves_the_old_file_whole(tmp_path):
    out = tmp_path / "x.bsdf"
    out.write_bytes(b"the previous file")
    with pytest.raises(RuntimeError):
        bk.tabulate(_Failing(), out, resolution=8, n_theta=8, ndf_resolution=8)
    assert out.read_bytes() == b"the previous file"
    assert os.listdir(tmp_path) == ["x.bsdf"]


# ----------------------------------------------------------------- the CLI
def test_cli_json_summary(cli, tmp_path):
    out = tmp_path / "g.bsdf"
    r = cli("tabulate", "microfacet", "-p", "alpha=0.3", "--format", "rgl", "-o", str(out), "--json",
            "--resolution", "16", "--n-theta", "8", "--ndf-resolution", "16")
    assert r.returncode == 0, r.stderr
    obj = json.loads(r.stdout)
    assert obj["path"] == str(out) and obj["format"] == "rgl" and obj["bytes"] == os.path.getsize(out)
    assert obj["shape"]["resolution"] == 16 and obj["shape"]["n_theta"] == 8 and 0 <= obj["error"] < 0.05
    assert bk.model(str(out)).eval(np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, 1.0])).max() > 0


def test_cli_text(cli, tmp_path):
    r = cli("tabulate", "lambert", "-o", str(tmp_path / "l.binary"))
    assert r.returncode == 0, r.stderr
    assert "wrote" in r.stdout and "tabulation error" in r.stdout


@pytest.mark.parametrize("args,match", [
    (["microfacet", "--format", "xyz", "-o", "{d}/x.bsdf"], "unknown format"),
    (["microfacet"], "missing -o"),
    (["merl/chrome", "-p", "alpha=0.1", "-o", "{d}/x.bsdf"], "takes no parameters"),
    (["microfacet", "-p", "alpha=-1", "-o", "{d}/x.bsdf"], "alpha"),
    (["microfacet", "-o", "{d}", "--format", "rgl"], "must end in .bsdf"),
    (["microfacet", "-o", "{d}/sub.bsdf"], "is a folder"),
    (["ward", "-o", "{d}/x.binary"], "isotropic BRDFs only"),
    (["microfacet", "-o", "{d}/x.bsdf", "--resolution", "1"], "resolution must lie in"),
])
def test_cli_errors_are_one_line(cli, tmp_path, args, match):
    (tmp_path / "sub.bsdf").mkdir()
    r = cli("tabulate", *[a.format(d=tmp_path) for a in args])
    assert r.returncode == 2
    assert r.stderr.startswith("brdfkit: error:") and match in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr


def test_formats_figure_checks_its_path_first(tmp_path):
    from brdfkit.measured import figures

    with pytest.raises(ValueError, match="must end in .png"):
        figures.write_formats_figure(str(tmp_path / "x.txt"))
    assert figures.main([str(tmp_path / "missing" / "tree" / "x.png")]) == 2
    assert os.listdir(tmp_path) == []
