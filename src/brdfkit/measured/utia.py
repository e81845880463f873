"""The UTIA anisotropic BRDF database ``.bin`` format: reader, writer, interpolation.

Reference: J. Filip, R. Vávra, "Template-Based Sampling of Anisotropic BRDFs",
Computer Graphics Forum 33(7) (Pacific Graphics 2014), and the loader published
with the database (http://btf.utia.cas.cz/, J. Filip's ``TBDRF`` C++ reader and
its Python port by A. Sztrajman) -- read for the layout and interpolation only.

Layout of a ``.bin`` file: no header, ``3·6·48·6·48`` little-endian float64
(1 990 656 bytes), C order::

    float64 data[channel=3][θi=6][φi=48][θv=6][φv=48]

=========  =====  ============================================================
axis       count  grid
=========  =====  ============================================================
channel    3      R, G, B
θi, θv     6      0°, 15°, …, 75°  (step 15°)
φi, φv     48     0°, 7.5°, …, 352.5° (step 7.5°), periodic in 360°
=========  =====  ============================================================

Values are used as stored (no scale factor is applied by the reference loader);
brdfkit treats them as f_r in 1/sr without the cosine factor, like every
brdfkit model.

Interpolation (as the reference loader): quadrilinear in (θi, φi, θv, φv)
degrees, φ periodic (the corner after 352.5° is 0°).  Above the last θ sample
(75° < θ ≤ 90°) the reference keeps the last two θ samples (60°, 75°) and so
extrapolates linearly; brdfkit does the same and clamps the result at 0
(linear extrapolation can go negative).  Below the horizon (θ > 90°, i.e.
cos θ ≤ 0) the value is 0, as in the reference.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from ..models.base import BRDF
from ..params import Param

N_CHANNELS = 3
N_THETA = 6
N_PHI = 48
STEP_THETA_DEG = 15.0
STEP_PHI_DEG = 7.5
SHAPE = (N_CHANNELS, N_THETA, N_PHI, N_THETA, N_PHI)
FILE_BYTES = int(np.prod(SHAPE)) * 8


def grid_angles() -> tuple[np.ndarray, np.ndarray]:
    """``(θ (6,), φ (48,))`` of the UTIA grid in radians."""
    th = np.deg2rad(np.arange(N_THETA) * STEP_THETA_DEG)
    ph = np.deg2rad(np.arange(N_PHI) * STEP_PHI_DEG)
    return th, ph


def _snap(u: np.ndarray) -> np.ndarray:
    """Grid coordinates within 1e-9 of an integer snapped to it (radian→degree rounding), so grid points are exact."""
    r = np.round(u)
    return np.where(np.abs(u - r) < 1e-9, r, u)


def _theta_corners(theta_deg: np.ndarray):
    """Lower index (clamped to 0..4) and weight of the upper one (may exceed 1: extrapolation above 75°)."""
    u = _snap(theta_deg / STEP_THETA_DEG)
    i0 = np.clip(np.floor(u), 0, N_THETA - 2).astype(np.intp)
    w1 = u - i0
    return i0, w1


def _phi_corners(phi_deg: np.ndarray):
    """Lower index in 0..47, upper index (periodic), weight of the upper one in [0, 1)."""
    u = _snap(np.mod(phi_deg, 360.0) / STEP_PHI_DEG)
    i0 = np.floor(u).astype(np.intp)
    w1 = u - i0
    i0 = np.mod(i0, N_PHI)  # u rounded to exactly 48.0
    return i0, np.mod(i0 + 1, N_PHI), w1


def utia_lookup(table: np.ndarray, theta_i, phi_i, theta_v, phi_v) -> np.ndarray:
    """Quadrilinear lookup in a ``(3, 6, 48, 6, 48)`` table; angles in radians, returns ``(..., 3)``.

    Zero where either θ > 90°; linear extrapolation above 75° clamped at 0.
    """
    ti, pi_, tv, pv = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (theta_i, phi_i, theta_v, phi_v)))
    shape = ti.shape
    ti, pi_, tv, pv = (np.degrees(x.ravel()) for x in (ti, pi_, tv, pv))
    a0, wa = _theta_corners(ti)
    c0, wc = _theta_corners(tv)
    b0, b1, wb = _phi_corners(pi_)
    d0, d1, wd = _phi_corners(pv)
    out = np.zeros((ti.size, N_CHANNELS))
    for a, fa in ((a0, 1.0 - wa), (a0 + 1, wa)):
        for b, fb in ((b0, 1.0 - wb), (b1, wb)):
            for c, fc in ((c0, 1.0 - wc), (c0 + 1, wc)):
                for d, fd in ((d0, 1.0 - wd), (d1, wd)):
                    w = fa * fb * fc * fd
                    out += table[:, a, b, c, d].T * w[:, None]
    out = np.maximum(out, 0.0)
    below = (ti > 90.0) | (tv > 90.0)
    out[below] = 0.0
    return out.reshape(shape + (N_CHANNELS,))


def _spherical(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    z = np.clip(w[..., 2] / np.linalg.norm(w, axis=-1), -1.0, 1.0)
    return np.arccos(z), np.arctan2(w[..., 1], w[..., 0])


class UTIABRDF(BRDF):
    """A UTIA table as an anisotropic measured model: ``eval``, ``check``, ``plot``, ``render``, ``fit``.

    ``table`` has shape ``(3, 6, 48, 6, 48)`` (RGB, θi, φi, θv, φv) in 1/sr.
    φ is measured from the local x (tangent) axis.
    """

    name = "utia"
    title = "tabulated anisotropic BRDF in the UTIA format (Filip & Vávra 2014)"
    reference = "Filip, Vávra, Template-Based Sampling of Anisotropic BRDFs, Computer Graphics Forum 33(7), 2014"
    isotropic = False
    measured = True
    kernel_float32 = False
    spec = (
        Param(
            "interpolation",
            "choice",
            "quadrilinear",
            doc="table lookup: quadrilinear in (θi, φi, θv, φv), φ periodic (as the UTIA loader)",
            choices=("quadrilinear",),
            fit=False,
        ),
    )

    def __init__(self, table, interpolation: str = "quadrilinear", label: str = "utia", source: str = "") -> None:
        table = np.asarray(table, dtype=np.float64)
        if table.shape != SHAPE:
            raise ValueError(f"utia: table must have shape {SHAPE}, got {table.shape}")
        if not np.isfinite(table).all() or (table < 0).any():
            raise ValueError("utia: table has NaN, infinite or negative values")
        self.table = np.ascontiguousarray(table)
        self.table.setflags(write=False)
        self.label = label
        self.source = source
        super().__init__(interpolation=interpolation)

    def __repr__(self) -> str:
        return f"<UTIABRDF {self.label!r}>"

    def with_params(self, **changes: Any) -> "BRDF":
        raise ValueError(f"{self.name}: a measured material has no parameters to change")

    def eval_angles(self, theta_i, phi_i, theta_v, phi_v) -> np.ndarray:
        """f_r ``(..., 3)`` at spherical angles (radians)."""
        return utia_lookup(self.table, theta_i, phi_i, theta_v, phi_v)

    def _eval(self, wi, wo, p):
        wi = np.asarray(wi, dtype=np.float64)
        wo = np.asarray(wo, dtype=np.float64)
        wi, wo = np.broadcast_arrays(wi, wo)
        ti, pi_ = _spherical(wi)
        tv, pv = _spherical(wo)
        return utia_lookup(self.table, ti, pi_, tv, pv)


def read_utia_table(path: str | os.PathLike) -> np.ndarray:
    """The ``(3, 6, 48, 6, 48)`` table of a UTIA ``.bin`` file; malformed files raise a one-line ``ValueError``."""
    path = os.fspath(path)
    if os.path.isdir(path):
        raise ValueError(f"{path}: is a directory, not a UTIA .bin file")
    size = os.path.getsize(path)  # OSError if missing
    if size != FILE_BYTES:
        what = "empty" if size == 0 else ("truncated" if size < FILE_BYTES else "has trailing data")
        raise ValueError(f"{path}: {what}: {size} bytes, a UTIA .bin file has exactly {FILE_BYTES} bytes")
    with open(path, "rb") as fh:
        data = np.frombuffer(fh.read(), dtype="<f8")
    if not np.isfinite(data).all():
        raise ValueError(f"{path}: UTIA data has NaN or infinite values")
    if (data < 0).any():
        raise ValueError(f"{path}: UTIA data has negative values")
    return data.reshape(SHAPE).astype(np.float64)


def load_utia(path: str | os.PathLike) -> UTIABRDF:
    """Read a UTIA ``.bin`` file as a model."""
    table = read_utia_table(path)
    label = os.path.basename(os.fspath(path))
    if label.endswith(".bin"):
        label = label[:-4]
    return UTIABRDF(table, label=label, source=os.fspath(path))


def tabulate_utia(model: BRDF) -> np.ndarray:
    """Sample ``model`` (f_r, RGB or grey broadcast to RGB) at the UTIA grid: a ``(3, 6, 48, 6, 48)`` table."""
    th, ph = grid_angles()
    TI, PI, TV, PV = np.meshgrid(th, ph, th, ph, indexing="ij")

    def vec(t, p):
        return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)

    f = np.asarray(model.eval(vec(TI, PI), vec(TV, PV)), dtype=np.float64)
    if f.shape == TI.shape:
        f = np.repeat(f[..., None], 3, axis=-1)
    return np.moveaxis(np.maximum(f, 0.0), -1, 0).copy()


def write_utia_table(table, path: str | os.PathLike) -> None:
    """Write a ``(3, 6, 48, 6, 48)`` table as a UTIA ``.bin`` file (atomically)."""
    table = np.asarray(table, dtype=np.float64)
    if table.shape != SHAPE:
        raise ValueError(f"UTIA table must have shape {SHAPE}, got {table.shape}")
    from ..fileio import atomic_open

    with atomic_open(path, "wb") as fh:
        fh.write(np.ascontiguousarray(table, dtype="<f8").tobytes())
