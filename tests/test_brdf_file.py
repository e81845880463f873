"""BRDF Explorer ``.brdf`` files: the parser, the GLSL wrapper, and the models they make.

The files under ``tests/data/*.brdf`` were written for these tests in BRDF
Explorer's format (Lambert, Ward 1992, GGX with an RGB f0 and a bool); their
GLSL runs through the headless GL context and must equal brdfkit's own numpy
models at the shared parity vectors (float32 GLSL against float64 numpy at the
same float32 inputs: 1e-4 relative, 1e-6 1/sr absolute, plus twice the
float64 function's own change when the inputs move by 4 float32 ulps, as the
GLSL parity tests allow: a sharp GGX peak, alpha = 0.05, moves by 1.4e-4
relative under such a change, which no float32 program can resolve).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.interchange.brdf_explorer import BrdfShader, parse_brdf_text
from brdfkit.render.glsl import compile_source, common_source, has_shader, parity_vectors, shader_source
from _numeric_helpers import float32_spread, lifted_pairs

DATA = Path(__file__).parent / "data"
F0 = [0.95, 0.64, 0.54]
KD = [0.1, 0.2, 0.3]


def _vectors():
    v = parity_vectors()
    return v["wi"], v["wo"], v["kind"]


CASES = [
    ("lambert.brdf", {"kd": 0.3}, ("lambert", {"kd": 0.3})),
    ("lambert.brdf", {}, ("lambert", {"kd": 0.5})),  # the file's default
    (
        "ward.brdf",
        {"kd": 0.25, "ks": 0.2, "alpha_x": 0.12, "alpha_y": 0.4},
        ("ward", {"kd": 0.25, "ks": 0.2, "alpha_x": 0.12, "alpha_y": 0.4}),
    ),
    (
        "ward.brdf",
        {"kd": 0.0, "ks": 1.0, "alpha_x": 0.5, "alpha_y": 0.05},
        ("ward", {"kd": 0.0, "ks": 1.0, "alpha_x": 0.5, "alpha_y": 0.05}),
    ),
    (
        "ggx.brdf",
        {"alpha": 0.3},
        ("microfacet", dict(distribution="ggx", alpha=0.3, fresnel="schlick", f0=F0, kd=KD, shadowing="smith")),
    ),
    (
        "ggx.brdf",
        {"alpha": 0.05, "f0": [0.04, 0.5, 1.0], "useDiffuse": False},
        ("microfacet", dict(distribution="ggx", alpha=0.05, fresnel="schlick", f0=[0.04, 0.5, 1.0], kd=0.0)),
    ),
]


@pytest.mark.parametrize("fname,given,ours", CASES, ids=[f"{c[0]}-{i}" for i, c in enumerate(CASES)])
def test_brdf_file_equals_our_model(fname, given, ours):
    m = bk.load_brdf(DATA / fname, **given)
    ref = bk.model(ours[0], **ours[1])
    wi, wo, kind = _vectors()
    got = m.eval(wi.astype(np.float64), wo.astype(np.float64))
    want = ref.eval(wi.astype(np.float64), wo.astype(np.float64))
    assert got.dtype == np.float64 and got.shape == want.shape
    assert np.isfinite(got).all() and (got >= 0).all()
    spread = float32_spread(ref, wi.astype(np.float64), wo.astype(np.float64), seed=11)
    err = np.abs(got - want) - (1e-4 * np.abs(want) + 1e-6 + 2 * spread)
    worst = int(np.argmax(err.max(axis=-1)))
    assert err.max() <= 0, f"{fname}: worst at {kind[worst]} wi={wi[worst]} wo={wo[worst]}: {got[worst]} vs {want[worst]}"
    # below the horizon the wrapper returns 0 without calling the file's BRDF
    below = (wi[:, 2] <= 0) | (wo[:, 2] <= 0)
    assert below.any() and (got[below] == 0).all()
    # a non-trivial comparison: the values span a range
    assert want.max() > 10 * max(want[~below].min(), 1e-9) or fname == "lambert.brdf"


def test_parameters_become_params():
    sh = parse_brdf_text((DATA / "ggx.brdf").read_text(), name="ggx.brdf")
    assert isinstance(sh, BrdfShader)
    by = {p.name: p for p in sh.params}
    assert [p.name for p in sh.params] == ["alpha", "f0", "kd", "useDiffuse"]
    assert by["alpha"].kind == "scalar" and by["alpha"].range == (0.001, 1.0) and by["alpha"].default == 0.2
    assert by["f0"].kind == "rgb" and tuple(by["f0"].default) == (0.95, 0.64, 0.54) and by["f0"].range == (0.0, 1.0)
    assert by["useDiffuse"].kind == "bool" and by["useDiffuse"].default is True
    # the wrapped source follows our convention: u_<param> uniforms and brdf(wi, wo)
    for decl in ("uniform float u_alpha;", "uniform vec3 u_f0;", "uniform vec3 u_kd;", "uniform int u_useDiffuse;"):
        assert decl in sh.glsl
    assert "vec3 brdf(vec3 bk_wi, vec3 bk_wo)" in sh.glsl
    assert "vec3 BRDF( vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y )" in sh.raw_glsl
    # raw_glsl keeps the file's numbering: its line k is line shader_line + k of the file
    file_lines = (DATA / "ggx.brdf").read_text().splitlines()
    for k, line in enumerate(sh.raw_glsl.splitlines()):
        if line.strip():
            assert file_lines[sh.shader_line - 1 + k] == line
    compile_source(common_source() + sh.glsl, version="330 core")


def test_model_through_the_registry_and_the_glsl_module():
    path = str(DATA / "ward.brdf")
    m = bk.model(path, kd=0.2)
    assert m.params["kd"] == 0.2 and m.params["alpha_y"] == 0.3  # the file's default
    assert has_shader(m) and "u_alpha_x" in shader_source(m)
    with pytest.raises(ValueError, match=r"alpha_x.*out of range.*\[0\.001, 1\]"):
        bk.model(path, alpha_x=2.0)
    with pytest.raises(ValueError, match="unknown parameter 'shininess'"):
        bk.load_brdf(path, shininess=3)
    # float32 in, float32 out; a single pair broadcasts
    wi = np.array([0.3, 0.1, 0.9486833], dtype=np.float32)
    f = m.eval(wi, wi)
    assert f.dtype == np.float32 and f.shape == (3,)
    np.testing.assert_allclose(f, bk.model("ward", kd=0.2).eval(wi.astype(float), wi.astype(float)), rtol=1e-4)


def test_comment_lines_float_brdf_and_isfunc():
    text = """analytic
# a header comment
::begin parameters
# a comment among the parameters
float s 0 10 2
::end parameters
::begin shader
    # BRDF Explorer skips this line, also inside the shader
float BRDF( vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y ) { return s * dot(N, L); }
::end shader
::begin isFunc
vec3 sampleBRDF( float u, float v, vec3 normal, vec3 tangent, vec3 bitangent, out vec3 wi, out float pdf ) { wi = normal; pdf = 1.0; return vec3(1.0); }
::end isFunc
"""
    sh = parse_brdf_text(text, name="mem.brdf")
    assert sh.returns == "float" and "sampleBRDF" in sh.is_func
    assert "skips this line" not in sh.glsl
    from brdfkit.interchange.brdf_explorer import model_class

    m = model_class(sh)(s=3.0)
    wi = np.array([[0.6, 0.0, 0.8], [0.0, 0.6, -0.8]])
    wo = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(m.eval(wi, wo), [[2.4] * 3, [0.0] * 3], rtol=1e-6)


GOOD_HEAD = "analytic\n::begin parameters\nfloat a 0 1 0.5\n::end parameters\n"
GOOD_SHADER = "::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(a); }\n::end shader\n"

MALFORMED = [
    ("", r"^m\.brdf: empty file"),
    ("bparam ward.brdf\n::begin parameters\n::end parameters\n", r"^m\.brdf:1: .*parameter file"),
    ("glsl\n" + GOOD_SHADER, r"^m\.brdf:1: the first line must be 'analytic'"),
    ("analytic\n::begin parameters\nint n 0 4 1\n::end parameters\n" + GOOD_SHADER, r"^m\.brdf:3: unknown parameter type 'int'"),
    ("analytic\n::begin parameters\nfloat a 0 1\n::end parameters\n" + GOOD_SHADER, r"^m\.brdf:3: expected 'float NAME MIN MAX DEFAULT'"),
    ("analytic\n::begin parameters\nfloat a 0 one 0.5\n::end parameters\n" + GOOD_SHADER, r"^m\.brdf:3: a: MAX must be a number"),
    ("analytic\n::begin parameters\nfloat a 1 0 0.5\n::end parameters\n" + GOOD_SHADER, r"^m\.brdf:3: a: MIN 1 is larger than MAX 0"),
    ("analytic\n::begin parameters\nfloat a 0 1 2\n::end parameters\n" + GOOD_SHADER, r"^m\.brdf:3: a: DEFAULT 2 lies outside \[0, 1\]"),
    ("analytic\n::begin parameters\nfloat a 0 1 nan\n::end parameters\n" + GOOD_SHADER, r"^m\.brdf:3: a: DEFAULT must be finite"),
    ("analytic\n::begin parameters\nbool b maybe\n::end parameters\n" + GOOD_SHADER, r"^m\.brdf:3: b: DEFAULT must be 0 or 1"),
    ("analytic\n::begin parameters\ncolor c 0.1 0.2 1.5\n::end parameters\n" + GOOD_SHADER, r"^m\.brdf:3: c: B = 1.5 lies outside \[0, 1\]"),
    ("analytic\n::begin parameters\nfloat 2a 0 1 0\n::end parameters\n" + GOOD_SHADER, r"^m\.brdf:3: parameter name '2a' is not a valid GLSL identifier"),
    ("analytic\n::begin parameters\nfloat a 0 1 0\nbool a 1\n::end parameters\n" + GOOD_SHADER, r"^m\.brdf:4: parameter 'a' is declared twice"),
    ("analytic\n::begin parameters\n::begin shader\n", r"^m\.brdf:3: '::begin shader' inside section 'parameters' \(opened on line 2\)"),
    (GOOD_HEAD + "::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(a); }\n", r"^m\.brdf:5: section 'shader' is never closed"),
    (GOOD_HEAD + "::end shader\n", r"^m\.brdf:5: '::end shader' does not close a section \(no open section\)"),
    (GOOD_HEAD, r"^m\.brdf: no '::begin shader' section"),
    (GOOD_HEAD + "::begin shader\nvec3 brdf(vec3 wi, vec3 wo) { return vec3(a); }\n::end shader\n", r"^m\.brdf:6: the shader section defines no 'vec3 BRDF"),
    (GOOD_HEAD + "::begin shader\n// vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)\n::end shader\n", r"^m\.brdf:6: the shader section defines no"),
    ("analytic\nfloat a 0 1 0\n" + GOOD_SHADER, r"^m\.brdf:2: text outside any section"),
    (GOOD_HEAD + GOOD_SHADER + GOOD_SHADER, r"^m\.brdf:\d+: section 'shader' appears twice"),
]


@pytest.mark.parametrize("text,pattern", MALFORMED, ids=[f"malformed-{i}" for i in range(len(MALFORMED))])
def test_malformed_file_one_line_naming_file_and_line(text, pattern):
    with pytest.raises(ValueError, match=pattern) as e:
        parse_brdf_text(text, name="m.brdf")
    assert "\n" not in str(e.value)


def test_well_formed_minimal_file_parses():
    sh = parse_brdf_text(GOOD_HEAD + GOOD_SHADER, name="m.brdf")
    assert [p.name for p in sh.params] == ["a"] and sh.shader_line == 6


def test_trailing_comments_and_parameters_named_like_our_arguments():
    """'# ...' after a parameter line and words after '::begin NAME' are ignored (as BRDF Explorer
    does); parameters called wi / wo do not clash with the wrapper's own arguments."""
    from brdfkit.interchange.brdf_explorer import model_class

    text = (
        "analytic\n::begin parameters   # the sliders\n"
        "float wi 0 2 1.5   # a weight called wi\n"
        "float wo 0 2 0.5\n"
        "::end parameters\n::begin shader\n"
        "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(wi * L.z + wo * V.z); }\n"
        "::end shader\n"
    )
    m = model_class(parse_brdf_text(text, name="names.brdf"))(wi=2.0)
    np.testing.assert_allclose(m.eval(np.array([0.6, 0.0, 0.8]), np.array([0.0, 0.0, 1.0])), [2.1] * 3, rtol=1e-6)


def test_glsl_error_is_one_line_with_the_compiler_message_and_file_line():
    with pytest.raises(ValueError) as e:
        bk.load_brdf(DATA / "broken_glsl.brdf")
    msg = str(e.value)
    assert "\n" not in msg
    assert msg.startswith(f"{DATA / 'broken_glsl.brdf'}: GLSL error: ")
    assert "undeclared_thing" in msg
    # the #line directives make the compiler name the file's own line (11)
    assert ":11(" in msg or ":11:" in msg, msg


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "brdfkit", *args], capture_output=True, text=True, timeout=300)


def test_cli_takes_a_brdf_path_wherever_a_model_name_goes():
    r = _cli("eval", str(DATA / "ward.brdf"), "-p", "kd=0.2", "--wi", "30,0", "--wo", "30,180", "--json")
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout)["value"]
    want = bk.model("ward", kd=0.2).eval_angles(np.radians(30), 0.0, np.radians(30), np.pi)
    np.testing.assert_allclose(got, want, rtol=1e-5)
    r = _cli("eval", str(DATA / "broken_glsl.brdf"), "--wi", "0,0", "--wo", "0,0")
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("brdfkit: error: ") and "GLSL error" in lines[0], r.stderr
    assert "Traceback" not in r.stderr
    r = _cli("eval", str(DATA / "missing.brdf"), "--wi", "0,0", "--wo", "0,0")
    assert r.returncode == 2 and "no such .brdf file" in r.stderr and "Traceback" not in r.stderr


def test_wrapper_passes_L_wi_V_wo_and_the_local_frame():
    """BRDF(L, V, N, X, Y) gets L = wi (toward the light), V = wo, N = +z, X = +x, Y = +y."""
    from brdfkit.interchange.brdf_explorer import model_class

    text = (
        "analytic\n::begin shader\n"
        "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {\n"
        "    return vec3(dot(L, X) + 2.0, dot(L, Y) + 2.0, 10.0 * dot(V, N) + dot(V, X) + 2.0 + 0.0 * dot(N, Y));\n"
        "}\n::end shader\n"
    )
    m = model_class(parse_brdf_text(text, name="frame.brdf"))()
    wi, wo = lifted_pairs(200, seed=3, lift=0.05)
    want = np.stack([wi[:, 0] + 2, wi[:, 1] + 2, 10 * wo[:, 2] + wo[:, 0] + 2], axis=1)
    np.testing.assert_allclose(m.eval(wi, wo), want, rtol=1e-6)


def test_render_and_plot_take_a_brdf_file(tmp_path):
    """The renderer shades with the file's GLSL: the image equals that of the same built-in model."""
    import imageio.v3 as iio

    scene = {
        "mesh": "sphere", "size": [96, 96], "shading": "phong",
        "camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 40},
        "lights": [{"position": [1, 1, 1, 0], "diffuse": [1, 1, 1]}],
    }
    mats = {
        "file": {"model": str(DATA / "ggx.brdf"), "params": {"alpha": 0.3}},
        "ours": {"model": "microfacet", "params": {"alpha": 0.3, "fresnel": "schlick", "f0": F0, "kd": KD}},
    }
    imgs = {}
    for key, mat in mats.items():
        (tmp_path / f"{key}.json").write_text(json.dumps(dict(scene, material=mat)))
        r = _cli("render", "--scene", str(tmp_path / f"{key}.json"), "-o", str(tmp_path / f"{key}.png"))
        assert r.returncode == 0, r.stderr
        imgs[key] = iio.imread(tmp_path / f"{key}.png").astype(int)
    assert imgs["file"].mean() > 20  # a lit sphere, not a black frame
    assert np.abs(imgs["file"] - imgs["ours"]).max() <= 1
    r = _cli("plot", str(DATA / "ward.brdf"), "--vs", "ward", "--kind", "polar", "-o", str(tmp_path / "p.png"))
    assert r.returncode == 0 and (tmp_path / "p.png").stat().st_size > 1000, r.stderr


# --------------------------------------------------------------------------- GLSL ES (WebGL 2)
from brdfkit.interchange.brdf_explorer import glsl_es_source, load_brdf_class, promote_int_literals, rename_builtin_overloads  # noqa: E402


@pytest.mark.parametrize(
    "src,want",
    [
        ("float a = 1 - x;", "float a = 1.0 - x;"),
        ("return mix(1, b, clamp(1-u, 0, 1));", "return mix(1.0, b, clamp(1.0-u, 0.0, 1.0));"),
        ("if (NdotL < 0 || NdotV < 0) return vec3(0);", "if (NdotL < 0.0 || NdotV < 0.0) return vec3(0.0);"),
        ("float c = x[0] + y[2];", "float c = x[0] + y[2];"),
        ("for (int i = 0; i < 4; i++) s += w[i];", "for (int i = 0; i < 4; i++) s += w[i];"),
        ("int n = 3; float e = 1e5 + 2.5 + .5 + 3.;", "int n = 3; float e = 1e5 + 2.5 + .5 + 3.;"),
        ("float v2 = x2; // 2 apples", "float v2 = x2; // 2 apples"),
        ("float p = pow(m, 5) /* 5 */;", "float p = pow(m, 5.0) /* 5 */;"),
    ],
)
def test_promote_int_literals(src, want):
    assert promote_int_literals(src) == want


def test_rename_builtin_overloads():
    src = "vec3 reflect(vec3 I, vec3 N) { return I; }\nvec3 f(vec3 a) { return reflect(a, a) + reflection; }\n"
    out = rename_builtin_overloads(src)
    assert "vec3 bk_user_reflect(vec3 I, vec3 N)" in out and "return bk_user_reflect(a, a) + reflection;" in out
    assert rename_builtin_overloads("float g(float x) { return sqrt(x); }") == "float g(float x) { return sqrt(x); }"


@pytest.mark.parametrize("fname,given,ours", CASES[::2], ids=[c[0] for c in CASES[::2]])
def test_glsl_es_source_evaluates_as_our_model(fname, given, ours):
    """The WebGL 2 dialect of a file, compiled as GLSL ES 3.00, still equals our numpy model."""
    from brdfkit.render.glsl import common_source, eval_glsl

    cls = load_brdf_class(DATA / fname)
    es = glsl_es_source(cls)
    assert es is not None and es == cls.brdf_shader.glsl_es
    m = cls(**given)
    ref = bk.model(ours[0], **ours[1])
    wi, wo, _ = _vectors()
    got = eval_glsl(m, wi, wo, version="300 es", source=common_source() + es).astype(np.float64)
    want = ref.eval(wi.astype(np.float64), wo.astype(np.float64))
    spread = float32_spread(ref, wi.astype(np.float64), wo.astype(np.float64), seed=11)
    assert (np.abs(got - want) <= 1e-4 * np.abs(want) + 1e-6 + 2 * spread).all()


def test_glsl_es_source_refuses_what_it_cannot_fix():
    """Desktop GLSL that the textual fixes do not cover (an int variable passed to a float
    parameter) compiles as 3.30 but not as ES 3.00: no ES source rather than a wrong one."""
    from brdfkit.interchange.brdf_explorer import model_class

    text = (
        "analytic\n::begin shader\n"
        "float halve(float x) { return 0.5 * x; }\n"
        "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { int n = 2; return vec3(halve(n) * L.z); }\n"
        "::end shader\n"
    )
    sh = parse_brdf_text(text, name="intarg.brdf")
    m = model_class(sh)()  # fine as desktop GLSL 3.30
    np.testing.assert_allclose(m.eval(np.array([0.6, 0.0, 0.8]), np.array([0.0, 0.0, 1.0])), [0.8] * 3, rtol=1e-6)
    assert glsl_es_source(sh) is None


def test_shader_json_is_plain_json_for_the_explorer():
    from brdfkit.interchange.brdf_explorer import shader_json

    sh = parse_brdf_text((DATA / "ggx.brdf").read_text(), name="ggx.brdf")
    obj = json.loads(json.dumps(shader_json(sh)))
    assert [r["name"] for r in obj["params"]] == ["alpha", "f0", "kd", "useDiffuse"]
    assert obj["params"][0]["min"] == 0.001 and obj["params"][0]["max"] == 1.0 and obj["params"][3]["kind"] == "bool"
    assert obj["glsl"] == sh.glsl and obj["glsl_es"] == sh.glsl_es and "1.0 - LdotH" in obj["glsl_es"]


def test_unreadable_files_are_one_line_errors(tmp_path):
    binary = tmp_path / "bin.brdf"
    binary.write_bytes(b"\xff\xfe\x00\x81 not text")
    with pytest.raises(ValueError, match=r"bin\.brdf: not a text file"):
        bk.load_brdf(binary)
    with pytest.raises(ValueError, match=r"nope\.brdf: no such \.brdf file"):
        bk.load_brdf(tmp_path / "nope.brdf")
    folder = tmp_path / "dir.brdf"
    folder.mkdir()
    with pytest.raises(ValueError, match=r"dir\.brdf: no such \.brdf file"):
        bk.model(str(folder))


def test_check_takes_a_brdf_file():
    """brdfkit check on Lambert written as a .brdf file: reciprocal, albedo = kd at every angle."""
    r = _cli("check", str(DATA / "lambert.brdf"), "-p", "kd=0.7", "--json")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["reciprocal"] is True and out["energy_conserving"] is True
    assert out["max_albedo"] == pytest.approx(0.7, rel=1e-4)
    assert max(out["albedo"]["theta_deg"]) >= 89
    np.testing.assert_allclose(np.asarray(out["albedo"]["rgb"]), 0.7, rtol=1e-4)


def test_bparam_file_gives_the_saved_values(tmp_path):
    """A parameter file as BRDF Explorer's "Save parameters" writes it: the .brdf it names, with
    the saved current values (float lines carry MIN MAX VALUE); a name the BRDF lacks is skipped."""
    text = (
        f"bparam {DATA / 'ggx.brdf'}\n\n::begin parameters\n"
        "float alpha 0.001000 1.000000 0.350000\nbool useDiffuse 0\ncolor f0 0.100000 0.200000 0.300000\n"
        "float gone 0 1 0.5\n::end parameters\n"
    )
    (tmp_path / "saved.bparam").write_text(text)
    m = bk.load_brdf(tmp_path / "saved.bparam")
    assert m.params["alpha"] == 0.35 and m.params["useDiffuse"] is False
    np.testing.assert_allclose(m.params["f0"], [0.1, 0.2, 0.3])
    ref = bk.model("microfacet", alpha=0.35, fresnel="schlick", f0=[0.1, 0.2, 0.3], kd=0.0)
    wi, wo, _ = _vectors()
    keep = (wi[:, 2] > 0.05) & (wo[:, 2] > 0.05)
    np.testing.assert_allclose(m.eval(wi[keep], wo[keep]), ref.eval(wi[keep], wo[keep]), rtol=2e-4, atol=1e-6)
    assert bk.load_brdf(tmp_path / "saved.bparam", alpha=0.5).params["alpha"] == 0.5
    # the named file moved: found beside the parameter file, else a one-line error
    (tmp_path / "moved.bparam").write_text("bparam /nowhere/ggx.brdf\n::begin parameters\n::end parameters\n")
    with pytest.raises(ValueError, match=r"moved\.bparam: the BRDF it names, '/nowhere/ggx\.brdf', is not found"):
        bk.load_brdf(tmp_path / "moved.bparam")
    (tmp_path / "ggx.brdf").write_text((DATA / "ggx.brdf").read_text())
    assert bk.load_brdf(tmp_path / "moved.bparam").params["alpha"] == 0.2


def test_crlf_line_ends_and_tabs():
    from brdfkit.interchange.brdf_explorer import model_class

    text = (DATA / "ggx.brdf").read_text().replace("\n", "\r\n").replace("    ", "\t")
    m = model_class(parse_brdf_text(text, name="crlf.brdf"))()
    wi, wo, _ = _vectors()
    np.testing.assert_array_equal(m.eval(wi, wo), bk.load_brdf(DATA / "ggx.brdf").eval(wi, wo))


def test_a_brdf_file_model_is_fittable():
    """Its GLSL runs in float32, so the fitter takes the file's finite-difference step (fit_diff_step):
    fitting ggx.brdf to the microfacet model it spells recovers that model's parameters."""
    src = bk.model("microfacet", alpha=0.3, fresnel="schlick", f0=0.9, kd=0)
    r = bk.fit(str(DATA / "ggx.brdf"), src, samples=400)
    assert r.params["alpha"] == pytest.approx(0.3, rel=1e-3)
    assert np.allclose(r.params["f0"], 0.9, rtol=1e-3)
    assert np.all(np.asarray(r.params["kd"]) < 1e-3)
