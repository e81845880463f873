"""Extra JSON/binary endpoints of the explorer, kept apart from the HTTP plumbing in :mod:`.server`.

``ROUTES`` maps ``(method, path)`` (e.g. ``("GET", "/api/nbrdf")``) to a handler
``handler(query: dict[str, list[str]], body: bytes) -> (status, content_type, payload_bytes)``.
The server dispatches to this table after its own routes; a handler raises
``ValueError`` for bad input, which the server answers with 400 and the
one-line message (never a traceback, never a file-system path).

Endpoints (all local; nothing here reaches outside the machine):

``GET /api/measured``
    ``{"materials": [...]}``: the 159 built-in measured materials (``set/name``).
``GET /api/nbrdf?name=SET/NAME``
    ``{"name", "weights"}``: the material's Neural-BRDF network as 211 vec4
    (844 float32) for ``u_nbrdf[211]`` in ``render/shaders/nbrdf.glsl``: the layers
    cut into 4×4 blocks (column-major mat4, 21 units padded with zeros to 24) so
    that the shader reads every weight at a constant index (:func:`nbrdf_weights`).
``GET /api/nbrdf/shader``
    GLSL ES 3.00 defining ``vec3 brdf(vec3 wi, vec3 wo)`` for a Neural-BRDF network
    (:func:`nbrdf_source`).
``GET /api/measured/shader``
    GLSL ES 3.00 defining ``brdf()`` for a MERL table in a 3D texture (``measured.glsl``).
``GET /api/glsl?file=NAME.glsl``
    one file of ``render/shaders`` as text (the page assembles the renderer's pipeline
    from ``pipeline_*.glsl`` exactly as :mod:`brdfkit.render.renderer` does).
``GET /api/mesh?name=sphere|torus|plane|teapot&tessellation=N``
    a built-in mesh of :mod:`brdfkit.render.meshes` as JSON ``{"name", "positions",
    "normals", "tangents", "faces"}`` (flat lists).
``POST /api/mesh`` (body: an OBJ file)
    the same for an uploaded OBJ, read by :func:`brdfkit.render.meshes.load_mesh`.
``POST /api/merl`` (body: a MERL ``.binary`` file)
    read with :func:`brdfkit.measured.merl.load_merl`; answers ``application/octet-stream``: the table as the
    float32 RGBA texels of ``measured.glsl``'s ``u_table`` (90×90×180×4,
    :func:`brdfkit.render.glsl.table_texels`).
``POST /api/measured/file?name=FILE`` (body: an RGL ``.bsdf`` or a ``.bin`` file, UTIA or MERL, told by content)
    read by :func:`brdfkit.sources.load_measured` (the readers of ``bk.model``); answers
    ``application/octet-stream``: the textures of its GLSL twin (``rgl.glsl``, ``utia.glsl``, or
    ``measured.glsl`` for a MERL ``.bin``) in :func:`brdfkit.render.tables.pack`'s format, the header
    also carrying ``name``, ``title`` and ``isotropic``. A bad file: 400 and one line naming the
    file by the name given (never a path on the server).
``GET /api/measured/shader?format=rgl|utia``
    GLSL ES 3.00 defining ``brdf()`` for those tables (without ``format``: the MERL table's, below).
``POST /api/brdf?name=FILE.brdf`` (body: a Disney BRDF Explorer ``.brdf`` file)
    parsed by :mod:`brdfkit.interchange.brdf_explorer`; ``{"name", "glsl", "info"}``: its
    GLSL ES 3.00 (``glsl_es_source``, checked there against the 3.30 original) defining
    ``brdf()``, and its parameter table in the ``/api/models`` row format.
``GET /api/opengl``
    the fixed-function model's twelve materials (:data:`brdfkit.opengl.MATERIALS`) and
    OpenGL's default light.
``GET /api/envs``, ``GET /api/env?name=NAME``, ``GET /api/ibl/sampler?model=NAME&params=JSON``
    the built-in environment maps; one map as the renderer's IBL textures (binary, see
    :func:`env_payload`); a model's importance-sampling uniforms for ``ibl.glsl``.
``GET /api/validate?model=NAME&params=JSON``
    ``{"ok": true, "params"}`` or ``{"ok": false, "error"}`` (always status 200).
``GET /api/albedo?model=NAME&params=JSON&n=K``
    the directional albedo ρ(θi) at K angles from 0° to 89° by the engine's
    quadrature (:func:`brdfkit.analysis.albedo`, ``over="wo"``).
"""

from __future__ import annotations

import json
import os
import tempfile
from typing import Callable

import numpy as np

from ..sources import identify, resolve
from .jsonio import jsonable, loads, ui_model_info

Handler = Callable[[dict, bytes], tuple[int, str, bytes]]

ROUTES: dict[tuple[str, str], Handler] = {}

JSON = "application/json; charset=utf-8"
TEXT = "text/plain; charset=utf-8"
MAX_UPLOAD = 64 * 1024 * 1024  # a MERL file is 33 MB
NBRDF_VEC4 = 211  # u_nbrdf[211] in nbrdf.glsl (nbrdf_blocks)


def _params(query: dict) -> dict:
    """The ``params`` query value: a JSON object (the server's depth-checked parser), ``{}`` if absent."""
    params = loads(_one(query, "params", "{}") or "{}", "params", 'give a JSON object like {"kd": 0.5}')
    if not isinstance(params, dict):
        raise ValueError('params: must be a JSON object like {"kd": 0.5}')
    return params


def web_model_class(name: str):
    """The registered model class a web request names (:func:`web_model`'s rules; measured data has none)."""
    return identify(name, files=False).model_class()


def web_model(name: str, params: dict | None = None):
    """The model a web request names: a registry name or a built-in measured material, nothing else.

    :func:`brdfkit.sources.resolve` with ``files=False``: ``bk.model`` also takes file paths
    (``.brdf``, ``.binary``, ...) for local use, but a request from the page must never make
    the server read a file of its choosing (nor quote a line of one in an error); the
    resolver refuses paths from their text alone, before anything on disk is looked at.
    """
    return resolve(name, params, files=False)


def route(method: str, path: str):
    def deco(fn: Handler) -> Handler:
        ROUTES[(method, path)] = fn
        return fn

    return deco


def _json(obj) -> tuple[int, str, bytes]:
    return 200, JSON, json.dumps(obj, separators=(",", ":"), allow_nan=False).encode("utf-8")


def _one(query: dict, key: str, default: str | None = None) -> str:
    v = query.get(key)
    if not v:
        if default is None:
            raise ValueError(f"missing query parameter '{key}'")
        return default
    if len(v) > 1:
        raise ValueError(f"query parameter '{key}' given {len(v)} times; give it once")
    return v[0]


def _only(query: dict, allowed: set[str]) -> None:
    for k in query:
        if k not in allowed:
            raise ValueError(f"unknown query parameter '{k}'; allowed: {', '.join(sorted(allowed))}")


def _body(body: bytes, what: str) -> bytes:
    if not body:
        raise ValueError(f"{what}: the request body is empty; POST the file's bytes")
    if len(body) > MAX_UPLOAD:
        raise ValueError(f"{what}: {len(body)} bytes is more than the {MAX_UPLOAD} allowed")
    return body


def _with_temp_file(body: bytes, suffix: str, fn, label: str = "the uploaded file"):
    """``fn(path)`` on the body written (atomically) to a file in a private temporary folder;
    an error's message names the file ``label``, never the temporary path."""
    from ..fileio import write_bytes

    with tempfile.TemporaryDirectory(prefix="brdfkit-web-") as d:
        path = os.path.join(d, "upload" + suffix)
        write_bytes(path, body)
        try:
            return fn(path)
        except (OSError, ValueError) as e:
            msg = str(e).replace(path, label).replace(d, "")
            raise ValueError(msg.strip().splitlines()[0] if msg.strip() else type(e).__name__) from None


# ---------------------------------------------------------------------------
# measured materials
# ---------------------------------------------------------------------------
@route("GET", "/api/measured")
def measured_list(query: dict, body: bytes):
    _only(query, set())
    from ..measured import nbrdf

    return _json({"materials": list(nbrdf.materials())})


def nbrdf_blocks(fc1, b1, fc2, b2, fc3, b3) -> np.ndarray:
    """A network's layers as the ``NBRDF_VEC4`` × 4 float32 values of ``u_nbrdf`` (nbrdf.glsl).

    ``fc*`` are (inputs, units) as in the npz (x·W). Units are padded with zeros to 24 =
    6 groups of 4; a mat4 is 4 vec4 columns, column c holding input c's weights to the
    group's 4 units (GLSL's ``mat4 * vec4``). Layout, in vec4:

    * ``[6k, 6k+6)``, group k of layer 1: a mat4 for the inputs (x0, x2, x3, x4), then
      x5's column, then the bias (x1 = 0 contributes nothing);
    * ``36 + 24k + 4m``: the mat4 from group m of layer 1 to group k of layer 2;
      ``180 + k``: layer 2's bias;
    * ``186 + 4m``: the mat4 from group m of layer 2 to the 3 outputs (+ a zero); ``210``: the bias.
    """
    def pad(a, rows, cols):
        out = np.zeros((rows, cols), np.float32)
        a = np.asarray(a, np.float32).reshape(a.shape[0], -1)
        out[: a.shape[0], : a.shape[1]] = a
        return out

    w1, w2, w3 = pad(fc1, len(fc1), 24), pad(fc2, 24, 24), pad(fc3, 24, 4)
    v1, v2, v3 = pad(np.reshape(b1, (1, -1)), 1, 24)[0], pad(np.reshape(b2, (1, -1)), 1, 24)[0], pad(np.reshape(b3, (1, -1)), 1, 4)[0]
    vec4: list[np.ndarray] = []
    for k in range(6):  # layer 1: columns = inputs 0, 2, 3, 4, then 5, then the bias
        g = slice(4 * k, 4 * k + 4)
        vec4 += [w1[i, g] for i in (0, 2, 3, 4, 5)] + [v1[g]]
    for k in range(6):  # layer 2
        for m in range(6):
            vec4 += [w2[4 * m + c, 4 * k:4 * k + 4] for c in range(4)]
    vec4 += [v2[4 * k:4 * k + 4] for k in range(6)]
    for m in range(6):  # layer 3
        vec4 += [w3[4 * m + c] for c in range(4)]
    vec4.append(v3)
    flat = np.concatenate(vec4).astype(np.float32)
    if flat.size != 4 * NBRDF_VEC4:
        raise ValueError(f"unexpected network shape ({flat.size} floats, expected {4 * NBRDF_VEC4})")
    return flat


def nbrdf_weights(name: str) -> np.ndarray:
    """The network of a built-in material as the 844 float32 values ``nbrdf.glsl`` reads."""
    from ..measured import nbrdf

    return nbrdf_blocks(*nbrdf.layers(nbrdf.resolve(name)))


@route("GET", "/api/nbrdf")
def nbrdf_payload(query: dict, body: bytes):
    _only(query, {"name"})
    from ..measured import nbrdf

    name = nbrdf.resolve(_one(query, "name"))
    return _json({"name": name, "weights": [float(x) for x in nbrdf_weights(name)]})


def nbrdf_source() -> str:
    """GLSL (no ``#version``) defining ``brdf()`` for a Neural-BRDF network.

    common.glsl, then measured.glsl for its Rusinkiewicz angles (``bk_merl_angles``;
    its own table ``brdf()`` renamed away by a ``#define``), then nbrdf.glsl.
    """
    from ..render import glsl

    return (
        glsl.common_source()
        + "\n#define brdf bk_merl_table_brdf\n"
        + glsl.shader_file("measured.glsl")
        + "\n#undef brdf\n"
        + glsl.shader_file("nbrdf.glsl")
    )


@route("GET", "/api/nbrdf/shader")
def nbrdf_shader(query: dict, body: bytes):
    _only(query, set())
    return 200, TEXT, ("#version 300 es\n" + nbrdf_source()).encode("utf-8")


_TABLE_SHADERS = {"merl": "measured.glsl", "rgl": "rgl.glsl", "utia": "utia.glsl"}


@route("GET", "/api/measured/shader")
def measured_shader(query: dict, body: bytes):
    _only(query, {"format"})
    from ..render import glsl

    fmt = _one(query, "format", "merl")
    if fmt not in _TABLE_SHADERS:
        raise ValueError(f"unknown table format {fmt!r}; valid: {', '.join(_TABLE_SHADERS)}")
    src = glsl.common_source() + "\n" + glsl.shader_file(_TABLE_SHADERS[fmt])
    return 200, TEXT, ("#version 300 es\n" + src).encode("utf-8")


MEASURED_SUFFIXES = (".bsdf", ".bin")
MAX_TABLE_BYTES = 512 << 20  # the textures sent back for one file


def _read_measured_upload(data: bytes, name: str):
    """The model of an uploaded measured file (its kind by ``name``'s suffix, a .bin by content)."""
    from ..sources import load_measured

    suffix = os.path.splitext(name)[1].lower()
    if suffix not in MEASURED_SUFFIXES:
        raise ValueError(f"{name}: expected an RGL .bsdf or a UTIA/MERL .bin file")
    try:
        return _with_temp_file(data, suffix, load_measured, label=name)
    except ValueError:
        raise
    except Exception as e:  # a reader's unforeseen failure on a malformed file: still one line, never a 500
        raise ValueError(f"{name}: not a readable {suffix} file ({type(e).__name__})") from None


@route("POST", "/api/measured/file")
def measured_file_upload(query: dict, body: bytes):
    _only(query, {"name"})
    from ..render import tables

    name = os.path.basename(_one(query, "name"))[:200] or "uploaded"
    model = _read_measured_upload(_body(body, name), name)
    fmt = tables.format_of(model)
    if fmt:
        ts = tables.table_set(model)
    else:  # a MERL .bin: measured.glsl's u_table, nearest lookup
        from ..render import glsl

        ts = tables.TableSet("merl", "measured.glsl", (tables.Texture("u_table", glsl.table_texels(model)),),
                             {"u_interpolation": 0})
    titles = {"rgl": "RGL .bsdf file (Dupuy & Jakob 2018), evaluated as Mitsuba 3's measured",
              "utia": "UTIA .bin file (Filip & Vávra 2014), quadrilinear",
              "merl": "MERL table (dropped file), nearest bin"}
    size = sum(t.data.nbytes for t in ts.textures)
    if size > MAX_TABLE_BYTES:
        raise ValueError(f"{name}: its tables take {size >> 20} MiB, more than the explorer's {MAX_TABLE_BYTES >> 20} MiB")
    return 200, "application/octet-stream", tables.pack(
        ts, name=name, title=titles[ts.format], isotropic=bool(getattr(model, "isotropic", False)))


@route("POST", "/api/merl")
def merl_upload(query: dict, body: bytes):
    _only(query, set())
    from ..measured.merl import load_merl
    from ..render import glsl

    data = _body(body, "MERL file")
    model = _with_temp_file(data, ".binary", load_merl)
    texels = np.ascontiguousarray(glsl.table_texels(model), dtype="<f4")
    return 200, "application/octet-stream", texels.tobytes()


# ---------------------------------------------------------------------------
# Disney BRDF Explorer .brdf files (parsed by brdfkit.interchange)
# ---------------------------------------------------------------------------
_BRDF_WORKER = r"""
import json, sys
sys.path[:0] = json.loads(sys.argv[1])
from brdfkit.interchange.brdf_explorer import glsl_es_source, model_class, parse_brdf_text
text = sys.stdin.buffer.read().decode("utf-8")
try:
    cls = model_class(parse_brdf_text(text, sys.argv[2]))
    es = glsl_es_source(cls)
    out = {"ok": es is not None, "glsl": es, "error": None if es is not None else
           sys.argv[2] + ": its GLSL does not compile as GLSL ES 3.00 (WebGL 2)"}
except ValueError as e:
    out = {"ok": False, "error": (str(e).strip().splitlines() or ["invalid .brdf file"])[0]}
sys.stdout.write(json.dumps(out))
"""
_BRDF_CACHE: dict[str, str] = {}


def _brdf_glsl_es(text: str, name: str) -> str:
    """The GLSL ES 3.00 of a .brdf file, compiled and checked by brdfkit.interchange in a
    child process: its checks run OpenGL through brdfkit.render.glsl's one headless context,
    which stays current in the thread that used it last, and the server answers every
    request in a new thread (and may share its process with other GL users)."""
    import hashlib
    import subprocess
    import sys

    key = hashlib.blake2b((name + "\0" + text).encode("utf-8"), digest_size=16).hexdigest()
    if key in _BRDF_CACHE:
        return _BRDF_CACHE[key]
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    try:
        r = subprocess.run([sys.executable, "-c", _BRDF_WORKER, json.dumps([root]), name], input=text.encode("utf-8"),
                           capture_output=True, timeout=120)
        out = json.loads(r.stdout.decode("utf-8") or "null")
    except (subprocess.TimeoutExpired, json.JSONDecodeError, OSError):
        out = None
    if not isinstance(out, dict):
        raise ValueError(f"{name}: could not be compiled (the GLSL check failed to run)")
    if not out["ok"]:
        raise ValueError(out["error"])
    _BRDF_CACHE[key] = out["glsl"]
    return out["glsl"]


@route("POST", "/api/brdf")
def brdf_upload(query: dict, body: bytes):
    """A ``.brdf`` file: ``{"name", "glsl" (GLSL ES 3.00 defining brdf()), "info" (its parameter table)}``."""
    _only(query, {"name"})
    from ..interchange.brdf_explorer import parse_brdf_text
    from ..render import glsl

    name = os.path.basename(_one(query, "name", "uploaded.brdf"))
    try:
        text = _body(body, name).decode("utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"{name}: not a text file (a .brdf file is UTF-8 text)") from None
    shader = parse_brdf_text(text, name)  # the parse needs no GL: its errors come straight back
    from ..interchange.brdf_explorer import BrdfExplorerModel

    cls = type("BrdfFile", (BrdfExplorerModel,), {"name": name, "spec": shader.params, "brdf_shader": shader})
    es = _brdf_glsl_es(text, name)
    info = ui_model_info(cls, {**glsl.GLSL_TYPES, "bool": "bool"})  # a .brdf file's booleans are `uniform bool`
    return _json({"name": name, "glsl": "#version 300 es\n" + glsl.common_source() + "\n" + es, "info": jsonable(info)})


# ---------------------------------------------------------------------------
# shaders, meshes, the fixed-function table
# ---------------------------------------------------------------------------
@route("GET", "/api/glsl")
def glsl_file(query: dict, body: bytes):
    _only(query, {"file"})
    from ..render import glsl

    name = _one(query, "file")
    files = sorted(p.name for p in glsl.SHADER_DIR.glob("*.glsl"))
    if name not in files:
        raise ValueError(f"no shader file {name!r}; available: {', '.join(files)}")
    return 200, TEXT, glsl.shader_file(name).encode("utf-8")


MESH_TESSELLATION = (2, 256)


def _mesh_json(mesh) -> tuple[int, str, bytes]:
    def flat(a, dtype=np.float32):
        return np.asarray(a, dtype=dtype).reshape(-1).tolist()

    return _json({
        "name": mesh.name,
        "positions": [round(x, 6) for x in flat(mesh.positions)],
        "normals": [round(x, 6) for x in flat(mesh.normals)],
        "tangents": [round(x, 6) for x in flat(mesh.tangents)],
        "faces": flat(mesh.faces, np.int64),
    })


@route("GET", "/api/mesh")
def mesh_builtin(query: dict, body: bytes):
    _only(query, {"name", "tessellation"})
    from ..render import meshes

    name = _one(query, "name")
    text = _one(query, "tessellation", "32")
    try:
        t = int(text)
    except ValueError:
        raise ValueError(f"tessellation must be an integer, got {text!r}") from None
    lo, hi = MESH_TESSELLATION
    if not lo <= t <= hi:
        raise ValueError(f"tessellation {t} is out of range; allowed [{lo}, {hi}]")
    kwargs = {
        "sphere": {"segments": 2 * t, "rings": t},
        "torus": {"segments": 2 * t, "sides": t},
        "plane": {"divisions": t},
        "teapot": {"subdivisions": max(1, t // 3)},
    }
    if name not in kwargs:
        raise ValueError(f"unknown built-in mesh {name!r}; valid: {', '.join(kwargs)}")
    return _mesh_json(meshes.builtin(name, **kwargs[name]))


@route("POST", "/api/mesh")
def mesh_upload(query: dict, body: bytes):
    _only(query, set())
    from ..render import meshes

    data = _body(body, "OBJ file")
    mesh = _with_temp_file(data, ".obj", meshes.load_mesh)
    import dataclasses

    mesh = dataclasses.replace(mesh, name="uploaded OBJ")
    if mesh.n_triangles > 2_000_000:
        raise ValueError(f"OBJ file: {mesh.n_triangles} triangles is more than the 2000000 allowed")
    return _mesh_json(mesh)


@route("GET", "/api/opengl")
def opengl_table(query: dict, body: bytes):
    _only(query, set())
    from dataclasses import asdict

    from .. import opengl

    mats = {name: asdict(m) for name, m in opengl.MATERIALS.items()}
    light = asdict(opengl.Light())
    return _json({"materials": mats, "light": light, "light_model": asdict(opengl.LightModel())})


# ---------------------------------------------------------------------------
# image-based lighting (brdfkit.render.environment / ibl, the renderer's ibl*.glsl)
# ---------------------------------------------------------------------------
@route("GET", "/api/envs")
def env_list(query: dict, body: bytes):
    _only(query, set())
    from ..render import environment

    return _json({"environments": dict(environment.BUILTINS)})


@route("GET", "/api/env")
def env_payload(query: dict, body: bytes):
    """A built-in environment as the renderer's three IBL textures, little-endian binary:
    int32 ×6 (the rgba, marginal and conditional textures' heights and widths), float32 ×10
    (world_to_map row-major 3×3, strength), then the float32 texels of the three textures
    (:func:`brdfkit.render.ibl.env_texture_data`)."""
    _only(query, {"name"})
    from ..render import environment, ibl

    name = _one(query, "name")
    if name not in environment.BUILTINS:
        raise ValueError(f"unknown environment {name!r}; built-ins: {', '.join(environment.BUILTINS)}")
    env = environment.Environment(name, environment.builtin_map(name))
    rgba, marg, cond = ibl.env_texture_data(env)
    head = np.array([rgba.shape[0], rgba.shape[1], marg.shape[0], marg.shape[1], cond.shape[0], cond.shape[1]], "<i4")
    extra = np.concatenate([np.asarray(env.world_to_map(), np.float64).reshape(-1), [float(env.strength)]]).astype("<f4")
    parts = [head.tobytes(), extra.tobytes()] + [np.ascontiguousarray(a, "<f4").tobytes() for a in (rgba, marg, cond)]
    return 200, "application/octet-stream", b"".join(parts)


@route("GET", "/api/ibl/sampler")
def ibl_sampler(query: dict, body: bytes):
    """The ``bki_lobe``, ``bki_lobe_params``, ``bki_diffuse_prob`` uniforms of a model's sampler
    (:func:`brdfkit.render.ibl.sampler_uniforms`)."""
    _only(query, {"model", "params"})
    from ..render import ibl

    name = _one(query, "model")
    params = _params(query)
    m = web_model(name, params)
    return _json(jsonable(ibl.sampler_uniforms(m)))


# ---------------------------------------------------------------------------
# parameter validation (params.py through bk.model): the page checks URL and file values here
# ---------------------------------------------------------------------------
@route("GET", "/api/validate")
def validate_payload(query: dict, body: bytes):
    """``{"ok": true, "params": effective}`` or ``{"ok": false, "error": one line}`` (status 200 either way:
    a bad value is an answer here, not a failed request)."""
    _only(query, {"model", "params"})
    from ..params import to_jsonable

    name = _one(query, "model")
    try:
        m = web_model(name, _params(query))
    except ValueError as e:
        return _json({"ok": False, "error": str(e).strip().splitlines()[0]})
    return _json({"ok": True, "params": jsonable(to_jsonable(m.params))})


# ---------------------------------------------------------------------------
# albedo by the engine (the page's own is GPU quadrature)
# ---------------------------------------------------------------------------
@route("GET", "/api/albedo")
def albedo_payload(query: dict, body: bytes):
    _only(query, {"model", "params", "n"})
    from ..analysis import albedo

    name = _one(query, "model")
    params = _params(query)
    text = _one(query, "n", "30")
    try:
        n = int(text)
    except ValueError:
        raise ValueError(f"n must be an integer, got {text!r}") from None
    if not 2 <= n <= 200:
        raise ValueError(f"n {n} is out of range; allowed [2, 200]")
    m = web_model(name, params)
    theta = np.radians(np.linspace(0.0, 89.0, n))
    rho = np.asarray(albedo(m, theta, over="wo", level="fast", include_delta=False), dtype=np.float64)
    rho = np.where(np.isfinite(rho), rho, 0.0)
    return _json({
        "model": name,
        "theta_deg": np.degrees(theta).tolist(),
        "rgb": rho.tolist(),
        "method": "brdfkit.analysis.albedo (engine quadrature, level=fast, mirror part excluded)",
    })
