"""``eval_grad`` under the contract's property tests (hypothesis), every analytic model, compiled engine.

Random parameters over each model's declared ranges (test_contract's strategy, which reaches the
bounds), with the choices drawn from test_eval_grad's covering combinations (whose compiled twins that
file builds too), and test_contract's directions: uniform over the whole sphere, near-specular, equal,
both at one grazing elevation 10^e (e down to −40), and the special pairs (normal incidence, exactly at
the horizon, just below it, wi = −wo, ...). In float64 and float32:

* ``f`` is ``eval``'s value: bit for bit in float64 (the many-tangent twin is the kernel's own source,
  run on the same scalar path), within float32 rounding in float32 where the value is well conditioned;
* no derivative is NaN (one beyond the float range is ±inf, grad.py's docstring), and every derivative
  is 0 below the horizon;
* the arrays come back in the dtype that went in, in SPEC.md's shapes.

HTSG is left out, as in test_eval_grad (its compiled twins take minutes to compile cold); its
reference-engine gradient is tested there.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import brdfkit as bk
from test_contract import SETTINGS, _moderate, _model_or_reject, drawn_pairs, params_strategy
from test_eval_grad import ANALYTIC, REFERENCE_ONLY, _covering

MODELS = [n for n in ANALYTIC if n not in REFERENCE_ONLY]


def _check(m, wi, wo, dtype) -> None:
    wi, wo = np.asarray(wi, dtype=dtype), np.asarray(wo, dtype=dtype)
    where = f"{m!r} in {np.dtype(dtype).name}"
    f, grads = m.eval_grad(wi, wo)
    ref = m.eval(wi, wo)
    assert f.dtype == np.dtype(dtype) and f.shape == ref.shape, where
    if dtype == np.float64:
        np.testing.assert_array_equal(f, ref, err_msg=where)
    else:  # the float32 twin and its forward rebuild may round (and fuse) differently: a few ulps where
        # the value is well conditioned (test_contract's float32 pairs: z >= 0.1, f in [1e-3, 1e3]; at
        # grazing pairs Oren-Nayar's tan β · cos(φi − φo) amplifies one rounding of cos to 0.3 %)
        ok = _moderate(wi, wo, ref.astype(np.float64))
        np.testing.assert_allclose(f[ok], ref[ok], rtol=1e-5, err_msg=where)
    below = (wi[:, 2] <= 0) | (wo[:, 2] <= 0)
    assert grads, where
    for k, g in grads.items():
        assert g.dtype == np.dtype(dtype), f"{where}: d/d{k} is {g.dtype}"
        assert g.shape in ((len(wi), 3), (len(wi), 3, 3)), f"{where}: d/d{k} has shape {g.shape}"
        nan = np.isnan(g).reshape(len(wi), -1).any(axis=1)
        if nan.any():
            i = int(np.argmax(nan))
            raise AssertionError(f"{where}: d/d{k} is NaN at wi={wi[i].tolist()}, wo={wo[i].tolist()}")
        nz = below & (g != 0).reshape(len(wi), -1).any(axis=1)
        if nz.any():
            i = int(np.argmax(nz))
            raise AssertionError(f"{where}: d/d{k} != 0 below the horizon at wi={wi[i].tolist()}, wo={wo[i].tolist()}")


@pytest.mark.parametrize("name", MODELS)
def test_gradient_random_parameters_and_directions(name):
    cls = bk.registry.get(name)
    combos = _covering(cls)

    @SETTINGS
    @given(params=params_strategy(cls.spec), choices=st.sampled_from(combos), seed=st.integers(0, 2**32 - 1),
           grazing=st.lists(st.tuples(st.floats(0, 360), st.floats(0, 360), st.floats(-40.0, -1.0)), max_size=4))
    def run(params, choices, seed, grazing):
        params = {**params, **choices}
        if "multiscatter" in params:
            params["multiscatter"] = False  # no gradient with it (test_eval_grad)
        m = _model_or_reject(name, params)
        wi, wo = drawn_pairs(seed, grazing=grazing)
        _check(m, wi, wo, np.float64)
        _check(m, wi, wo, np.float32)

    run()
