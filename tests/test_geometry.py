"""brdfkit.geometry: angle conversions, half vector, Rusinkiewicz angles, reflection, frames."""

import math

import numpy as np
import pytest

from brdfkit import geometry as g


def _unit(rng, n, upper=True):
    return g.random_unit_vectors(n, rng, hemisphere=upper)


def test_spherical_round_trip_and_known_vectors():
    np.testing.assert_allclose(g.spherical_to_vector(0.0, 1.3), [0, 0, 1], atol=1e-16)
    np.testing.assert_allclose(g.spherical_to_vector(math.pi / 2, math.pi / 2), [0, 1, 0], atol=1e-16)
    rng = np.random.default_rng(0)
    v = _unit(rng, 1000, upper=False)
    th, ph = g.vector_to_spherical(v)
    assert np.all((ph >= 0) & (ph < 2 * math.pi))
    np.testing.assert_allclose(g.spherical_to_vector(th, ph), v, atol=1e-14)


def test_half_vector_plain_and_robust_cases():
    wi = np.array([0.6, 0.0, 0.8])
    wo = np.array([-0.6, 0.0, 0.8])
    np.testing.assert_allclose(g.half_vector(wi, wo), [0, 0, 1], atol=1e-16)
    a, b = np.array([3.0, 0, 4]) / 5, np.array([0.0, 0, 1])
    np.testing.assert_allclose(g.half_vector(a, b), (a + b) / np.linalg.norm(a + b), rtol=1e-15)
    # grazing pair whose naive sum underflows when squared: normalize(wi + wo) would be 0/0
    np.testing.assert_array_equal(g.half_vector(np.array([1.0, 0, 1e-300]), np.array([-1.0, 0, 1e-300])), [0, 0, 1])
    # opposite directions: undefined, the convention is +z
    np.testing.assert_array_equal(g.half_vector(np.array([0.0, 0.6, 0.8]), np.array([0.0, -0.6, -0.8])), [0, 0, 1])
    f32 = g.half_vector(a.astype(np.float32), b.astype(np.float32))
    assert f32.dtype == np.float32
    np.testing.assert_allclose(f32, (a + b) / np.linalg.norm(a + b), rtol=1e-6)


def test_scaled_sum_keeps_component_ratios_and_length():
    rng = np.random.default_rng(1)
    wi, wo = _unit(rng, 500), _unit(rng, 500)
    s, m = g.scaled_sum(wi, wo)
    np.testing.assert_allclose(s * m[:, None], wi + wo, rtol=1e-14, atol=1e-16)
    np.testing.assert_allclose(np.max(np.abs(s), axis=-1), 1.0)


def test_reflect_about_normal_and_general_axis():
    w = np.array([0.3, -0.4, math.sqrt(1 - 0.25)])
    np.testing.assert_allclose(g.reflect(w), [-0.3, 0.4, w[2]])
    n = g.normalize(np.array([1.0, 1.0, 1.0]))
    r = g.reflect(w, n)
    np.testing.assert_allclose(g.dot(r, n), g.dot(w, n), rtol=1e-14)  # same angle to n
    np.testing.assert_allclose(g.normalize(r + w), n, atol=1e-14)  # n bisects w and r


def test_rusinkiewicz_round_trip_and_known_configuration():
    rng = np.random.default_rng(2)
    wi, wo = _unit(rng, 2000), _unit(rng, 2000)
    th, ph, td, pd = g.to_rusinkiewicz(wi, wo)
    wi2, wo2 = g.from_rusinkiewicz(th, ph, td, pd)
    np.testing.assert_allclose(wi2, wi, atol=1e-12)
    np.testing.assert_allclose(wo2, wo, atol=1e-12)
    # light at 60° in the x-z plane, viewer at the normal: h halfway, θh = θd = 30°, φh = φd = 0
    wi = g.spherical_to_vector(math.radians(60), 0.0)
    wo = np.array([0.0, 0.0, 1.0])
    th, ph, td, pd = g.to_rusinkiewicz(wi, wo)
    assert th == pytest.approx(math.radians(30), abs=1e-12) and td == pytest.approx(math.radians(30), abs=1e-12)
    assert ph == pytest.approx(0, abs=1e-12) and min(pd, 2 * math.pi - pd) == pytest.approx(0, abs=1e-12)
    # swapping wi and wo shifts φd by π (reciprocity) and keeps θh, θd
    a = g.to_rusinkiewicz(g.spherical_to_vector(0.4, 0.3), g.spherical_to_vector(0.9, 2.0))
    b = g.to_rusinkiewicz(g.spherical_to_vector(0.9, 2.0), g.spherical_to_vector(0.4, 0.3))
    assert a[0] == pytest.approx(b[0]) and a[2] == pytest.approx(b[2])
    assert (a[3] - b[3]) % (2 * math.pi) == pytest.approx(math.pi)


def test_frame_from_normal_is_orthonormal_and_local_round_trips():
    rng = np.random.default_rng(3)
    n = _unit(rng, 500, upper=False)
    t, b = g.frame_from_normal(n)
    for x, y in ((t, b), (t, n), (b, n)):
        np.testing.assert_allclose(g.dot(x, y), 0, atol=1e-14)
    for x in (t, b):
        np.testing.assert_allclose(g.dot(x, x), 1, rtol=1e-14)
    np.testing.assert_allclose(np.cross(t, b), n, atol=1e-14)  # right-handed: t × b = n
    v = _unit(rng, 500, upper=False)
    np.testing.assert_allclose(g.from_local(g.to_local(v, t, b, n), t, b, n), v, atol=1e-14)
    np.testing.assert_allclose(g.rotate_z(np.array([1.0, 0, 0.5]), math.pi / 2), [0, 1, 0.5], atol=1e-16)


def _ulps(a: float, b: float) -> float:
    return abs(a - b) / math.ulp(b) if b != 0.0 else abs(a) / 5e-324


def test_hypot_c_matches_math_hypot_across_the_range_compiled_and_plain():
    """The kernels' branch-free hypot: within 2 ulp of libm's, from subnormal to huge, both engines."""
    rng = np.random.default_rng(7)
    mags = 10.0 ** rng.uniform(-320, 300, size=(3000, 2))
    signs = rng.choice([-1.0, 1.0], size=(3000, 2))
    pairs = [tuple(x) for x in mags * signs]
    pairs += [(0.0, 0.0), (0.0, 5e-324), (-5e-324, 5e-324), (3.0, 4.0), (1e-200, 1e-200), (1e300, 1e300),
              (1.0, 1e-170), (2.2250738585072014e-308, 0.0), (0.0, -1.0)]
    for a, b in pairs:
        want = math.hypot(a, b)
        for f in (g.hypot_c, g.hypot_c.py_func):
            got = f(a, b)
            assert _ulps(got, want) <= 2, (f, a, b, got, want)
    assert g.hypot_c(0.0, 0.0) == 0.0 and g.hypot_c(3.0, 4.0) == 5.0


def test_hypot_c_is_exact_with_a_zero_argument():
    for c in (0.3, 1.0, 5e-324, 1e-200, 0.7071067811865476, 1e300):
        for f in (g.hypot_c, g.hypot_c.py_func):
            assert f(0.0, c) == c and f(-c, 0.0) == c
