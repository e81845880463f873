"""``select(cond, a, b)``: a choice between two values already computed, without a branch.

In Python it is ``a if cond else b``. Compiled, it is LLVM's ``select`` instruction. A conditional
expression compiles to a branch and a phi; LLVM then moves each value's computation into the arm
that uses it (a math call included), and a loop whose body holds a call in such an arm does not
vectorise (LLVM would need a masked vector variant of the call). With ``select`` both values stay
computed in the block that chooses between them, so a loop over pairs that calls ``exp`` or
``erfc`` on both sides still vectorises (HTSG's span, :mod:`brdfkit.models.htsg`). Both values must be
harmless where they are not chosen (finite arguments in every math function's domain), since both
are computed.
"""

from __future__ import annotations

from numba import types
from numba.extending import intrinsic, overload


def select(cond, a, b):
    """``a`` if ``cond`` else ``b``; compiled: LLVM's ``select`` (no branch)."""
    return a if cond else b


@intrinsic
def _select(typingctx, cond, a, b):
    ty = typingctx.unify_types(a, b)
    if ty is None or not isinstance(ty, (types.Float, types.Integer, types.Boolean)):
        return None
    sig = ty(cond, a, b)

    def codegen(context, builder, signature, args):
        c, x, y = args
        c = context.cast(builder, c, cond, types.boolean)
        return builder.select(c, context.cast(builder, x, a, ty), context.cast(builder, y, b, ty))

    return sig, codegen


@overload(select, jit_options={"cache": True})
def _select_overload(cond, a, b):
    def impl(cond, a, b):
        return _select(cond, a, b)

    return impl


__all__ = ["select"]
