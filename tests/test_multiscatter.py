"""Multiple-scattering compensation of the microfacet model (Kulla & Conty 2017): white furnace,
reciprocity, the Fresnel-weighted form, the tables, the GLSL twin."""

from __future__ import annotations

import math

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.analysis import check
from brdfkit.analysis.albedo import albedo
from brdfkit.terms import multiscatter as ms

ANGLES = np.radians(np.arange(0.0, 80.01, 5.0))
ALPHAS = (0.05, 0.2, 0.37, 0.5, 0.64, 0.75, 0.9, 1.0)  # several of them between table nodes


@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
@pytest.mark.parametrize("shadowing", ["smith", "smith-correlated"])
def test_white_furnace_within_one_percent(distribution, shadowing):
    """F = 1: single scattering loses up to 69 %; with the compensation the albedo is 1 within 1 %
    for every α up to 1 and every viewing angle up to 80°."""
    worst = 0.0
    for a in ALPHAS:
        m = bk.model("microfacet", distribution=distribution, shadowing=shadowing, alpha=a, fresnel="none",
                     multiscatter=True)
        e = albedo(m, ANGLES)[:, 0]
        worst = max(worst, float(np.abs(e - 1).max()))
    assert worst < 0.01, worst


def test_single_scattering_loses_what_the_issue_says():
    """The figures of the issue (α = 1, F = 1, normal incidence): 31 % GGX, 46 % Beckmann."""
    g = albedo(bk.model("microfacet", alpha=1.0, fresnel="none"), 0.0)[0]
    b = albedo(bk.model("microfacet", distribution="beckmann", alpha=1.0, fresnel="none"), 0.0)[0]
    assert g == pytest.approx(0.307, abs=0.002) and b == pytest.approx(0.462, abs=0.002)


def test_reciprocal_with_coloured_conductor():
    m = bk.model("microfacet", alpha=0.7, multiscatter=True, eta=(0.27, 0.68, 1.32), k=(3.61, 2.62, 2.29))
    r = check(m)
    assert r["reciprocal"] and r["reciprocity_error"] < 1e-9
    assert r["energy_conserving"]
    wi = bk.geometry.random_unit_vectors(2000, np.random.default_rng(1), hemisphere=True)
    wo = bk.geometry.random_unit_vectors(2000, np.random.default_rng(2), hemisphere=True)
    np.testing.assert_allclose(m.eval(wi, wo), m.eval(wo, wi), rtol=1e-12)


def test_lobe_is_symmetric_and_adds_exactly_the_missing_energy():
    """∫ f_ms cos θi dωi = 1 − E_table(μo) (exactly, by the piecewise-linear E_avg), by quadrature."""
    m0 = bk.model("microfacet", alpha=0.8, fresnel="none")
    m1 = m0.with_params(multiscatter=True)
    th = np.radians([0.0, 30.0, 60.0, 75.0])
    added = albedo(m1, th)[:, 0] - albedo(m0, th)[:, 0]
    row = ms.albedo_row(ms.table("ggx", "smith"), 0.8)
    expect = 1 - ms.albedo_lookup(row, np.cos(th))
    np.testing.assert_allclose(added, expect, rtol=2e-5)


def test_fresnel_weighted_energy_matches_kulla_conty():
    """The hemispherical average of what the lobe adds is F_avg² E_avg (1 − E_avg) / (1 − F_avg (1 − E_avg)),
    here for copper (a coloured conductor); and it never pushes the albedo above 1."""
    p = dict(alpha=0.9, eta=(0.27, 0.68, 1.32), k=(3.61, 2.62, 2.29))
    m0 = bk.model("microfacet", **p)
    m1 = bk.model("microfacet", multiscatter=True, **p)
    x, w = np.polynomial.legendre.leggauss(24)
    mu = 0.5 * (x + 1)
    added = albedo(m1, np.arccos(mu)) - albedo(m0, np.arccos(mu))
    avg = 2 * (added * (mu * w * 0.5)[:, None]).sum(0)
    row = ms.albedo_row(ms.table("ggx", "smith"), 0.9)
    e_avg = ms.average_albedo(row)
    from brdfkit.models.microfacet import fresnel_term

    f_avg = ms.fresnel_average(lambda c: fresnel_term("conductor", c, m1.params, np.dtype(np.float64)))
    expect = f_avg**2 * e_avg * (1 - e_avg) / (1 - f_avg * (1 - e_avg))
    np.testing.assert_allclose(avg, expect, rtol=2e-3)
    assert np.all(albedo(m1, ANGLES) <= 1.0)
    assert np.all(added[0] > 0.01)  # a visible amount at α = 0.9


def test_schlick_f0_one_equals_no_fresnel():
    a = bk.model("microfacet", alpha=0.6, fresnel="schlick", f0=1.0, multiscatter=True)
    b = bk.model("microfacet", alpha=0.6, fresnel="none", multiscatter=True)
    wi = bk.geometry.random_unit_vectors(500, np.random.default_rng(3), hemisphere=True)
    wo = bk.geometry.random_unit_vectors(500, np.random.default_rng(4), hemisphere=True)
    np.testing.assert_allclose(a.eval(wi, wo), b.eval(wi, wo), rtol=1e-12)


def test_fresnel_average_closed_form():
    """Schlick: 2∫(f0 + (1 − f0)(1 − μ)^5) μ dμ = f0 + (1 − f0)/21."""
    f0 = np.array([0.04, 0.5, 0.95])
    got = ms.fresnel_average(lambda mu: f0 + (1 - f0) * (1 - mu[:, None]) ** 5)
    np.testing.assert_allclose(got, f0 + (1 - f0) / 21, rtol=1e-13)


def test_average_albedo_is_the_moment_of_the_interpolant():
    row = ms.albedo_row(ms.table("beckmann", "smith"), 0.55)
    mu = np.linspace(0, 1, 200001)
    num = 2 * np.trapezoid(ms.albedo_lookup(row, mu) * mu, mu)
    assert ms.average_albedo(row) == pytest.approx(num, rel=1e-9)


def test_tables_reproduce_from_the_quadrature():
    """Spot check of the shipped tables against a fresh run of the project's quadrature."""
    mu = ms.mu_grid()
    al = ms.alpha_grid()
    for d, s, k in (("ggx", "smith", 32), ("beckmann", "smith-correlated", 13), ("ggx", "v-groove", 7)):
        m = bk.model("microfacet", distribution=d, shadowing=s, alpha=float(al[k]), fresnel="none")
        e = albedo(m, np.arccos(mu[::4]), level="fine")[:, 0]  # as analysis.multiscatter_tables
        np.testing.assert_allclose(ms.table(d, s)[k, ::4], e, atol=2e-6)
    assert np.all(ms.table("ggx", "smith")[0] == 1.0)
    t = ms.table("ggx", "smith")[:, mu >= math.cos(math.radians(80))]
    assert np.all(np.diff(t, axis=0) <= 1e-12)  # up to 80°, rougher loses more (not so within 2° of grazing)


def test_threejs_figures():
    """The issue's white-furnace figures of three.js, single scattering, reproduced at (roughness, cos)
    with roughness² = α (three.js's perceptual roughness), GGX, height-correlated Smith."""
    single = {(0.5, 0.5): 0.86, (0.75, 0.5): 0.66, (1.0, 0.5): 0.45, (1.0, 1.0): 0.31}
    for (r, c), v in single.items():
        m = bk.model("microfacet", alpha=r * r, shadowing="smith-correlated", fresnel="none")
        assert albedo(m, math.acos(c))[0] == pytest.approx(v, abs=0.015)
        mc = m.with_params(multiscatter=True)
        assert albedo(mc, math.acos(c))[0] == pytest.approx(1.0, abs=0.01)


def test_glsl_twin_adds_the_same_lobe():
    from brdfkit.render import glsl

    rng = np.random.default_rng(5)
    wi = bk.geometry.random_unit_vectors(3000, rng, hemisphere=True)
    wo = bk.geometry.random_unit_vectors(3000, rng, hemisphere=True)
    for p in (dict(alpha=1.0, fresnel="none"), dict(alpha=0.45, distribution="beckmann"),
              dict(alpha_x=0.3, alpha_y=0.8, fresnel="schlick", shadowing="smith-correlated")):
        m = bk.model("microfacet", multiscatter=True, **p)
        ref = m.eval(wi, wo) - m.with_params(multiscatter=False).eval(wi, wo)
        got = glsl.eval_glsl(m, wi, wo).astype(np.float64) - glsl.eval_glsl(m.with_params(multiscatter=False), wi, wo)
        big = ref > 1e-3 * ref.max()
        assert big.mean() > 0.5
        np.testing.assert_allclose(got[big], ref[big], rtol=2e-3)


def test_bad_input_is_a_value_error():
    with pytest.raises(ValueError, match="multiscatter"):
        bk.model("microfacet", multiscatter="maybe")


def test_glsl_tables_are_the_shipped_tables():
    """shaders/multiscatter_tables.glsl (included by microfacet.glsl) carries the tables as constants; they must
    be the current .npz (regenerate with ``python -m brdfkit.render.generate``)."""
    from brdfkit.render import glsl

    text = glsl.shader_file("multiscatter_tables.glsl")
    assert text.endswith(ms.glsl_tables())
    assert text.count("const vec4 BK_MS_MISSING4[") == 1
    assert glsl.shader_source("microfacet").count(ms.glsl_tables()) == 1


def test_build_tables_writes_what_the_term_reads(tmp_path, monkeypatch):
    """The table builder (brdfkit.analysis.multiscatter_tables) with a stand-in quadrature: every table, on the
    term's grids, the mirror row 1, written atomically to the path given; the term then reads such a file."""
    from brdfkit.analysis import multiscatter_tables as mt

    calls = []

    def fake_albedo(m, theta, level):
        calls.append((m.params["distribution"], m.params["shadowing"], m.params["alpha_x"], level))
        assert m.params["fresnel"] == "none" and np.all(np.asarray(m.params["kd"]) == 0)
        return np.cos(theta)[:, None] * np.array([1.0, 1.0, 1.0]) * (1.0 - 0.5 * m.params["alpha_x"])

    monkeypatch.setattr(mt, "albedo", fake_albedo)
    path = tmp_path / "sub" / "ms.npz"
    out = mt.build_tables(path, level="coarse")
    assert len(calls) == len(ms.DISTRIBUTIONS) * len(ms.SHADOWINGS) * (ms.N_ALPHA - 1)
    assert {c[3] for c in calls} == {"coarse"}
    with np.load(path) as z:
        assert sorted(z.files) == sorted(out)
        np.testing.assert_array_equal(z["mu"], ms.mu_grid())
        t = z[ms.table_key("ggx", "v-groove")]
    assert t.shape == (ms.N_ALPHA, ms.N_MU) and np.all(t[0] == 1.0)
    np.testing.assert_allclose(t[-1], 0.5 * ms.mu_grid(), rtol=1e-12)  # cos(arccos μ)
    assert [p.name for p in (tmp_path / "sub").iterdir()] == ["ms.npz"]
    monkeypatch.setattr(ms, "DATA_PATH", path)
    ms.reload_tables()
    try:
        np.testing.assert_array_equal(ms.table("ggx", "v-groove"), t)
    finally:
        monkeypatch.undo()
        ms.reload_tables()
    assert ms.table("ggx", "v-groove")[-1, -1] != t[-1, -1]  # the shipped file again