"""The SPEC contract tests of ``test_contract.py``, run again on the reference engine.

``test_contract.py`` runs on the default (compiled) engine. The same property
tests — hypothesis-drawn parameters and directions, every parameter at its
bounds, special configurations (exact horizon, grazing, wi == wo, mirror,
wi == -wo), float32 vs float64, broadcasting — are collected here a second time
with ``bk.set_engine("reference")`` in force, so both engines meet the contract
(no NaN, Inf or negative values, zero below the horizon, dtypes and shapes).
"""

from __future__ import annotations

import pytest

from brdfkit import engine

# Re-exported test functions are collected (with their parametrisation) in this module,
# where the autouse fixture below switches the engine around each of them.
from test_contract import (  # noqa: F401
    test_all_parameters_at_one_end,
    test_broadcasting_matches_pairwise,
    test_defaults_special_and_random_directions,
    test_each_parameter_at_its_bounds,
    test_float32_close_to_float64_at_defaults,
    test_float32_close_to_float64_random_parameters,
    test_isotropic_models_ignore_a_common_rotation,
    test_random_parameters_and_directions,
)


@pytest.fixture(autouse=True)
def _reference_engine():
    old = engine.engine()
    engine.set_engine("reference")
    try:
        yield
    finally:
        engine.set_engine(old)


def test_this_module_runs_on_the_reference_engine():
    assert engine.engine() == "reference"
