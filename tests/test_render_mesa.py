"""The renderer's fixed-function path against Mesa's own legacy OpenGL (OSMesa, GL_SMOOTH / GL_FLAT).

Same mesh, same projection and modelview, same lights, no antialiasing: a
Gouraud render of a sphere in the seed's gold must match Mesa's GL_SMOOTH
render within 2/255 on interior pixels, and the flat render Mesa's GL_FLAT.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage

from brdfkit import opengl
from brdfkit.render import make_scene, render

import _mesa_reference as mesa

LIGHTS = [
    opengl.Light(position=(-2.0, 2.5, 3.0, 1.0), diffuse=(1, 1, 1), specular=(1, 1, 1), ambient=(0.1, 0.1, 0.1),
                 quadratic_attenuation=0.02),
    opengl.Light(position=(1.0, -0.5, 1.0, 0.0), diffuse=(0.3, 0.3, 0.5), specular=(0.5, 0.5, 0.5)),
]


def _compare(shading: str, mesh: dict, local_viewer: bool) -> tuple[float, int]:
    scene = make_scene(
        mesh=mesh,
        material="gold",
        shading=shading,
        size=(128, 128),
        camera={"eye": [0.3, 0.8, 3.4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 40},
        lights=LIGHTS,
        light_model={"ambient": [0.2, 0.2, 0.2], "local_viewer": local_viewer},
        antialias=False,
    )
    ours = render(scene).uint8
    m = scene.mesh
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "mesa.npy"
        mesa.call(
            {
                "mode": "render",
                "width": 128,
                "height": 128,
                "projection": scene.projection.tolist(),
                "modelview": scene.modelview.tolist(),
                "positions": m.positions.tolist(),
                "normals": m.normals.tolist(),
                "faces": m.faces.tolist(),
                "material": mesa.as_json(scene.material),
                "lights": [mesa.as_json(L) for L in scene.lights],
                "light_model": mesa.as_json(scene.light_model),
                "shade_model": "smooth" if shading == "gouraud" else "flat",
                "background": [0, 0, 0, 1],
                "out": str(out),
            }
        )
        ref = np.load(out)
    cover_ours = ours[..., :3].max(-1) > 0
    cover_ref = ref[..., :3].max(-1) > 0
    # the same pixels are covered (same rasteriser rules), up to a few edge pixels
    assert np.count_nonzero(cover_ours != cover_ref) <= 8
    interior = ndimage.binary_erosion(cover_ours & cover_ref, iterations=2)
    assert interior.sum() > 1500
    diff = np.abs(ours[..., :3].astype(int) - ref[..., :3].astype(int))[interior]
    return int(diff.max()), int(interior.sum())


@pytest.mark.parametrize("local_viewer", [False, True])
def test_gouraud_matches_mesa_gl_smooth(local_viewer):
    worst, n = _compare("gouraud", {"builtin": "sphere", "segments": 20, "rings": 10}, local_viewer)
    assert worst <= 2, f"max difference {worst}/255 over {n} interior pixels"


def test_flat_matches_mesa_gl_flat():
    worst, n = _compare("flat", {"builtin": "sphere", "segments": 20, "rings": 10}, False)
    assert worst <= 2, f"max difference {worst}/255 over {n} interior pixels"


def test_gouraud_teapot_matches_mesa():
    worst, n = _compare("gouraud", {"builtin": "teapot", "subdivisions": 4}, False)
    assert worst <= 2, f"max difference {worst}/255 over {n} interior pixels"
