"""Measured BRDFs: the MERL format, 159 built-in measured materials, and fitting analytic models.

>>> import brdfkit as bk
>>> gold = bk.material("merl/gold-metallic-paint")      # a model like any other
>>> bk.save_merl(gold, "gold.binary"); m = bk.load_merl("gold.binary")
>>> r = bk.fit("ward", m); r.params, r.error
"""

from __future__ import annotations

from .merl import MERLBRDF, MeasuredBRDF, load_merl, save_merl, tabulate
from .nbrdf import NeuralBRDF, material, materials


# fitting (scipy) lives in the submodule brdfkit.measured.fit: ``from brdfkit.measured.fit import fit``

__all__ = ["MERLBRDF", "MeasuredBRDF", "NeuralBRDF", "load_merl", "save_merl", "tabulate", "material", "materials"]
