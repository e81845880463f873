"""The explorer's extra endpoints (brdfkit.web.api ROUTES) through a real server on 127.0.0.1.

Measured materials (the network weights equal the shipped npz), the nbrdf/measured GLSL
(compiled by glslang as GLSL ES 3.00 where glslang is installed), meshes equal to
brdfkit.render.meshes, an uploaded OBJ, a MERL upload equal to glsl.table_texels of
bk.load_merl, the fixed-function table, validation answers, the engine's albedo; bad input:
400 with one line, never a traceback or a file-system path.
"""

from __future__ import annotations

import json
from urllib.parse import urlencode

import numpy as np
import pytest

import brdfkit as bk
from brdfkit import opengl
from brdfkit.measured import nbrdf
from brdfkit.render import glsl, meshes

from _web_helpers import get_json, request


def test_measured_list_and_weights(server):
    status, body = get_json(server, "/api/measured")
    assert status == 200 and body["materials"] == list(nbrdf.materials()) and len(body["materials"]) == 159
    status, body = get_json(server, "/api/nbrdf?name=gold-metallic-paint")  # a bare name resolves
    assert status == 200 and body["name"] == "merl/gold-metallic-paint"
    w = np.asarray(body["weights"], dtype=np.float64)
    assert w.size == 211 * 4
    # the blocks read as nbrdf.glsl reads them (mat4 = 4 vec4 columns, M * v) give the numpy network
    u = w.reshape(211, 4)

    def m4(i):
        return u[i:i + 4].T  # column c = u[i + c]

    rng = np.random.default_rng(1)
    th, td, pd = rng.uniform(0, np.pi / 2, 50), rng.uniform(0, np.pi / 2, 50), rng.uniform(0, np.pi, 50)
    got = []
    for a, b, c in zip(th, td, pd):
        xa = np.array([np.sin(a), np.cos(a), np.sin(b) * np.cos(c), np.sin(b) * np.sin(c)])
        x5 = np.cos(b)
        h1 = [np.maximum(m4(6 * k) @ xa + u[6 * k + 4] * x5 + u[6 * k + 5], 0) for k in range(6)]
        h2 = [np.maximum(u[180 + k] + sum(m4(36 + 24 * k + 4 * m) @ h1[m] for m in range(6)), 0) for k in range(6)]
        z = u[210] + sum(m4(186 + 4 * m) @ h2[m] for m in range(6))
        assert z[3] == 0
        got.append(np.maximum(np.expm1(np.minimum(z[:3], 80)), 0))
    ref = nbrdf.material("merl/gold-metallic-paint").eval_rusinkiewicz(th, td, pd)
    assert np.allclose(got, ref, rtol=1e-12, atol=0)


def test_shaders_for_measured_materials(server):
    for path in ("/api/nbrdf/shader", "/api/measured/shader"):
        status, ctype, text = request(server, path)
        assert status == 200 and ctype.startswith("text/plain")
        text = text.decode()
        assert text.startswith("#version 300 es\n") and "vec3 brdf(vec3 wi, vec3 wo)" in text
        if glsl.glslang_available():
            glsl.glslang_validate_source(text[len("#version 300 es\n"):])
    assert "uniform vec4 u_nbrdf[211];" in request(server, "/api/nbrdf/shader")[2].decode()


def test_glsl_files(server):
    status, _, text = request(server, "/api/glsl?file=pipeline_vertex.glsl")
    assert status == 200 and text.decode() == glsl.shader_file("pipeline_vertex.glsl")
    for bad in ("../server.py", "nope.glsl", "/etc/passwd"):
        status, body = get_json(server, "/api/glsl?" + urlencode({"file": bad}))
        assert status == 400 and "no shader file" in body["error"] and "/work" not in body["error"]


@pytest.mark.parametrize("name,t,kw", [("sphere", 8, {"segments": 16, "rings": 8}), ("torus", 6, {"segments": 12, "sides": 6}),
                                       ("plane", 4, {"divisions": 4}), ("teapot", 9, {"subdivisions": 3})])
def test_builtin_meshes(server, name, t, kw):
    status, body = get_json(server, f"/api/mesh?name={name}&tessellation={t}")
    assert status == 200
    ref = meshes.builtin(name, **kw)
    assert np.allclose(np.reshape(body["positions"], (-1, 3)), ref.positions, atol=1e-6)
    assert np.allclose(np.reshape(body["normals"], (-1, 3)), ref.normals, atol=1e-6)
    assert np.array_equal(np.reshape(body["faces"], (-1, 3)), ref.faces)
    assert len(body["tangents"]) == len(body["positions"])


def test_uploaded_obj(server):
    obj = b"v 0 0 0\nv 2 0 0\nv 0 2 0\nv 0 0 2\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
    status, body = get_json(server, "/api/mesh", obj)
    assert status == 200 and len(body["faces"]) == 12
    P = np.reshape(body["positions"], (-1, 3))
    assert np.isclose(np.linalg.norm(P, axis=1).max(), 1.0, atol=1e-6)  # normalised to the unit sphere
    status, body = get_json(server, "/api/mesh", b"this is not an obj")
    assert status == 400 and "\n" not in body["error"] and "/tmp" not in body["error"]


def test_merl_upload_equals_table_texels(server, tmp_path):
    m = bk.model("microfacet", alpha=0.2, kd=0.1)
    path = tmp_path / "w.binary"
    bk.save_merl(m, path)
    status, ctype, data = request(server, "/api/merl", path.read_bytes())
    assert status == 200 and ctype == "application/octet-stream"
    got = np.frombuffer(data, dtype="<f4").reshape(90, 90, 180, 4)
    assert np.array_equal(got, glsl.table_texels(bk.load_merl(path)))
    for body, needle in [(b"", "empty"), (b"\x00" * 100, "MERL")]:
        status, resp = get_json(server, "/api/merl", body)
        assert status == 400 and "\n" not in resp["error"] and "Traceback" not in resp["error"], resp
        assert "/tmp" not in resp["error"]


def test_opengl_table(server):
    status, body = get_json(server, "/api/opengl")
    assert status == 200 and list(body["materials"]) == list(opengl.MATERIALS) and len(body["materials"]) == 12
    assert body["materials"]["gold"]["shininess"] == opengl.MATERIALS["gold"].shininess
    assert body["light"]["position"] == list(opengl.Light().position)


def test_validate(server):
    status, body = get_json(server, "/api/validate?" + urlencode({"model": "ward", "params": json.dumps({"alpha_x": 0.1})}))
    assert status == 200 and body["ok"] is True and body["params"]["alpha_x"] == 0.1
    for params, needle in [({"alpha_x": 2}, "out of range"), ({"bogus": 1}, "unknown parameter"), ("[1]", "JSON object")]:
        q = urlencode({"model": "ward", "params": params if isinstance(params, str) else json.dumps(params)})
        status, body = get_json(server, "/api/validate?" + q)
        assert status == 200 and body["ok"] is False and needle in body["error"], body


def test_albedo_engine(server):
    status, body = get_json(server, "/api/albedo?" + urlencode({"model": "lambert", "params": json.dumps({"kd": [0.2, 0.5, 0.9]}), "n": 5}))
    assert status == 200 and body["theta_deg"] == [0.0, 22.25, 44.5, 66.75, 89.0]
    assert np.allclose(body["rgb"], [[0.2, 0.5, 0.9]] * 5, rtol=1e-6)
    status, body = get_json(server, "/api/albedo?model=merl/chrome&n=3")
    assert status == 200 and np.all(np.asarray(body["rgb"]) > 0)


@pytest.mark.parametrize("path,needle", [
    ("/api/nbrdf?name=no-such-material", "unknown measured material"),
    ("/api/nbrdf", "missing query parameter 'name'"),
    ("/api/nbrdf?name=a&name=b", "once"),
    ("/api/measured?x=1", "unknown query parameter"),
    ("/api/mesh?name=cube", "unknown built-in mesh"),
    ("/api/mesh?name=sphere&tessellation=1000", "out of range"),
    ("/api/mesh?name=sphere&tessellation=abc", "integer"),
    ("/api/albedo?" + urlencode({"model": "lambert", "params": json.dumps({"kd": 3})}), "out of range"),
    ("/api/albedo?model=lambert&n=1", "out of range"),
])
def test_bad_input_is_400_with_one_line(server, path, needle):
    status, body = get_json(server, path)
    assert status == 400 and set(body) == {"error"}
    assert needle in body["error"] and "\n" not in body["error"], body


def test_post_to_an_unknown_path_is_404(server):
    status, body = get_json(server, "/api/nothing", b"x")
    assert status == 404 and "error" in body


DATA = __import__("pathlib").Path(__file__).resolve().parent / "data"


def test_brdf_file_upload(server):
    status, body = get_json(server, "/api/brdf?name=ward.brdf", (DATA / "ward.brdf").read_bytes())
    assert status == 200, body
    assert body["glsl"].startswith("#version 300 es\n") and "vec3 brdf(vec3 wi, vec3 wo)" in body["glsl"]
    assert [r["name"] for r in body["info"]["params"]] == ["kd", "ks", "alpha_x", "alpha_y"]
    assert body["info"]["params"][2]["uniform"] == {"name": "u_alpha_x", "type": "float"}
    status, body = get_json(server, "/api/brdf?name=broken_glsl.brdf", (DATA / "broken_glsl.brdf").read_bytes())
    assert status == 400 and "broken_glsl.brdf" in body["error"] and "\n" not in body["error"], body
    status, body = get_json(server, "/api/brdf?name=x.brdf", b"\xff\xfe\x00")
    assert status == 400 and "x.brdf" in body["error"]


def test_brdf_upload_while_this_process_holds_the_gl_context(server):
    """The headless context stays current in the thread that used it last (here: this one);
    the upload, answered in a server thread, must still work (it compiles in a child process)."""
    glsl.eval_glsl("lambert", np.array([[0.0, 0.0, 1.0]]), np.array([[0.0, 0.0, 1.0]]))
    text = (DATA / "ward.brdf").read_text().replace("float kd 0 1 0.4", "float kd 0 1 0.35")  # not cached
    status, body = get_json(server, "/api/brdf?name=ward2.brdf", text.encode())
    assert status == 200, body
    assert body["info"]["params"][0]["default"] == 0.35
    glsl.eval_glsl("lambert", np.array([[0.0, 0.0, 1.0]]), np.array([[0.0, 0.0, 1.0]]))  # and this thread still can


def test_environment_maps_and_samplers(server):
    from brdfkit.render import environment, ibl

    status, body = get_json(server, "/api/envs")
    assert status == 200 and body["environments"] == environment.BUILTINS
    status, ctype, data = request(server, "/api/env?name=furnace")
    assert status == 200 and ctype == "application/octet-stream"
    head = np.frombuffer(data[:24], "<i4")
    extra = np.frombuffer(data[24:64], "<f4")
    env = environment.Environment("furnace", environment.builtin_map("furnace"))
    rgba, marg, cond = ibl.env_texture_data(env)
    assert list(head) == [*rgba.shape[:2], *marg.shape, *cond.shape]
    assert np.allclose(extra[:9].reshape(3, 3), env.world_to_map()) and extra[9] == env.strength
    off = 64
    for a in (rgba, marg, cond):
        got = np.frombuffer(data[off:off + a.size * 4], "<f4").reshape(a.shape)
        assert np.array_equal(got, a)
        off += a.size * 4
    assert off == len(data)
    status, body = get_json(server, "/api/env?name=moon")
    assert status == 400 and "sky" in body["error"]
    q = urlencode({"model": "microfacet", "params": json.dumps({"alpha": 0.3, "distribution": "beckmann"})})
    status, body = get_json(server, "/api/ibl/sampler?" + q)
    ref = ibl.sampler_uniforms(bk.model("microfacet", alpha=0.3, distribution="beckmann"))
    assert status == 200 and body["bki_lobe"] == ref["bki_lobe"] and np.allclose(body["bki_lobe_params"], ref["bki_lobe_params"])
