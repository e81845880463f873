"""Reciprocity: the test set catches asymmetries anywhere (grazing included); verdicts from theory."""

from __future__ import annotations

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.analysis import direction_pairs, reciprocity_error, reciprocity_report
from brdfkit.models.base import BRDF


class _Tilted(BRDF):
    """Test-only: (1 + wi.x/2)/π — not reciprocal; worst relative asymmetry approaches 2/3."""

    name = "test-tilted"

    def _eval(self, wi, wo, p):
        v = (1 + 0.5 * wi[..., 0]) / np.pi
        return np.repeat(v[..., None], 3, -1)


class _GrazingOnly(BRDF):
    """Test-only: 2 where wi is within 0.5° of the horizon, else 1 — asymmetric only at grazing."""

    name = "test-grazing"

    def _eval(self, wi, wo, p):
        v = np.where(wi[..., 2] < np.sin(np.radians(0.5)), 2.0, 1.0)
        return np.repeat(v[..., None], 3, -1)


class _AnisoSymmetric(BRDF):
    """Test-only: anisotropic but symmetric, exp(−(hx²/0.01 + hy²/0.2))."""

    name = "test-aniso"
    isotropic = False

    def _eval(self, wi, wo, p):
        h = wi + wo
        h = h / np.linalg.norm(h, axis=-1, keepdims=True)
        v = np.exp(-(h[..., 0] ** 2 / 0.01 + h[..., 1] ** 2 / 0.2)) * wi[..., 2] * wo[..., 2]
        return np.repeat(v[..., None], 3, -1)


def test_pairs_are_unit_upper_and_include_grazing():
    a, b = direction_pairs()
    for v in (a, b):
        np.testing.assert_allclose(np.linalg.norm(v, axis=-1), 1.0, atol=1e-12)
        assert np.all(v[:, 2] > 0)
    assert np.degrees(np.arccos(a[:, 2].min())) > 89.8
    assert len(a) > 50000


def test_deterministic():
    m = _Tilted()
    assert reciprocity_error(m) == reciprocity_error(m)


def test_lambert_is_reciprocal():
    assert reciprocity_error(bk.model("lambert")) == 0.0


def test_tilted_is_not_and_error_is_relative():
    r = reciprocity_report(_Tilted())
    # |f(a,b) − f(b,a)| / max = |a.x − b.x|/2 / (1 + max(a.x, b.x)/2) ≤ 2/3, approached by the set
    assert 0.6 < r["error"] <= 2 / 3 + 1e-12
    assert not r["reciprocal"]


def test_grazing_asymmetry_is_found():
    r = reciprocity_report(_GrazingOnly())
    assert r["error"] == pytest.approx(0.5)
    assert max(r["worst"]["wi_deg"][0], r["worst"]["wo_deg"][0]) >= 89.4


def test_symmetric_anisotropic_passes():
    assert reciprocity_error(_AnisoSymmetric()) < 1e-12


@pytest.mark.parametrize(
    "name, params",
    [
        ("phong", {"normalized": True, "shininess": 1e4}),
        ("blinn-phong", {"normalized": True, "shininess": 50}),
        ("cook-torrance", {"m": 0.05, "ior": 2.0}),
        ("ward", {"alpha_x": 0.05, "alpha_y": 0.3}),
        ("oren-nayar", {"sigma": 1.0, "variant": "qualitative"}),
        ("oren-nayar", {"sigma": 1.0, "variant": "full"}),
        ("microfacet", {"alpha_x": 0.1, "alpha_y": 0.5, "fresnel": "conductor"}),
    ],
)
def test_symmetric_formulas_are_reciprocal(name, params):
    """Each formula is symmetric in wi, wo by construction (see docs/physics.md)."""
    r = reciprocity_report(bk.model(name, **params))
    assert r["reciprocal"], r


@pytest.mark.parametrize("name", ["phong", "blinn-phong"])
@pytest.mark.parametrize("s", [1.0, 100.0])
def test_lighting_equation_forms_are_not_reciprocal(name, s):
    """ks·lobe/cos θi: swapping wi, wo changes the 1/cos θi while the lobe is symmetric."""
    r = reciprocity_report(bk.model(name, normalized=False, shininess=s, kd=0.0, ks=1.0))
    assert not r["reciprocal"]
    assert r["error"] > 0.5
    w = r["worst"]
    fa, fb = w["f_wi_wo"][0], w["f_wo_wi"][0]
    ci, co = np.cos(np.radians(w["wi_deg"][0])), np.cos(np.radians(w["wo_deg"][0]))
    # the ratio is exactly cos θo / cos θi (floors at 1e-4 aside)
    assert fa / fb == pytest.approx(max(co, 1e-4) / max(ci, 1e-4), rel=1e-3)  # angles rounded to 1e-4°


def _numpy_worst(fab, fba):
    """The numpy form the compiled reduction replaced (kept here as its oracle)."""
    big = np.maximum(np.abs(fab), np.abs(fba))
    floor = 1e-12 * float(big.max()) if big.size else 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(big > max(floor, 1e-300), np.abs(fab - fba) / np.where(big > 0, big, 1.0), 0.0)
    flat = int(np.argmax(rel))
    return float(rel.flat[flat]), flat


@pytest.mark.parametrize("case", ["random", "ties", "zeros", "tiny", "negative", "single"])
def test_worst_asymmetry_is_the_numpy_formula_bit_for_bit(case):
    """The compiled reduction of reciprocity_report gives numpy's value and first-maximum index: ties go
    to the first, pairs below 1e-12 of the largest value (or 1e-300) are skipped, all-zero gives (0, 0)."""
    from brdfkit.analysis.reciprocity import worst_asymmetry

    rng = np.random.default_rng(7)
    a = rng.uniform(0.0, 2.0, (500, 3))
    b = a * rng.uniform(0.9, 1.1, a.shape)
    if case == "ties":
        b = a.copy()
        b[[10, 20, 30], [0, 1, 2]] *= 2.0  # three equal maxima: the first counts
    elif case == "zeros":
        a[:] = 0.0
        b[:] = 0.0
    elif case == "tiny":
        a[5:] *= 1e-13  # all but five pairs below the floor: their asymmetry (up to 10 %) does not count
        b[5:] = a[5:] * 1.5
    elif case == "negative":
        a[3, 1] = -0.5
    elif case == "single":
        a, b = a[:1], b[:1]
    got = worst_asymmetry(np.ascontiguousarray(a), np.ascontiguousarray(b))
    want = _numpy_worst(a, b)
    assert (float(got[0]), int(got[1])) == want
    if case == "ties":
        assert want == (0.5, 10 * 3 + 0)
    if case == "zeros":
        assert want == (0.0, 0)


# --- the tolerance follows the evaluation's precision (issue 30) ----------------------------------

DATA = __import__("pathlib").Path(__file__).parent / "data"

PHONG_BRDF = """analytic

# The lecture's Phong term read as a BRDF, (r.v)^s / (n.l): not reciprocal (test-only file).
::begin parameters
float ks 0 1 0.5
float s 1 200 32
::end parameters

::begin shader
vec3 BRDF( vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y )
{
    vec3 R = reflect(-L, N);
    return vec3(ks * pow(max(dot(R, V), 0.0), s) / max(dot(N, L), 1e-4));
}
::end shader
"""


def test_evaluation_precision_is_read_from_the_values():
    from brdfkit.analysis.reciprocity import evaluation_precision

    x = np.linspace(0.1, 1.0, 1000) / np.pi
    assert evaluation_precision(x) == "float64"
    assert evaluation_precision(x.astype(np.float32).astype(np.float64)) == "float32"
    assert evaluation_precision(np.zeros(10)) == "float64"
    assert evaluation_precision(np.array([1.0, 2.0] * 500)) == "float64"  # a step of exact numbers: no evidence


def test_float32_brdf_file_ggx_is_reciprocal_under_the_float32_tolerance():
    """``brdfkit check tests/data/ggx.brdf -p alpha=0.3`` said "reciprocal: NO": float32 GLSL rounding
    (7.6e-5 near grazing) judged against the float64 tolerance."""
    from brdfkit.analysis import check
    from brdfkit.analysis.reciprocity import RECIPROCITY_TOL, RECIPROCITY_TOL_FLOAT32

    m = bk.load_brdf(DATA / "ggx.brdf", alpha=0.3)
    r = reciprocity_report(m)
    assert r["precision"] == "float32" and r["tolerance"] == RECIPROCITY_TOL_FLOAT32
    assert RECIPROCITY_TOL < r["error"] < RECIPROCITY_TOL_FLOAT32 / 5  # rounding, well inside the tolerance
    assert r["reciprocal"]
    c = check(m, level="fast")
    assert c["reciprocal"] and c["reciprocity_precision"] == "float32"
    assert c["reciprocity_tolerance"] == pytest.approx(9.8e-4, rel=1e-2)


def test_non_reciprocal_models_stay_no_in_either_precision(tmp_path):
    r = reciprocity_report(bk.model("phong", normalized=False))
    assert r["precision"] == "float64" and not r["reciprocal"] and r["error"] > 0.5
    path = tmp_path / "phong.brdf"
    path.write_text(PHONG_BRDF)
    r = reciprocity_report(bk.load_brdf(path))
    assert r["precision"] == "float32" and not r["reciprocal"] and r["error"] > 0.5


def test_check_states_the_tolerance_and_precision(capsys):
    from brdfkit.cli import main

    assert main(["check", str(DATA / "ggx.brdf"), "-p", "alpha=0.3", "--level", "fast"]) == 0
    out = capsys.readouterr().out
    assert "reciprocal:        yes" in out and "tolerance 9.8e-04, float32 evaluation" in out
