"""Smoke tests of the package skeleton: registry, parameter validation, eval contract."""

import numpy as np
import pytest

import brdfkit as bk


def test_lambert_is_kd_over_pi():
    m = bk.model("lambert", kd=[0.1, 0.2, 0.3])
    f = m.eval(np.array([0.0, 0.0, 1.0]), np.array([0.6, 0.0, 0.8]))
    np.testing.assert_allclose(f, np.array([0.1, 0.2, 0.3]) / np.pi, rtol=1e-15)


def test_below_horizon_is_zero():
    m = bk.model("lambert")
    f = m.eval(np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]]), np.array([0.0, 0.0, 1.0]))
    assert f[0, 0] > 0 and np.all(f[1:] == 0)


def test_unknown_model_names_choices():
    with pytest.raises(ValueError, match="valid models: .*lambert"):
        bk.model("nope")


@pytest.mark.parametrize("bad", [2.0, -0.1, float("nan"), float("inf")])
def test_out_of_range_parameter(bad):
    with pytest.raises(ValueError, match="kd"):
        bk.model("lambert", kd=bad)
