"""Example files shipped inside the package, so that they are found from any folder.

* ``scene.json``: a scene file (a Cook-Torrance teapot under two lights), the one
  ``brdfkit render --scene example`` renders;
* ``ggx.brdf``: a Disney BRDF Explorer shader (GGX microfacet with a diffuse term).

:func:`path` gives a file's path; on the command line::

    python -m brdfkit.examples               # the files, one path a line
    python -m brdfkit.examples ggx.brdf      # one file's path, e.g.
    brdfkit check "$(python -m brdfkit.examples ggx.brdf)" -p alpha=0.3

In a clone, ``docs/scene.json`` and ``tests/data/ggx.brdf`` are links to these files (one file,
one place).
"""

from __future__ import annotations

from pathlib import Path

FOLDER = Path(__file__).resolve().parent

FILES = ("scene.json", "ggx.brdf")
"""The example files, by name."""

SCENE = "example"
"""The name ``brdfkit render --scene`` takes for ``scene.json``."""


def path(name: str) -> Path:
    """The path of the shipped example file ``name`` (one of :data:`FILES`)."""
    if name not in FILES:
        raise ValueError(f"unknown example {name!r}; examples: {', '.join(FILES)}")
    return FOLDER / name


__all__ = ["FILES", "FOLDER", "SCENE", "path"]
