"""Mesa's own fixed-function OpenGL, as an independent reference (run as a subprocess).

PyOpenGL picks its platform at import time, so this script runs in its own
process with ``PYOPENGL_PLATFORM=osmesa`` (Debian's ``libosmesa6``), away from
the EGL context the test process uses. It reads one JSON request on stdin and
prints one JSON answer on stdout.

Requests
--------
``{"mode": "shade", "cases": [case, ...]}``
    each case: ``material``, ``lights`` (list), ``light_model`` (objects with
    the ``brdfkit.opengl`` field names, colours RGBA), ``positions`` and
    ``normals`` (eye space, N×3). Every vertex is sent as a ``GL_POINTS``
    vertex in ``GL_FEEDBACK`` mode with ``GL_3D_COLOR``: the feedback buffer
    returns the colour that Mesa's fixed-function lighting computed for it.
    The projection maps every vertex to the centre of the view volume, so
    nothing is clipped. Answer: ``{"colors": [[[r, g, b, a], ...], ...]}``.

``{"mode": "render", ...}``
    ``width``, ``height``, ``projection`` and ``modelview`` (4×4 row-major),
    ``positions``/``normals`` (object space, V×3), ``faces`` (F×3),
    ``material``, ``lights``, ``light_model``, ``shade_model``
    (``"smooth"`` | ``"flat"``), ``background`` RGBA, ``out`` (a .npy path).
    Draws the triangles with legacy ``glBegin(GL_TRIANGLES)``, ``GL_NORMALIZE``
    and the depth test, and saves the RGBA8 framebuffer (top row first) to
    ``out``. Answer: ``{"renderer": ...}``.

Nothing here imports brdfkit: the reference owes nothing to the code it checks.
"""

from __future__ import annotations

import ctypes
import dataclasses
import json
import os
import sys

import ctypes.util
import subprocess
from pathlib import Path

import numpy as np

# Bound by _load_gl() in the subprocess only: the test process never imports PyOpenGL.
gl = osmesa = raw = None  # type: ignore[assignment]


def _load_gl() -> None:
    global gl, osmesa, raw
    os.environ["PYOPENGL_PLATFORM"] = "osmesa"
    from OpenGL import GL as _gl
    from OpenGL import osmesa as _osmesa
    from OpenGL.raw.GL.VERSION import GL_1_0 as _raw

    gl, osmesa, raw = _gl, _osmesa, _raw

_LIGHT_DEFAULTS = {
    "position": [0.0, 0.0, 1.0, 0.0],
    "ambient": [0.0, 0.0, 0.0, 1.0],
    "diffuse": [1.0, 1.0, 1.0, 1.0],
    "specular": [1.0, 1.0, 1.0, 1.0],
    "constant_attenuation": 1.0,
    "linear_attenuation": 0.0,
    "quadratic_attenuation": 0.0,
    "spot_direction": [0.0, 0.0, -1.0],
    "spot_exponent": 0.0,
    "spot_cutoff": 180.0,
}


def _f4(v):
    return (ctypes.c_float * len(v))(*[float(x) for x in v])


def _context(w: int, h: int):
    ctx = osmesa.OSMesaCreateContextExt(osmesa.OSMESA_RGBA, 24, 0, 0, None)
    if not ctx:
        raise SystemExit("OSMesaCreateContextExt failed")
    buf = (ctypes.c_ubyte * (w * h * 4))()
    if not osmesa.OSMesaMakeCurrent(ctx, buf, gl.GL_UNSIGNED_BYTE, w, h):
        raise SystemExit("OSMesaMakeCurrent failed")
    return ctx, buf


def _setup_lighting(req) -> None:
    """Material, light model and lights; lights are given in eye space (identity modelview)."""
    gl.glMatrixMode(gl.GL_MODELVIEW)
    gl.glLoadIdentity()
    gl.glEnable(gl.GL_LIGHTING)
    gl.glEnable(gl.GL_NORMALIZE)
    m = req["material"]
    face = gl.GL_FRONT_AND_BACK
    gl.glMaterialfv(face, gl.GL_AMBIENT, _f4(m["ambient"]))
    gl.glMaterialfv(face, gl.GL_DIFFUSE, _f4(m["diffuse"]))
    gl.glMaterialfv(face, gl.GL_SPECULAR, _f4(m["specular"]))
    gl.glMaterialfv(face, gl.GL_EMISSION, _f4(m["emission"]))
    gl.glMaterialf(face, gl.GL_SHININESS, float(m["shininess"]))
    lm = req["light_model"]
    gl.glLightModelfv(gl.GL_LIGHT_MODEL_AMBIENT, _f4(lm["ambient"]))
    gl.glLightModeli(gl.GL_LIGHT_MODEL_LOCAL_VIEWER, 1 if lm["local_viewer"] else 0)
    gl.glLightModeli(gl.GL_LIGHT_MODEL_TWO_SIDE, 0)
    for i in range(8):
        gl.glDisable(gl.GL_LIGHT0 + i)
    for i, given in enumerate(req["lights"]):
        L = dict(_LIGHT_DEFAULTS)
        L.update(given)
        li = gl.GL_LIGHT0 + i
        gl.glEnable(li)
        gl.glLightfv(li, gl.GL_POSITION, _f4(L["position"]))
        gl.glLightfv(li, gl.GL_AMBIENT, _f4(L["ambient"]))
        gl.glLightfv(li, gl.GL_DIFFUSE, _f4(L["diffuse"]))
        gl.glLightfv(li, gl.GL_SPECULAR, _f4(L["specular"]))
        gl.glLightf(li, gl.GL_CONSTANT_ATTENUATION, float(L["constant_attenuation"]))
        gl.glLightf(li, gl.GL_LINEAR_ATTENUATION, float(L["linear_attenuation"]))
        gl.glLightf(li, gl.GL_QUADRATIC_ATTENUATION, float(L["quadratic_attenuation"]))
        gl.glLightfv(li, gl.GL_SPOT_DIRECTION, _f4(L["spot_direction"]))
        gl.glLightf(li, gl.GL_SPOT_EXPONENT, float(L["spot_exponent"]))
        gl.glLightf(li, gl.GL_SPOT_CUTOFF, float(L["spot_cutoff"]))


def shade(req) -> dict:
    _ctx, _buf = _context(16, 16)
    out = []
    for case in req["cases"]:
        _setup_lighting(case)
        gl.glMatrixMode(gl.GL_PROJECTION)
        # Every vertex lands at clip (0, 0, 0, 1): inside the view volume, never clipped.
        gl.glLoadMatrixf(_f4([0] * 15 + [1]))
        gl.glMatrixMode(gl.GL_MODELVIEW)
        gl.glLoadIdentity()
        pos = case["positions"]
        nrm = case["normals"]
        size = 8 * len(pos) + 16
        fb = (ctypes.c_float * size)()
        raw.glFeedbackBuffer(size, gl.GL_3D_COLOR, fb)
        raw.glRenderMode(gl.GL_FEEDBACK)
        gl.glBegin(gl.GL_POINTS)
        for p, n in zip(pos, nrm):
            gl.glNormal3f(*[float(x) for x in n])
            gl.glVertex3f(*[float(x) for x in p])
        gl.glEnd()
        count = raw.glRenderMode(gl.GL_RENDER)
        vals = list(fb[:count])
        cols = []
        i = 0
        while i < len(vals):
            tok = int(vals[i])
            if tok != int(gl.GL_POINT_TOKEN):
                raise SystemExit(f"unexpected feedback token {tok}")
            cols.append(vals[i + 4 : i + 8])
            i += 8
        if len(cols) != len(pos):
            raise SystemExit(f"feedback returned {len(cols)} vertices for {len(pos)}")
        out.append(cols)
    return {"colors": out, "renderer": gl.glGetString(gl.GL_RENDERER).decode()}


def render(req) -> dict:
    w, h = int(req["width"]), int(req["height"])
    _ctx, buf = _context(w, h)
    gl.glViewport(0, 0, w, h)
    _setup_lighting(req)
    gl.glShadeModel(gl.GL_SMOOTH if req["shade_model"] == "smooth" else gl.GL_FLAT)
    gl.glEnable(gl.GL_DEPTH_TEST)
    gl.glDepthFunc(gl.GL_LESS)
    gl.glDisable(gl.GL_CULL_FACE)
    gl.glDisable(gl.GL_DITHER)
    bg = req["background"]
    gl.glClearColor(*[float(x) for x in bg])
    gl.glClear(gl.GL_COLOR_BUFFER_BIT | gl.GL_DEPTH_BUFFER_BIT)
    gl.glMatrixMode(gl.GL_PROJECTION)
    gl.glLoadMatrixf(_f4(np.asarray(req["projection"], dtype=np.float64).T.reshape(-1)))
    gl.glMatrixMode(gl.GL_MODELVIEW)
    gl.glLoadMatrixf(_f4(np.asarray(req["modelview"], dtype=np.float64).T.reshape(-1)))
    P = req["positions"]
    N = req["normals"]
    gl.glBegin(gl.GL_TRIANGLES)
    for tri in req["faces"]:
        for v in tri:
            gl.glNormal3f(*[float(x) for x in N[v]])
            gl.glVertex3f(*[float(x) for x in P[v]])
    gl.glEnd()
    gl.glFinish()
    img = np.frombuffer(bytes(buf), dtype=np.uint8).reshape(h, w, 4)[::-1].copy()
    np.save(req["out"], img)
    return {"renderer": gl.glGetString(gl.GL_RENDERER).decode()}


# --------------------------------------------------------------------------- client side (test process)
SCRIPT = Path(__file__).resolve()


def osmesa_available() -> bool:
    return ctypes.util.find_library("OSMesa") is not None


def call(request: dict, timeout: float = 120.0, llvm: bool = True) -> dict:
    """Run the reference script with ``request`` on stdin; return its JSON answer.

    ``llvm=False`` sets ``DRAW_USE_LLVM=0``: Mesa's draw module then runs the
    same fixed-function vertex program through its interpreter instead of
    compiling it with LLVM for every new lighting state (much faster for many
    small cases).
    """
    if not osmesa_available():
        import pytest

        pytest.skip("libOSMesa not installed (apt-get install libosmesa6)")
    env = dict(os.environ)
    env["PYOPENGL_PLATFORM"] = "osmesa"
    if not llvm:
        env["DRAW_USE_LLVM"] = "0"
    proc = subprocess.run(
        [sys.executable, str(SCRIPT)],
        input=json.dumps(request),
        capture_output=True,
        text=True,
        env=env,
        timeout=timeout,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"Mesa reference failed ({proc.returncode}): {proc.stderr.strip()[-2000:]}")
    return json.loads(proc.stdout)


def as_json(obj) -> dict:
    """A ``brdfkit.opengl`` Material, Light or LightModel as a request object (its field names)."""
    return dataclasses.asdict(obj)


# --------------------------------------------------------------------------- entry point (subprocess)
def main() -> None:
    _load_gl()
    req = json.load(sys.stdin)
    mode = req.get("mode")
    if mode == "shade":
        ans = shade(req)
    elif mode == "render":
        ans = render(req)
    else:
        raise SystemExit(f"unknown mode {mode!r}")
    json.dump(ans, sys.stdout)


if __name__ == "__main__":
    main()
