"""``brdfkit.torch.eval(name, params, wi, wo)``: a model as a PyTorch autograd function (SPEC.md, "Gradients").

``params`` is a dict of parameter values as :func:`brdfkit.model` takes them. A continuous parameter
(scalar or RGB, the ones :meth:`BRDF.eval_grad` differentiates) may be a tensor: a scalar as a 0-d
tensor, an RGB one as a shape ``(3,)`` tensor (or a 0-d one: grey). Choices, bools and integers
(``distribution="ggx"``, ``fresnel="schlick"``, ``lobes=2``) are plain Python values in the same dict;
a tensor there is a ``ValueError``. ``wi`` and ``wo`` are tensors of shape ``(..., 3)``; the result is
``f`` of shape ``broadcast(wi, wo)``, as ``m.eval`` gives it (the forward pass is ``m.eval``), float32 for float32 directions.

The backward pass uses the model's exact derivatives, ``m.eval_grad(wi, wo, wrt=...)`` for the parameter
tensors that require grad (only those are computed), in the forward pass. Gradients flow to the parameter tensors only: ``eval_grad``
gives no derivative with respect to the directions, so ``wi`` and ``wo`` get ``None`` (a direction tensor
that requires grad is accepted; its ``.grad`` stays unset). Not twice differentiable. A model without
derivatives (a measured material, ``microfacet`` with ``multiscatter=True``) raises ``ValueError`` as
soon as a parameter requires grad. CPU tensors only; the values go through numpy.

Torch is imported on first use (``brdfkit`` itself never imports it); without it the call raises
``ImportError`` naming the extra, ``pip install brdfkit[torch]``.
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

_FN = None


def _torch():
    try:
        import torch
    except ImportError:
        raise ImportError("brdfkit.torch needs PyTorch: pip install brdfkit[torch]") from None
    return torch


def _function(torch):
    global _FN
    if _FN is not None:
        return _FN

    class _Eval(torch.autograd.Function):
        @staticmethod
        def forward(ctx, model, names, sizes, wi, wo, *values):
            a = wi.detach().cpu().numpy()
            b = wo.detach().cpu().numpy()
            want = list(ctx.needs_input_grad[5:])
            f = model.eval(a, b)  # the values are eval's (eval_grad's float32 f may differ in the last bits)
            if any(want):
                wrt = [n for n, w in zip(names, want) if w]  # only the derivatives the graph needs
                try:
                    _, grads = model.eval_grad(a, b, wrt=wrt)
                except ValueError as e:
                    raise ValueError(f"brdfkit.torch.eval: {e}") from None
                ctx.grads = [grads[n] if w else None for n, w in zip(names, want)]
            else:
                ctx.grads = [None] * len(values)
            ctx.sizes = sizes
            ctx.dtypes = [v.dtype for v in values]
            return torch.from_numpy(np.ascontiguousarray(f))

        @staticmethod
        @torch.autograd.function.once_differentiable
        def backward(ctx, gout):
            go = gout.detach().cpu().numpy()
            out = [None, None, None, None, None]
            for g, size, dt in zip(ctx.grads, ctx.sizes, ctx.dtypes):
                if g is None:
                    out.append(None)
                    continue
                if g.ndim == go.ndim:  # scalar parameter: (..., 3)
                    r = np.sum(go * g)
                else:  # rgb: (..., 3 out, 3 in)
                    r = np.einsum("no,noi->i", go.reshape(-1, 3), g.reshape(-1, 3, 3))
                    if size == 0:  # a 0-d tensor for an rgb parameter (grey): it sets every channel
                        r = r.sum()
                out.append(torch.as_tensor(np.asarray(r, dtype=np.float64)).to(dt))
            return tuple(out)

    _FN = _Eval
    return _FN


def _check_kind(model: str, k: str, v, p) -> None:
    """A tensor only for a continuous parameter, 0-d for a scalar (``p`` None: left to the model's checks)."""
    if p is None:
        return
    if p.kind not in ("scalar", "rgb"):
        raise ValueError(f"brdfkit.torch.eval: {model}: parameter '{k}' is not continuous ({p.kind}): "
                         f"pass it as a plain Python value, not a tensor")
    if p.kind == "scalar" and v.ndim != 0:
        raise ValueError(f"brdfkit.torch.eval: {model}: parameter '{k}' is a scalar: a 0-d tensor, "
                         f"got shape {tuple(v.shape)}")


def eval(name: str, params: Mapping[str, Any], wi, wo):  # noqa: A001 (the SPEC's name)
    """``f(wi, wo)`` of the model ``name`` with ``params`` as a differentiable torch tensor (module docstring)."""
    torch = _torch()
    from . import registry as _registry
    from .sources import model as _model

    if not isinstance(params, Mapping):
        raise TypeError(f"brdfkit.torch.eval: params must be a dict, got {type(params).__name__}")
    for what, t in (("wi", wi), ("wo", wo)):
        if not isinstance(t, torch.Tensor):
            raise TypeError(f"brdfkit.torch.eval: {what} must be a torch tensor, got {type(t).__name__}")
        if t.device.type != "cpu":
            raise ValueError(f"brdfkit.torch.eval: {what} is on {t.device}; CPU tensors only")
        if t.dtype not in (torch.float32, torch.float64):
            raise ValueError(f"brdfkit.torch.eval: {what} must be float32 or float64, got {t.dtype}")
        if t.ndim == 0 or t.shape[-1] != 3:
            raise ValueError(f"brdfkit.torch.eval: {what} must have shape (..., 3), got {tuple(t.shape)}")
    spec = {p.name: p for p in _registry.get(name).spec} if name in _registry.names() else {}
    plain: dict[str, Any] = {}
    names, sizes, values = [], [], []
    for k, v in params.items():
        if isinstance(v, torch.Tensor):
            if v.device.type != "cpu":
                raise ValueError(f"brdfkit.torch.eval: parameter '{k}' is on {v.device}; CPU tensors only")
            if v.ndim == 0:
                plain[k] = float(v.detach())
            elif v.shape == (3,):
                plain[k] = v.detach().cpu().numpy().astype(np.float64)
            else:
                raise ValueError(f"brdfkit.torch.eval: parameter '{k}' must be a 0-d or shape (3,) tensor, "
                                 f"got shape {tuple(v.shape)}")
            _check_kind(name, k, v, spec.get(k))
            names.append(k)
            sizes.append(v.ndim and 3)
            values.append(v)
        else:
            plain[k] = v
    m = _model(name, **plain)
    by = {p.name: p for p in m.spec}
    for k, v in zip(names, values):
        _check_kind(m.name, k, v, by.get(k))
    return _function(torch).apply(m, tuple(names), tuple(sizes), wi, wo, *values)


__all__ = ["eval"]
