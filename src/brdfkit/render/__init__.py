"""Headless OpenGL rendering (moderngl, EGL): meshes, cameras, flat/Gouraud/Phong shading, images.

>>> from brdfkit import render
>>> scene = render.make_scene(mesh="teapot", material={"model": "cook-torrance", "params": {"m": 0.3}})
>>> frame = render.render(scene)
>>> frame.save("teapot.png")

See :mod:`brdfkit.render.renderer` (the pipeline), :mod:`brdfkit.render.scene`
(scene files), :mod:`brdfkit.render.image` (tone mapping, PNG/EXR),
:mod:`brdfkit.render.meshes` (sphere, torus, Utah teapot, OBJ/PLY) and
:mod:`brdfkit.render.glsl` (the models' GLSL).
"""

from __future__ import annotations

from .camera import look_at, perspective
from .meshes import Mesh, builtin, load_mesh, sphere, teapot, torus
from .renderer import BACKENDS, SHADINGS, Renderer, Scene, default_renderer, render_linear
from .scene import Frame, Look, default_look, load_scene, make_scene, render, scene_from_json

__all__ = [
    "BACKENDS",
    "SHADINGS",
    "Frame",
    "Look",
    "Mesh",
    "Renderer",
    "Scene",
    "builtin",
    "default_look",
    "default_renderer",
    "load_mesh",
    "load_scene",
    "look_at",
    "make_scene",
    "perspective",
    "render",
    "render_linear",
    "scene_from_json",
    "sphere",
    "teapot",
    "torus",
]
