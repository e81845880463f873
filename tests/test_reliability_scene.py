"""Scene files and meshes as untrusted input (issue 14).

Every bad scene must end in ``brdfkit: error: ...`` naming the field, exit 2
(before the fix: ``internal error``, exit 1); tessellation options are
bounded; garbage meshes are refused instead of rendering a black image.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from brdfkit.cli import main
from brdfkit.render import meshes, scene as sc

BAD_SCENES = {
    "size-zero": ({"size": [0, 64]}, "size"),
    "size-overflow": ('{"size": [1e400, 64]}', "size"),
    "size-huge-int": ('{"size": [1' + "0" * 400 + ", 64]}", "size"),
    "size-too-big": ({"size": [100000, 64]}, "size"),
    "size-text": ({"size": "64"}, "size"),
    "size-fraction": ({"size": [64.5, 64]}, "size"),
    "size-bool": ({"size": [True, 64]}, "size"),
    "size-three": ({"size": [64, 64, 64]}, "size"),
    "camera-list": ({"camera": [0, 0, 3]}, "camera"),
    "camera-text": ({"camera": "front"}, "camera"),
    "camera-eye-text": ({"camera": {"eye": "far"}}, "camera"),
    "camera-matrix": ({"camera": {"projection": [[1, 0, 0]], "modelview": 5}}, "camera"),
    "mesh-path-number": ({"mesh": {"path": 5}}, "mesh"),
    "mesh-number": ({"mesh": 5}, "mesh"),
    "mesh-unknown-option": ({"mesh": {"builtin": "sphere", "radiuss": 2}}, "mesh"),
    "tessellation-huge": ({"mesh": {"builtin": "sphere", "segments": 100000, "rings": 100000}}, "mesh"),
    "tessellation-inf": ('{"mesh": {"builtin": "torus", "sides": 1e400}}', "mesh"),
    "tessellation-text": ({"mesh": {"builtin": "teapot", "subdivisions": "many"}}, "mesh"),
    "tessellation-teapot": ({"mesh": {"builtin": "teapot", "subdivisions": 10000}}, "mesh"),
    "merl-number": ({"material": {"merl": 5}}, "material"),
    "measured-number": ({"material": {"measured": 5}}, "material"),
    "model-number": ({"material": {"model": 5}}, "material"),
    "model-param-overflow": ('{"material": {"model": "ward", "params": {"alpha_x": 1' + "0" * 400 + "}}}", "material"),
    "lights-object": ({"lights": {"a": 1}}, "lights"),
    "light-number": ({"lights": [5]}, "lights"),
    "light-field-text": ({"lights": [{"position": "up"}]}, "lights"),
    "background-text": ({"background": [0, 0, "x", 1]}, "background"),
    "background-number": ({"background": 5}, "background"),
    "shading-number": ({"shading": 5}, "shading"),
    "tonemap-number": ({"tonemap": 5}, "tonemap"),
    "exposure-huge-int": ('{"exposure": 1' + "0" * 400 + "}", "exposure"),
    "antialias-text": ({"antialias": "yes"}, "antialias"),
    "light-model-number": ({"light_model": 5}, "light_model"),
    "deep-array": ("[" * 100_000 + "]" * 100_000, "deeper"),
    "deep-object": ('{"mesh": ' + '{"a": ' * 3000 + "1" + "}" * 3000 + "}", "deeper"),
    "not-utf8": (b'{"mesh": "\xff"}', "UTF-8"),
    "top-level-list": ("[1, 2]", "JSON object"),
}


@pytest.mark.parametrize("case", sorted(BAD_SCENES))
def test_bad_scene_is_a_one_line_error_naming_the_field(case, tmp_path, capsys):
    content, field = BAD_SCENES[case]
    p = tmp_path / "scene.json"
    if isinstance(content, bytes):
        p.write_bytes(content)
    else:
        p.write_text(content if isinstance(content, str) else json.dumps(content))
    out = tmp_path / "out.png"
    rc = main(["render", "--scene", str(p), "-o", str(out), "--backend", "numpy"])
    err = capsys.readouterr().err.strip()
    assert rc == 2, err
    assert err.startswith("brdfkit: error:") and "\n" not in err, err
    assert field in err, err
    assert not out.exists()


def test_environment_field_is_validated_like_the_others():
    base = {"mesh": {"builtin": "sphere", "segments": 8, "rings": 4}, "size": [8, 8], "shading": "phong",
            "material": {"model": "lambert", "params": {"kd": 0.5}}}
    scene, _ = sc.scene_from_json({**base, "environment": {"name": "furnace"}})
    assert scene.size == (8, 8)
    with pytest.raises(ValueError, match="environment: unknown field.*file"):
        sc.scene_from_json({**base, "environment": {"file": "sky.hdr"}})


def test_tessellation_is_bounded_at_its_edges():
    for (name, opt), (lo, hi) in meshes.TESSELLATION_LIMITS.items():
        with pytest.raises(ValueError, match=opt):
            meshes.builtin(name, **{opt: hi + 1})
        with pytest.raises(ValueError, match=opt):
            meshes.builtin(name, **{opt: lo - 1})
    # the upper edge itself still builds (a small mesh for the cheap one)
    m = meshes.builtin("plane", divisions=1024)
    assert m.n_triangles == 2 * 1024 * 1024


def _obj(tmp_path: Path, text: bytes, name: str = "m.obj") -> Path:
    p = tmp_path / name
    p.write_bytes(text)
    return p


TRI = b"v 0 0 0\nv 1 0 0\nv 0 1 0\n"


@pytest.mark.parametrize(
    "text, match",
    [
        (TRI + b"f 0 0 0\n", "degenerate"),  # OBJ indices start at 1: 0 is garbage
        (b"v 0 0 0\nv 0 0 0\nv 0 0 0\nf 1 2 3\n", "degenerate"),
        (b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "degenerate"),  # collinear
        (b"v 0 0 0\nv 1e308 0 0\nv 0 1e308 0\nf 1 2 3\n", "finite"),
        (TRI + b"f 1 2 9\n", "mesh"),
    ],
)
def test_garbage_meshes_are_refused(tmp_path, text, match):
    with pytest.raises(ValueError, match=match):
        meshes.load_mesh(_obj(tmp_path, text))


def test_garbage_mesh_in_a_scene_is_exit_2(tmp_path, capsys):
    _obj(tmp_path, TRI + b"f 0 0 0\n")
    p = tmp_path / "s.json"
    p.write_text(json.dumps({"mesh": "m.obj", "size": [16, 16]}))
    rc = main(["render", "--scene", str(p), "-o", str(tmp_path / "o.png"), "--backend", "numpy"])
    err = capsys.readouterr().err
    assert rc == 2 and "degenerate" in err, err


def test_degenerate_triangles_are_dropped_and_the_rest_kept(tmp_path):
    m = meshes.load_mesh(_obj(tmp_path, TRI + b"v 5 5 5\nf 1 2 3\nf 4 4 4\nf 1 1 2\n"), normalize=False)
    assert m.n_triangles == 1
    assert np.all(np.isfinite(m.normals)) and np.allclose(np.linalg.norm(m.normals, axis=1), 1.0, atol=1e-6)


def test_non_utf8_obj_loads(tmp_path):
    # a Latin-1 byte in a comment sent trimesh to an optional module: "No module named 'charset_normalizer'"
    m = meshes.load_mesh(_obj(tmp_path, b"# caf\xe9 cr\xe8me\n" + TRI + b"f 1 2 3\n"))
    assert m.n_triangles == 1


def test_mesh_class_validates_indices_and_coordinates():
    P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    N = np.tile([0.0, 0.0, 1.0], (3, 1))
    T = np.tile([1.0, 0.0, 0.0], (3, 1))
    with pytest.raises(ValueError, match="do not exist"):
        meshes.Mesh(P, N, T, [[0, 1, 3]])
    with pytest.raises(ValueError, match="do not exist"):
        meshes.Mesh(P, N, T, [[0, 1, -1]])
    with pytest.raises(ValueError, match="finite"):
        meshes.Mesh(P * np.array([1, np.nan, 1]), N, T, [[0, 1, 2]])
    with pytest.raises(ValueError, match="finite"):
        meshes.Mesh(P * 1e38, N, T, [[0, 1, 2]])
    with pytest.raises(ValueError, match="degenerate"):
        meshes.Mesh(P, N, T, [[0, 1, 1]])
    assert meshes.Mesh(P, N, T, [[0, 1, 2]]).n_triangles == 1


def test_shipped_example_scene_renders(tmp_path, capsys):
    docs = Path(__file__).resolve().parents[1] / "docs" / "scene.json"
    scene, look = sc.load_scene(docs)
    assert scene.mesh.n_triangles > 0
    out = tmp_path / "scene.png"
    obj = sc.read_scene_file(docs)
    obj["size"] = [48, 48]
    small = tmp_path / "small.json"
    small.write_text(json.dumps(obj))
    rc = main(["render", "--scene", str(small), "-o", str(out), "--backend", "numpy"])
    assert rc == 0, capsys.readouterr().err
    from PIL import Image

    img = np.asarray(Image.open(out))
    assert img.shape[:2] == (48, 48) and img[..., :3].max() > 50  # something lit, not a black frame


# --------------------------------------------------------------------------- fuzz
from hypothesis import example, given, HealthCheck, settings, strategies as st  # noqa: E402

_json = st.recursive(
    st.none() | st.booleans() | st.integers(-(10**30), 10**30) | st.floats(allow_nan=True, allow_infinity=True)
    | st.sampled_from(["teapot", "sphere", "gold", "phong", "lambert", "aces", "x", ""]),
    lambda kids: st.lists(kids, max_size=5) | st.dictionaries(st.text(max_size=8), kids, max_size=4),
    max_leaves=12,
)
_small_mesh = st.fixed_dictionaries(
    {"builtin": st.sampled_from(["sphere", "torus", "plane", "teapot", "cube"])},
    optional={"segments": _json | st.integers(-5, 40), "rings": _json | st.integers(-5, 20),
              "sides": _json | st.integers(-5, 20), "divisions": _json | st.integers(-5, 20),
              "subdivisions": _json | st.integers(-5, 6), "radius": _json},
)
_scene = st.fixed_dictionaries(
    {},
    optional={
        "mesh": _small_mesh | _json,
        "camera": _json | st.fixed_dictionaries({}, optional={"eye": _json, "fov_deg": _json, "target": _json}),
        "size": _json | st.lists(st.integers(-3, 40), min_size=2, max_size=2),
        "lights": _json | st.lists(st.dictionaries(st.sampled_from(["position", "diffuse", "spot_cutoff", "x"]), _json), max_size=3),
        "light_model": _json,
        "material": _json | st.fixed_dictionaries({"model": st.sampled_from(["ward", "lambert", "nope"])}, optional={"params": _json}),
        "shading": _json, "background": _json, "antialias": _json,
        "tonemap": _json, "exposure": _json, "srgb": _json,
    },
)


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_scene)
@example({"shading": "teapot"})  # found by this test: the renderer's message did not name the scene field
def test_fuzzed_scenes_build_or_fail_with_one_line_value_error(obj):
    try:
        scene, look = sc.scene_from_json(obj)
    except (ValueError, OSError) as e:
        msg = str(e)
        assert msg and "\n" not in msg.strip(), msg
        # the message names what is wrong: a scene field, or the look's tonemap/exposure/srgb
        assert msg.startswith(("scene", "a scene", "tonemap", "exposure", "srgb")), msg
        return
    assert 1 <= scene.size[0] <= sc.MAX_SIZE and 1 <= scene.size[1] <= sc.MAX_SIZE
    assert scene.mesh.n_triangles > 0 and np.all(np.isfinite(scene.mesh.positions))
    assert np.all(np.isfinite(scene.projection)) and np.all(np.isfinite(scene.modelview))


_num = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=64), st.integers(-3, 3)).map(lambda x: repr(x) if not isinstance(x, float) else f"{x!r}")
_obj_line = st.one_of(
    st.tuples(st.just("v"), _num, _num, _num).map(" ".join),
    st.tuples(st.just("vn"), _num, _num, _num).map(" ".join),
    st.tuples(st.just("f"), *[st.integers(-4, 6).map(str)] * 3).map(" ".join),
    st.tuples(st.just("f"), *[st.integers(-4, 6).map(str)] * 4).map(" ".join),
    st.sampled_from(["# comment \udcff", "o thing", "usemtl \xe9", "s off", "garbage line", "", "f", "v 1"]),
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(st.lists(_obj_line, max_size=14))
def test_fuzzed_obj_files_load_validly_or_fail_with_value_error(tmp_path, lines):
    p = tmp_path / "fuzz.obj"
    p.write_bytes("\n".join(lines).encode("utf-8", "surrogateescape"))
    try:
        m = meshes.load_mesh(p)
    except ValueError as e:
        assert "\n" not in str(e).strip()
        return
    assert m.n_triangles > 0
    assert np.all(np.isfinite(m.positions)) and np.all(np.isfinite(m.normals)) and np.all(np.isfinite(m.tangents))
    assert meshes.triangle_areas(m.positions, m.faces).min() > 0
    assert m.faces.min() >= 0 and m.faces.max() < m.n_vertices
