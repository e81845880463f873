"""The GLSL twin of every analytic model, and a harness that runs it through real OpenGL.

Every model module ``brdfkit/models/<module>.py`` has a GLSL file
``render/shaders/<module>.glsl`` defining ::

    vec3 brdf(vec3 wi, vec3 wo)

in the local shading frame (normal ``+z``, tangent ``+x``; ``wi`` toward the
light, ``wo`` toward the viewer), returning f_r in 1/sr without the cosine and
``vec3(0)`` where ``wi.z <= 0`` or ``wo.z <= 0`` — the same contract as
``model.eval``. The file declares the uniforms it reads, one per parameter,
named ``u_<param>``: ``float`` for a scalar, ``vec3`` for an RGB triple,
``int`` for a bool (0/1), an int, or a choice (the index into the parameter's
``choices``). The shared Fresnel / D / G terms live in ``shaders/common.glsl``
(mirroring :mod:`brdfkit.terms`), which :func:`shader_source` prepends.

The sources use only the subset common to GLSL 3.30 and GLSL ES 3.00 and carry
no ``#version`` line: the caller prepends ``#version 330 core`` (desktop) or
``#version 300 es`` (WebGL 2).

Functions
---------
:func:`shader_source`       common.glsl + the model's file
:func:`uniform_values`      uniform name -> value for a model instance
:func:`uniform_declarations` the ``uniform`` lines a model's spec implies
:func:`eval_glsl`           run ``brdf()`` on N direction pairs through moderngl
                            (headless EGL; transform feedback) -> (N, 3) float32
:func:`compile_check`       compile (and link) a model's GLSL as GLSL ES 3.00 or
                            3.30 core with the GL driver's own compiler
                            (:func:`compile_source` for any source)
:func:`glslang_validate`    validate with the Khronos reference compiler
                            ``glslangValidator`` (Debian package ``glslang-tools``)
:func:`parity_vectors`      the deterministic direction pairs the parity tests use
:func:`table_texels`        a measured model's table as the texels of ``measured.glsl``

Measured models
---------------
Every measured model (a MERL table from :func:`brdfkit.load_merl`, a built-in
Neural-BRDF material from :func:`brdfkit.material`) shares
``shaders/measured.glsl``: ``brdf()`` computes the Rusinkiewicz angles as
:func:`brdfkit.measured.merl.symmetric_half_diff` does and reads the MERL
table from the 3D texture ``uniform highp sampler3D u_table`` (RGBA32F,
180 × 90 × 90 texels, NEAREST, ``texelFetch`` at the bin indices): MERL's
nearest lookup, or trilinear over the measured corners when a MERL model's
``interpolation`` is ``"trilinear"`` (``u_interpolation`` = 1). A Neural-BRDF
material is tabulated at the MERL bin centres first, so the GLSL shows its
MERL-grid version. :class:`TableTextures` uploads a table once per context
and binds it to texture unit 0; :func:`eval_glsl` and the renderer do that.

Accuracy
--------
The shaders agree with the numpy models to 1e-4 relative in float32 (the
parity tests; measured over ~450 000 compared values: ≤ 1.3e-5 for every
model, typically 1e-6, except within float32 reach of the critical angle of a
Fresnel index < 1, where the exact function's slope is infinite). That takes
more than a literal transcription: GL's ``acos``/``asin`` (1e-4 absolute on
llvmpipe), ``atan`` (2e-5) and ``log``/``log2`` (1.6e-7 *absolute* near 1,
so ``pow(x, 1e5)`` is off by 1 %) are replaced by ``bk_acos``, ``bk_atan``,
``bk_log``/``bk_log1p`` and ``bk_pow`` in common.glsl, ``erf`` (absent from
GLSL) is ``bk_erf``/``bk_erfc``, and expressions that cancel in float32 are
rearranged (``1 − n·h`` from the half vector's components in Blinn-Phong,
``(n−1)(n+1)`` in the Fresnel terms, ``1 − (1 − x)⁵`` as a polynomial in
Ashikhmin-Shirley, Schlick's ``1 + (r−1)t²`` from ``H``, HTSG's series via
Stirling's formula in the form ``−m (x − log1p x)``).

The harness's context is a separate moderngl context; every use is wrapped so
that a context another part of the process had current (the renderer's) is
current again afterwards (glcontext's EGL backend does not restore it).

Example::

    import brdfkit as bk
    from brdfkit.render import glsl
    m = bk.model("lambert", kd=0.3)
    wi, wo = glsl.parity_vectors()["wi"], glsl.parity_vectors()["wo"]
    f_gl = glsl.eval_glsl(m, wi, wo)       # equals m.eval(wi, wo) to ~1e-6
"""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from ..geometry import normalize, random_unit_vectors, reflect, spherical_to_vector
from .context import EGLCurrent as _EGLCurrent, context_info, create_context

SHADER_DIR = Path(__file__).resolve().with_name("shaders")

GLSL_TYPES = {"scalar": "float", "rgb": "vec3", "bool": "int", "choice": "int", "int": "int"}

VERSIONS = ("330 core", "300 es")

# vertices per transform-feedback draw (buffers are reused between draws)
_CHUNK = 1 << 18


class GLSLError(RuntimeError):
    """A shader failed to compile or link; the message carries the compiler log."""


# ---------------------------------------------------------------------------
# sources
# ---------------------------------------------------------------------------
def _model_class(model_or_name: Any) -> type:
    from .. import registry
    from ..models.base import BRDF

    if isinstance(model_or_name, str):
        return registry.get(model_or_name)
    if isinstance(model_or_name, BRDF):
        return type(model_or_name)
    if isinstance(model_or_name, type) and issubclass(model_or_name, BRDF):
        return model_or_name
    raise ValueError(f"expected a model name, a model or a model class, got {model_or_name!r}")


def is_measured(model_or_name: Any) -> bool:
    """Whether a model (instance or class) is a measured one (:class:`brdfkit.measured.MeasuredBRDF`)."""
    from ..measured.merl import MeasuredBRDF

    if isinstance(model_or_name, type):
        return issubclass(model_or_name, MeasuredBRDF)
    return isinstance(model_or_name, MeasuredBRDF)


def shader_path(model_or_name: Any) -> Path:
    """``render/shaders/<module>.glsl`` for a model (name, instance or class); may not exist.

    Every measured model (MERL table, Neural-BRDF material) shares ``measured.glsl``.
    """
    cls = _model_class(model_or_name)
    if is_measured(cls):
        return SHADER_DIR / "measured.glsl"
    if cls.glsl_source:  # a model that carries its own GLSL (a .brdf file); hook declared on BRDF
        return Path(cls.source_path or cls.name)
    module = cls.__module__.rsplit(".", 1)[-1]
    return SHADER_DIR / f"{module}.glsl"


def has_shader(model_or_name: Any) -> bool:
    """Whether the model has a GLSL file (or carries its own source, ``glsl_source``)."""
    if _model_class(model_or_name).glsl_source:
        return True
    return shader_path(model_or_name).is_file()


@lru_cache(maxsize=None)
def _read(path: Path, mtime_ns: int) -> str:
    return path.read_text(encoding="utf-8")


def _read_file(path: Path) -> str:
    return _read(path, path.stat().st_mtime_ns)


def shader_file(name: str) -> str:
    """The text of ``shaders/<name>``, read from disk only when the file changed."""
    return _read_file(SHADER_DIR / name)


def common_source() -> str:
    """The text of ``shaders/common.glsl``."""
    return shader_file("common.glsl")


def shader_source(model_or_name: Any) -> str:
    """common.glsl followed by the model's GLSL file (no ``#version`` line).

    Defines ``vec3 brdf(vec3 wi, vec3 wo)`` and declares the model's ``u_<param>``
    uniforms. ``ValueError`` if the model has no GLSL file.
    """
    cls = _model_class(model_or_name)
    own = cls.glsl_source
    if own:  # foreign GLSL wrapped in our convention (brdfkit.interchange.brdf_explorer)
        return common_source() + f"\n// ---- {cls.name} ----\n" + own
    path = shader_path(cls)
    if not path.is_file():
        raise ValueError(f"model '{cls.name}' has no GLSL implementation (expected {path.name} in {SHADER_DIR})")
    return common_source() + f"\n// ---- {path.name} ----\n" + _read_file(path)


# ---------------------------------------------------------------------------
# uniforms
# ---------------------------------------------------------------------------
def uniform_declarations(model_or_name: Any) -> str:
    """The ``uniform`` declarations a model's parameter spec implies, one per line."""
    cls = _model_class(model_or_name)
    return "".join(f"uniform {GLSL_TYPES[p.kind]} u_{p.name};\n" for p in cls.spec)


def declared_uniforms(source: str) -> dict[str, str]:
    """``{name: type}`` of the ``uniform`` declarations in GLSL ``source`` (comments ignored)."""
    text = re.sub(r"//[^\n]*", "", source)
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    out = {}
    for m in re.finditer(r"\buniform\s+(?:(?:lowp|mediump|highp)\s+)?(\w+)\s+(\w+)\s*;", text):
        out[m.group(2)] = m.group(1)
    return out


def uniform_values(model: Any) -> dict[str, Any]:
    """Uniform name -> value for a model instance (a name means its defaults).

    ``float`` for a scalar, an ``(r, g, b)`` tuple of floats for an RGB
    parameter, ``int`` for a bool (0/1), an int parameter, or a choice (its
    index in the parameter's ``choices``). A parameter whose value is ``None``
    (a derived parameter that is undefined for this instance, e.g. the
    microfacet model's ``alpha`` when ``alpha_x != alpha_y``) is left out: the
    shaders never read such parameters.
    """
    if isinstance(model, str):
        from .. import registry

        model = registry.get(model)()
    cls = _model_class(model)
    out: dict[str, Any] = {}
    for p in cls.spec:
        v = model.params[p.name]
        if v is None:
            continue
        if p.kind == "scalar":
            out[f"u_{p.name}"] = float(v)
        elif p.kind == "rgb":
            a = np.asarray(v, dtype=np.float64).reshape(-1)
            if a.size == 1:
                a = np.repeat(a, 3)
            out[f"u_{p.name}"] = tuple(float(x) for x in a)
        elif p.kind == "bool":
            out[f"u_{p.name}"] = int(bool(v))
        elif p.kind == "choice":
            out[f"u_{p.name}"] = int(p.choices.index(v))
        else:  # int
            out[f"u_{p.name}"] = int(v)
    return out


# ---------------------------------------------------------------------------
# measured models: the MERL table as a 3D texture
# ---------------------------------------------------------------------------
TABLE_UNIFORM = "u_table"
TABLE_TEXTURE_UNIT = 0
_TABLE_CACHE_SIZE = 4  # textures kept per GL context (about 23 MB each)


def table_key(model: Any) -> str:
    """A key identifying a measured model's table: the material for a Neural-BRDF
    material, a digest of the table for a MERL table (computed once per instance)."""
    key = getattr(model, "_bk_table_key", None)
    if key is None:
        from ..measured.merl import MERLBRDF

        if isinstance(model, MERLBRDF):
            import hashlib

            key = "merl:" + hashlib.blake2b(np.ascontiguousarray(model.table).tobytes(), digest_size=16).hexdigest()
        elif hasattr(model, "material"):
            key = f"{type(model).__name__}:{model.material}"
        else:
            key = f"{type(model).__name__}:{id(model)}"
        try:
            object.__setattr__(model, "_bk_table_key", key)
        except AttributeError:  # pragma: no cover - a model without a __dict__
            pass
    return key


@lru_cache(maxsize=2)
def _texels_cached(key: str, model_ref: Any) -> np.ndarray:
    from ..measured.merl import table_rgba

    out = table_rgba(model_ref.model)
    out.setflags(write=False)
    return out


class _Ref:
    """Carries the model into the lru_cache without making it part of the key."""

    def __init__(self, model: Any) -> None:
        self.model = model

    def __hash__(self) -> int:
        return 0

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _Ref)


def table_texels(model: Any) -> np.ndarray:
    """A measured model's table as the texels of ``measured.glsl``'s ``u_table``.

    float32, shape ``(90, 90, 180, 4)`` = [θh][θd][φd][rgba] (OpenGL's depth,
    height, width, components): rgb = the bin's value clamped at 0 per channel
    (f_r in 1/sr), alpha = 1 where every channel was measured, else 0. A MERL
    table is used as it is; any other measured model (a Neural-BRDF material)
    is tabulated at the MERL bin centres first (:func:`brdfkit.measured.tabulate`,
    about 2 s; the last two are cached).
    """
    if not is_measured(model):
        raise ValueError(f"table_texels: expected a measured model, got {model!r}")
    return _texels_cached(table_key(model), _Ref(model))


class TableTextures:
    """The 3D textures of measured tables uploaded to one moderngl context (a small LRU)."""

    def __init__(self, ctx: Any, size: int = _TABLE_CACHE_SIZE) -> None:
        self.ctx = ctx
        self.size = size
        self._tex: dict[str, Any] = {}

    def get(self, model: Any):
        key = table_key(model)
        tex = self._tex.pop(key, None)
        if tex is None:
            import moderngl

            data = table_texels(model)
            th, td, pd, _ = data.shape
            tex = self.ctx.texture3d((pd, td, th), 4, data.tobytes(), dtype="f4")
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
            tex.repeat_x = tex.repeat_y = tex.repeat_z = False
            while len(self._tex) >= self.size:
                old = next(iter(self._tex))
                self._tex.pop(old).release()
        self._tex[key] = tex  # most recently used last
        return tex

    def bind(self, prog: Any, model: Any, location: int = TABLE_TEXTURE_UNIT) -> None:
        """Upload (once) and bind ``model``'s table to texture unit ``location`` for ``prog``."""
        self.get(model).use(location=location)
        u = prog.get(TABLE_UNIFORM, None)
        if u is not None:
            u.value = location

    def release(self) -> None:
        for tex in self._tex.values():
            tex.release()
        self._tex.clear()


# ---------------------------------------------------------------------------
# the GL context and programs
# ---------------------------------------------------------------------------
class _GL:
    """A lazily created headless context with cached programs and buffers."""

    def __init__(self) -> None:
        import moderngl

        self.moderngl = moderngl
        ctx = create_context()
        self.ctx = ctx
        self.programs: dict[str, Any] = {}
        self.vaos: dict[str, Any] = {}
        with _EGLCurrent(), ctx:  # create our objects in our own context
            # a draw call needs a complete framebuffer, even with rasterisation off
            self.fbo = ctx.simple_framebuffer((1, 1))
            self.fbo.use()
            self.buf_wi = ctx.buffer(reserve=_CHUNK * 12)
            self.buf_wo = ctx.buffer(reserve=_CHUNK * 12)
            self.buf_f = ctx.buffer(reserve=_CHUNK * 12)
            self.tables = TableTextures(ctx)

    def program(self, key: str, vertex: str, fragment: str | None, varyings: tuple[str, ...]):
        prog = self.programs.get(key)
        if prog is None:
            try:
                prog = self.ctx.program(vertex_shader=vertex, fragment_shader=fragment, varyings=list(varyings))
            except Exception as e:
                raise GLSLError(str(e)) from None
            self.programs[key] = prog
        return prog


_STATE: _GL | None = None


def _gl() -> _GL:
    global _STATE
    if _STATE is None:
        _STATE = _GL()
    return _STATE


def gl_info() -> dict[str, str]:
    """Vendor, renderer and version of the GL context :func:`eval_glsl` uses."""
    gl = _gl()
    with _EGLCurrent(), gl.ctx:
        return context_info(gl.ctx)


def _header(version: str) -> str:
    if version not in VERSIONS:
        raise ValueError(f"GLSL version must be one of {', '.join(VERSIONS)}; got {version!r}")
    return f"#version {version}\n"


_EVAL_MAIN = """
in vec3 bk_in_wi;
in vec3 bk_in_wo;
out vec3 bk_out_f;
void main() {
    bk_out_f = brdf(bk_in_wi, bk_in_wo);
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
"""

_FRAG_MAIN = """
out vec4 bk_frag_color;
void main() {
    vec3 wi = normalize(vec3(0.3, 0.2, 1.0));
    vec3 wo = normalize(vec3(-0.2, 0.1, 1.0));
    bk_frag_color = vec4(brdf(wi, wo), 1.0);
}
"""

_FRAG_TRIVIAL = """
precision highp float;
out vec4 bk_frag_color;
void main() { bk_frag_color = vec4(0.0); }
"""


def _eval_program(source: str, version: str):
    gl = _gl()
    vertex = _header(version) + source + _EVAL_MAIN
    fragment = None if version == "330 core" else _header(version) + _FRAG_TRIVIAL
    return gl.program("eval:" + vertex, vertex, fragment, ("bk_out_f",))


def set_uniforms(prog, values: dict[str, Any]) -> None:
    """Set ``{name: value}`` (as from :func:`uniform_values`) on a moderngl program, skipping absent ones."""
    for name, value in values.items():
        u = prog.get(name, None)
        if u is None:  # declared but unused: optimised away by the compiler
            continue
        u.value = value


def eval_glsl(model: Any, wi, wo, version: str = "330 core", source: str | None = None) -> np.ndarray:
    """Evaluate the model's GLSL ``brdf(wi, wo)`` through OpenGL (moderngl, headless).

    ``wi``, ``wo``: arrays of shape ``(..., 3)`` (broadcast against each other),
    converted to float32. Returns float32 of shape ``(..., 3)``. Each pair is one
    vertex of a transform-feedback draw, ``version`` picks the ``#version`` line
    (``"330 core"`` or ``"300 es"``). The context and the compiled programs are
    cached, so repeated calls cost only the transfer and the shading.
    ``source`` replaces :func:`shader_source` (tests of the harness and of the
    shared terms); the model still supplies the uniform values.
    """
    if isinstance(model, str):
        from .. import registry

        model = registry.get(model)()
    wi = np.asarray(wi, dtype=np.float32)
    wo = np.asarray(wo, dtype=np.float32)
    if wi.shape[-1:] != (3,) or wo.shape[-1:] != (3,):
        raise ValueError(f"eval_glsl: directions must have a last axis of length 3, got {wi.shape} and {wo.shape}")
    wi, wo = np.broadcast_arrays(wi, wo)
    shape = wi.shape
    wi = np.ascontiguousarray(wi.reshape(-1, 3))
    wo = np.ascontiguousarray(wo.reshape(-1, 3))
    n = wi.shape[0]
    out = np.empty((n, 3), dtype=np.float32)
    if n == 0:
        return out.reshape(shape)

    src = shader_source(model) if source is None else source
    values = uniform_values(model)
    gl = _gl()
    # another moderngl context in the process (the renderer's) may be current: make ours
    # current for the duration and give theirs back afterwards
    with _EGLCurrent(), gl.ctx:
        prog = _eval_program(src, version)
        set_uniforms(prog, values)
        if is_measured(model):
            gl.tables.bind(prog, model)
        key = id(prog)
        vao = gl.vaos.get(key)
        if vao is None:
            # an input the shader ignores is optimised away: skip it instead of failing
            vao = gl.ctx.vertex_array(
                prog, [(gl.buf_wi, "3f", "bk_in_wi"), (gl.buf_wo, "3f", "bk_in_wo")], skip_errors=True
            )
            gl.vaos[key] = vao
        gl.fbo.use()
        for start in range(0, n, _CHUNK):
            stop = min(n, start + _CHUNK)
            m = stop - start
            gl.buf_wi.write(wi[start:stop].tobytes())
            gl.buf_wo.write(wo[start:stop].tobytes())
            vao.transform(gl.buf_f, gl.moderngl.POINTS, vertices=m)
            out[start:stop] = np.frombuffer(gl.buf_f.read(size=m * 12), dtype=np.float32).reshape(m, 3)
    return out.reshape(shape)


def compile_source(source: str, version: str = "300 es") -> None:
    """Compile and link GLSL ``source`` (defining ``brdf``) as a vertex and a fragment shader.

    The GL driver's own compiler does the work; ``"300 es"`` goes through
    ``GL_ARB_ES3_compatibility`` (which Mesa provides on a desktop context).
    Raises :class:`GLSLError` with the compiler log on failure.
    """
    gl = _gl()
    if version == "300 es" and "GL_ARB_ES3_compatibility" not in gl.ctx.extensions:  # pragma: no cover
        raise GLSLError("this OpenGL driver cannot compile GLSL ES 3.00 (no GL_ARB_ES3_compatibility)")
    vertex = _header(version) + source + _EVAL_MAIN
    fragment = _header(version) + source + _FRAG_MAIN
    with _EGLCurrent(), gl.ctx:
        gl.program("check:" + vertex + fragment, vertex, fragment, ("bk_out_f",))


def compile_check(model_or_name: Any, version: str = "300 es") -> None:
    """Compile and link the model's GLSL, as a vertex and a fragment shader, with the GL driver.

    ``version`` is ``"300 es"`` (the WebGL 2 dialect) or ``"330 core"``.
    Raises :class:`GLSLError` with the compiler log on failure.
    """
    compile_source(shader_source(model_or_name), version)


def glslang_available() -> bool:
    """Whether the Khronos reference compiler ``glslangValidator`` is on the PATH."""
    return shutil.which("glslangValidator") is not None


def glslang_validate_source(source: str, version: str = "300 es") -> None:
    """Validate GLSL ``source`` (defining ``brdf``) with ``glslangValidator``, vertex and fragment stage.

    Raises :class:`GLSLError` with the validator's log on failure and
    ``FileNotFoundError`` if the tool is missing (Debian: ``apt-get install glslang-tools``).
    """
    exe = shutil.which("glslangValidator")
    if exe is None:
        raise FileNotFoundError("glslangValidator not found (Debian package glslang-tools)")
    header = _header(version)
    with tempfile.TemporaryDirectory() as tmp:
        for stage, main in (("vert", _EVAL_MAIN), ("frag", _FRAG_MAIN)):
            path = Path(tmp) / f"brdf.{stage}"
            path.write_text(header + source + main, encoding="utf-8")
            r = subprocess.run([exe, str(path)], capture_output=True, text=True)
            if r.returncode != 0:
                raise GLSLError(f"glslangValidator ({version}, {stage}):\n{r.stdout}{r.stderr}".strip())


def glslang_validate(model_or_name: Any, version: str = "300 es") -> None:
    """Validate the model's GLSL with ``glslangValidator`` (see :func:`glslang_validate_source`)."""
    glslang_validate_source(shader_source(model_or_name), version)


# ---------------------------------------------------------------------------
# shared test vectors
# ---------------------------------------------------------------------------
def _sph(theta_deg, phi_deg) -> np.ndarray:
    """Unit vectors from polar angle and azimuth in degrees."""
    return spherical_to_vector(np.radians(theta_deg), np.radians(phi_deg))


def _grazing(z: float, phi_deg) -> np.ndarray:
    p = np.radians(np.asarray(phi_deg, dtype=np.float64))
    r = np.sqrt(1.0 - z * z)
    return np.stack(np.broadcast_arrays(r * np.cos(p), r * np.sin(p), np.full_like(p, z)), axis=-1)


@lru_cache(maxsize=None)
def _parity_vectors(n_random: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(20261122)
    wis, wos, kinds = [], [], []

    def add(kind, wi, wo):
        wi, wo = np.broadcast_arrays(np.atleast_2d(wi), np.atleast_2d(wo))
        wis.append(wi)
        wos.append(wo)
        kinds.extend([kind] * wi.shape[0])

    def hemi(n):
        return random_unit_vectors(n, rng)

    z = np.array([0.0, 0.0, 1.0])
    # uniform random pairs over the upper hemisphere
    add("random", hemi(n_random), hemi(n_random))
    # pairs near the mirror direction (specular peaks), cones of 1°..15° around it
    wo = hemi(n_random // 2)
    jitter = rng.normal(size=wo.shape) * np.radians(rng.choice([1.0, 5.0, 15.0], size=(wo.shape[0], 1)))
    wi = normalize(reflect(wo) + jitter)
    wi[:, 2] = np.abs(wi[:, 2]) + 1e-3
    add("near-mirror", normalize(wi), wo)
    # normal incidence and viewing
    add("normal", z, z)
    add("normal-wi", z, _sph([20, 45, 70, 89], [0, 90, 200, 300]))
    add("normal-wo", _sph([20, 45, 70, 89], [10, 120, 230, 330]), z)
    # wi == wo (retro-reflection), various angles and azimuths
    w = _sph([5, 30, 60, 80, 89.5], [0, 45, 90, 135, 250])
    add("wi==wo", w, w)
    # exact mirror pairs
    w = _sph([1, 10, 30, 45, 60, 75, 85, 89], [0, 30, 60, 90, 120, 180, 270, 315])
    add("mirror", reflect(w), w)
    # near-grazing: z = 1e-3 for wi, wo, both (same side, mirror, perpendicular)
    g = _grazing(1e-3, [0, 60, 90, 180])
    add("grazing-wi", g, _sph([0, 30, 60, 85], [20, 80, 300, 180]))
    add("grazing-wo", _sph([0, 30, 60, 85], [200, 100, 10, 45]), g)
    add("grazing-both", g, g)
    add("grazing-both", reflect(g), g)
    add("grazing-both", _grazing(1e-3, [90, 150, 0, 270]), g)
    # a hair above the horizon (z = cos 90° in float64, 6e-17)
    h = _sph([90, 90], [0, 45])
    add("grazing-6e-17", h, _sph([30, 60], [0, 90]))
    add("grazing-6e-17", _sph([30, 60], [0, 90]), h)
    add("grazing-6e-17", h, reflect(h))
    # exactly at and below the horizon: the result must be 0
    h[:, 2] = 0.0
    add("horizon", h, _sph([30, 60], [0, 90]))
    add("horizon", _sph([30, 60], [0, 90]), h)
    b = _sph([100, 179], [10, 200])
    add("below", b, _sph([30, 60], [0, 90]))
    add("below", _sph([30, 60], [0, 90]), b)
    w = _sph([30, 70], [40, 160])
    add("below", w, -w)  # wi == -wo

    wi = np.concatenate(wis).astype(np.float32)
    wo = np.concatenate(wos).astype(np.float32)
    for a in (wi, wo):
        a.setflags(write=False)
    k = np.array(kinds)
    k.setflags(write=False)
    return wi, wo, k


def parity_vectors(n_random: int = 512) -> dict[str, np.ndarray]:
    """The shared, deterministic test vectors of the GLSL == numpy parity tests.

    Returns ``{"wi": (N, 3) float32, "wo": (N, 3) float32, "kind": (N,) str}``:
    ``n_random`` uniform pairs over the upper hemisphere, ``n_random/2`` pairs
    near the mirror configuration, and special pairs (normal incidence,
    ``wi == wo``, exact mirror, near-grazing ``z = 1e-3`` and ``z = 6e-17``,
    exactly at (``z = 0``) and below the horizon, ``wi == -wo``). Built in float64 from a fixed seed, then cast
    to float32, so numpy and GLSL read bit-identical inputs.
    """
    wi, wo, kind = _parity_vectors(int(n_random))
    return {"wi": wi, "wo": wo, "kind": kind}


__all__ = [
    "SHADER_DIR",
    "GLSLError",
    "shader_path",
    "has_shader",
    "common_source",
    "shader_source",
    "uniform_declarations",
    "declared_uniforms",
    "uniform_values",
    "set_uniforms",
    "eval_glsl",
    "compile_source",
    "compile_check",
    "glslang_available",
    "glslang_validate_source",
    "glslang_validate",
    "gl_info",
    "parity_vectors",
    "is_measured",
    "table_key",
    "table_texels",
    "TableTextures",
]
