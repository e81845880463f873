"""Two-lobe fits: a model class with a second specular lobe of the same form (Ngan et al. 2005)."""

from __future__ import annotations

from dataclasses import replace

from ..models.base import BRDF

#: parameters that belong to the diffuse part of a model (a second lobe has none)
DIFFUSE_PARAMS = ("kd", "rd")
_TWO_LOBE: dict[type, type] = {}


def two_lobe(cls: type[BRDF]) -> type[BRDF]:
    """``cls`` plus a second specular lobe of the same form (Ngan et al. 2005's two-lobe fits).

    The class's parameters are ``cls``'s plus a copy ``<name>_2`` of every fitted scalar/rgb
    parameter except the diffuse ones (:data:`DIFFUSE_PARAMS`); options (choices, bools) are
    shared; ties (``Param.tie``) carry over: ``alpha_y_2`` is tied to ``alpha_x_2``. ``eval`` is
    ``cls(params) + cls(params_2 with kd = rd = 0)``: the first term keeps the diffuse part, the
    second is one more lobe. (The Lafortune model has lobes of its own:
    ``fit(..., lobes=2)`` sets its ``lobes`` parameter instead.)
    """
    if cls in _TWO_LOBE:
        return _TWO_LOBE[cls]
    copied = [p for p in cls.spec if p.name not in DIFFUSE_PARAMS and p.kind in ("scalar", "rgb") and p.fit]
    copied_names = {p.name for p in copied}
    # a tie (Param.tie) carries over to the copies when its twin is copied too: alpha_y_2 → alpha_x_2
    second = tuple(replace(p, name=p.name + "_2", doc=f"{p.doc} (second lobe)",
                           tie=p.tie + "_2" if p.tie in copied_names else "") for p in copied)
    base_names = tuple(p.name for p in cls.spec)
    zero_diffuse = {p.name: 0.0 for p in cls.spec if p.name in DIFFUSE_PARAMS}

    class TwoLobe(BRDF):
        name = cls.name + "+lobe2"
        title = f"{cls.name} with a second specular lobe"
        reference = cls.reference
        isotropic = cls.isotropic
        spec = tuple(cls.spec) + second
        base = cls

        def _setup(self) -> None:
            p = self.params
            one = {k: p[k] for k in base_names}
            two = dict(one, **zero_diffuse, **{q.name[:-2]: p[q.name] for q in second})
            self.lobe1, self.lobe2 = cls(**one), cls(**two)

        def _eval(self, wi, wo, p):
            return self.lobe1.eval(wi, wo) + self.lobe2.eval(wi, wo)

    TwoLobe.__name__ = TwoLobe.__qualname__ = cls.__name__ + "TwoLobe"
    _TWO_LOBE[cls] = TwoLobe
    return TwoLobe


__all__ = ["two_lobe", "DIFFUSE_PARAMS"]
