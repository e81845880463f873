"""The fitter's prepared evaluation (issue 10) gives the same residuals, bit for bit, as building
and evaluating the model every call, for every model the fitter fits and both engines."""

from __future__ import annotations

import numpy as np
import pytest

from brdfkit import engine, registry
from brdfkit.measured import fit as F

#: every registered analytic model, options the fitter is run with (bench_fit, CLI examples),
#: and the two-lobe forms (a wrapper without a kernel; Lafortune's own lobes)
CASES = [(n, {}, 1) for n in registry.names()] + [
    ("microfacet", {"distribution": "ggx", "fresnel": "schlick"}, 1),
    ("microfacet", {"distribution": "beckmann", "multiscatter": True}, 1),
    ("ward", {"normalization": "dur"}, 1),
    ("cook-torrance", {}, 2),
    ("lafortune", {}, 2),
]


def _cls(name, fixed, lobes):
    cls = registry.get(name)
    fixed = dict(fixed)
    if lobes == 2:
        if any(p.name == "lobes" for p in cls.spec):
            fixed["lobes"] = 2
        else:
            cls = F.two_lobe(cls)
    return cls, fixed


@pytest.fixture
def restore_engine():
    old = engine.engine()
    yield
    engine.set_engine(old)


@pytest.mark.parametrize("eng, n", [("compiled", 3000), ("compiled", 700), ("reference", 40)])
@pytest.mark.parametrize("name, fixed, lobes", CASES, ids=[f"{n}-{f}-{l}" for n, f, l in CASES])
def test_prepared_residuals_are_bit_identical(name, fixed, lobes, eng, n, restore_engine):
    cls, fixed = _cls(name, fixed, lobes)
    try:
        packer = F.ParamPacker(cls, fixed)
    except ValueError as e:  # a model the fitter cannot fit says so at once
        pytest.skip(str(e))
    if len(packer) == 0:
        pytest.skip("nothing free")
    engine.set_engine(eng)
    data = F.sample("merl/gold-metallic-paint", n=n, seed=7)
    rng = np.random.default_rng(11)
    pts = [packer.x_of(packer.fixed), *packer.random_x(rng, 3), packer.lb, packer.ub]
    for metric in ("ngan", "log"):
        T = F._transform(metric)
        new = F._residual_fn(packer, data, T, metric)
        old = F._residual_fn(packer, data, T, metric, prepared=False)
        for x in pts:
            a, b = new(x), old(x)
            assert a.dtype == b.dtype and a.shape == b.shape
            assert np.array_equal(a, b), f"{cls.name} {metric} at {x}: max diff {np.max(np.abs(a - b))}"
            assert np.any(a != 0)


@pytest.mark.parametrize("name", [n for n in registry.names()])
def test_unvalidated_model_equals_the_validated_one(name):
    packer = F.ParamPacker(registry.get(name))
    if len(packer) == 0:
        pytest.skip("nothing free")
    ev = F._PreparedEval(packer, F.sample("merl/gold-metallic-paint", n=64, seed=1))
    rng = np.random.default_rng(2)
    for x in [packer.lb, packer.ub, *packer.random_x(rng, 4)]:
        fast, ref = ev.model(x), packer.model(x)
        assert type(fast) is type(ref) and list(fast.params) == list(ref.params)
        assert fast.isotropic == ref.isotropic and list(fast.active_params()) == list(ref.active_params())
        for k, v in ref.params.items():
            assert np.array_equal(fast.params[k], v), k
            if isinstance(v, np.ndarray):
                assert not fast.params[k].flags.writeable
        if ref.kernel is not None:
            pf, cf = fast.kernel_args()
            pr, cr = ref.kernel_args()
            assert np.array_equal(pf, pr) and np.array_equal(cf, cr)


def test_microfacet_skips_revalidation_and_a_subclass_does_not_inherit_that():
    """microfacet declares from_valid_is_init beside its __init__ (it only resolves the alpha aliases),
    so the fitter builds it unvalidated; a subclass with an __init__ of its own is validated again."""
    cls = registry.get("microfacet")
    data = F.sample("merl/gold-metallic-paint", n=64, seed=1)
    assert F._PreparedEval(F.ParamPacker(cls), data).unvalidated

    class Sub(cls):
        def __init__(self, **params):
            super().__init__(**params)

    assert not F._PreparedEval(F.ParamPacker(Sub), data).unvalidated
    ani = F.ParamPacker(cls, tie_isotropic=False)
    ev = F._PreparedEval(ani, data)
    x = ani.x_of(dict(ani.fixed, alpha_x=0.1, alpha_y=0.4))
    fast, ref = ev.model(x), ani.model(x)
    assert fast.params["alpha"] is None and ref.params["alpha"] is None and not fast.isotropic


def test_a_value_outside_the_spec_raises_the_spec_error():
    packer = F.ParamPacker(registry.get("cook-torrance"))
    ev = F._PreparedEval(packer, F.sample("merl/gold-metallic-paint", n=64, seed=1))
    x = packer.x_of(packer.fixed)
    x[0] = np.nan
    with pytest.raises(ValueError, match=r"cook-torrance: parameter 'kd'\[r\] must be finite"):
        ev(x)


def test_bad_directions_are_refused_once_when_prepared():
    data = F.sample("merl/gold-metallic-paint", n=64, seed=1)
    data.wi[3] *= 1.01
    with pytest.raises(ValueError, match="ward: wi must be unit vectors"):
        F._PreparedEval(F.ParamPacker(registry.get("ward")), data)
