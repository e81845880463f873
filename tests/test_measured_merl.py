"""MERL reader/writer, lookup, interpolation and the built-in Neural-BRDF materials.

The expectations are derived independently of brdfkit.measured: MERL's own
index arithmetic and half/difference rotation (BRDFRead.cpp) are re-implemented
here scalar by scalar, files are built byte by byte with ``struct``, and the
networks are evaluated straight from the README's formula.
"""

from __future__ import annotations

import math
import os
import struct
import subprocess
import sys

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.geometry import from_rusinkiewicz, to_rusinkiewicz
from brdfkit.measured import merl as M
from brdfkit.models.base import BRDF
from brdfkit.params import Param

SC = (1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0)
NH, ND, NP = 90, 90, 180


# ---------------------------------------------------------------- MERL's C code, in scalar Python
def merl_theta_half_index(theta_half):
    if theta_half <= 0.0:
        return 0
    temp = math.sqrt((theta_half / (math.pi / 2.0)) * NH * NH)
    return min(max(int(temp), 0), NH - 1)


def merl_theta_diff_index(theta_diff):
    tmp = int(theta_diff / (math.pi * 0.5) * ND)
    return min(max(tmp, 0), ND - 1)


def merl_phi_diff_index(phi_diff):
    if phi_diff < 0.0:
        phi_diff += math.pi
    tmp = int(phi_diff / math.pi * NP)
    return min(max(tmp, 0), NP - 1)


def _rotate(v, axis, angle):  # Rodrigues, as MERL's rotate_vector
    v, axis = np.asarray(v, float), np.asarray(axis, float)
    c, s = math.cos(angle), math.sin(angle)
    return v * c + axis * np.dot(axis, v) * (1 - c) + np.cross(axis, v) * s


def merl_half_diff(wi, wo):
    """MERL's std_coords_to_half_diff_coords (angles from atan2: φd in (−π, π])."""
    h = (np.asarray(wi) + np.asarray(wo)) / np.linalg.norm(np.asarray(wi) + np.asarray(wo))
    theta_h = math.acos(h[2])
    phi_h = math.atan2(h[1], h[0])
    tmp = _rotate(wi, (0, 0, 1), -phi_h)
    d = _rotate(tmp, (0, 1, 0), -theta_h)
    return theta_h, math.acos(max(-1.0, min(1.0, d[2]))), math.atan2(d[1], d[0])


def raw_value(c, i, j, k):
    """A distinct stored value for every bin and channel (file units)."""
    return 1.0 + c + 10.0 * i + 1000.0 * j + 100000.0 * k


def write_by_hand(path, func=raw_value, dims=(NH, ND, NP)):
    with open(path, "wb") as fh:
        fh.write(struct.pack("<3i", *dims))
        c_, i_, j_, k_ = np.meshgrid(np.arange(3), np.arange(dims[0]), np.arange(dims[1]), np.arange(dims[2]), indexing="ij")
        fh.write(np.asarray(func(c_, i_, j_, k_), dtype="<f8").tobytes())


@pytest.fixture(scope="module")
def handmade(tmp_path_factory):
    p = tmp_path_factory.mktemp("merl") / "hand.binary"
    write_by_hand(p)
    return p


def _random_pairs(n, seed=1):
    rng = np.random.default_rng(seed)
    wi = bk.geometry.random_unit_vectors(n, rng)
    wo = bk.geometry.random_unit_vectors(n, rng)
    return wi, wo


def test_geometry_matches_merl_half_diff():
    wi, wo = _random_pairs(300)
    th, _ph, td, pd = to_rusinkiewicz(wi, wo)
    for a in range(300):
        eth, etd, epd = merl_half_diff(wi[a], wo[a])
        assert th[a] == pytest.approx(eth, abs=1e-9)
        assert td[a] == pytest.approx(etd, abs=1e-9)
        # φd in [0, 2π) here vs (−π, π] in MERL: the same angle
        assert math.cos(pd[a] - epd) == pytest.approx(1.0, abs=1e-9)


def test_reader_nearest_matches_merl_lookup(handmade):
    m = bk.load_merl(handmade)
    wi, wo = _random_pairs(500, seed=2)
    got = m.lookup_nearest(*[v for v in np.array(to_rusinkiewicz(wi, wo))[[0, 2, 3]]])
    for a in range(500):
        eth, etd, epd = merl_half_diff(wi[a], wo[a])
        i, j, k = merl_theta_half_index(eth), merl_theta_diff_index(etd), merl_phi_diff_index(epd)
        expect = [raw_value(c, i, j, k) * SC[c] for c in range(3)]
        np.testing.assert_allclose(got[a], expect, rtol=1e-12)
    # eval (nearest) is the same lookup, in 1/sr, for directions above the horizon
    np.testing.assert_allclose(m.eval(wi, wo), got, rtol=1e-12)


def test_header_and_channel_scales_on_write(tmp_path):
    table = np.empty((3, NH, ND, NP))
    table[0], table[1], table[2] = 0.1, 0.2, 0.3
    table[:, 5, 6, 7] = -1.0  # missing
    p = tmp_path / "c.binary"
    M.write_merl_table(table, p)
    raw = p.read_bytes()
    assert struct.unpack("<3i", raw[:12]) == (90, 90, 180)
    assert len(raw) == 12 + 3 * NH * ND * NP * 8
    vals = np.frombuffer(raw[12:], dtype="<f8").reshape(3, NH, ND, NP)
    for c, v in enumerate((0.1, 0.2, 0.3)):
        assert vals[c, 0, 0, 0] == pytest.approx(v / SC[c], rel=1e-12)
        assert vals[c, 5, 6, 7] < 0
    back = M.read_merl_table(p)
    assert back[0, 0, 0, 0] == pytest.approx(0.1, rel=1e-12)
    assert (back[:, 5, 6, 7] < 0).all()


class _Glossy(BRDF):
    """A test-only isotropic lobe with colour: kd/π + ks (n·h)^s (not registered)."""

    name = "test-glossy"
    spec = (
        Param("kd", "rgb", (0.2, 0.4, 0.6), (0.0, 1.0)),
        Param("ks", "rgb", 0.5, (0.0, 10.0)),
        Param("s", "scalar", 40.0, (1.0, 1e4), log_scale=True),
    )

    def _eval(self, wi, wo, p):
        h = wi + wo
        h = h / np.linalg.norm(h, axis=-1, keepdims=True)
        return p["kd"] / np.pi + p["ks"] * (h[..., 2:3] ** p["s"])


def _centre_directions(i, j, k):
    th = ((i + 0.5) / NH) ** 2 * np.pi / 2
    td = (j + 0.5) / ND * np.pi / 2
    pd = (k + 0.5) / NP * np.pi
    return from_rusinkiewicz(th, 0.7 * np.ones_like(th), td, pd)


def _save_load_at_centres(model, path, n, seed):
    """Write ``model`` as a MERL file, read it back; ``n`` random bin centres as directions.

    Returns ``(loaded model, (i, j, k) bin indices, wi, wo, both-above-the-horizon mask)``.
    """
    bk.save_merl(model, path)
    m = bk.load_merl(path)
    rng = np.random.default_rng(seed)
    i, j, k = rng.integers(0, NH, n), rng.integers(0, ND, n), rng.integers(0, NP, n)
    wi, wo = _centre_directions(i, j, k)
    up = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    return m, (i, j, k), wi, wo, up


def test_tabulate_save_load_round_trip(tmp_path):
    model = _Glossy()
    m, (i, j, k), wi, wo, up = _save_load_at_centres(model, tmp_path / "g.binary", 4000, seed=3)
    table_vals = np.moveaxis(m.table[:, i, j, k], 0, -1)
    # read back == the table at the bin centres, for nearest and trilinear lookups
    np.testing.assert_allclose(m.eval(wi[up], wo[up]), table_vals[up], rtol=1e-12)
    tri = m.with_params(interpolation="trilinear")
    np.testing.assert_allclose(tri.eval(wi[up], wo[up]), table_vals[up], rtol=1e-9)
    # ... and the table holds the analytic model's values there
    np.testing.assert_allclose(table_vals[up], model.eval(wi[up], wo[up]), rtol=1e-9)
    # below the horizon: marked missing in the file, zero from eval
    assert (table_vals[~up] < 0).all()
    assert (m.eval(wi[~up], wo[~up]) == 0).all()


def test_trilinear_between_bins_and_missing(tmp_path):
    table = np.zeros((3, NH, ND, NP))
    table[:, 40, 30, 10] = 1.0
    table[:, 40, 30, 11] = 3.0
    table[:, 40, 30, 12] = -1.0  # missing
    m = M.MERLBRDF(table, interpolation="trilinear")
    th = ((40 + 0.5) / NH) ** 2 * np.pi / 2
    td = (30 + 0.5) / ND * np.pi / 2
    mid = (11.0) / NP * np.pi  # halfway between the centres of bins 10 and 11
    v = m.lookup_trilinear(th, td, mid)
    np.testing.assert_allclose(v, 2.0, rtol=1e-12)
    # between 11 (3.0) and the missing 12: only the measured corner counts
    v = m.lookup_trilinear(th, td, 12.0 / NP * np.pi)
    np.testing.assert_allclose(v, 3.0, rtol=1e-12)
    # φd is periodic with period π: φd and φd + π agree
    np.testing.assert_allclose(m.lookup_trilinear(th, td, mid + np.pi), 2.0, rtol=1e-12)
    wi, wo = _random_pairs(2000, seed=4)
    f = m.eval(wi, wo)
    assert np.isfinite(f).all() and (f >= 0).all()


@pytest.mark.parametrize(
    "content, words",
    [
        (b"", "empty"),
        (struct.pack("<3i", 90, 90, 180) + b"\0" * 800, "truncated"),
        (struct.pack("<3i", 90, 90, 90) + b"\0" * (3 * 90 * 90 * 90 * 8), "dimensions 90x90x90"),
        (b"this is a text file, not a BRDF\n" * 40, "dimensions"),
        (b"\x01\x02", "too short"),
    ],
)
def test_malformed_files_raise_valueerror(tmp_path, content, words):
    p = tmp_path / "bad.binary"
    p.write_bytes(content)
    with pytest.raises(ValueError, match=words) as ei:
        bk.load_merl(p)
    assert "\n" not in str(ei.value)
    assert str(p) in str(ei.value)


def test_malformed_file_cli_one_line_no_traceback(tmp_path):
    p = tmp_path / "bad.binary"
    p.write_bytes(struct.pack("<3i", 90, 90, 180) + b"\0" * 64)
    r = subprocess.run([sys.executable, "-m", "brdfkit.cli", "fit", str(p), "--model", "lambert"],
                       capture_output=True, text=True)
    assert r.returncode != 0
    assert "Traceback" not in r.stderr
    assert "truncated" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def test_load_missing_file_is_oserror(tmp_path):
    with pytest.raises(OSError):
        bk.load_merl(tmp_path / "nope.binary")


def test_non_isotropic_model_cannot_be_saved(tmp_path):
    class Aniso(_Glossy):
        isotropic = False

    with pytest.raises(ValueError, match="isotropic"):
        bk.save_merl(Aniso(), tmp_path / "a.binary")


# ---------------------------------------------------------------- the built-in materials
def test_material_list():
    names = bk.materials()
    assert len(names) == 159
    sets = [n.split("/")[0] for n in names]
    assert sets.count("merl") == 100 and sets.count("rgl") == 51 and sets.count("nielsen") == 8
    assert "merl/gold-metallic-paint" in names
    with pytest.raises(ValueError, match="unknown measured material"):
        bk.material("merl/no-such-thing")
    assert bk.material("gold-metallic-paint").material == "merl/gold-metallic-paint"


def test_naming_a_material_reads_the_index_not_the_networks(tmp_path, monkeypatch):
    """The material list comes from the weights file's index; a network is read when a model is built,
    read-only and shape-checked: a file whose network has the wrong shape is a one-line ValueError."""
    from brdfkit.measured import nbrdf

    full = nbrdf.layers("merl/chrome")
    assert [a.shape for a in full] == [(6, 21), (21,), (21, 21), (21,), (21, 3), (3,)]
    assert all(a.dtype == np.float32 and not a.flags.writeable for a in full)
    bad = {f"merl/x/{k}": np.zeros((2, 2), np.float32) for k in nbrdf.LAYERS}
    path = tmp_path / "w.npz"
    np.savez(path, **bad)
    monkeypatch.setattr(nbrdf, "_DATA", str(path))
    for cached in (nbrdf._entries, nbrdf.materials, nbrdf.layers):
        cached.cache_clear()
    try:
        assert nbrdf.materials() == ("merl/x",)
        with pytest.raises(ValueError, match=r"merl/x: unexpected network shape \[\(2, 2\)"):
            bk.material("merl/x")
    finally:
        monkeypatch.undo()
        for cached in (nbrdf._entries, nbrdf.materials, nbrdf.layers):
            cached.cache_clear()
    assert len(nbrdf.materials()) == 159


def test_nbrdf_matches_readme_formula():
    path = os.path.join(os.path.dirname(M.__file__), "data", "nbrdf_weights.npz")
    z = np.load(path)
    rng = np.random.default_rng(5)
    th = rng.random(200) * np.pi / 2
    td = rng.random(200) * np.pi / 2 * 0.9
    pd = rng.random(200) * 2 * np.pi
    # eval folds φd into [0, π) (MERL's reciprocity domain) before the network
    pf = np.mod(pd, np.pi)
    x = np.stack([np.sin(th), 0 * th, np.cos(th), np.sin(td) * np.cos(pf), np.sin(td) * np.sin(pf), np.cos(td)], -1)
    for name in ("merl/gold-metallic-paint", "rgl/spectralon_rgb", "nielsen/bluebook"):
        w = {k: z[f"{name}/{k}"].astype(np.float64) for k in ("fc1", "b1", "fc2", "b2", "fc3", "b3")}
        a1 = np.maximum(x @ w["fc1"] + w["b1"], 0)
        a2 = np.maximum(a1 @ w["fc2"] + w["b2"], 0)
        expect = np.maximum(np.exp(a2 @ w["fc3"] + w["b3"]) - 1, 0)
        wi, wo = from_rusinkiewicz(th, rng.random(200) * 2 * np.pi, td, pd)
        up = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        got = bk.material(name).eval(wi, wo)
        np.testing.assert_allclose(got[up], expect[up], rtol=2e-4, atol=1e-6)
        assert (got[~up] == 0).all()


def test_nbrdf_is_exactly_reciprocal():
    rng = np.random.default_rng(11)
    wi = rng.normal(size=(2000, 3))
    wo = rng.normal(size=(2000, 3))
    wi[:, 2] = np.abs(wi[:, 2])
    wo[:, 2] = np.abs(wo[:, 2])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    for name in ("merl/chrome", "rgl/spectralon_rgb"):
        m = bk.material(name)
        np.testing.assert_array_equal(m.eval(wi, wo), m.eval(wo, wi))


def test_nbrdf_contract_float32_and_horizon():
    m = bk.material("merl/chrome")
    wi, wo = _random_pairs(1000, seed=6)
    wi[:10, 2] = 0.0
    wi[:10] = bk.geometry.normalize(wi[:10])  # at the horizon, still unit vectors
    f64 = m.eval(wi, wo)
    f32 = m.eval(wi.astype(np.float32), wo.astype(np.float32))
    assert f32.dtype == np.float32 and f64.dtype == np.float64
    assert np.isfinite(f64).all() and (f64 >= 0).all()
    assert (f64[:10] == 0).all()
    np.testing.assert_allclose(f32, f64, rtol=1e-3, atol=1e-4)


def test_material_to_merl_file(tmp_path):
    mat = bk.material("merl/blue-acrylic")
    m, _, wi, wo, up = _save_load_at_centres(mat, tmp_path / "blue.binary", 500, seed=7)
    np.testing.assert_allclose(m.eval(wi[up], wo[up]), mat.eval(wi[up], wo[up]), rtol=1e-9, atol=1e-12)


def test_table_is_exactly_reciprocal_even_on_bin_boundaries(handmade):
    """Every bin holds a different value, so a pair and its swap must pick the very same bin."""
    m = bk.load_merl(handmade)
    rng = np.random.default_rng(8)
    wi, wo = _random_pairs(3000, seed=9)
    # in-plane pairs (φd = 0 or π: the φd fold boundary) and θ on a grid of bin edges
    t = np.radians(rng.integers(1, 90, (2, 2000)).astype(float))
    p = rng.random(2000) * 2 * np.pi
    a = np.stack([np.sin(t[0]) * np.cos(p), np.sin(t[0]) * np.sin(p), np.cos(t[0])], -1)
    b = np.stack([-np.sin(t[1]) * np.cos(p), -np.sin(t[1]) * np.sin(p), np.cos(t[1])], -1)
    wi, wo = np.concatenate([wi, a]), np.concatenate([wo, b])
    for interp in ("nearest", "trilinear"):
        mm = m.with_params(interpolation=interp)
        assert np.array_equal(mm.eval(wi, wo), mm.eval(wo, wi))


def test_texture3d_layout(handmade):
    m = bk.load_merl(handmade)
    tex = M.texture3d(m)
    assert tex.shape == (NH, ND, NP, 3) and tex.dtype == np.float32 and tex.flags.c_contiguous
    for (i, j, k) in [(0, 0, 0), (89, 3, 179), (40, 60, 17)]:
        np.testing.assert_allclose(tex[i, j, k], [raw_value(c, i, j, k) * SC[c] for c in range(3)], rtol=1e-6)
