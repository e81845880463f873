"""Fortran-ordered ``(n, 3)`` directions give a Fortran-ordered result at every size, under both engines
(README: "the result comes back in the same order"), with the values of the same directions in rows."""

from __future__ import annotations

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.engine import driver
from brdfkit.geometry import random_unit_vectors
from brdfkit.models.base import BRDF
from brdfkit.params import kd_param

#: around one chunk (the compiled engine's structure-of-arrays driver starts above it), and several chunks
SIZES = [1, 7, driver.CHUNK - 1, driver.CHUNK, driver.CHUNK + 1, 3 * driver.CHUNK + 5]
#: the compiled engine also on a large call (the reference engine runs ~10 µs per pair: kept to SIZES)
LARGE = 1 << 16


@pytest.fixture
def engine_named(request):
    old = bk.engine()
    bk.set_engine(request.param)
    yield request.param
    bk.set_engine(old)


def _pair(n: int, dtype, seed: int = 3) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed + n)
    return random_unit_vectors(n, rng).astype(dtype), random_unit_vectors(n, rng).astype(dtype)


def _check(m, n: int, dtype) -> None:
    wi, wo = _pair(n, dtype)
    want = m.eval(wi, wo)
    got = m.eval(np.asfortranarray(wi), np.asfortranarray(wo))
    assert got.shape == (n, 3) and got.dtype == dtype
    assert got.flags.f_contiguous, (n, dtype)
    if dtype == np.float64 or bk.engine() == "reference" or not driver.runs_soa(n, m.kernel_args()[0]):
        np.testing.assert_array_equal(got, want)  # the same rows computation, copied to Fortran order
    else:  # the structure-of-arrays loop may fuse float32 multiply-adds differently (1 ulp on a few values)
        np.testing.assert_allclose(got, want, rtol=1e-6, atol=0)


@pytest.mark.parametrize("engine_named", ["compiled", "reference"], indirect=True)
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("n", SIZES)
def test_fortran_ordered_input_comes_back_fortran_ordered(engine_named, dtype, n):
    _check(bk.model("microfacet", distribution="ggx", fresnel="conductor", alpha=0.3), n, dtype)


@pytest.mark.parametrize("engine_named", ["compiled"], indirect=True)
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_fortran_ordered_large_call_comes_back_fortran_ordered(engine_named, dtype):
    _check(bk.model("microfacet", distribution="ggx", fresnel="conductor", alpha=0.3), LARGE, dtype)


@pytest.mark.parametrize("engine_named", ["compiled", "reference"], indirect=True)
@pytest.mark.parametrize("n", [7, driver.CHUNK + 1])
def test_rows_and_other_layouts_still_come_back_as_rows(engine_named, n):
    """Only a pair of Fortran-ordered arrays changes the result's order: rows, a mix, or broadcast
    directions give C-ordered results as before."""
    m = bk.model("lambert")
    wi, wo = _pair(n, np.float64)
    assert m.eval(wi, wo).flags.c_contiguous
    assert m.eval(np.asfortranarray(wi), wo).flags.c_contiguous
    assert m.eval(wi[:1], wo).flags.c_contiguous


class _NumpyOnly(BRDF):
    """A model without a kernel (the numpy fallback), as a third-party model may be written."""

    name = "_numpy_only_fortran"
    spec = (kd_param(0.5),)

    def _eval(self, wi, wo, p):
        return p["kd"] / np.pi * (1 + 0 * wi[..., :1])


@pytest.mark.parametrize("engine_named", ["compiled", "reference"], indirect=True)
@pytest.mark.parametrize("n", [7, driver.CHUNK + 1])
def test_a_model_without_a_kernel_also_keeps_fortran_order(engine_named, n):
    m = _NumpyOnly(kd=(0.1, 0.2, 0.3))
    wi, wo = _pair(n, np.float32)
    got = m.eval(np.asfortranarray(wi), np.asfortranarray(wo))
    assert got.flags.f_contiguous and got.dtype == np.float32
    np.testing.assert_array_equal(got, m.eval(wi, wo))
