"""Built-in meshes (sphere, torus, plane, Utah teapot), OBJ/PLY loading, cameras."""

from __future__ import annotations

import numpy as np
import pytest

from brdfkit.render import camera, meshes, teapot_data


def _face_normals(m):
    P = m.positions.astype(np.float64)
    F = m.faces
    return np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])


def _signed_volume(m):
    P = m.positions.astype(np.float64)
    F = m.faces
    return np.einsum("ij,ij->i", P[F[:, 0]], np.cross(P[F[:, 1]], P[F[:, 2]])).sum() / 6


def _check_frame(m):
    n = m.normals.astype(np.float64)
    t = m.tangents.astype(np.float64)
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(t, axis=1), 1, atol=1e-6)
    # winding agrees with the vertex normals (counter-clockwise seen from outside)
    fn = _face_normals(m)
    agree = np.einsum("ij,ij->i", fn, n[m.faces].sum(axis=1)) > 0
    assert agree.mean() > 0.99


def test_sphere_is_a_unit_sphere_with_outward_normals_and_azimuthal_tangents():
    m = meshes.sphere(24, 12)
    P = m.positions.astype(np.float64)
    np.testing.assert_allclose(np.linalg.norm(P, axis=1), 1, atol=1e-6)
    np.testing.assert_allclose(m.normals, P, atol=1e-6)
    # tangent = ∂P/∂φ direction: perpendicular to the normal and to the y axis
    t = m.tangents.astype(np.float64)
    away = np.linalg.norm(P[:, [0, 2]], axis=1) > 1e-3
    assert np.abs(np.einsum("ij,ij->i", t, m.normals))[away].max() < 1e-6
    assert np.abs(t[:, 1]).max() < 1e-6
    _check_frame(m)
    # volume of the inscribed polyhedron approaches 4π/3 from below
    assert 0.9 * 4 / 3 * np.pi < _signed_volume(m) < 4 / 3 * np.pi


def test_torus_geometry():
    R, r = 0.7, 0.3
    m = meshes.torus(48, 24, major=R, minor=r)
    P = m.positions.astype(np.float64)
    ring = np.linalg.norm(P[:, [0, 2]], axis=1)
    np.testing.assert_allclose((ring - R) ** 2 + P[:, 1] ** 2, r * r, atol=1e-6)
    centre = np.c_[P[:, 0] / ring * R, np.zeros(len(P)), P[:, 2] / ring * R]
    np.testing.assert_allclose(m.normals, (P - centre) / r, atol=1e-5)
    _check_frame(m)
    vol = 2 * np.pi**2 * R * r * r
    assert 0.95 * vol < _signed_volume(m) < vol


def test_plane():
    m = meshes.plane(4, half_size=2)
    assert m.n_triangles == 32
    assert np.all(m.positions[:, 1] == 0) and np.abs(m.positions).max() == 2
    assert np.all(_face_normals(m)[:, 1] > 0)


def test_teapot_data_is_newells():
    assert len(teapot_data.PATCHES) == 32 and len(teapot_data.VERTICES) == 306
    assert all(len(p) == 16 for p in teapot_data.PATCHES)
    assert max(max(p) for p in teapot_data.PATCHES) == 305
    # the first rim control point, the lid's apex and the bottom centre
    assert teapot_data.VERTICES[0] == (1.4, 0.0, 2.4)
    assert teapot_data.VERTICES[203] == (0.0, 0.0, 3.15)
    assert teapot_data.VERTICES[269] == (0.0, 0.0, 0.0)


def test_teapot_tessellation():
    m = meshes.teapot(8)
    assert m.n_triangles > 32 * 8 * 8 * 2 * 0.95  # degenerate triangles at the apexes dropped
    assert np.linalg.norm(m.positions, axis=1).max() == pytest.approx(1.0, abs=1e-6)
    _check_frame(m)
    # outward orientation: the (not quite closed) surface encloses a positive volume
    assert _signed_volume(m) > 0.2
    # y is up: the lid's knob is the highest point, on the axis
    top = m.positions[np.argmax(m.positions[:, 1])]
    assert abs(top[0] - m.positions[:, 0].mean()) < 0.3 and abs(top[2]) < 1e-6
    # Bezier patches interpolate their corner control points: the rim's first corner
    # (1.4, 0, 2.4) and the bottom centre (0, 0, 0) are mesh vertices, at the right distance apart
    P = m.positions.astype(np.float64)
    rim = np.array([1.4, 2.4, 0.0])  # y-up
    bottom = np.array([0.0, 0.0, 0.0])
    # the mesh is (p - c) / s; recover s and c from the lid apex (0, 3.15, 0) and the bottom centre
    apex_i = np.argmax(P[:, 1])
    bottom_i = np.argmin(np.linalg.norm(P - P[P[:, 1] == P[:, 1].min()].mean(0), axis=1))
    s_ = (P[apex_i, 1] - P[bottom_i, 1]) / 3.15
    c = P[bottom_i] - bottom * s_
    target = c + rim * s_
    assert np.linalg.norm(P - target, axis=1).min() < 1e-6


def test_load_mesh_roundtrip(tmp_path):
    import trimesh

    src = meshes.sphere(16, 8)
    tm = trimesh.Trimesh(vertices=src.positions * 3 + 5, faces=src.faces, process=False)
    for ext in ("obj", "ply"):
        path = tmp_path / f"ball.{ext}"
        tm.export(path)
        m = meshes.load_mesh(path)
        assert m.n_triangles == src.n_triangles
        # normalised into the unit sphere, centred
        assert np.linalg.norm(m.positions, axis=1).max() == pytest.approx(1.0, abs=1e-5)
        # smooth normals point outward, generated tangents are perpendicular and horizontal
        cos = np.einsum("ij,ij->i", m.normals, m.positions / np.linalg.norm(m.positions, axis=1, keepdims=True))
        assert cos.min() > 0.95
        assert np.abs(np.einsum("ij,ij->i", m.tangents, m.normals)).max() < 1e-5
    with pytest.raises(OSError):
        meshes.load_mesh(tmp_path / "missing.obj")
    with pytest.raises(ValueError, match="unknown built-in mesh"):
        meshes.builtin("cube")
    with pytest.raises(ValueError, match="mesh must be"):
        meshes.mesh_from_spec(3)


def test_look_at_and_perspective_match_glu():
    m = camera.look_at((0, 0, 5), (0, 0, 0), (0, 1, 0))
    np.testing.assert_allclose(m, [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, -5], [0, 0, 0, 1]], atol=1e-12)
    # looking down -x from +x: eye-space -z is world -x
    m = camera.look_at((3, 0, 0), (0, 0, 0), (0, 1, 0))
    np.testing.assert_allclose(m @ [0, 0, 0, 1], [0, 0, -3, 1], atol=1e-12)
    np.testing.assert_allclose(m[:3, :3] @ [-1, 0, 0], [0, 0, -1], atol=1e-12)
    p = camera.perspective(90, 2.0, 1, 3)
    # gluPerspective: f = cot(fov/2) = 1
    np.testing.assert_allclose(p, [[0.5, 0, 0, 0], [0, 1, 0, 0], [0, 0, -2, -3], [0, 0, -1, 0]], atol=1e-12)
    # the near and far planes map to -1 and +1
    for z, ndc in ((-1, -1), (-3, 1)):
        c = p @ [0, 0, z, 1]
        assert c[2] / c[3] == pytest.approx(ndc)
    with pytest.raises(ValueError, match="fov_deg"):
        camera.perspective(0, 1)
    with pytest.raises(ValueError, match="4x4"):
        camera.camera_matrices({"projection": [[1, 2]], "modelview": np.eye(4).tolist()}, 1.0)
    with pytest.raises(ValueError, match="unknown field"):
        camera.camera_matrices({"eye": [0, 0, 1], "zoom": 2}, 1.0)
