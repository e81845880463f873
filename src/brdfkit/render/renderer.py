"""Headless OpenGL rendering with moderngl: flat, Gouraud and Phong shading of triangle meshes.

The context is an EGL standalone context (Mesa's llvmpipe on a machine
without a GPU, the GPU's driver where there is one), created once per
process. A frame is drawn into a float32 RGBA framebuffer (4× MSAA when
``antialias``), with the depth test on and no face culling, and read back as
*linear* RGBA: premultiplied colour and coverage alpha, top row first.
:mod:`brdfkit.render.image` turns that into a picture.

Shading modes
-------------
``flat``     lighting per vertex, the triangle takes its provoking (last)
             vertex's colour — OpenGL's ``GL_FLAT``.
``gouraud``  lighting per vertex in the vertex shader, colour interpolated —
             OpenGL's ``GL_SMOOTH``.
``phong``    normal (and tangent) interpolated, lighting per fragment.

Materials are an :class:`brdfkit.opengl.Material` (OpenGL's fixed-function
equation, ``shaders/opengl_fixed.glsl``) or any registered BRDF (its GLSL
file through :mod:`brdfkit.render.glsl`, lit by ``shaders/pipeline_brdf.glsl``).

Backends
--------
``glsl``   all lighting on the GPU (or llvmpipe) in GLSL — the default.
``numpy``  the same lighting evaluated by the numpy reference
           (:mod:`brdfkit.render.lighting`, the models' ``eval``): per vertex
           for flat/Gouraud (the colours become a vertex attribute), per pixel
           for Phong (OpenGL rasterises a G-buffer of eye-space position,
           normal and tangent; antialiasing is then 2×2 supersampling). Slow,
           but independent of the GLSL, and usable for a model without a
           GLSL file.
``auto``   ``glsl`` when the material has GLSL, else ``numpy``.

Image-based lighting
--------------------
A scene with an ``environment`` (:mod:`brdfkit.render.environment`) is lit by it
instead of the lights: ``shaders/ibl.glsl`` estimates the reflected radiance per
fragment with multiple importance sampling of the BRDF and of the map, in passes of
``IBL_SPP_PER_PASS`` samples accumulated up to ``scene.samples``; pixels the mesh
does not cover show the map (``visible``). Its ``numpy`` backend is the brute-force
integral of :func:`brdfkit.render.ibl.reference_shade` over every texel.

Measured materials (a MERL table, a built-in Neural-BRDF material) have GLSL
too: ``shaders/measured.glsl`` looks the MERL table up in a 3D texture
(uploaded once per material and kept in a small cache; a Neural-BRDF material
is first tabulated at the MERL bin centres, about 2 s). Their ``numpy``
backend evaluates the model itself (for a Neural-BRDF material: the network,
not the table).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from .. import opengl
from ..geometry import normalize
from ..opengl import Light, LightModel
from .meshes import Mesh
from .context import EGLCurrent as _EGLCurrent, context_info, create_context

SHADINGS = ("flat", "gouraud", "phong")
BACKENDS = ("auto", "glsl", "numpy")
MSAA_SAMPLES = 4


@dataclass
class Scene:
    """Everything one frame needs. Matrices are row-major, applied to column vectors (OpenGL's convention)."""

    mesh: Mesh
    projection: np.ndarray
    modelview: np.ndarray
    size: tuple[int, int] = (512, 512)
    lights: Sequence[Light] = field(default_factory=lambda: [Light()])
    light_model: LightModel = field(default_factory=LightModel)
    material: Any = field(default_factory=lambda: opengl.MATERIALS["gold"])
    shading: str = "phong"
    background: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    antialias: bool = True
    environment: Any = None  # an environment.Environment: image-based lighting instead of the lights
    samples: int = 64  # samples per pixel of the image-based lighting (each one BRDF + one environment sample)

    def __post_init__(self) -> None:
        if self.shading not in SHADINGS:
            raise ValueError(f"shading must be one of {', '.join(SHADINGS)}; got {self.shading!r}")
        w, h = (int(x) for x in self.size)
        if not (1 <= w <= 8192 and 1 <= h <= 8192):
            raise ValueError(f"size must be two integers in [1, 8192], got {self.size!r}")
        self.size = (w, h)
        self.projection = np.asarray(self.projection, dtype=np.float64).reshape(4, 4)
        self.modelview = np.asarray(self.modelview, dtype=np.float64).reshape(4, 4)
        self.lights = list(self.lights)
        if len(self.lights) > opengl.MAX_LIGHTS:
            raise ValueError(f"at most {opengl.MAX_LIGHTS} lights are supported, got {len(self.lights)}")
        bg = np.asarray(self.background, dtype=np.float64).reshape(-1)
        if bg.size == 3:
            bg = np.append(bg, 1.0)
        if bg.size != 4 or not np.all((bg >= 0) & (bg <= 1)):
            raise ValueError(f"background must be RGB or RGBA in [0, 1], got {self.background!r}")
        self.background = tuple(float(x) for x in bg)  # type: ignore[assignment]
        if self.environment is not None:
            from .environment import Environment, check_samples

            if not isinstance(self.environment, Environment):
                raise ValueError("environment must be an Environment (see brdfkit.render.environment)")
            self.samples = check_samples(self.samples)
            if self.is_opengl:
                raise ValueError("environment lighting needs a BRDF material (a model or a measured one), not an OpenGL material")
            if self.shading != "phong":
                raise ValueError(f"environment lighting is per pixel: use shading 'phong', not {self.shading!r}")

    @property
    def is_opengl(self) -> bool:
        return isinstance(self.material, opengl.Material)


def _read_shader(name: str) -> str:
    """A pipeline shader's text; cached (re-read only when the file changes), as this runs per frame."""
    from .glsl import shader_file

    return shader_file(name)


def _normal_matrix(mv: np.ndarray) -> np.ndarray:
    m = mv[:3, :3]
    try:
        return np.linalg.inv(m).T
    except np.linalg.LinAlgError:
        raise ValueError("modelview's upper 3x3 is singular: normals cannot be transformed") from None


def has_glsl(material: Any) -> bool:
    if isinstance(material, opengl.Material):
        return True
    try:
        from . import glsl

        return bool(glsl.has_shader(material))
    except (ImportError, ValueError):  # no GLSL harness, or not a registered model (e.g. measured data)
        return False


class Renderer:
    """A headless OpenGL context with cached programs. :func:`default_renderer` shares one per process."""

    def __init__(self) -> None:
        import moderngl

        self.moderngl = moderngl
        ctx = create_context()
        self.ctx = ctx
        self._programs: dict[str, Any] = {}
        self._tables: Any = None  # measured tables as 3D textures (glsl.TableTextures), made on first use

    @property
    def info(self) -> dict[str, str]:
        return context_info(self.ctx)

    # ------------------------------------------------------------------ programs
    def _program(self, lighting: str, where: str, shading: str, model: Any = None):
        """``lighting``: "opengl" | "brdf" | "none"; ``where``: "vertex" | "fragment" | "attribute" | "gbuffer"."""
        defines = []
        if shading == "flat":
            defines.append("#define BKR_FLAT")
        if where == "vertex":
            defines.append("#define BKR_LIGHT_IN_VERTEX")
        elif where == "fragment":
            defines.append("#define BKR_LIGHT_IN_FRAGMENT")
        elif where == "attribute":
            defines.append("#define BKR_VERTEX_COLOR")
        elif where == "gbuffer":
            defines.append("#define BKR_GBUFFER")
        elif where == "ibl":
            defines.append("#define BKR_IBL")
        head = "#version 330 core\n" + "\n".join(defines) + "\n"
        if lighting == "opengl":
            light_src = _read_shader("pipeline_lights.glsl") + _read_shader("opengl_fixed.glsl")
        elif lighting == "brdf":
            from . import glsl

            light_src = glsl.shader_source(model) + _read_shader("pipeline_lights.glsl") + _read_shader("pipeline_brdf.glsl")
        elif lighting == "ibl":
            from . import glsl

            light_src = (glsl.shader_source(model) + _read_shader("pipeline_lights.glsl")
                         + _read_shader("ibl_sampling.glsl") + _read_shader("ibl.glsl"))
        else:
            light_src = _read_shader("pipeline_lights.glsl")
        vs = head + (light_src if where == "vertex" else _read_shader("pipeline_lights.glsl")) + _read_shader(
            "pipeline_vertex.glsl"
        )
        fs = head + (light_src if where in ("fragment", "ibl") else "") + _read_shader("pipeline_fragment.glsl")
        key = vs + "\x00" + fs
        prog = self._programs.get(key)
        if prog is None:
            try:
                prog = self.ctx.program(vertex_shader=vs, fragment_shader=fs)
            except Exception as e:
                raise RuntimeError(f"shader compilation failed: {e}") from None
            self._programs[key] = prog
        return prog

    # ------------------------------------------------------------------ uniforms
    @staticmethod
    def _set(prog, name: str, value: Any) -> None:
        u = prog.get(name, None)
        if u is None:
            return
        arr = np.asarray(value)
        if arr.dtype.kind in "iub" and not isinstance(value, float):
            u.value = int(value)
            return
        data = np.asarray(value, dtype=np.float32).reshape(-1)
        length = getattr(u, "array_length", 1) or 1
        per = u.dimension
        need = length * per
        if data.size < need:
            data = np.concatenate([data, np.zeros(need - data.size, np.float32)])
        u.write(data[:need].tobytes())

    def _set_common(self, prog, scene: Scene) -> None:
        mv = scene.modelview
        self._set(prog, "bkr_modelview", mv.T)  # column-major for GL
        self._set(prog, "bkr_projection", scene.projection.T)
        self._set(prog, "bkr_normal_matrix", _normal_matrix(mv).T)

    def _set_lights(self, prog, scene: Scene) -> None:
        ls = scene.lights
        k = opengl.MAX_LIGHTS

        def arr(fn, width):
            out = np.zeros((k, width), np.float32)
            for i, L in enumerate(ls):
                out[i] = fn(L)
            return out

        self._set(prog, "bkr_num_lights", len(ls))
        self._set(prog, "bkr_light_position", arr(lambda L: L.position, 4))
        self._set(prog, "bkr_light_ambient", arr(lambda L: L.ambient[:3], 3))
        self._set(prog, "bkr_light_diffuse", arr(lambda L: L.diffuse[:3], 3))
        self._set(prog, "bkr_light_specular", arr(lambda L: L.specular[:3], 3))
        self._set(
            prog,
            "bkr_light_attenuation",
            arr(lambda L: (L.constant_attenuation, L.linear_attenuation, L.quadratic_attenuation), 3),
        )
        self._set(
            prog,
            "bkr_light_spot_direction",
            arr(lambda L: normalize(np.asarray(L.spot_direction, dtype=np.float64)), 3),
        )
        self._set(prog, "bkr_light_spot_exponent", arr(lambda L: [L.spot_exponent], 1))
        self._set(
            prog,
            "bkr_light_spot_cos_cutoff",
            arr(lambda L: [math.cos(math.radians(L.spot_cutoff)) if L.is_spot else -2.0], 1),
        )
        self._set(prog, "bkr_scene_ambient", scene.light_model.ambient[:3])
        self._set(prog, "bkr_local_viewer", int(scene.light_model.local_viewer))

    def _set_material(self, prog, scene: Scene) -> None:
        m = scene.material
        if isinstance(m, opengl.Material):
            self._set(prog, "bkr_mat_ambient", m.ambient)
            self._set(prog, "bkr_mat_diffuse", m.diffuse)
            self._set(prog, "bkr_mat_specular", m.specular)
            self._set(prog, "bkr_mat_emission", m.emission)
            self._set(prog, "bkr_mat_shininess", m.shininess)
        else:
            from . import glsl
            from .lighting import ambient_albedo

            glsl.set_uniforms(prog, glsl.uniform_values(m))
            if glsl.is_measured(m):
                if self._tables is None:
                    self._tables = glsl.TableTextures(self.ctx)
                self._tables.bind(prog, m)
            self._set(prog, "bkr_ambient_albedo", ambient_albedo(m))

    # ------------------------------------------------------------------ drawing
    def _vao(self, prog, mesh: Mesh, colors: np.ndarray | None = None):
        ctx = self.ctx
        content = []
        buffers = []
        for name, data in (
            ("in_position", mesh.positions),
            ("in_normal", mesh.normals),
            ("in_tangent", mesh.tangents),
            ("in_color", colors),
        ):
            if data is None or name not in prog:
                continue
            buf = ctx.buffer(np.ascontiguousarray(data, dtype=np.float32).tobytes())
            buffers.append(buf)
            content.append((buf, f"{data.shape[1]}f", name))
        ibo = ctx.buffer(mesh.faces.astype(np.int32).tobytes())
        buffers.append(ibo)
        vao = ctx.vertex_array(prog, content, index_buffer=ibo, index_element_size=4)
        return vao, buffers

    def _draw(self, prog, scene: Scene, size: tuple[int, int], samples: int, attachments: int = 1, colors=None):
        """Draw into a float framebuffer; returns a list of (H, W, 4) float32 arrays, bottom row first."""
        ctx = self.ctx
        w, h = size
        samples = samples if samples <= ctx.max_samples else ctx.max_samples
        rbs = [ctx.renderbuffer((w, h), 4, samples=samples, dtype="f4") for _ in range(attachments)]
        depth = ctx.depth_renderbuffer((w, h), samples=samples)
        fbo = ctx.framebuffer(color_attachments=rbs, depth_attachment=depth)
        vao, buffers = self._vao(prog, scene.mesh, colors)
        release = [vao, fbo, depth, *rbs, *buffers]
        try:
            fbo.use()
            ctx.viewport = (0, 0, w, h)
            ctx.enable(self.moderngl.DEPTH_TEST)
            ctx.disable(self.moderngl.CULL_FACE)
            ctx.depth_func = "<"
            fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
            vao.render(self.moderngl.TRIANGLES)
            out = []
            if samples > 0:
                for rb in rbs:
                    res_rb = ctx.renderbuffer((w, h), 4, dtype="f4")
                    res = ctx.framebuffer(color_attachments=[res_rb])
                    release += [res, res_rb]
                    src = ctx.framebuffer(color_attachments=[rb])
                    release.append(src)
                    ctx.copy_framebuffer(res, src)
                    out.append(np.frombuffer(res.read(components=4, dtype="f4"), np.float32).reshape(h, w, 4))
            else:
                for i in range(attachments):
                    out.append(
                        np.frombuffer(fbo.read(components=4, dtype="f4", attachment=i), np.float32).reshape(h, w, 4)
                    )
            return out
        finally:
            for obj in release:
                obj.release()

    def time_draws(self, scene: Scene, frames: int = 5) -> float:
        """Seconds per frame of the GLSL path's draw alone (program, buffers and framebuffer
        made once; each frame clears, draws and waits for the GL to finish; no read-back)."""
        with _EGLCurrent(), self.ctx:
            return self._time_draws(scene, frames)

    def _time_draws(self, scene: Scene, frames: int) -> float:
        import time

        prog = self._lit_program(scene)
        ctx = self.ctx
        w, h = scene.size
        samples = min(MSAA_SAMPLES, ctx.max_samples) if scene.antialias else 0
        rb = ctx.renderbuffer((w, h), 4, samples=samples, dtype="f4")
        depth = ctx.depth_renderbuffer((w, h), samples=samples)
        fbo = ctx.framebuffer(color_attachments=[rb], depth_attachment=depth)
        vao, buffers = self._vao(prog, scene.mesh)
        try:
            fbo.use()
            ctx.viewport = (0, 0, w, h)
            ctx.enable(self.moderngl.DEPTH_TEST)
            ctx.disable(self.moderngl.CULL_FACE)

            def one() -> None:
                fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
                vao.render(self.moderngl.TRIANGLES)
                ctx.finish()

            one()  # warm-up (shader variants are compiled lazily by some drivers)
            t0 = time.perf_counter()
            for _ in range(frames):
                one()
            return (time.perf_counter() - t0) / frames
        finally:
            for obj in (vao, fbo, depth, rb, *buffers):
                obj.release()

    def render_linear(self, scene: Scene, backend: str = "auto") -> np.ndarray:
        """Linear RGBA, (H, W, 4) float32, top row first: premultiplied colour, alpha = coverage."""
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {', '.join(BACKENDS)}; got {backend!r}")
        if backend == "auto":
            backend = "glsl" if has_glsl(scene.material) else "numpy"
        # Each call makes this context current and afterwards restores the caller's
        # (glcontext's EGL backend leaves the last-entered context current).
        with _EGLCurrent(), self.ctx:
            if scene.environment is not None:
                img = self._render_ibl(scene) if backend == "glsl" else self._render_ibl_numpy(scene)
            elif backend == "numpy":
                img = self._render_numpy(scene)
            else:
                img = self._render_glsl(scene)
        img = np.ascontiguousarray(img[::-1])
        if scene.environment is not None and scene.environment.visible:
            img = _over_environment(img, scene)
        return img

    def _lit_program(self, scene: Scene):
        """The GLSL path's program for ``scene``, with every uniform set (shared by rendering and timing)."""
        lighting = "opengl" if scene.is_opengl else "brdf"
        if not scene.is_opengl:
            from . import glsl

            if not glsl.has_shader(scene.material):
                raise ValueError(f"model '{scene.material.name}' has no GLSL file; use backend 'numpy'")
        where = "fragment" if scene.shading == "phong" else "vertex"
        prog = self._program(lighting, where, scene.shading, scene.material)
        self._set_common(prog, scene)
        self._set_lights(prog, scene)
        self._set_material(prog, scene)
        return prog

    def _render_glsl(self, scene: Scene) -> np.ndarray:
        prog = self._lit_program(scene)
        samples = MSAA_SAMPLES if scene.antialias else 0
        return self._draw(prog, scene, scene.size, samples)[0]

    # ------------------------------------------------------------------ image-based lighting
    def _env_textures(self, env) -> list:
        """The environment's three textures (radiance+pdf, marginal CDF, conditional CDFs), cached per map."""
        from .ibl import env_texture_data

        cache = getattr(self, "_env_cache", None)
        if cache is None:
            cache = self._env_cache = {}
        key = (id(env.rgb), env.rgb.shape)
        hit = cache.get(key)
        if hit is not None and hit[0] is env.rgb:
            return hit[1]
        for _, texs in cache.values():
            for tex in texs:
                tex.release()
        cache.clear()
        rgba, marg, cond = env_texture_data(env)
        texs = []
        for data, comps in ((rgba, 4), (marg, 1), (cond, 1)):
            tex = self.ctx.texture((data.shape[1], data.shape[0]), comps, np.ascontiguousarray(data).tobytes(), dtype="f4")
            tex.filter = (self.moderngl.NEAREST, self.moderngl.NEAREST)
            tex.repeat_x = tex.repeat_y = False
            texs.append(tex)
        cache[key] = (env.rgb, texs)
        return texs

    def _ibl_program(self, scene: Scene):
        from . import glsl
        from .ibl import eye_to_map, sampler_uniforms

        if not glsl.has_shader(scene.material):
            raise ValueError(f"model '{scene.material.name}' has no GLSL file; use backend 'numpy'")
        prog = self._program("ibl", "ibl", scene.shading, scene.material)
        self._set_common(prog, scene)
        self._set_material(prog, scene)
        env = scene.environment
        for unit, (name, tex) in enumerate(zip(("bki_env", "bki_env_marg", "bki_env_cond"), self._env_textures(env)), 1):
            tex.use(location=unit)
            if name in prog:
                prog[name].value = unit
        for name, value in sampler_uniforms(scene.material).items():
            self._set(prog, name, value)
        self._set(prog, "bki_eye_to_map", eye_to_map(scene.modelview, env).T)  # column-major for GL
        self._set(prog, "bki_strength", float(env.strength))
        return prog

    IBL_SPP_PER_PASS = 8

    def _render_ibl(self, scene: Scene, passes_out: list | None = None) -> np.ndarray:
        """Progressive accumulation: passes of up to IBL_SPP_PER_PASS samples per pixel, averaged."""
        prog = self._ibl_program(scene)
        ctx = self.ctx
        w, h = scene.size
        samples = min(MSAA_SAMPLES, ctx.max_samples) if scene.antialias else 0
        rb = ctx.renderbuffer((w, h), 4, samples=samples, dtype="f4")
        depth = ctx.depth_renderbuffer((w, h), samples=samples)
        fbo = ctx.framebuffer(color_attachments=[rb], depth_attachment=depth)
        res_rb = ctx.renderbuffer((w, h), 4, dtype="f4") if samples else None
        res = ctx.framebuffer(color_attachments=[res_rb]) if samples else None
        vao, buffers = self._vao(prog, scene.mesh)
        acc = np.zeros((h, w, 4), np.float64)
        try:
            ctx.viewport = (0, 0, w, h)
            ctx.enable(self.moderngl.DEPTH_TEST)
            ctx.disable(self.moderngl.CULL_FACE)
            ctx.depth_func = "<"
            done = 0
            k = 0
            while done < scene.samples:
                spp = min(self.IBL_SPP_PER_PASS, scene.samples - done)
                self._set(prog, "bki_spp", spp)
                self._set(prog, "bki_pass", k)
                fbo.use()
                fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
                vao.render(self.moderngl.TRIANGLES)
                if samples:
                    ctx.copy_framebuffer(res, fbo)
                    data = res.read(components=4, dtype="f4")
                else:
                    data = fbo.read(components=4, dtype="f4")
                img = np.frombuffer(data, np.float32).reshape(h, w, 4)
                acc += img * spp
                if passes_out is not None:
                    passes_out.append(img.copy())
                done += spp
                k += 1
            return (acc / scene.samples).astype(np.float32)
        finally:
            for obj in (vao, fbo, depth, rb, *buffers, *(x for x in (res, res_rb) if x is not None)):
                obj.release()

    def time_ibl_pass(self, scene: Scene, passes: int = 3) -> float:
        """Seconds per sample per pixel of the IBL path (``passes`` passes of IBL_SPP_PER_PASS samples,
        read-back included, after one warm-up pass)."""
        import dataclasses
        import time

        warm = dataclasses.replace(scene, samples=1)
        run = dataclasses.replace(scene, samples=self.IBL_SPP_PER_PASS * passes)
        with _EGLCurrent(), self.ctx:
            self._render_ibl(warm)
            t0 = time.perf_counter()
            self._render_ibl(run)
            return (time.perf_counter() - t0) / run.samples

    def gbuffer(self, scene: Scene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Eye-space position, normal and tangent per pixel ((H, W, 4) each, top row first; alpha = coverage),
        rasterised without antialiasing — the inputs of per-pixel shading."""
        with _EGLCurrent(), self.ctx:
            prog = self._program("none", "gbuffer", "phong")
            self._set_common(prog, scene)
            out = self._draw(prog, scene, scene.size, 0, attachments=3)
        return tuple(np.ascontiguousarray(a[::-1]) for a in out)  # type: ignore[return-value]

    def _shade_gbuffer(self, scene: Scene, shade) -> np.ndarray:
        """Per-pixel shading in numpy: a G-buffer (2× supersampled with ``antialias``), then
        ``shade(P, N, T)`` (eye-space positions, normals, tangents of the covered pixels, float64)
        -> RGB, averaged back to ``scene.size``. Shared by the numpy Phong path and the IBL reference."""
        ss = 2 if scene.antialias else 1
        w, h = scene.size
        prog = self._program("none", "gbuffer", scene.shading)
        self._set_common(prog, scene)
        pos, nrm, tan = self._draw(prog, scene, (w * ss, h * ss), 0, attachments=3)
        cover = pos[..., 3] > 0
        img = np.zeros((h * ss, w * ss, 4), np.float64)
        if cover.any():
            img[cover, :3] = shade(*(a[cover][:, :3].astype(np.float64) for a in (pos, nrm, tan)))
            img[cover, 3] = 1.0
        if ss > 1:
            img = img.reshape(h, ss, w, ss, 4).mean(axis=(1, 3))
        return img.astype(np.float32)

    def _render_ibl_numpy(self, scene: Scene) -> np.ndarray:
        """The brute-force numpy reference (:func:`brdfkit.render.ibl.reference_shade`) on a G-buffer."""
        from .ibl import reference_shade

        return self._shade_gbuffer(
            scene, lambda P, N, T: reference_shade(scene.material, P, N, T, scene.modelview, scene.environment)
        )

    def _render_numpy(self, scene: Scene) -> np.ndarray:
        from .lighting import shade_points

        mv = scene.modelview
        if scene.shading in ("flat", "gouraud"):
            m = scene.mesh
            ph = np.c_[m.positions.astype(np.float64), np.ones(m.n_vertices)] @ mv.T
            P = ph[:, :3] / ph[:, 3:4]
            n = normalize(m.normals.astype(np.float64) @ _normal_matrix(mv).T)
            t = m.tangents.astype(np.float64) @ mv[:3, :3].T
            rgb = shade_points(scene.material, P, n, t, scene.lights, scene.light_model)
            colors = np.c_[rgb, np.ones(len(rgb))].astype(np.float32)
            prog = self._program("none", "attribute", scene.shading)
            self._set_common(prog, scene)
            samples = MSAA_SAMPLES if scene.antialias else 0
            return self._draw(prog, scene, scene.size, samples, colors=colors)[0]
        # phong: G-buffer, then per-pixel lighting in numpy
        return self._shade_gbuffer(
            scene, lambda P, N, T: shade_points(scene.material, P, N, T, scene.lights, scene.light_model)
        )


def _over_environment(img: np.ndarray, scene: Scene) -> np.ndarray:
    """Composite premultiplied ``img`` (top row first) over the environment seen through each pixel."""
    from .ibl import background_radiance

    bg = background_radiance(scene.projection, scene.modelview, scene.size, scene.environment)
    out = img.astype(np.float32, copy=True)
    a = out[..., 3:4]
    out[..., :3] += ((1.0 - a) * bg).astype(np.float32)
    out[..., 3] = 1.0
    return out


_DEFAULT: Renderer | None = None


def default_renderer() -> Renderer:
    """The process's shared :class:`Renderer` (created on first use)."""
    global _DEFAULT
    if _DEFAULT is None:
        _DEFAULT = Renderer()
    return _DEFAULT


def render_linear(scene: Scene, backend: str = "auto") -> np.ndarray:
    """:meth:`Renderer.render_linear` on the shared renderer."""
    return default_renderer().render_linear(scene, backend)
