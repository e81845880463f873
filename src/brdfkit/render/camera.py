"""Camera matrices with OpenGL's conventions (row-major numpy arrays applied to column vectors).

``look_at`` is ``gluLookAt`` and ``perspective`` is ``gluPerspective``: the eye
sits at the origin of eye space looking down −z with +y up, and the
projection maps the view frustum to the clip cube [−1, 1]³.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np


def look_at(eye, target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0)) -> np.ndarray:
    """The modelview matrix of ``gluLookAt(eye, target, up)``."""
    eye = np.asarray(eye, dtype=np.float64)
    target = np.asarray(target, dtype=np.float64)
    up = np.asarray(up, dtype=np.float64)
    f = target - eye
    if np.linalg.norm(f) == 0:
        raise ValueError("camera eye and target must differ")
    f /= np.linalg.norm(f)
    s = np.cross(f, up)
    if np.linalg.norm(s) < 1e-9:
        raise ValueError("camera up must not be parallel to the viewing direction")
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def perspective(fov_deg: float, aspect: float, near: float = 0.1, far: float = 100.0) -> np.ndarray:
    """The projection matrix of ``gluPerspective(fov_deg, aspect, near, far)`` (vertical field of view)."""
    if not (0 < fov_deg < 180):
        raise ValueError(f"camera fov_deg must be in (0, 180), got {fov_deg}")
    if not (0 < near < far):
        raise ValueError(f"camera needs 0 < near < far, got near={near}, far={far}")
    f = 1.0 / math.tan(math.radians(fov_deg) / 2)
    m = np.zeros((4, 4))
    m[0, 0] = f / aspect
    m[1, 1] = f
    m[2, 2] = (far + near) / (near - far)
    m[2, 3] = 2 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


DEFAULT_CAMERA = {"eye": [0.0, 1.0, 3.45], "target": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0], "fov_deg": 36.0}


def _matrix(name: str, value: Any) -> np.ndarray:
    try:
        m = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"camera {name} must be a 4x4 matrix (list of 4 rows)") from None
    if m.shape == (16,):
        m = m.reshape(4, 4)
    if m.shape != (4, 4) or not np.all(np.isfinite(m)):
        raise ValueError(f"camera {name} must be a finite 4x4 matrix (list of 4 rows), got shape {m.shape}")
    return m


def camera_matrices(spec: Mapping[str, Any] | None, aspect: float) -> tuple[np.ndarray, np.ndarray]:
    """``(projection, modelview)`` from a scene's camera object (see SPEC.md)."""
    spec = dict(DEFAULT_CAMERA if spec is None else spec)
    if "projection" in spec or "modelview" in spec:
        extra = set(spec) - {"projection", "modelview"}
        if extra or "projection" not in spec or "modelview" not in spec:
            raise ValueError("camera with matrices needs exactly 'projection' and 'modelview' (4x4, row-major)")
        return _matrix("projection", spec["projection"]), _matrix("modelview", spec["modelview"])
    allowed = {"eye", "target", "up", "fov_deg", "near", "far"}
    extra = set(spec) - allowed
    if extra:
        raise ValueError(
            f"camera: unknown field(s) {', '.join(sorted(extra))}; use projection+modelview or {', '.join(sorted(allowed))}"
        )
    full = dict(DEFAULT_CAMERA)
    full.update(spec)
    try:
        eye = np.asarray(full["eye"], dtype=np.float64).reshape(3)
        target = np.asarray(full["target"], dtype=np.float64).reshape(3)
        up = np.asarray(full["up"], dtype=np.float64).reshape(3)
        fov = float(full["fov_deg"])
    except (TypeError, ValueError):
        raise ValueError("camera eye, target, up must be 3 numbers each and fov_deg a number") from None
    # Default clip planes (scene units) suit an object of about unit radius at the target
    # (the unit sphere, the teapot, a mesh scaled by load_mesh): near halfway to its front
    # (at dist - 1), far well past its back (at dist + 1). Give near/far for other scenes.
    dist = float(np.linalg.norm(eye - target))
    near = float(full.get("near", max(1e-3, dist - 2.0) * 0.5))
    far = float(full.get("far", dist + 4.0))
    return perspective(fov, aspect, near, far), look_at(eye, target, up)
