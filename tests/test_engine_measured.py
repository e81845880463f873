"""The measured materials' kernels (Neural-BRDF network, MERL nearest and trilinear lookup): compiled
engine vs the same source run as the reference, and vs an independent numpy evaluation."""

from __future__ import annotations

import numpy as np
import pytest

import brdfkit as bk
from brdfkit import engine
from brdfkit.geometry import random_unit_vectors
from brdfkit.measured.merl import MERLBRDF, SHAPE, symmetric_half_diff
from brdfkit.measured.nbrdf import SETS, materials


def _pairs(n, seed):
    rng = np.random.default_rng(seed)
    wi = random_unit_vectors(n, rng)
    wo = random_unit_vectors(n, rng, hemisphere=False)
    wo[: n // 2, 2] = np.abs(wo[: n // 2, 2])
    return wi, wo


def _both(m, wi, wo):
    old = engine.engine()
    try:
        engine.set_engine("compiled")
        c64, c32 = m.eval(wi, wo), m.eval(wi.astype(np.float32), wo.astype(np.float32))
        engine.set_engine("reference")
        r64, r32 = m.eval(wi, wo), m.eval(wi.astype(np.float32), wo.astype(np.float32))
    finally:
        engine.set_engine(old)
    return c64, c32, r64, r32


def _close(a, b, rtol):
    np.testing.assert_allclose(a, b, rtol=rtol, atol=0)


def _one_per_set():
    names = materials()
    return [next(n for n in names if n.startswith(s + "/")) for s in SETS] + ["merl/gold-metallic-paint"]


@pytest.mark.parametrize("name", _one_per_set())
def test_nbrdf_compiled_equals_reference_and_numpy(name):
    m = bk.material(name)
    wi, wo = _pairs(300, 5)
    c64, c32, r64, r32 = _both(m, wi, wo)
    _close(c64, r64, 1e-12)
    _close(c32, r32, 2.0**-23)
    # independently: the network as numpy matrix products on the same folded angles
    th, td, pd = symmetric_half_diff(wi, wo)
    w1, b1, w2, b2, w3, b3 = (a.astype(np.float64) for a in m._layers)
    sd = np.sin(td)
    x = np.stack([np.sin(th), 0 * th, np.cos(th), sd * np.cos(pd), sd * np.sin(pd), np.cos(td)], axis=-1)
    a = np.maximum(x @ w1 + b1, 0)
    a = np.maximum(a @ w2 + b2, 0)
    f = np.maximum(np.expm1(np.minimum(a @ w3 + b3, 80.0)), 0)
    up = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    np.testing.assert_allclose(c64[up], f[up], rtol=1e-11, atol=1e-14)
    assert np.all(c64[~up] == 0)


@pytest.fixture(scope="module")
def table():
    rng = np.random.default_rng(3)
    t = rng.random((3,) + SHAPE)
    t[1, :, :, ::5] = -1.0  # missing bins (in one channel: the whole corner counts as missing)
    t[:, 80:, 80:] = -1.0
    return t


@pytest.mark.parametrize("interp", ["nearest", "trilinear"])
def test_merl_compiled_equals_reference(table, interp):
    m = MERLBRDF(table, interpolation=interp)
    wi, wo = _pairs(200, 9)
    c64, c32, r64, r32 = _both(m, wi, wo)
    _close(c64, r64, 1e-12)
    _close(c32, r32, 2.0**-23)
    assert np.all(c64 >= 0)


def test_merl_nearest_is_the_table_value_at_the_bin(table):
    """Independent of the kernel: numpy indexing with MERL's reader formulas (floor, clamp)."""
    m = MERLBRDF(table)
    wi, wo = _pairs(400, 10)
    up = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    th, td, pd = symmetric_half_diff(wi[up], wo[up])
    i = np.clip(np.floor(np.sqrt(th / (np.pi / 2)) * 90), 0, 89).astype(int)
    j = np.clip(np.floor(td / (np.pi / 2) * 90), 0, 89).astype(int)
    k = np.clip(np.floor(pd / np.pi * 180), 0, 179).astype(int)
    expect = np.maximum(np.moveaxis(table[:, i, j, k], 0, -1), 0)
    np.testing.assert_array_equal(m.eval(wi[up], wo[up]), expect)
