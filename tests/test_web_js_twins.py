"""The page's JavaScript copies of Python logic, pinned to the Python they copy.

Each test imports one of the page's ES modules in a real browser (Debian's chromium,
headless, as tests/test_web_browser.py) and evaluates the JavaScript function at many
inputs next to the Python function it copies:

* ``numbers.srgbEncode`` = :func:`brdfkit.render.image.srgb_encode` on [0, 1], and
  ``numbers.srgbToLinear`` is its inverse (1e-6 relative, 1e-9 absolute; both in doubles);
* ``numbers.fromHalfDiff`` (the CSV slice, θh/θd plots) =
  :func:`brdfkit.geometry.from_rusinkiewicz` with φh = 0 (1e-9 absolute);
* ``numbers.effectiveParams`` (the alpha / alpha_x / alpha_y rule) = the parameters the
  Python model takes for the same given values, for every model with the three;
* ``brdfs.intConstants`` (a choice's index, a bool as 0/1) =
  :func:`brdfkit.render.glsl.uniform_values` for every choice of every model;
* ``numbers.eyeToMap`` = :func:`brdfkit.render.ibl.eye_to_map` (float32 on the page:
  1e-6 absolute);
* ``shaders.pipelineSources`` = the vertex and fragment sources of
  :meth:`brdfkit.render.renderer.Renderer._program` for every lighting and shading, but for
  the header (GLSL ES 3.00 and its precision lines instead of 3.30 core).

Skipped, with the reason, when /usr/bin/chromium or the Python package playwright is missing.
"""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from brdfkit import geometry, registry
from brdfkit.render import glsl, ibl
from brdfkit.render.image import srgb_encode

CHROMIUM = "/usr/bin/chromium"
if not os.path.exists(CHROMIUM):
    pytest.skip(f"{CHROMIUM} not found (Debian: apt-get install chromium)", allow_module_level=True)
playwright_api = pytest.importorskip("playwright.sync_api", reason="the Python package playwright is not installed")

from brdfkit.web import start_in_thread  # noqa: E402

ARGS = ["--headless=new", "--no-sandbox", "--disable-gpu", "--use-gl=angle", "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader", "--disable-background-networking", "--no-first-run"]


@pytest.fixture(scope="module")
def page():
    srv, thread = start_in_thread("127.0.0.1", 0)
    pw = playwright_api.sync_playwright().start()
    browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
    errors: list[str] = []
    pg = browser.new_page(viewport={"width": 1024, "height": 768})
    pg.on("pageerror", lambda e: errors.append(str(e)))
    pg.goto(srv.url)
    pg.wait_for_function("window.brdfkitStatus && window.brdfkitStatus.ready", timeout=90_000)
    try:
        yield pg
        assert errors == [], errors
    finally:
        browser.close()
        pw.stop()
        srv.shutdown()
        srv.server_close()
        thread.join(5)


def js(pg, module: str, body: str, arg=None):
    """``body`` (a function body with ``m``, the imported module, and ``arg``) evaluated on the page."""
    return pg.evaluate(f"async (arg) => {{ const m = await import('/static/js/{module}'); {body} }}", arg)


def test_srgb_encode_and_decode_equal_python(page):
    x = np.concatenate([np.linspace(0.0, 1.0, 2001), np.geomspace(1e-7, 1.0, 300), [0.0031308, 0.04045]])
    enc = np.array(js(page, "numbers.js", "return arg.map(m.srgbEncode);", x.tolist()))
    np.testing.assert_allclose(enc, srgb_encode(x), rtol=1e-6, atol=1e-9)
    dec = np.array(js(page, "numbers.js", "return arg.map(m.srgbToLinear);", x.tolist()))
    np.testing.assert_allclose(srgb_encode(dec), x, rtol=1e-6, atol=1e-9)  # the inverse of Python's encode


def test_from_half_diff_equals_python_rusinkiewicz(page):
    rng = np.random.default_rng(7)
    n = 500
    th, td = rng.uniform(0, np.pi / 2, n), rng.uniform(0, np.pi / 2, n)
    pd = rng.uniform(0, 2 * np.pi, n)
    th[:3], td[:3], pd[:3] = [0, np.pi / 2, 0], [0, 0, np.pi / 2], [0, np.pi, np.pi / 2]
    got = js(page, "numbers.js", "return arg.map(([a, b, c]) => m.fromHalfDiff(a, b, c));",
             np.stack([th, td, pd], -1).tolist())
    wi, wo = geometry.from_rusinkiewicz(th, np.zeros(n), td, pd)
    np.testing.assert_allclose(np.array([g[0] for g in got]), wi, atol=1e-9)
    np.testing.assert_allclose(np.array([g[1] for g in got]), wo, atol=1e-9)


def _alpha_models() -> list[str]:
    return [n for n in registry.names() if {"alpha", "alpha_x", "alpha_y"} <= {p.name for p in registry.get(n).spec}]


def test_alpha_rule_equals_python(page):
    names = _alpha_models()
    assert names, "no model with alpha, alpha_x and alpha_y"
    given_sets = [{}, {"alpha": 0.3}, {"alpha": 0.05}, {"alpha_x": 0.1, "alpha_y": 0.4},
                  {"alpha_x": 0.25, "alpha_y": 0.25}, {"alpha_x": 0.7}, {"alpha_y": 0.02}]
    for name in names:
        for given in given_sets:
            got = js(page, "brdfs.js", "return (await import('/static/js/numbers.js')).effectiveParams(m.infoOf(arg.name), arg.given);",
                     {"name": name, "given": given})
            want = registry.get(name)(**given).params
            for k in ("alpha", "alpha_x", "alpha_y"):
                w = want[k]
                assert (got[k] is None) == (w is None), (name, given, k, got[k], w)
                if w is not None:
                    assert abs(got[k] - float(w)) <= 1e-9, (name, given, k, got[k], w)


def test_int_uniforms_equal_python(page):
    checked = 0
    for name in registry.names():
        cls = registry.get(name)
        ints = [p for p in cls.spec if glsl.GLSL_TYPES[p.kind] == "int"]
        for p in ints:
            values = list(p.choices) if p.kind == "choice" else [True, False] if p.kind == "bool" else [p.default]
            for v in values:
                try:
                    model = cls(**{p.name: v})
                except ValueError:  # a combination the model refuses
                    continue
                got = js(page, "brdfs.js", "return m.intConstants(arg.name, arg.params);", {"name": name, "params": {p.name: v}})
                want = glsl.uniform_values(model)
                assert got is not None and got[f"u_{p.name}"] == want[f"u_{p.name}"], (name, p.name, v, got, want)
                for q in ints:  # the other int uniforms at their defaults
                    assert got[f"u_{q.name}"] == want[f"u_{q.name}"], (name, q.name, got, want)
                checked += 1
    assert checked > 5


def test_eye_to_map_equals_python(page):
    rng = np.random.default_rng(3)
    for _ in range(40):
        orbit = {"yaw": float(rng.uniform(-360, 360)), "pitch": float(rng.uniform(-89, 89)), "zoom": float(rng.uniform(0.2, 8))}
        q, _r = np.linalg.qr(rng.normal(size=(3, 3)))
        w2m = q * np.sign(np.linalg.det(q))  # a rotation
        got = js(page, "numbers.js", """
            const M = m.objectMatrices(arg.orbit, 560, 420);
            return {mv: Array.from(M.mv), e2m: Array.from(m.eyeToMap(M.nm, arg.w2m))};""",
                 {"orbit": orbit, "w2m": w2m.reshape(-1).tolist()})
        mv = np.array(got["mv"]).reshape(4, 4).T  # column-major -> row-major

        class Env:
            def world_to_map(self):
                return w2m

        want = ibl.eye_to_map(mv, Env())
        e2m = np.array(got["e2m"]).reshape(3, 3).T
        np.testing.assert_allclose(e2m, want, atol=1e-6)


def _python_pipeline(lighting: str, where: str, shading: str, model) -> tuple[str, str]:
    """The (vertex, fragment) sources brdfkit.render.renderer.Renderer._program compiles."""
    from brdfkit.render.renderer import Renderer

    seen = []

    class Ctx:
        def program(self, vertex_shader, fragment_shader):
            seen.append((vertex_shader, fragment_shader))
            return object()

    class Fake:
        ctx = Ctx()
        _programs: dict = {}

    Renderer._program(Fake(), lighting, where, shading, model)
    return seen[0]


def _split_head(src: str) -> tuple[list[str], str]:
    """The header lines (#version, #define, precision) and the rest."""
    lines = src.split("\n")
    k = 0
    while k < len(lines) and lines[k].startswith(("#version", "#define BKR_", "precision ")):
        k += 1
    return lines[:k], "\n".join(lines[k:])


@pytest.mark.parametrize("kind", ["obj-flat", "obj-gouraud", "obj-phong", "gl-flat", "gl-gouraud", "gl-phong", "ibl-phong", "ibl-flat"])
def test_pipeline_assembly_equals_the_renderer(page, kind):
    what, shading = kind.split("-")
    lighting = {"obj": "brdf", "gl": "opengl", "ibl": "ibl"}[what]
    where = "ibl" if what == "ibl" else "fragment" if shading == "phong" else "vertex"
    model = registry.get("microfacet")()
    files = {f: glsl.shader_file(f) for f in ("pipeline_lights.glsl", "pipeline_vertex.glsl", "pipeline_fragment.glsl",
                                              "pipeline_brdf.glsl", "opengl_fixed.glsl", "ibl_sampling.glsl", "ibl.glsl")}
    brdf = "#version 300 es\n" + glsl.shader_source(model)  # as /api/shader/<model> serves it
    got = js(page, "shaders.js", "return m.pipelineSources(arg.kind, arg.files, arg.brdf);",
             {"kind": kind, "files": files, "brdf": brdf})
    want = _python_pipeline(lighting, where, shading, model)
    for stage, js_src, py_src in (("vertex", got["vs"], want[0]), ("fragment", got["fs"], want[1])):
        js_head, js_rest = _split_head(js_src)
        py_head, py_rest = _split_head(py_src)
        assert js_rest == py_rest, (kind, stage)
        assert js_head[0] == "#version 300 es" and py_head[0] == "#version 330 core"
        assert [h for h in js_head if h.startswith("#define")] == [h for h in py_head if h.startswith("#define")], (kind, stage)
        assert json.dumps([h for h in js_head if h.startswith("precision")]) == json.dumps(
            ["precision highp float;", "precision highp int;", "precision highp sampler2D;", "precision highp sampler3D;"])
