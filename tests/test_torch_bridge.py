"""``brdfkit.torch.eval`` (SPEC.md, "Gradients"): a model as a PyTorch autograd function.

gradcheck (float64) against torch's own finite differences for several models, with scalar, anisotropic
and RGB parameters; the forward values equal ``m.eval``'s exactly, in float64 and float32; a small Adam
loop recovers a model's parameters from its own values; bad input raises a one-line error.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

# PyPI's Linux torch brings triton, which a torch.optim optimiser imports when it is built (through
# torch._dynamo); triton's bundled LLVM segfaults a process into which Mesa's llvmpipe (the OpenGL of
# the rendering tests that may run earlier in this worker) has already loaded its own LLVM. Torch on
# the CPU does not need triton: it is hidden here, as uninstalling it would (docs/api.md, "PyTorch").
sys.modules.setdefault("triton", None)
torch = pytest.importorskip("torch", reason="PyTorch not installed (the optional extra brdfkit[torch])")

import brdfkit as bk  # noqa: E402
from brdfkit import torch as bt  # noqa: E402
from brdfkit.geometry import random_unit_vectors  # noqa: E402


def _pairs(n=12, seed=3, dtype=torch.float64):
    """Upper-hemisphere pairs, half near the mirror direction (where the lobes are)."""
    rng = np.random.default_rng(seed)
    wi = random_unit_vectors(n, rng)
    wo = random_unit_vectors(n, rng)
    wi[:, 2] = np.abs(wi[:, 2]) + 0.05
    wo[:, 2] = np.abs(wo[:, 2]) + 0.05
    k = n // 2
    wi[:k] = np.stack([-wo[:k, 0], -wo[:k, 1], wo[:k, 2]], -1) + rng.normal(size=(k, 3)) * 0.1
    wi /= np.linalg.norm(wi, axis=-1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=-1, keepdims=True)
    return torch.from_numpy(wi).to(dtype), torch.from_numpy(wo).to(dtype)


def _t(x):
    return torch.tensor(x, dtype=torch.float64, requires_grad=True)


CASES = [
    ("microfacet", {"alpha": _t(0.3), "f0": _t([0.9, 0.6, 0.3]), "kd": _t([0.1, 0.2, 0.05])},
     {"distribution": "ggx", "fresnel": "schlick"}),
    ("ward", {"alpha_x": _t(0.15), "alpha_y": _t(0.4), "kd": _t([0.3, 0.2, 0.1]), "ks": _t(0.2)}, {}),
    ("cook-torrance", {"m": _t(0.25), "ks": _t([0.4, 0.5, 0.6]), "ior": _t([1.4, 1.5, 1.6])}, {}),
    ("lafortune", {"cx_1": _t(-0.9), "cz_1": _t(0.8), "n_1": _t(15.0), "ks_1": _t([0.5, 0.4, 0.3])}, {}),
]


@pytest.mark.parametrize("name,tensors,plain", CASES, ids=[c[0] for c in CASES])
def test_gradcheck(name, tensors, plain):
    wi, wo = _pairs()
    keys = list(tensors)

    def f(*vals):
        return bt.eval(name, {**plain, **dict(zip(keys, vals))}, wi, wo)

    assert torch.autograd.gradcheck(f, tuple(tensors[k] for k in keys), eps=1e-6, atol=1e-6, rtol=1e-5)


@pytest.mark.parametrize("dtype", [torch.float64, torch.float32])
def test_forward_is_eval(dtype):
    wi, wo = _pairs(dtype=dtype)
    params = {"alpha_x": _t(0.15), "alpha_y": _t(0.4), "kd": _t([0.3, 0.2, 0.1]), "ks": _t(0.2)}
    f = bt.eval("ward", params, wi, wo)
    m = bk.model("ward", alpha_x=0.15, alpha_y=0.4, kd=(0.3, 0.2, 0.1), ks=0.2)
    ref = m.eval(wi.numpy(), wo.numpy())
    assert f.dtype == dtype and f.shape == wi.shape
    assert np.array_equal(f.detach().numpy(), ref)
    f.sum().backward()  # float32 directions, float64 parameters: gradients in the parameters' dtype
    assert params["ks"].grad.dtype == torch.float64 and torch.isfinite(params["ks"].grad)


def test_broadcast_and_grey_rgb():
    """(n, 1, 3) against (1, k, 3) directions give (n, k, 3), as eval does; a 0-d tensor for an RGB
    parameter (grey) gets the derivative summed over its channels."""
    wi, wo = _pairs(6)
    kd = _t(0.3)
    f = bt.eval("lambert", {"kd": kd}, wi[:, None, :], wo[None, :4, :])
    assert f.shape == (6, 4, 3)
    f.sum().backward()
    assert kd.grad.item() == pytest.approx(6 * 4 * 3 / np.pi, rel=1e-12)  # f = kd/π everywhere above


def test_recovers_parameters():
    """Adam from a wrong start recovers microfacet's alpha and diffuse colour from the model's own values
    (to 1e-3)."""
    wi, wo = _pairs(64, seed=7)
    fixed = {"fresnel": "schlick", "f0": (0.9, 0.7, 0.4)}
    target = torch.from_numpy(bk.model("microfacet", alpha=0.25, kd=(0.2, 0.4, 0.1), **fixed)
                              .eval(wi.numpy(), wo.numpy()))
    alpha, kd = _t(0.5), _t([0.5, 0.5, 0.5])
    opt = torch.optim.Adam([alpha, kd], lr=0.02)
    for _ in range(400):
        opt.zero_grad()
        f = bt.eval("microfacet", {**fixed, "alpha": alpha, "kd": kd}, wi, wo)
        loss = ((torch.log1p(f) - torch.log1p(target)) ** 2).mean()
        loss.backward()
        opt.step()
        with torch.no_grad():
            alpha.clamp_(1e-3, 1.0)
            kd.clamp_(0.0, 1.0)
    assert alpha.item() == pytest.approx(0.25, abs=1e-3)
    assert np.allclose(kd.detach().numpy(), [0.2, 0.4, 0.1], atol=1e-3)


def test_no_grad_to_directions():
    wi, wo = _pairs(4)
    wi.requires_grad_(True)
    ks = _t(0.2)
    bt.eval("ward", {"ks": ks}, wi, wo).sum().backward()
    assert wi.grad is None and ks.grad is not None


@pytest.mark.parametrize("name,params,match", [
    ("no-such-model", {}, "unknown model"),
    ("ward", {"foo": _t(1.0)}, "unknown parameter 'foo'"),
    ("ward", {"alpha_x": _t([0.1, 0.2])}, "0-d or shape \\(3,\\) tensor"),
    ("ward", {"alpha_x": _t([0.1, 0.2, 0.3])}, "is a scalar"),
    ("ward", {"normalization": torch.tensor(1.0)}, "not continuous"),
    ("ward", {"alpha_x": _t(2.0)}, "out of range"),
    ("microfacet", {"multiscatter": True, "alpha": _t(0.3)}, "no gradient"),
])
def test_bad_input(name, params, match):
    wi, wo = _pairs(4)
    with pytest.raises(ValueError, match=match):
        bt.eval(name, params, wi, wo)


def test_bad_directions():
    wi, wo = _pairs(4)
    with pytest.raises(ValueError, match="shape \\(..., 3\\)"):
        bt.eval("lambert", {}, wi[:, :2], wo)
    with pytest.raises(TypeError, match="torch tensor"):
        bt.eval("lambert", {}, wi.numpy(), wo)
    with pytest.raises(ValueError, match="unit"):
        bt.eval("lambert", {}, 2 * wi, wo)
