"""The renderer: GLSL against the numpy reference, hand-derived pixels, provoking vertex, MSAA, tone mapping."""

from __future__ import annotations

import math

import numpy as np
import pytest

import brdfkit as bk
from brdfkit import opengl
from brdfkit.opengl import Light, LightModel
from brdfkit.render import Mesh, Scene, glsl, make_scene, render, render_linear
from brdfkit.render import image as im
from brdfkit.render import scene as sc

LIGHTS = [
    Light(position=(-2, 2.5, 3, 1), diffuse=(1, 0.9, 0.8), ambient=0.05, quadratic_attenuation=0.01),
    Light(position=(1, 0.3, 0.5, 0), diffuse=(0.3, 0.3, 0.4)),
    Light(position=(0, 3, 2, 1), spot_direction=(0, -1, -0.3), spot_cutoff=35, spot_exponent=4, diffuse=0.5),
]
SMALL_SPHERE = {"builtin": "sphere", "segments": 32, "rings": 16}


def _scene(material, shading, mesh=SMALL_SPHERE, size=(64, 64), **kw):
    kw.setdefault("lights", LIGHTS)
    kw.setdefault("light_model", {"ambient": [0.1, 0.1, 0.1]})
    kw.setdefault("antialias", False)
    return make_scene(mesh=mesh, material=material, shading=shading, size=size, **kw)


def _compare(a, b, rtol):
    cover = (a[..., 3] > 0) & (b[..., 3] > 0)
    assert np.count_nonzero((a[..., 3] > 0) != (b[..., 3] > 0)) == 0
    assert cover.sum() > 1000
    d = np.abs(a[..., :3] - b[..., :3])[cover]
    rel = d / np.maximum(np.abs(b[..., :3][cover]), 1e-2)
    assert rel.max() <= rtol, rel.max()


@pytest.mark.parametrize("shading", ["flat", "gouraud", "phong"])
def test_fixed_function_glsl_equals_opengl_shade(shading):
    """opengl_fixed.glsl (on the GPU) against brdfkit.opengl.shade (numpy), same rasterisation."""
    s = _scene("gold", shading, light_model={"ambient": [0.2, 0.2, 0.2], "local_viewer": shading == "phong"})
    _compare(render_linear(s, "glsl"), render_linear(s, "numpy"), 2e-4)


GLSL_MODELS = [n for n in bk.models() if glsl.has_shader(n)]


@pytest.mark.parametrize("name", GLSL_MODELS)
def test_brdf_glsl_render_equals_numpy_render(name):
    """Per-fragment GLSL lighting against numpy lighting of a G-buffer with model.eval (float64)."""
    m = bk.model(name)
    s = _scene(m, "phong")
    _compare(render_linear(s, "glsl"), render_linear(s, "numpy"), 1e-4)
    s = _scene(m, "gouraud")
    _compare(render_linear(s, "glsl"), render_linear(s, "numpy"), 1e-3)


def test_every_model_renders_through_auto():
    for name in bk.models():
        f = render(_scene(bk.model(name), "phong", size=(32, 32)))
        assert np.isfinite(f.linear).all() and f.linear[..., :3].min() >= 0
        assert f.linear[..., :3].max() > 0, name


def test_lambert_pixel_by_hand():
    """The centre of a unit sphere seen head-on, lit by a headlight: n = l = v = +z.

    L = kd/π · (π · d) · cos 0 + L_a · kd = kd (d + a) with a directional light of colour d
    and ambient a (the albedo of Lambert is kd)."""
    kd = np.array([0.2, 0.5, 0.7])
    s = _scene(
        bk.model("lambert", kd=kd),
        "phong",
        mesh={"builtin": "sphere", "segments": 128, "rings": 64},
        size=(65, 65),
        camera={"eye": [0, 0, 4], "fov_deg": 30},
        lights=[Light(position=(0, 0, 1, 0), diffuse=(0.8, 0.8, 0.8))],
        light_model={"ambient": [0.1, 0.1, 0.1]},
    )
    img = render_linear(s, "glsl")
    np.testing.assert_allclose(img[32, 32, :3], kd * 0.9, rtol=2e-3)
    # half-way to the limb (in the image, x = 0.5 on the sphere): cos = sqrt(1 - 0.25)
    # the pixel column where the sphere's x = 0.5: project (0.5, 0, z) with the camera
    z = math.sqrt(0.75)
    clip = s.projection @ s.modelview @ [0.5, 0, z, 1]
    col = (clip[0] / clip[3] + 1) / 2 * 65 - 0.5
    c0, c1 = int(math.floor(col)), int(math.floor(col)) + 1
    # the cosine factor at the two neighbouring pixels brackets cos = 0.866
    lo = img[32, c1, 0] / (kd[0] * 0.8)
    hi = img[32, c0, 0] / (kd[0] * 0.8)
    amb = 0.1 / 0.8
    assert lo - amb <= math.sqrt(0.75) + 1e-3 and hi - amb >= math.sqrt(0.75) - 1e-3


def test_flat_takes_the_last_vertex():
    """GL_FLAT: the whole triangle gets the colour lit at its provoking (last) vertex."""
    P = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]])
    N = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [-0.6, 0.5, 0.62]])
    mesh = Mesh(P, N, np.tile([1.0, 0, 0], (3, 1)), np.array([[0, 1, 2]]))
    mat = opengl.Material(ambient=0.1, diffuse=(0.7, 0.5, 0.2), specular=0.5, shininess=20)
    lights = [Light(position=(0.3, 0.4, 1.0, 0.0))]
    ortho = np.diag([0.8, 0.8, -0.1, 1.0])  # orthographic; z = -1 is inside the clip volume
    s = Scene(mesh, ortho, _translate(0, 0, -1), (48, 48), lights, LightModel(), mat, "flat", antialias=False)
    img = render_linear(s, "glsl")
    inside = img[..., 3] > 0
    eye_last = np.array([[0.0, 1.0, -1.0]])
    expect = opengl.shade(eye_last, N[2:3], mat, lights, LightModel())[0, :3]
    np.testing.assert_allclose(img[inside][:, :3], np.tile(expect, (inside.sum(), 1)), atol=2e-6)
    first = opengl.shade(np.array([[-1.0, -1.0, -1.0]]), N[0:1], mat, lights, LightModel())[0, :3]
    assert np.abs(first - expect).max() > 0.05  # the choice of vertex matters in this test


def _translate(x, y, z):
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def test_spotlight_cone_in_the_picture():
    """A spotlight straight down the view axis onto a plane facing the camera lights a disc of
    radius d·tan(cutoff) and nothing outside it."""
    s = _scene(
        "silver",
        "phong",
        mesh={"builtin": "plane", "divisions": 8, "half_size": 1.0},
        size=(101, 101),
        camera={"eye": [0, 4, 0], "target": [0, 0, 0], "up": [0, 0, -1], "fov_deg": 30},
        lights=[Light(position=(0, 0, 0, 1), spot_direction=(0, 0, -1), spot_cutoff=10, diffuse=1, specular=0)],
        light_model={"ambient": [0, 0, 0]},
    )
    img = render_linear(s, "glsl")
    lit = img[..., 0] > 1e-4
    # pixel radius of the cone's footprint: tan(10°)/tan(15°) of the half-width
    r_expect = math.tan(math.radians(10)) / math.tan(math.radians(15)) * 50.5
    yy, xx = np.mgrid[0:101, 0:101]
    r = np.hypot(xx - 50, yy - 50)
    assert lit[r < r_expect - 1.5].all()
    assert not lit[r > r_expect + 1.5].any()


def test_ward_brushed_highlight_follows_the_tangent():
    """Anisotropic Ward on a sphere whose tangents circle the y axis: with αx << αy the
    highlight is long vertically, with αx >> αy horizontally."""
    def extent(ax, ay):
        m = bk.model("ward", kd=0.0, ks=0.3, alpha_x=ax, alpha_y=ay)
        s = _scene(m, "phong", mesh={"builtin": "sphere", "segments": 96, "rings": 48}, size=(96, 96),
                   lights=[Light(position=(0, 0, 1, 0))], light_model={"ambient": [0, 0, 0]},
                   camera={"eye": [0, 0, 3.6], "fov_deg": 36})
        y = render_linear(s)[..., 1]
        w = y > 0.5 * y.max()
        yy, xx = np.nonzero(w)
        return np.ptp(yy) + 1, np.ptp(xx) + 1

    h, w = extent(0.04, 0.4)
    assert h > 3 * w
    h, w = extent(0.4, 0.04)
    assert w > 3 * h


def test_msaa_gives_fractional_coverage_and_camera_forms_agree():
    s = _scene("gold", "gouraud", size=(64, 64), antialias=True)
    a = render_linear(s)[..., 3]
    frac = (a > 0) & (a < 1)
    assert frac.sum() > 20  # antialiased silhouette
    assert np.all(a[a > 0] > 0) and a.max() == 1.0
    # the same camera given as matrices renders the same picture
    obj = {"mesh": SMALL_SPHERE, "size": [64, 64], "material": {"opengl": "gold"}, "antialias": False}
    s1, _ = sc.scene_from_json(dict(obj, camera={"eye": [1, 1, 3], "fov_deg": 40}))
    s2, _ = sc.scene_from_json(
        dict(obj, camera={"projection": s1.projection.tolist(), "modelview": s1.modelview.tolist()})
    )
    np.testing.assert_array_equal(render_linear(s1), render_linear(s2))


def test_tone_mapping_and_encoding():
    np.testing.assert_allclose(im.srgb_encode(np.array([0.0, 0.0031308, 0.5, 1.0])),
                               [0.0, 0.04044994, 0.7353569, 1.0], atol=1e-6)
    np.testing.assert_allclose(im.tonemap(np.array([1.0, 3.0]), "reinhard"), [0.5, 0.75])
    assert im.tonemap(np.array([0.0]), "aces")[0] == 0.0 and im.tonemap(np.array([1e6]), "aces")[0] == 1.0
    assert im.tonemap(np.array([2.0]), "clamp")[0] == 1.0
    # premultiplied half coverage over a white background, no encoding: 0.5*c + 0.5*1
    lin = np.array([[[0.2, 0.1, 0.0, 0.5]]])
    d = im.to_display(lin, "clamp", 1.0, False, (1, 1, 1, 1))
    np.testing.assert_allclose(d[0, 0], [0.7, 0.6, 0.5, 1.0])
    assert im.to_uint8(np.array([0.5 / 255, 1.49 / 255, 1.0]))[0] == 1
    with pytest.raises(ValueError, match="tonemap"):
        im.tonemap(np.ones(1), "filmic")
    with pytest.raises(ValueError, match="exposure"):
        sc.Look("clamp", -1.0, False)


def test_default_look_depends_on_the_material():
    assert sc.default_look(opengl.MATERIALS["gold"]) == sc.Look("clamp", 1.0, False)
    assert sc.default_look(bk.model("lambert")) == sc.Look("aces", 1.0, True)


def test_outputs(tmp_path):
    f = render(_scene("ruby", "phong", size=(40, 30)))
    f.save(tmp_path / "a.png")
    f.save(tmp_path / "a.exr")
    f.save(tmp_path / "a.npy")
    from PIL import Image

    png = np.asarray(Image.open(tmp_path / "a.png"))
    assert png.shape == (30, 40, 3)
    np.testing.assert_array_equal(png, f.uint8[..., :3])
    np.testing.assert_array_equal(np.load(tmp_path / "a.npy"), f.linear)
    np.testing.assert_allclose(im.read_exr(tmp_path / "a.exr"), f.linear)
    with pytest.raises(ValueError, match="must end in"):
        f.save(tmp_path / "a.jpg")


@pytest.mark.parametrize(
    "obj, fragment",
    [
        ({"shading": "toon"}, "shading"),
        ({"material": {"model": "ward", "params": {"alpha_x": -1}}}, "alpha_x"),
        ({"material": {"opengl": "unobtainium"}}, "unknown material"),
        ({"lights": [{"position": [0, 0, 1, 0]}] * 9}, "at most 8"),
        ({"camera": {"eye": [0, 0, 0]}}, "eye and target"),
        ({"size": [64]}, "size"),
        ({"background": [2, 0, 0]}, "background"),
        ({"mesh": "cube"}, "mesh"),
    ],
)
def test_scene_errors_are_one_line(obj, fragment):
    with pytest.raises((ValueError, OSError), match=fragment) as e:
        sc.scene_from_json(obj)
    assert "\n" not in str(e.value)


def test_gouraud_misses_the_highlight_inside_a_big_triangle():
    """The gallery's figure, measured: chrome on a 12×6 sphere with the highlight at a face centre.

    Per-vertex lighting samples (n·h)^76.8 only at vertices ≥ 21° from the peak, where it is
    below 1%, so Gouraud's brightest pixel is far below Phong's (which reaches the specular
    colour at the peak)."""
    from brdfkit.render.gallery import FRONT, _highlight_light

    light = [_highlight_light(75.0, -15.0)]
    coarse = {"builtin": "sphere", "segments": 12, "rings": 6}
    out = {}
    for shading in ("gouraud", "phong"):
        s = _scene("chrome", shading, mesh=coarse, size=(96, 96), camera=FRONT, lights=light,
                   light_model={"ambient": [0, 0, 0]})
        out[shading] = render_linear(s)[..., 0].max()
    chrome = opengl.MATERIALS["chrome"]
    assert out["phong"] > chrome.specular[0] * 0.95
    assert out["gouraud"] < out["phong"] - 0.3


@pytest.mark.parametrize("material", ["opengl", "ward"])
@pytest.mark.parametrize("where", ["vertex", "fragment"])
def test_pipeline_shaders_compile_as_glsl_es_300(material, where):
    """The renderer's own shader files stay in the GLSL 3.30 / ES 3.00 common subset (for the browser)."""
    from brdfkit.render.renderer import _read_shader, default_renderer

    ctx = default_renderer().ctx
    if "GL_ARB_ES3_compatibility" not in ctx.extensions:
        pytest.skip("driver cannot compile GLSL ES 3.00")
    if material == "opengl":
        light = _read_shader("pipeline_lights.glsl") + _read_shader("opengl_fixed.glsl")
    else:
        light = glsl.shader_source("ward") + _read_shader("pipeline_lights.glsl") + _read_shader("pipeline_brdf.glsl")
    d = "#define BKR_LIGHT_IN_VERTEX\n" if where == "vertex" else "#define BKR_LIGHT_IN_FRAGMENT\n"
    vs = "#version 300 es\n" + d + (light if where == "vertex" else _read_shader("pipeline_lights.glsl"))
    vs += _read_shader("pipeline_vertex.glsl")
    fs = "#version 300 es\n" + d + (light if where == "fragment" else "precision highp float;\n")
    fs += _read_shader("pipeline_fragment.glsl")
    from brdfkit.render.context import EGLCurrent

    # another test's context may be current in this worker: make this one current as the renderer does
    with EGLCurrent(), ctx:
        ctx.program(vertex_shader=vs, fragment_shader=fs).release()
