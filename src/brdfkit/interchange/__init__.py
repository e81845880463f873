"""Interchange: reading other tools' material formats and writing ours into theirs.

* :mod:`.brdf_explorer` -- Disney BRDF Explorer's ``.brdf`` files (parameters + GLSL)
  as brdfkit models (:func:`brdfkit.load_brdf`).
* :mod:`.export` -- a model as a Mitsuba 3 BSDF, a MaterialX/OpenPBR document or a
  glTF binary (:func:`brdfkit.export`).
* :mod:`.notebook` -- how a model and a fit result show themselves in Jupyter.
"""
