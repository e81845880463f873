"""The explorer's HTTP server (brdfkit.web): JSON API, static files, errors, `brdfkit serve`.

Runs a real server on 127.0.0.1 (port 0) in a thread and talks to it with urllib.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import urllib.request
from pathlib import Path
from urllib.parse import quote, urlencode

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.render import glsl
from brdfkit.web import STATIC_DIR, make_server

from _web_helpers import get_json as _get_json
from _web_helpers import request


def get(srv, path: str):
    """(status, content type, body bytes) of GET path."""
    return request(srv, path, timeout=30)


def get_json(srv, path: str):
    return _get_json(srv, path, timeout=30)


def eval_url(model: str, params=None, wi=None, wo=None, **extra) -> str:
    q = {"model": model}
    if params is not None:
        q["params"] = params if isinstance(params, str) else json.dumps(params)
    if wi is not None:
        q["wi"] = wi if isinstance(wi, str) else json.dumps(np.asarray(wi).tolist())
    if wo is not None:
        q["wo"] = wo if isinstance(wo, str) else json.dumps(np.asarray(wo).tolist())
    q.update(extra)
    return "/api/eval?" + urlencode(q)


def test_binds_loopback_and_free_port(server):
    host, port = server.server_address[:2]
    assert host == "127.0.0.1"
    assert 0 < port < 65536
    assert server.url == f"http://127.0.0.1:{port}/"


def test_models_list_matches_registry(server):
    status, body = get_json(server, "/api/models")
    assert status == 200
    names = [m["name"] for m in body["models"]]
    assert names == bk.models()
    for m in body["models"]:
        info = bk.model_info(m["name"])
        cls = bk.registry.get(m["name"])
        assert m["title"] == info["title"] and m["reference"] == info["reference"]
        assert [p["name"] for p in m["params"]] == [p.name for p in cls.spec]
        assert m["glsl"] is True  # every analytic model has a GLSL twin
        for row, spec in zip(m["params"], cls.spec):
            assert row["kind"] == spec.kind
            assert row["log_scale"] == spec.log_scale
            assert row["open_lo"] == spec.open_lo and row["open_hi"] == spec.open_hi
            assert row["uniform"]["name"] == f"u_{spec.name}"
            if spec.kind == "choice":
                assert row["choices"] == list(spec.choices)
                assert row["default"] in row["choices"]
            if spec.kind in ("scalar", "rgb", "int"):
                lo, hi = spec.range
                assert row["min"] == lo
                assert row["max"] == (None if math.isinf(hi) else hi)
            # the default validates (the UI starts from it)
            spec.validate(m["name"], row["default"])


def test_models_declare_the_uniforms_the_ui_sets(server):
    _, body = get_json(server, "/api/models")
    for m in body["models"]:
        _, _, src = get(server, "/api/shader/" + quote(m["name"]))
        declared = glsl.declared_uniforms(src.decode())
        for row in m["params"]:
            u = row["uniform"]
            assert declared.get(u["name"]) == u["type"], (m["name"], u)


def test_shader_source_is_glsl_es(server):
    for name in bk.models():
        status, ctype, body = get(server, "/api/shader/" + quote(name))
        assert status == 200 and ctype.startswith("text/plain")
        text = body.decode("utf-8")
        assert text.startswith("#version 300 es\n")
        assert text[len("#version 300 es\n"):] == glsl.shader_source(name)
        assert "vec3 brdf(vec3 wi, vec3 wo)" in text
        assert [ln for ln in text.splitlines() if ln.lstrip().startswith("#version")] == ["#version 300 es"]


@pytest.mark.parametrize("name", ["lambert", "microfacet", "ward", "oren-nayar", "htsg"])
def test_eval_equals_numpy_single(server, name):
    params = {
        "lambert": {"kd": [0.2, 0.4, 0.6]},
        "microfacet": {"alpha_x": 0.1, "alpha_y": 0.4, "distribution": "beckmann", "fresnel": "schlick"},
        "ward": {"kd": 0.1, "ks": 0.2, "alpha_x": 0.05, "alpha_y": 0.2},
        "oren-nayar": {"sigma": 0.5, "variant": "full"},
        "htsg": {},
    }[name]
    wi = np.array([0.3, -0.2, 0.9])
    wo = np.array([-0.25, 0.1, 0.8])
    status, body = get_json(server, eval_url(name, params, "0.3,-0.2,0.9", "-0.25,0.1,0.8"))
    assert status == 200, body
    m = bk.model(name, **params)
    ref = m.eval(wi / np.linalg.norm(wi), wo / np.linalg.norm(wo))
    assert np.allclose(body["value"], ref, rtol=1e-12, atol=0)
    assert body["model"] == name
    assert np.allclose(body["wi"], wi / np.linalg.norm(wi))
    for k, v in params.items():
        got = body["params"][k]
        assert (got == v) if isinstance(v, str) else np.allclose(got, v)


def test_eval_batch_equals_numpy(server):
    v = glsl.parity_vectors(32)
    wi, wo = v["wi"].astype(np.float64), v["wo"].astype(np.float64)
    ok = (np.linalg.norm(wi, axis=1) > 0) & (np.linalg.norm(wo, axis=1) > 0)
    wi, wo = wi[ok], wo[ok]
    for name in bk.models():
        status, body = get_json(server, eval_url(name, {}, wi, wo))
        assert status == 200, body
        ref = bk.model(name).eval(wi / np.linalg.norm(wi, axis=1, keepdims=True),
                                  wo / np.linalg.norm(wo, axis=1, keepdims=True))
        got = np.asarray(body["value"])
        assert got.shape == ref.shape
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-300)


def test_eval_broadcasts_one_direction_against_many(server):
    wo = [[0.0, 0.0, 1.0], [0.5, 0.0, 0.5], [0.0, -0.3, 0.7]]
    status, body = get_json(server, eval_url("phong", {"normalized": False}, "[0.2,0.1,1]", wo))
    assert status == 200, body
    ref = bk.model("phong", normalized=False).eval(
        np.array([0.2, 0.1, 1.0]) / np.linalg.norm([0.2, 0.1, 1.0]),
        np.asarray(wo) / np.linalg.norm(wo, axis=1, keepdims=True))
    assert np.allclose(body["value"], ref, rtol=1e-12)


def test_eval_below_horizon_is_zero(server):
    status, body = get_json(server, eval_url("lambert", {}, "0,0,-1", "0,0,1"))
    assert status == 200 and body["value"] == [0.0, 0.0, 0.0]


BAD = [
    ("/api/eval?wi=0,0,1&wo=0,0,1", "model"),
    (eval_url("no-such-model", {}, "0,0,1", "0,0,1"), "unknown model"),
    (eval_url("lambert", {"kd": 2.0}, "0,0,1", "0,0,1"), "out of range"),
    (eval_url("lambert", {"bogus": 1}, "0,0,1", "0,0,1"), "unknown parameter"),
    (eval_url("lambert", "{not json", "0,0,1", "0,0,1"), "params"),
    (eval_url("lambert", "[1,2]", "0,0,1", "0,0,1"), "params"),
    (eval_url("microfacet", {"distribution": "cauchy"}, "0,0,1", "0,0,1"), "beckmann, ggx"),
    (eval_url("lambert", {}, "0,0,0", "0,0,1"), "zero vector"),
    (eval_url("lambert", {}, "0,0", "0,0,1"), "wi"),
    (eval_url("lambert", {}, "a,b,c", "0,0,1"), "wi"),
    (eval_url("lambert", {}, "0,0,1", "nan,0,1"), "finite"),
    (eval_url("lambert", {}, "0,0,1", "[[0,0,1],[0,0,1]"), "JSON"),
    (eval_url("lambert", {}, [[0, 0, 1]] * 2, [[0, 0, 1]] * 3), "broadcast"),
    (eval_url("lambert", {}, "0,0,1"), "wo"),
    (eval_url("lambert", {}, "0,0,1", "0,0,1", extra="1"), "unknown query parameter"),
    ("/api/eval?model=lambert&model=phong&wi=0,0,1&wo=0,0,1", "once"),
    ("/api/shader/no-such-model", "unknown model"),
]


@pytest.mark.parametrize("path,needle", BAD)
def test_bad_input_gives_400_with_one_line(server, path, needle):
    status, body = get_json(server, path)
    assert status == 400
    assert set(body) == {"error"}
    msg = body["error"]
    assert isinstance(msg, str) and msg and "\n" not in msg
    assert needle.lower() in msg.lower(), msg
    assert "Traceback" not in msg


def test_unknown_paths_404(server):
    for path in ("/api/nothing", "/nope.html", "/static/../server.py", "/%2e%2e/server.py", "/../../etc/passwd"):
        status, ctype, body = get(server, path)
        assert status == 404, path
        assert "error" in json.loads(body)


def _module_graph(server, entry: str) -> dict[str, str]:
    """Every ES module the page loads, from ``entry`` along its static imports: URL path -> text."""
    import posixpath
    import re

    seen: dict[str, str] = {}
    todo = [entry]
    while todo:
        path = todo.pop()
        if path in seen:
            continue
        status, ctype, body = get(server, path)
        assert status == 200, path
        assert ctype.split(";")[0].strip() == "text/javascript", (path, ctype)  # a module needs a JavaScript type
        seen[path] = text = body.decode("utf-8")
        for spec in re.findall(r'^\s*import\b[^;]*?from\s+"([^"]+)"', text, re.M):
            assert spec.startswith("./") or spec.startswith("../"), (path, spec)  # relative: nothing from outside
            todo.append(posixpath.normpath(posixpath.join(posixpath.dirname(path), spec)))
    return seen


def test_static_page_is_self_contained(server):
    status, ctype, html = get(server, "/")
    assert status == 200 and ctype.startswith("text/html")
    html = html.decode()
    assert '<script type="module" src="/static/js/main.js"></script>' in html
    for asset in ("/static/js/main.js", "/static/style.css"):
        assert asset in html
        s, c, body = get(server, asset)
        assert s == 200 and len(body) > 100, asset
    modules = _module_graph(server, "/static/js/main.js")
    served = {"/static/js/" + p.relative_to(STATIC_DIR / "js").as_posix() for p in (STATIC_DIR / "js").rglob("*.js")}
    assert set(modules) == served  # every module file is used, every import is served
    assert get(server, "/static/app.js")[0] == 404  # the one-closure script is gone
    # nothing fetched from outside: no absolute URLs in the page, its modules or the style sheet
    for text in [html, get(server, "/static/style.css")[2].decode(), *modules.values()]:
        assert "http://" not in text and "https://" not in text and "//cdn" not in text


def test_static_modules_are_small(server):
    """No module of the page is over ~600 lines (the page was one 2182-line closure)."""
    for p in (STATIC_DIR / "js").rglob("*.js"):
        n = p.read_text(encoding="utf-8").count("\n")
        assert n <= 600, f"{p.name}: {n} lines"


def test_static_types_and_no_way_out(server):
    assert get(server, "/static/style.css")[1].startswith("text/css")
    assert get(server, "/static/js/views/sphere.js")[1].startswith("text/javascript")
    for path in ("/static/js/../../server.py", "/static/js/%2e%2e/%2e%2e/server.py", "/static/js//main.js",
                 "/static/js/..%2fstore.js", "/static/js\\main.js", "/js/../../api.py"):
        status, _, body = get(server, path)
        assert status == 404 and "error" in json.loads(body), path


def test_wheel_data_lists_every_static_folder():
    """package-data ships every folder of the page (a wheel or sdist install must serve it)."""
    import fnmatch

    try:
        import tomllib
    except ImportError:  # pragma: no cover - Python < 3.11
        pytest.skip("tomllib needs Python 3.11")
    root = Path(__file__).resolve().parents[1]
    patterns = tomllib.loads((root / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]["brdfkit"]
    pkg = root / "src" / "brdfkit"
    for p in STATIC_DIR.rglob("*"):
        if p.is_file():
            rel = p.relative_to(pkg).as_posix()
            assert any(fnmatch.fnmatch(rel, pat) and rel.count("/") == pat.count("/") for pat in patterns), rel


def test_make_server_rejects_bad_port_and_host():
    for port in (-1, 65536, 1.5, "80", True):
        with pytest.raises(ValueError, match="port"):
            make_server("127.0.0.1", port)
    with pytest.raises(ValueError, match="host"):
        make_server("", 0)
    with pytest.raises(OSError, match="cannot listen"):
        make_server("256.0.0.1", 0)


def _cli(*args, timeout=60):
    return subprocess.run([sys.executable, "-m", "brdfkit", *args], capture_output=True, text=True,
                          timeout=timeout, env={**os.environ, "BRDFKIT_DEBUG": ""})


@pytest.mark.parametrize("args,needle", [
    (["--port", "70000"], "--port"),
    (["--port", "abc"], "--port"),
    (["--host", "256.1.1.1", "--port", "0"], "cannot listen"),
])
def test_cli_bad_host_or_port_is_one_line(args, needle):
    r = _cli("serve", "--no-browser", *args)
    assert r.returncode != 0
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0], r.stderr
    assert "Traceback" not in r.stderr


def test_cli_serve_prints_url_and_serves():
    proc = subprocess.Popen([sys.executable, "-m", "brdfkit", "serve", "--port", "0", "--no-browser"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        assert "http://127.0.0.1:" in line, (line, proc.stderr.read() if proc.poll() is not None else "")
        url = line[line.index("http://"):].split()[0]
        with urllib.request.urlopen(url + "api/models", timeout=30) as r:
            names = [m["name"] for m in json.loads(r.read())["models"]]
        assert names == bk.models()
    finally:
        proc.terminate()
        proc.wait(10)
        proc.stdout.close()
        proc.stderr.close()


def test_ui_model_info_rows_and_boolean_uniform_type_per_caller():
    """The one row builder behind /api/models and /api/brdf: booleans are `int` uniforms for the
    registry's shaders and `bool` for a .brdf file; an infinite bound is null."""
    from brdfkit.params import Param
    from brdfkit.web.jsonio import ui_model_info

    class Stub:
        spec = [Param("s", "scalar", 1.0, range=(-math.inf, 2.0), log_scale=False, open_hi=True),
                Param("b", "bool", True)]

        @classmethod
        def info(cls):
            return {"params": [p.as_row() for p in cls.spec]}

    rows = ui_model_info(Stub, glsl.GLSL_TYPES)["params"]
    assert rows[0]["min"] is None and rows[0]["max"] == 2.0
    assert (rows[0]["log_scale"], rows[0]["open_lo"], rows[0]["open_hi"]) == (False, False, True)
    assert rows[0]["uniform"] == {"name": "u_s", "type": "float"}
    assert rows[1]["uniform"] == {"name": "u_b", "type": "int"}
    rows = ui_model_info(Stub, {**glsl.GLSL_TYPES, "bool": "bool"})["params"]
    assert rows[1]["uniform"] == {"name": "u_b", "type": "bool"}
