"""Isotropic ties (issue 30): the pairs an anisotropic model shares one free value for when it is
fitted to isotropic data are declared on the model's own spec (``Param.tie``) and read from there."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from brdfkit import registry
from brdfkit.interchange.brdf_explorer import parse_brdf_file, parse_brdf_text
from brdfkit.measured import fit as F
from brdfkit.params import Param, isotropic_ties

DATA = Path(__file__).parent / "data"

#: the pairs fit.py hard-coded before the ties moved onto the specs (its ``_TIES`` and ``ISOTROPIC_TIES``)
OLD_TIES = (("alpha_x", "alpha_y"), ("nu", "nv"), ("n_u", "n_v"), ("alpha_u", "alpha_v"), ("m_x", "m_y"),
            ("cx_1", "cy_1"), ("cx_2", "cy_2"), ("cx_3", "cy_3"))
OLD_ISOTROPIC_TIES = OLD_TIES + tuple((a + "_2", b + "_2") for a, b in OLD_TIES[:5])


def _old_tied(cls, fixed=()):
    """The packer's ties as the hard-coded rule made them."""
    by_name = {p.name: p for p in cls.spec}
    if getattr(cls, "isotropic", True):
        return {}
    return {a: b for a, b in OLD_ISOTROPIC_TIES if a in by_name and b in by_name and a not in fixed
            and b not in fixed and by_name[a].fit and by_name[b].fit}


def _fitted_class(name, lobes):
    """The class fit(name, ..., lobes=lobes) fits (Lafortune's lobes=2 is its own parameter)."""
    cls = registry.get(name)
    if lobes == 2 and not any(p.name == "lobes" for p in cls.spec):
        cls = F.two_lobe(cls)
    return cls


@pytest.mark.parametrize("lobes", [1, 2])
@pytest.mark.parametrize("name", registry.names())
def test_spec_ties_are_the_old_hard_coded_pairs(name, lobes):
    cls = _fitted_class(name, lobes)
    names = {p.name for p in cls.spec}
    declared = set(isotropic_ties(cls.name, cls.spec).items())
    assert declared == {(a, b) for a, b in OLD_ISOTROPIC_TIES if a in names and b in names}
    assert F.ParamPacker(cls).tied == _old_tied(cls)


def test_the_anisotropic_models_declare_their_ties():
    ties = {n: isotropic_ties(n, registry.get(n).spec) for n in registry.names()}
    assert ties["ward"] == ties["microfacet"] == {"alpha_x": "alpha_y"}
    assert ties["ashikhmin-shirley"] == {"nu": "nv"}
    assert ties["lafortune"] == {"cx_1": "cy_1", "cx_2": "cy_2", "cx_3": "cy_3"}
    assert isotropic_ties("x", F.two_lobe(registry.get("ward")).spec) == {"alpha_x": "alpha_y",
                                                                         "alpha_x_2": "alpha_y_2"}
    assert all(not t for n, t in ties.items() if registry.get(n).isotropic)


@pytest.mark.parametrize("fixed", [{}, {"alpha_x": 0.3}, {"alpha_y": 0.3}])
def test_a_fixed_parameter_unties_the_pair(fixed):
    cls = registry.get("ward")
    packer = F.ParamPacker(cls, fixed)
    assert packer.tied == _old_tied(cls, fixed)
    assert ("alpha_y" in packer.free_names) == ("alpha_x" in fixed)
    assert F.ParamPacker(cls, tie_isotropic=False).tied == {}


def test_tied_parameters_take_one_value():
    packer = F.ParamPacker(registry.get("ashikhmin-shirley"))
    p = packer.params(packer.random_x(np.random.default_rng(0), 1)[0])
    assert p["nu"] == p["nv"] and "nv" not in packer.free_names


def test_brdf_file_ties_its_conventionally_named_pairs():
    ward = parse_brdf_file(DATA / "ward.brdf")
    assert {p.name: p.tie for p in ward.params} == {"kd": "", "ks": "", "alpha_x": "", "alpha_y": "alpha_x"}
    text = (DATA / "ward.brdf").read_text().replace("float alpha_x", "float n_u").replace("float alpha_y", "float n_v")
    text = text.replace("alpha_x", "n_u").replace("alpha_y", "n_v")
    assert isotropic_ties("f", parse_brdf_text(text, "as.brdf").params) == {"n_u": "n_v"}
    assert isotropic_ties("f", parse_brdf_file(DATA / "ggx.brdf").params) == {}


@pytest.mark.parametrize("kw", [dict(kind="rgb", default=0.5, tie="a"), dict(kind="scalar", default=0.5, tie="b")])
def test_a_tie_on_a_non_scalar_or_to_itself_is_refused(kw):
    with pytest.raises(TypeError, match="tie"):
        Param("b", **kw)


@pytest.mark.parametrize("spec, words", [
    ((Param("a", "scalar", 1.0), Param("b", "scalar", 1.0, tie="c")), "'c', which is not a parameter"),
    ((Param("a", "rgb", 1.0), Param("b", "scalar", 1.0, tie="a")), "same kind"),
    ((Param("a", "scalar", 1.0, tie="c"), Param("b", "scalar", 1.0, tie="a"), Param("c", "scalar", 1.0)),
     "tied itself"),
    ((Param("a", "scalar", 1.0), Param("b", "scalar", 1.0, tie="a"), Param("c", "scalar", 1.0, tie="a")),
     "both tied"),
])
def test_a_bad_tie_is_a_one_line_error_naming_the_model(spec, words):
    with pytest.raises(ValueError, match=words) as e:
        isotropic_ties("mymodel", spec)
    assert str(e.value).startswith("mymodel: ") and "\n" not in str(e.value)
