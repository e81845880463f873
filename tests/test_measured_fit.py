"""Fitting: synthetic data from known parameters is recovered; bounds, fixed values, metrics, weights."""

from __future__ import annotations

import json
import numpy as np
import pytest

import brdfkit as bk
from brdfkit import registry
from brdfkit.measured import fit as F
from brdfkit.models.base import BRDF
from brdfkit.params import Param
from _fit_helpers import Bright


class _GGXSchlickLambert(BRDF):
    """Test-only reference: kd/π + F_Schlick(f0) · D_GGX(α) · G1(wi) G1(wo) / (4 cosθi cosθo)."""

    name = "test-ggx"
    spec = (
        Param("kd", "rgb", 0.5, (0.0, 1.0)),
        Param("f0", "rgb", 0.04, (0.0, 1.0)),
        Param("alpha", "scalar", 0.3, (0.001, 1.0), log_scale=True),
        Param("mode", "choice", "a", choices=("a", "b")),
    )

    def _eval(self, wi, wo, p):
        a2 = p["alpha"] ** 2
        h = wi + wo
        h = h / np.linalg.norm(h, axis=-1, keepdims=True)
        nh = h[..., 2:3]
        D = a2 / (np.pi * (nh * nh * (a2 - 1) + 1) ** 2)

        def g1(w):
            c = w[..., 2:3]
            t2 = (1 - c * c) / (c * c)
            return 2 / (1 + np.sqrt(1 + a2 * t2))

        hi = np.sum(h * wi, axis=-1, keepdims=True)
        Fr = p["f0"] + (1 - p["f0"]) * (1 - hi) ** 5
        return p["kd"] / np.pi + Fr * D * g1(wi) * g1(wo) / (4 * wi[..., 2:3] * wo[..., 2:3])


TRUE = dict(kd=[0.05, 0.20, 0.45], f0=[0.9, 0.6, 0.3], alpha=0.12)


@pytest.mark.parametrize("metric", ["ngan", "cbrt"])
def test_recovers_known_ggx_schlick_lambert(metric):
    truth = _GGXSchlickLambert(**TRUE)
    r = F.fit(_GGXSchlickLambert, truth, metric=metric, samples=2000, starts=3, seed=1)
    assert r.params["alpha"] == pytest.approx(TRUE["alpha"], rel=0.03)
    np.testing.assert_allclose(r.params["kd"], TRUE["kd"], rtol=0.05)
    np.testing.assert_allclose(r.params["f0"], TRUE["f0"], rtol=0.05)
    assert r.params["mode"] == "a"  # choices stay at their default
    assert r.error < 1e-3
    assert r.error == pytest.approx(F.error(r.model, F.sample(truth, n=2000, seed=1), metric), rel=1e-9)


def test_fixed_parameters_are_held_and_json_has_every_parameter():
    truth = _GGXSchlickLambert(**TRUE)
    r = F.fit(_GGXSchlickLambert, truth, fixed={"alpha": 0.2, "mode": "b"}, samples=1500, starts=2)
    assert r.params["alpha"] == 0.2 and r.params["mode"] == "b"
    js = r.to_json()
    assert set(js["params"]) == {"kd", "f0", "alpha", "mode"}
    assert js["metric"] == "ngan" and js["error"] > 1e-3  # the wrong alpha cannot fit exactly
    with pytest.raises(ValueError, match="unknown parameter"):
        F.fit(_GGXSchlickLambert, truth, fixed={"nope": 1})
    with pytest.raises(ValueError, match="out of range"):
        F.fit(_GGXSchlickLambert, truth, fixed={"alpha": 5.0})


def test_parameters_stay_within_spec_bounds():
    # data brighter than any allowed lambert: kd = 1.6 is outside [0, 1]
    r = F.fit("lambert", Bright(), samples=500, starts=2)
    assert np.all(r.params["kd"] <= 1.0) and np.all(r.params["kd"] >= 0.999)


@pytest.mark.parametrize("metric", F.METRICS)
def test_every_metric_fits_lambert_exactly(metric):
    truth = bk.model("lambert", kd=[0.3, 0.5, 0.7])
    r = bk.fit("lambert", truth, metric=metric, samples=500, starts=2)
    np.testing.assert_allclose(r.params["kd"], [0.3, 0.5, 0.7], rtol=1e-5)
    assert r.error < 1e-6 and r.metric == metric


def test_unknown_metric_and_model():
    with pytest.raises(ValueError, match="valid metrics"):
        bk.fit("lambert", "merl/chrome", metric="l7")
    with pytest.raises(ValueError, match="unknown model"):
        bk.fit("no-such-model", "merl/chrome")


def test_sample_weights_integrate_over_direction_pairs():
    """Weighted means estimate uniform averages over (ωi, ωo): E[cosθi] = 1/2, E[cosθi cosθo] = 1/4."""
    s = F.sample(bk.model("lambert"), n=40000, seed=3, max_theta_deg=90)
    w = s.w / s.w.sum()
    assert np.sum(w * s.wi[:, 2]) == pytest.approx(0.5, rel=0.03)
    assert np.sum(w * s.wo[:, 2]) == pytest.approx(0.5, rel=0.03)
    assert np.sum(w * s.wi[:, 2] * s.wo[:, 2]) == pytest.approx(0.25, rel=0.04)
    s80 = F.sample(bk.model("lambert"), n=2000, seed=3)
    assert s80.wi[:, 2].min() > np.cos(np.radians(80)) and s80.wo[:, 2].min() > np.cos(np.radians(80))


def test_fit_from_merl_file_uses_measured_bins(tmp_path):
    truth = bk.model("lambert", kd=[0.1, 0.2, 0.3])
    p = tmp_path / "l.binary"
    bk.save_merl(truth, p)
    s = F.sample(str(p), n=1000)
    np.testing.assert_allclose(s.f, np.broadcast_to(np.array([0.1, 0.2, 0.3]) / np.pi, s.f.shape), rtol=1e-12)
    r = bk.fit("lambert", str(p), samples=1000)
    np.testing.assert_allclose(r.params["kd"], [0.1, 0.2, 0.3], rtol=1e-6)


@pytest.mark.skipif("microfacet" not in registry.names(), reason="microfacet model not registered yet")
def test_recovers_microfacet_ggx_schlick():
    fixed = dict(distribution="ggx", fresnel="schlick", shadowing="smith")
    spec = {p.name for p in registry.get("microfacet").spec}
    truth_params = dict(fixed, alpha=0.15, f0=[0.9, 0.6, 0.3], kd=[0.05, 0.2, 0.45])
    if "ks" in spec:
        truth_params["ks"] = 1.0
        fixed["ks"] = 1.0
    truth_params = {k: v for k, v in truth_params.items() if k in spec}
    truth = bk.model("microfacet", **truth_params)
    r = bk.fit("microfacet", truth, fixed={k: v for k, v in fixed.items() if k in spec}, samples=2000, starts=3)
    assert r.params["alpha"] == pytest.approx(0.15, rel=0.03)
    np.testing.assert_allclose(r.params["kd"], truth_params["kd"], rtol=0.05)
    np.testing.assert_allclose(r.params["f0"], truth_params["f0"], rtol=0.05)


def test_cli_fit_json_and_fixed(cli):
    r = cli("fit", "merl/blue-acrylic", "--model", "lambert", "--json", "--samples", "500", "--starts", "2")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert set(out) >= {"params", "error", "metric"}
    assert out["metric"] == "ngan" and len(out["params"]["kd"]) == 3 and out["error"] > 0
    r = cli("fit", "merl/blue-acrylic", "-m", "lambert", "-p", "kd=0.3", "--json", "--samples", "300")
    assert json.loads(r.stdout)["params"]["kd"] == [0.3, 0.3, 0.3]


@pytest.mark.parametrize(
    "args, words",
    [
        (("fit", "merl/blue-acrylic"), "missing --model"),
        (("fit", "merl/blue-acrylic", "-m", "nope"), "unknown model"),
        (("fit", "merl/nothing", "-m", "lambert"), "unknown measured material"),
        (("fit", "merl/blue-acrylic", "-m", "lambert", "--metric", "x"), "valid metrics"),
        (("fit", "merl/blue-acrylic", "-m", "lambert", "-p", "zz=1"), "unknown parameter"),
        (("fit", "--all-measured", "--set", "xx", "-m", "lambert"), "unknown measured set"),
    ],
)
def test_cli_errors_are_one_line(cli, args, words):
    r = cli(*args)
    assert r.returncode != 0
    assert words in r.stderr and "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def test_cli_report_and_small_batch(cli, tmp_path):
    rep = tmp_path / "rep"
    r = cli("fit", "nielsen/bluebook", "-m", "lambert", "--samples", "400", "--starts", "1", "--report", str(rep))
    assert r.returncode == 0, r.stderr
    for f in ("slices.png", "spheres.png", "fit.json", "index.md"):
        assert (rep / f).stat().st_size > 100
    assert (rep / "spheres.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    out = tmp_path / "batch"
    r = cli("fit", "--all-measured", "--set", "nielsen", "--limit", "3", "-m", "lambert",
             "--samples", "300", "--starts", "1", "--out", str(out))
    assert r.returncode == 0, r.stderr
    rows = (out / "fit_errors.csv").read_text().strip().splitlines()
    assert rows[0] == "material,lambert" and len(rows) == 4
    assert all(float(x.split(",")[1]) > 0 for x in rows[1:])
    assert (out / "fit_errors_sorted.png").exists() and "| material | lambert |" in (out / "fit_errors.md").read_text()


def test_cli_list_measured(cli):
    r = cli("list", "--measured", "--json")
    assert r.returncode == 0, r.stderr
    names = json.loads(r.stdout)
    assert len(names) == 159 and "merl/chrome" in names and "nielsen/bluebook" in names


# --------------------------------------------------------------------------- speed-ups (issue 10)
def _probe(name, fixed, n=600):
    data = F.sample("merl/gold-metallic-paint", n=n, seed=3)
    packer = F.ParamPacker(registry.get(name), fixed)
    res = F._residual_fn(packer, data, F._transform("ngan"), "ngan")
    rng = np.random.default_rng(4)
    F._freeze_unused(packer, res, rng)
    pts = [packer.x_of(packer.fixed), packer.random_x(rng, 1)[0]]
    return packer, res, pts, rng


@pytest.mark.parametrize("name, fixed", [("cook-torrance", {}), ("blinn-phong", {}),
                                         ("microfacet", {"distribution": "ggx", "fresnel": "schlick"})])
def test_constant_columns_are_the_lambertian_kd_only(name, fixed):
    packer, res, pts, _ = _probe(name, fixed)
    const = F.constant_columns(res, packer, pts)
    labels = sorted(f"{packer.slots[i].param.name}[{packer.slots[i].channel}]" for i in const)
    assert labels == ["kd[0]", "kd[1]", "kd[2]"]


def test_constant_columns_none_for_a_coupled_diffuse_term():
    # the paper form of Ashikhmin-Shirley: the diffuse term is rd·(1 − rs)·…, so ∂f/∂rd depends on rs
    packer, res, pts, _ = _probe("ashikhmin-shirley", {})
    assert F.constant_columns(res, packer, pts) == {}


def test_jacobian_with_constant_columns_equals_forward_differences():
    from scipy.optimize._numdiff import approx_derivative

    packer, res, pts, rng = _probe("cook-torrance", {})
    const = F.constant_columns(res, packer, pts)
    assert const
    x = packer.random_x(rng, 1)[0]
    J = F._jacobian(F._Start(res, packer, []), packer, const)(x)
    ref = approx_derivative(res, x, method="2-point", bounds=(packer.lb, packer.ub))
    scale = np.abs(ref).max(axis=0)
    assert np.all(np.abs(J - ref).max(axis=0) <= 1e-4 * scale + 1e-12)


def test_starts_joining_a_known_basin_stop_early_and_lose_nothing(monkeypatch):
    data = F.sample("merl/gold-metallic-paint", n=800, seed=2)
    kw = dict(fixed={"distribution": "ggx", "fresnel": "schlick"}, data=data, seed=2)
    joined = F.fit("microfacet", "merl/gold-metallic-paint", **kw)
    from brdfkit.measured import optimise

    monkeypatch.setattr(optimise, "JOIN_XTOL", 0.0)  # no start can join: each runs to convergence
    full = F.fit("microfacet", "merl/gold-metallic-paint", **kw)
    assert joined.nfev < full.nfev
    assert joined.error <= full.error * (1 + 1e-6)
    # a joined start stopped within JOIN_RTOL (in cost) of the best minimum
    best = min(joined.start_errors)
    assert sum(e <= best * (1 + F.JOIN_RTOL) ** 0.5 for e in joined.start_errors) >= 2


@pytest.mark.parametrize("name, fixed", [("microfacet", {}), ("microfacet", {"distribution": "ggx", "fresnel": "schlick"}),
                                         ("cook-torrance", {}), ("ashikhmin-shirley", {}), ("ward", {})])
def test_channel_grouped_jacobian_is_the_columnwise_one_bit_for_bit(name, fixed):
    packer, res, pts, rng = _probe(name, fixed)
    const = F.constant_columns(res, packer, pts)
    groups = F.channel_groups(res, packer, pts, skip=const)
    assert sorted(i for g in groups for i in g) == [i for i in range(len(packer)) if i not in const]
    assert any(len(g) > 1 for g in groups)  # every rgb parameter here is computed per channel
    for g in groups:
        chans = [packer.slots[i].channel for i in g]
        assert len(g) == 1 or (None not in chans and len(set(chans)) == len(g))
    for x in packer.random_x(rng, 3):
        one = F._Start(res, packer, [])
        J = F._jacobian(one, packer, const)(x)
        grouped = F._Start(res, packer, [])
        Jg = F._jacobian(grouped, packer, const, groups)(x)
        assert J.tobytes() == Jg.tobytes()
        assert grouped.nfev == len(groups) + 1 < one.nfev


def test_channel_groups_keep_a_slot_that_changes_other_channels_alone():
    packer, res, pts, _ = _probe("microfacet", {"distribution": "ggx", "fresnel": "schlick"})
    mixed = [i for i, s in enumerate(packer.slots) if s.param.name == "f0"][1]

    def coupled(x):  # channel 0 also depends on f0[1]
        r = res(x).copy()
        r[0::3] *= 1 + x[mixed]
        return r

    groups = F.channel_groups(coupled, packer, pts)
    assert [mixed] in groups
    assert all(len(g) == 1 or mixed not in g for g in groups)


def test_grouped_jacobian_joins_a_basin_at_the_same_column_point():
    packer, res, pts, rng = _probe("microfacet", {"distribution": "ggx", "fresnel": "schlick"})
    const = F.constant_columns(res, packer, pts)
    groups = F.channel_groups(res, packer, pts, skip=const)
    x = packer.random_x(rng, 1)[0]
    seen = []

    class Spy(F._Start):  # records the points and costs the basin test sees, in order
        def check(self, y, r):
            seen.append((y.tobytes(), float(r @ r)))

    spy = Spy(res, packer, [(x.copy(), 0.0)])
    spy.evaluate(x)  # the Jacobian's base point: not a column's
    F._jacobian(spy, packer, const)(x)
    assert len(seen) == len(packer) - len(const)
    joined = set()
    for t in sorted(c for _, c in seen):  # a basin each column's point (with those of lower cost) joins
        ck = t / (1 + F.JOIN_RTOL) * (1 + 1e-12)
        first = next(yc for yc in seen if yc[1] <= ck * (1 + F.JOIN_RTOL))
        for g in (None, groups):
            fn = F._Start(res, packer, [(x.copy(), ck)])
            fn.evaluate(x)
            with pytest.raises(F._Joined) as e:
                F._jacobian(fn, packer, const, g)(x)
            assert (e.value.x.tobytes(), e.value.cost) == first
        joined.add(first[0])
    assert len(joined) >= 2  # not always the first column


def test_starts_that_end_in_different_basins_search_on(monkeypatch):
    """He on RGL's chm_mint: the four default starts end in minima 3 % apart in cost (2.380 and 2.454),
    so up to EXTRA_STARTS more run, from the next best candidates; one of them reaches 2.085 (the
    published table's loss). The progress callback is told the larger total."""
    from brdfkit.measured import optimise

    data = F.sample("rgl/chm_mint_rgb", n=2000)
    seen = []
    r = F.fit("htsg", "rgl/chm_mint_rgb", data=data, progress=lambda done, total: seen.append((done, total)))
    hops = sum(s.log for s in F.ParamPacker(bk.sources.model_class("htsg")).slots)  # τ: optimise.HOPS
    assert hops == 1 and r.starts == 4 + optimise.EXTRA_STARTS + hops == len(r.start_errors)
    first = [e * e for e in r.start_errors[:4]]
    assert max(first) > (1 + optimise.SPREAD) * min(first)
    assert r.error < 2.0847 < 0.9 * min(r.start_errors[:4])
    assert seen[:4] == [(i, 4) for i in range(1, 5)] and seen[-1] == (r.starts, r.starts)
    monkeypatch.setattr(optimise, "EXTRA_STARTS", 0)
    monkeypatch.setattr(optimise, "HOPS", False)
    few = F.fit("htsg", "rgl/chm_mint_rgb", data=data)
    assert few.starts == 4 and few.start_errors == r.start_errors[:4] and few.error > 2.38
    # starts that agree do not search on
    agree = F.fit("ward", "merl/gold-metallic-paint", data=F.sample("merl/gold-metallic-paint", n=800, seed=2))
    assert agree.starts == 4


def test_a_log_scale_value_hops_to_its_other_basin(monkeypatch):
    """Cook-Torrance on merl/blue-metallic-paint2: every start ends with the blue index of refraction
    at 5.7 (cost 0.020443), but at 49 the cost is 1.1 % lower, behind a ridge; the hop of that value to
    the far end of its range reaches it (the published table's 0.142231), one run per log-scale value."""
    from brdfkit.measured import optimise

    data = F.sample("merl/blue-metallic-paint2", n=2000)
    r = F.fit("cook-torrance", "merl/blue-metallic-paint2", data=data)
    assert r.error < 0.14224 and r.params["ior"][2] > 20 and r.params["ior"][1] < 5
    packer = F.ParamPacker(bk.sources.model_class("cook-torrance"))
    at_5_7 = {**r.params, "ior": np.array([2.47, 3.03, 5.7])}  # in the basin every start ends in
    x = packer.x_of(at_5_7)
    logs = [i for i, s in enumerate(packer.slots) if s.log]
    hops = [optimise.decade_hop(packer, x, i) for i in logs]  # each to 20 % of its range from the far end
    assert [np.flatnonzero(h != x).tolist() for h in hops] == [[i] for i in logs]
    assert [s.param.name for s in packer.slots if s.log] == ["m"] + ["ior"] * 3
    assert np.exp(hops[-1][logs[-1]]) == pytest.approx(200 ** 0.8)  # 5.7 is in the lower half: to the upper
    assert at_5_7["m"] < 1e-3 ** 0.5  # m = 0.016, below its range's log middle (0.032): to the upper
    assert np.exp(hops[0][logs[0]]) == pytest.approx(1e-3 ** 0.2)
    assert r.starts == 4 + len(hops)  # the four starts agree: no extra starts
    monkeypatch.setattr(optimise, "HOPS", False)
    without = F.fit("cook-torrance", "merl/blue-metallic-paint2", data=data)
    assert without.starts == 4 and without.error > 0.1429 and without.params["ior"][2] < 10


def test_the_gradient_tolerance_is_relative_to_the_fits_cost(monkeypatch):
    """A dark material's fit has costs of 10⁻⁶: an absolute gradient tolerance (scipy's gtol = 10⁻⁸)
    stopped Ashikhmin-Shirley's on merl/green-latex 5·10⁻⁵ above the published table's 0.00279148, in
    the flat valley where f0 trades against ks; the last run from the best minimum, to a gradient
    tolerance relative to the best candidate's cost, reaches it."""
    import dataclasses

    from brdfkit.measured import optimise

    data = F.sample("merl/green-latex", n=2000)
    r = F.fit("ashikhmin-shirley", "merl/green-latex", fixed={"variant": "ngan"}, data=data)
    assert r.error < 0.00279149
    plan = optimise._plan_starts
    monkeypatch.setattr(optimise, "_plan_starts",
                        lambda *a, **k: dataclasses.replace(plan(*a, **k), cost_scale=1.0))
    absolute = F.fit("ashikhmin-shirley", "merl/green-latex", fixed={"variant": "ngan"}, data=data)
    assert absolute.error > 0.0027916 and absolute.nfev < r.nfev
