"""brdfkit.opengl: the fixed-function lighting equation, against hand derivations and against Mesa.

The Mesa comparison runs Mesa's own fixed-function pipeline (OSMesa, legacy
GL, feedback mode) in a subprocess (tests/_mesa_reference.py) over hundreds
of random cases and requires agreement to 5e-5.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from brdfkit import opengl
from brdfkit.opengl import MATERIALS, Light, LightModel, Material, shade

import _mesa_reference as mesa

SEED_TABLE = {
    # name: ambient, diffuse, specular, shininess fraction (the lecture's table, typed in independently)
    "emerald": ((0.0215, 0.1745, 0.0215), (0.07568, 0.61424, 0.07568), (0.633, 0.727811, 0.633), 0.6),
    "gold": ((0.24725, 0.1995, 0.0745), (0.75164, 0.60648, 0.22648), (0.628281, 0.555802, 0.366065), 0.4),
    "brass": ((0.329412, 0.223529, 0.027451), (0.780392, 0.568627, 0.113725), (0.992157, 0.941176, 0.807843), 0.21794872),
    "pearl": ((0.25, 0.20725, 0.20725), (1.0, 0.829, 0.829), (0.296648, 0.296648, 0.296648), 0.088),
}


def test_table_has_the_lectures_twelve_materials():
    assert list(MATERIALS) == [
        "emerald", "jade", "obsidian", "pearl", "ruby", "turquoise",
        "brass", "bronze", "chrome", "copper", "gold", "silver",
    ]
    for name, (a, d, s, frac) in SEED_TABLE.items():
        m = MATERIALS[name]
        assert m.ambient[:3] == pytest.approx(a) and m.diffuse[:3] == pytest.approx(d)
        assert m.specular[:3] == pytest.approx(s)
        assert m.shininess == pytest.approx(frac * 128)
        assert m.emission == (0.0, 0.0, 0.0, 1.0) and m.ambient[3] == 1.0


def test_defaults_are_opengls():
    m, L, lm = Material(), Light(), LightModel()
    assert m.ambient == (0.2, 0.2, 0.2, 1.0) and m.diffuse == (0.8, 0.8, 0.8, 1.0)
    assert m.specular == (0.0, 0.0, 0.0, 1.0) and m.shininess == 0.0
    assert L.position == (0.0, 0.0, 1.0, 0.0) and L.diffuse == (1.0, 1.0, 1.0, 1.0)
    assert L.spot_direction == (0.0, 0.0, -1.0) and L.spot_cutoff == 180.0
    assert (L.constant_attenuation, L.linear_attenuation, L.quadratic_attenuation) == (1.0, 0.0, 0.0)
    assert lm.ambient == (0.2, 0.2, 0.2, 1.0) and lm.local_viewer is False


def test_hand_computed_headlight():
    # Directional light along +z onto a normal tilted by 60° in x: n·l = 0.5;
    # infinite viewer: h = normalize(l + z) = z, n·h = 0.5.
    m = Material(ambient=0.1, diffuse=0.6, specular=0.5, shininess=2, emission=0.05)
    L = Light(position=(0, 0, 1, 0), ambient=0.2, diffuse=1.0, specular=1.0)
    lm = LightModel(ambient=0.3)
    n = np.array([[math.sin(math.pi / 3), 0, math.cos(math.pi / 3)]])
    c = shade([[0, 0, -5]], n, m, [L], lm)
    expect = 0.05 + 0.1 * 0.3 + (0.1 * 0.2 + 0.5 * 0.6 + 0.25 * 0.5)
    np.testing.assert_allclose(c[0, :3], expect, rtol=0, atol=1e-12)
    assert c[0, 3] == 1.0


def test_hand_computed_point_light_attenuation_and_spot():
    # Point light 2 units straight in front of the surface, spot pointing at it.
    m = Material(ambient=0, diffuse=1, specular=0, emission=0)
    L = Light(position=(0, 0, 0, 1), diffuse=1, specular=0, constant_attenuation=1,
              linear_attenuation=0.5, quadratic_attenuation=0.25,
              spot_direction=(0, 0, -1), spot_exponent=3, spot_cutoff=30)
    lm = LightModel(ambient=0)
    c = shade([[0, 0, -2]], [[0, 0, 1]], m, [L], lm)
    np.testing.assert_allclose(c[0, :3], 1 / (1 + 1 + 1), atol=1e-12)  # att = 1/(1 + .5*2 + .25*4), spot = 1
    # 20° off the spot axis: spot = cos(20°)^3; n·l = cos 20° for a normal facing the light direction along z
    p = np.array([[2 * math.tan(math.radians(20)), 0, -2]])
    d = np.linalg.norm(p)
    c = shade(p, [[0, 0, 1]], m, [L], lm)
    expect = math.cos(math.radians(20)) ** 4 / (1 + 0.5 * d + 0.25 * d * d)
    np.testing.assert_allclose(c[0, 0], expect, atol=1e-12)
    # 40° off axis: outside the 30° cone -> dark
    p = np.array([[2 * math.tan(math.radians(40)), 0, -2]])
    assert shade(p, [[0, 0, 1]], m, [L], lm)[0, 0] == 0.0


def test_no_highlight_on_the_unlit_side_and_clamping():
    m = Material(ambient=0, diffuse=0, specular=1, shininess=1, emission=0)
    lm = LightModel(ambient=0)
    # light from +x, normal slightly away from it: n·l < 0, but n·h > 0 with h between l and z
    n = np.array([[-0.1, 0, 1.0]])
    c = shade([[0, 0, -1]], n, m, [Light(position=(1, 0, 0, 0))], lm)
    assert np.all(c[:, :3] == 0)
    bright = Material(ambient=1, diffuse=1, specular=1, emission=1)
    c = shade([[0, 0, -1]], [[0, 0, 1]], bright, [Light(ambient=5)], LightModel(ambient=5))
    assert np.all(c[:, :3] == 1.0)


def test_local_viewer_changes_the_half_vector():
    m = Material(ambient=0, diffuse=0, specular=1, shininess=50, emission=0)
    lm_inf, lm_loc = LightModel(ambient=0), LightModel(ambient=0, local_viewer=True)
    L = Light(position=(0, 0, 1, 0))
    # Off-axis point with a normal facing +z: infinite viewer gives n·h = 1, local viewer does not.
    p, n = [[3, 0, -3]], [[0, 0, 1]]
    assert shade(p, n, m, [L], lm_inf)[0, 0] == pytest.approx(1.0)
    v = -np.array(p[0], float) / np.linalg.norm(p[0])
    h = (np.array([0, 0, 1.0]) + v) / np.linalg.norm(np.array([0, 0, 1.0]) + v)
    assert shade(p, n, m, [L], lm_loc)[0, 0] == pytest.approx(h[2] ** 50)


@pytest.mark.parametrize(
    "kwargs, fragment",
    [
        ({"spot_cutoff": 120}, "spot_cutoff"),
        ({"position": (1, 2)}, "position"),
        ({"diffuse": "red"}, "diffuse"),
        ({"linear_attenuation": -1}, "linear_attenuation"),
    ],
)
def test_bad_lights_raise_one_line_errors(kwargs, fragment):
    with pytest.raises(ValueError, match=fragment) as e:
        Light(**kwargs)
    assert "\n" not in str(e.value)


def test_bad_material_and_too_many_lights():
    with pytest.raises(ValueError, match="shininess"):
        Material(shininess=200)
    with pytest.raises(ValueError, match="unknown material"):
        shade([[0, 0, -1]], [[0, 0, 1]], "unobtainium")
    with pytest.raises(ValueError, match="at most 8"):
        shade([[0, 0, -1]], [[0, 0, 1]], "gold", [Light()] * 9)
    with pytest.raises(ValueError, match="unknown field"):
        opengl.light_from_json({"colour": 1})


# --------------------------------------------------------------------------- against Mesa
def _random_light(rng: np.random.Generator) -> Light:
    kind = rng.choice(["directional", "point", "spot", "directional-spot"])
    col = lambda hi: tuple(rng.uniform(0, hi, 3)) + (1.0,)  # noqa: E731
    hi = 2.0 if rng.random() < 0.3 else 1.0  # sometimes bright enough to saturate
    kw = dict(ambient=col(0.3), diffuse=col(hi), specular=col(hi))
    d = rng.normal(size=3)
    d /= np.linalg.norm(d)
    if kind.startswith("directional"):
        kw["position"] = tuple(d * rng.uniform(0.5, 3)) + (0.0,)
    else:
        w = rng.choice([1.0, 2.0])
        kw["position"] = tuple(rng.uniform(-4, 4, 3) * w) + (w,)
        kw["constant_attenuation"] = rng.uniform(0.2, 1.5)
        kw["linear_attenuation"] = rng.uniform(0, 0.5) if rng.random() < 0.7 else 0.0
        kw["quadratic_attenuation"] = rng.uniform(0, 0.2) if rng.random() < 0.7 else 0.0
    if "spot" in kind:
        sd = rng.normal(size=3)
        kw["spot_direction"] = tuple(sd * rng.uniform(0.5, 2))
        kw["spot_exponent"] = float(rng.choice([0.0, rng.uniform(0, 40)]))
        kw["spot_cutoff"] = float(rng.uniform(10, 90))
    return Light(**kw)


def _random_case(rng: np.random.Generator, i: int):
    names = list(MATERIALS)
    if i < 2 * len(names):
        mat = MATERIALS[names[i % len(names)]]
    else:
        mat = Material(
            ambient=tuple(rng.uniform(0, 1, 3)) + (1.0,),
            diffuse=tuple(rng.uniform(0, 1, 3)) + (float(rng.uniform(0.2, 1)),),
            specular=tuple(rng.uniform(0, 1, 3)) + (1.0,),
            emission=tuple(rng.uniform(0, 0.3, 3)) + (1.0,) if rng.random() < 0.5 else (0, 0, 0, 1),
            # Not 0: Mesa 22's generated fixed-function program gets shininess 0 wrong (it
            # yields (n·l)^(n·l) instead of (n·h)^0 = 1); see test_shininess_zero_follows_the_spec.
            shininess=float(rng.choice([1.0, 128.0, rng.uniform(0.5, 128)])),
        )
    n_lights = int(rng.integers(1, 5)) if i % 7 else 8
    lights = [_random_light(rng) for _ in range(n_lights)]
    lm = LightModel(ambient=tuple(rng.uniform(0, 0.5, 3)) + (1.0,), local_viewer=bool(i % 2))
    n_vert = 24
    P = np.column_stack([rng.uniform(-3, 3, n_vert), rng.uniform(-3, 3, n_vert), rng.uniform(-8, -0.5, n_vert)])
    N = rng.normal(size=(n_vert, 3)) * rng.uniform(0.3, 3, (n_vert, 1))  # not unit: GL_NORMALIZE
    return mat, lights, lm, P, N


def _compare_with_mesa(n_cases: int, seed: int, llvm: bool) -> None:
    rng = np.random.default_rng(seed)
    cases = [_random_case(rng, i) for i in range(n_cases)]
    req = {
        "mode": "shade",
        "cases": [
            {
                "material": mesa.as_json(m),
                "lights": [mesa.as_json(L) for L in ls],
                "light_model": mesa.as_json(lm),
                "positions": P.tolist(),
                "normals": N.tolist(),
            }
            for m, ls, lm, P, N in cases
        ],
    }
    ans = mesa.call(req, llvm=llvm)
    worst = 0.0
    saturated = spots = 0
    for (m, ls, lm, P, N), ref in zip(cases, ans["colors"]):
        ours = shade(P, N, m, ls, lm)
        ref = np.asarray(ref)
        err = np.abs(ours - ref).max()
        worst = max(worst, err)
        assert err <= 5e-5, (m, ls, lm, err)
        saturated += int(np.any(ours[:, :3] == 1.0))
        spots += sum(L.is_spot for L in ls)
    # the random cases really exercised saturation and spotlights
    assert saturated > n_cases // 16 and spots > n_cases // 3
    assert worst <= 5e-5


def test_shade_matches_mesa_fixed_function():
    """320 random cases (7680 vertices) through Mesa's fixed-function program (interpreted)."""
    _compare_with_mesa(320, 20261122, llvm=False)


def test_shade_matches_mesa_fixed_function_llvm():
    """A smaller set through llvmpipe's compiled path (what Mesa renders with)."""
    _compare_with_mesa(20, 7, llvm=True)


def test_shininess_zero_follows_the_spec():
    # OpenGL 2.1 §2.14.1: the specular factor is (n ⊙ h)^s_rm with f_i = 1 on the lit side;
    # s_rm = 0 gives exactly s_cm * s_cli wherever n·l > 0, whatever n·h is.
    m = Material(ambient=0, diffuse=0, specular=(0.3, 0.5, 0.7), shininess=0, emission=0)
    n = np.array([[0.0, 0.6, 0.8], [0.0, -0.6, 0.8], [0.0, 0.0, -1.0]])
    c = shade(np.zeros((3, 3)) + [0, 0, -2], n, m, [Light(position=(0, 1, 1, 0))], LightModel(ambient=0))
    np.testing.assert_allclose(c[:2, :3], [[0.3, 0.5, 0.7]] * 2, atol=1e-12)
    assert np.all(c[2, :3] == 0)
