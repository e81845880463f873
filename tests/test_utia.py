"""UTIA .bin reader: layout, grid exactness, interpolation, anisotropy, bad files."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import brdfkit as bk
from brdfkit.measured import utia
from _numeric_helpers import load_or_one_line_error


@pytest.fixture(scope="module")
def ward():
    return bk.model("ward", kd=[0.3, 0.2, 0.1], ks=[0.1, 0.1, 0.1], alpha_x=0.25, alpha_y=0.6)


@pytest.fixture(scope="module")
def ward_file(tmp_path_factory, ward):
    path = tmp_path_factory.mktemp("utia") / "ward.bin"
    utia.write_utia_table(utia.tabulate_utia(ward), path)
    return path


def _vec(t, p):
    return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)


def test_file_size_and_layout(ward_file, ward):
    assert ward_file.stat().st_size == 3 * 6 * 48 * 6 * 48 * 8
    raw = np.fromfile(ward_file, dtype="<f8")
    # channel 1, θi index 2 (30°), φi index 5 (37.5°), θv index 3 (45°), φv index 40 (300°)
    idx = (((1 * 6 + 2) * 48 + 5) * 6 + 3) * 48 + 40
    expect = ward.eval(_vec(np.radians(30), np.radians(37.5)), _vec(np.radians(45), np.radians(300)))
    assert raw[idx] == pytest.approx(float(np.asarray(expect)[1]), rel=1e-12)


def test_grid_points_exact(ward_file, ward):
    m = utia.load_utia(ward_file)
    rng = np.random.default_rng(1)
    th, ph = utia.grid_angles()
    a, c = rng.integers(0, 6, 200), rng.integers(0, 6, 200)
    b, d = rng.integers(0, 48, 200), rng.integers(0, 48, 200)
    got = m.eval_angles(th[a], ph[b], th[c], ph[d])
    np.testing.assert_allclose(got, np.moveaxis(m.table[:, a, b, c, d], 0, -1), rtol=0, atol=0)
    wi, wo = _vec(th[a], ph[b]), _vec(th[c], ph[d])
    np.testing.assert_allclose(m.eval(wi, wo), ward.eval(wi, wo), rtol=1e-9)


def test_interpolation_is_multilinear_and_periodic():
    # a table linear in θi (degrees) and periodic-linear in φv between two samples is reproduced exactly
    th, ph = utia.grid_angles()
    table = np.zeros(utia.SHAPE)
    table[:] = np.degrees(th)[None, :, None, None, None] + 1.0
    m = utia.UTIABRDF(table)
    got = m.eval_angles(np.radians([7.0, 33.3, 74.0]), 0.3, 0.2, 1.0)
    np.testing.assert_allclose(got[:, 0], [8.0, 34.3, 75.0], rtol=1e-12)
    # φ between 352.5° and 360° interpolates with the 0° sample
    table2 = np.zeros(utia.SHAPE)
    table2[:, :, 0] = 2.0
    m2 = utia.UTIABRDF(table2)
    np.testing.assert_allclose(m2.eval_angles(0.5, np.radians(356.25), 0.5, 0.0)[0], 1.0, rtol=1e-12)
    np.testing.assert_allclose(m2.eval_angles(0.5, np.radians(-3.75), 0.5, 0.0)[0], 1.0, rtol=1e-12)


def test_extrapolation_above_75_and_zero_below_horizon():
    th, _ = utia.grid_angles()
    table = np.zeros(utia.SHAPE)
    table[:] = np.degrees(th)[None, None, None, :, None]
    m = utia.UTIABRDF(table)
    np.testing.assert_allclose(m.eval_angles(0.1, 0.0, np.radians(85.0), 0.0)[0], 85.0, rtol=1e-12)
    assert m.eval_angles(0.1, 0.0, np.radians(95.0), 0.0)[0] == 0.0
    dec = utia.UTIABRDF(np.repeat(table[:, :, :, ::-1, :], 1, axis=3))  # 75 at θ=0 … 0 at 75°
    assert (dec.eval_angles(0.1, 0.0, np.radians(89.0), 0.0) >= 0).all()


def test_interpolation_error_against_model(ward_file, ward):
    m = utia.load_utia(ward_file)
    rng = np.random.default_rng(2)
    n = 4000
    ti, tv = np.radians(rng.uniform(0, 75, n)), np.radians(rng.uniform(0, 75, n))
    pi_, pv = rng.uniform(0, 2 * np.pi, n), rng.uniform(0, 2 * np.pi, n)
    got = m.eval_angles(ti, pi_, tv, pv)
    want = np.asarray(ward.eval(_vec(ti, pi_), _vec(tv, pv)))
    rel = np.abs(got - want).mean() / np.abs(want).mean()
    assert rel < 0.05  # grid 15°/7.5° on a fairly rough anisotropic Ward (measured ≈ see report)


def test_reciprocity_of_a_reciprocal_table(ward_file):
    m = utia.load_utia(ward_file)
    rng = np.random.default_rng(3)
    th, ph = utia.grid_angles()
    a, c = rng.integers(0, 6, 100), rng.integers(0, 6, 100)
    b, d = rng.integers(0, 48, 100), rng.integers(0, 48, 100)
    np.testing.assert_allclose(
        m.eval_angles(th[a], ph[b], th[c], ph[d]), m.eval_angles(th[c], ph[d], th[a], ph[b]), rtol=1e-9
    )


def test_anisotropy_visible(ward_file):
    m = utia.load_utia(ward_file)
    assert m.isotropic is False
    t = np.radians(45.0)
    f0 = m.eval_angles(t, 0.0, t, 0.0)  # retro-reflection: half vector tilted along x
    f90 = m.eval_angles(t, np.pi / 2, t, np.pi / 2)  # same tilt along y
    assert not np.allclose(f0, f90, rtol=0.05)


@pytest.mark.parametrize(
    "data, msg",
    [
        (b"", "empty"),
        (b"\0" * 100, "truncated"),
        (np.zeros(utia.SHAPE).tobytes() + b"x", "trailing"),
        (np.full(utia.SHAPE, np.nan).tobytes(), "NaN"),
        (np.full(utia.SHAPE, -1.0).tobytes(), "negative"),
        (np.full(utia.SHAPE, np.inf).tobytes(), "infinite"),
    ],
)
def test_bad_files(tmp_path, data, msg):
    p = tmp_path / "bad.bin"
    p.write_bytes(data)
    with pytest.raises(ValueError, match=msg) as e:
        utia.read_utia_table(p)
    assert "\n" not in str(e.value)


def test_directory(tmp_path):
    with pytest.raises(ValueError, match="directory"):
        utia.read_utia_table(tmp_path)


def test_sources_sniff_bin(ward_file, tmp_path):
    from brdfkit import sources
    from brdfkit.measured.merl import MERLBRDF

    m = sources.load_measured(ward_file)
    assert isinstance(m, utia.UTIABRDF)
    assert isinstance(bk.model(str(ward_file)), utia.UTIABRDF)
    merl = tmp_path / "m.bin"
    bk.save_merl(bk.model("lambert"), merl)
    assert isinstance(bk.model(str(merl)), MERLBRDF)
    bad = tmp_path / "bad.bin"
    bad.write_bytes(b"\0" * 1000)
    with pytest.raises(ValueError):
        bk.model(str(bad))


def test_cli_eval_and_info(ward_file, cli):
    import json

    r = cli("eval", str(ward_file), "--wi", "30,0", "--wo", "45,180", "--json")
    assert r.returncode == 0, r.stderr
    m = utia.load_utia(ward_file)
    want = m.eval_angles(np.radians(30), 0.0, np.radians(45), np.pi)
    assert json.dumps(json.loads(r.stdout))  # valid JSON
    assert f"{want[0]:.4g}"[:4] in r.stdout
    bad = ward_file.parent / "short.bin"
    bad.write_bytes(b"\0" * 1000)
    r = cli("eval", str(bad), "--wi", "30,0", "--wo", "45,180")
    assert r.returncode != 0 and "Traceback" not in r.stderr


def test_fit_recovers_anisotropy(ward_file):
    # a UTIA table of an anisotropic Ward: the fit keeps alpha_x and alpha_y apart (untied)
    r = bk.fit("ward", str(ward_file))
    assert r.params["alpha_x"] == pytest.approx(0.25, rel=0.15)
    assert r.params["alpha_y"] == pytest.approx(0.6, rel=0.1)


def test_cli_info_says_anisotropic(ward_file, cli):
    r = cli("info", str(ward_file))
    assert r.returncode == 0, r.stderr
    assert "(anisotropic)" in r.stdout and "UTIA" in r.stdout


def test_missing_file_and_absurd_values(tmp_path):
    with pytest.raises(ValueError, match="no such file"):
        utia.read_utia_table(tmp_path / "nope.bin")
    p = tmp_path / "huge.bin"
    p.write_bytes(np.full(utia.SHAPE, 1e300).tobytes())
    with pytest.raises(ValueError, match="absurd"):
        utia.read_utia_table(p)
    with pytest.raises(ValueError, match="absurd"):
        utia.UTIABRDF(np.full(utia.SHAPE, 1e300))


def test_extrapolation_never_overflows():
    """The largest table values allowed, extrapolated above 75° (weights up to 2): clamped, finite."""
    m = utia.UTIABRDF(np.full(utia.SHAPE, utia.MAX_VALUE))
    v = m.eval_angles(np.radians(89.0), 0.3, np.radians(89.5), 2.0)
    assert np.isfinite(v).all() and (v == utia.MAX_VALUE).all()


_SPECIAL = [np.nan, np.inf, -np.inf, -1.0, -0.0, 0.0, 1e-300, 1e30, 1e300, 5e-324]


@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(edits=st.lists(st.tuples(st.integers(0, int(np.prod(utia.SHAPE)) - 1), st.sampled_from(_SPECIAL)),
                      max_size=4),
       raw_edits=st.lists(st.tuples(st.integers(0, utia.FILE_BYTES - 1), st.integers(0, 255)), max_size=4),
       length=st.one_of(st.none(), st.integers(0, utia.FILE_BYTES + 16)))
def test_fuzz_mutated_files(tmp_path_factory, edits, raw_edits, length):
    """Special values in the table, flipped bytes, wrong sizes: a model whose values are finite and
    non-negative, or one ValueError line; memory bounded by the file's size."""
    table = np.full(utia.SHAPE, 0.25).ravel()
    for i, v in edits:
        table[i] = v
    raw = bytearray(table.tobytes())
    for pos, byte in raw_edits:
        raw[pos] = byte
    if length is not None:
        raw = (raw + bytes(16))[:length]
    p = tmp_path_factory.mktemp("ufuzz") / "f.bin"
    p.write_bytes(bytes(raw))
    m, peak = load_or_one_line_error(bk.model, str(p))
    assert peak < 8 * utia.FILE_BYTES + (4 << 20)
    if m is not None:
        rng = np.random.default_rng(0)
        wi, wo = (_vec(rng.uniform(0, np.pi / 2, 64), rng.uniform(0, 2 * np.pi, 64)) for _ in range(2))
        v = m.eval(wi, wo)
        assert np.isfinite(v).all() and (v >= 0).all()
