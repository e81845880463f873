"""The MERL BRDF binary format: reader, writer, lookup and interpolation.

Reference: W. Matusik, H. Pfister, M. Brand, L. McMillan, "A Data-Driven
Reflectance Model", ACM Transactions on Graphics 22(3) (SIGGRAPH 2003), and
the reader ``BRDFRead.cpp`` distributed with the MERL BRDF database.

Layout of a ``.binary`` file (little-endian)::

    int32   dims[3]                       = 90, 90, 180
    float64 R[90][90][180], G[...], B[...]  index order [θh][θd][φd]

Each entry is one bin of the Rusinkiewicz (1998) half/difference angles of an
isotropic BRDF (φh is irrelevant):

=========  =====  ==========================================================
angle      bins   index (MERL's reader; floor, clamped to the last bin)
=========  =====  ==========================================================
θh         90     ``sqrt(θh / (π/2)) · 90`` (square-root mapping: fine bins
                  near the specular peak); θh ≤ 0 → 0
θd         90     ``θd / (π/2) · 90``
φd         180    ``φd / π · 180`` after folding φd into [0, π)
                  (φd ≥ π → φd − π: reciprocity)
=========  =====  ==========================================================

Stored values times the channel scales ``(1, 1.15, 1.66) / 1500`` give f_r in
1/sr; negative values mark missing (unmeasured) bins. :class:`MERLBRDF`
returns 0 there.

The "bin centre" used by :func:`tabulate` / :func:`save_merl` is the middle of
each bin in *index* space: ``θh = ((i + ½)/90)² · π/2``, ``θd = (j + ½)/90 ·
π/2``, ``φd = (k + ½)/180 · π``. Nearest lookup (MERL's own) at a bin centre
returns that bin; trilinear interpolation puts each sample at its bin centre in
index space (θh, θd clamped at the ends, φd periodic with period π) and averages
only the measured corners.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from ..geometry import from_rusinkiewicz, half_vector
from ..models.base import BRDF
from ..params import Param

RES_THETA_H = 90
RES_THETA_D = 90
RES_PHI_D = 180
SHAPE = (RES_THETA_H, RES_THETA_D, RES_PHI_D)
N_BINS = RES_THETA_H * RES_THETA_D * RES_PHI_D
SCALES = np.array([1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0])
_HEADER_BYTES = 12
_FILE_BYTES = _HEADER_BYTES + 3 * N_BINS * 8
MISSING = -1.0  # value written (in file units) for a bin below the horizon / not measured

HALF_PI = np.pi / 2


# --------------------------------------------------------------------------- indices
def theta_h_index(theta_h) -> np.ndarray:
    """MERL's θh bin: ``floor(sqrt(θh/(π/2)) · 90)``, 0 for θh ≤ 0, clamped to 89."""
    th = np.asarray(theta_h, dtype=np.float64)
    u = np.sqrt(np.maximum(th, 0.0) / HALF_PI) * RES_THETA_H
    return np.clip(np.floor(u), 0, RES_THETA_H - 1).astype(np.intp)


def theta_d_index(theta_d) -> np.ndarray:
    """MERL's θd bin: ``floor(θd/(π/2) · 90)`` clamped to [0, 89]."""
    td = np.asarray(theta_d, dtype=np.float64)
    return np.clip(np.floor(td / HALF_PI * RES_THETA_D), 0, RES_THETA_D - 1).astype(np.intp)


def fold_phi_d(phi_d) -> np.ndarray:
    """φd folded into [0, π) (reciprocity: φd and φd + π are the same configuration).

    Values within 1e-9 of π are snapped to 0, so that an in-plane pair and its
    swap (φd = 0 and φd = π up to rounding) fall into the same bin.
    """
    pd = np.mod(np.asarray(phi_d, dtype=np.float64), np.pi)
    return np.where(pd > np.pi - 1e-9, 0.0, pd)


def phi_d_index(phi_d) -> np.ndarray:
    """MERL's φd bin: ``floor(fold(φd)/π · 180)`` clamped to [0, 179]."""
    pd = fold_phi_d(phi_d)
    return np.clip(np.floor(pd / np.pi * RES_PHI_D), 0, RES_PHI_D - 1).astype(np.intp)


def bin_centres() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(θh (90,), θd (90,), φd (180,))`` at the bin centres in index space."""
    th = ((np.arange(RES_THETA_H) + 0.5) / RES_THETA_H) ** 2 * HALF_PI
    td = (np.arange(RES_THETA_D) + 0.5) / RES_THETA_D * HALF_PI
    pd = (np.arange(RES_PHI_D) + 0.5) / RES_PHI_D * np.pi
    return th, td, pd


def symmetric_half_diff(wi, wo) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(θh, θd, φd folded into [0, π))``, bit-for-bit the same for ``(wi, wo)`` and ``(wo, wi)``.

    Mathematically the angles of :func:`brdfkit.geometry.to_rusinkiewicz` (φd
    folded); computed symmetrically so that a pair and its swap always fall into
    the same MERL bin, even on a bin boundary (a table is then exactly reciprocal).
    """
    wi = np.asarray(wi, dtype=np.float64)
    wo = np.asarray(wo, dtype=np.float64)
    h = half_vector(wi, wo)  # built from wi + wo, which is symmetric in the pair
    theta_h = np.arccos(np.clip(h[..., 2], -1.0, 1.0))
    phi_h = np.arctan2(h[..., 1], h[..., 0])
    ch, sh = np.cos(phi_h), np.sin(phi_h)
    ct, st = np.cos(theta_h), np.sin(theta_h)

    def to_h_frame(v):  # rotate by −φh about z, then by −θh about y
        x = ch * v[..., 0] + sh * v[..., 1]
        y = -sh * v[..., 0] + ch * v[..., 1]
        z = v[..., 2]
        return ct * x - st * z, y, st * x + ct * z

    xi, yi, zi = to_h_frame(wi)
    xo, yo, zo = to_h_frame(wo)
    theta_d = np.arccos(np.clip(0.5 * (zi + zo), -1.0, 1.0))
    vx, vy = xi - xo, yi - yo  # 2·(dx, dy); the swap negates it exactly
    flip = (vy < 0) | ((vy == 0) & (vx < 0))
    vx, vy = np.where(flip, -vx, vx), np.where(flip, -vy, vy)
    return theta_h, theta_d, fold_phi_d(np.arctan2(vy, vx))


# --------------------------------------------------------------------------- the model
class MeasuredBRDF(BRDF):
    """Base of tabulated / learned isotropic BRDFs given in Rusinkiewicz angles.

    Subclasses implement ``eval_rusinkiewicz(theta_h, theta_d, phi_d)`` → ``(..., 3)``
    (float64 angles, non-negative values). Not in the analytic-model registry.
    """

    isotropic = True
    measured = True

    def _eval(self, wi, wo, p):
        # φd folded into [0, π) by reciprocity, as MERL stores it; the symmetric
        # computation gives (wi, wo) and (wo, wi) bit-identical angles.
        th, td, pd = symmetric_half_diff(wi, wo)
        return self.eval_rusinkiewicz(th, td, pd)

    def eval_rusinkiewicz(self, theta_h, theta_d, phi_d) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    def with_params(self, **changes: Any) -> "BRDF":
        raise ValueError(f"{self.name}: a measured material has no parameters to change")


class MERLBRDF(MeasuredBRDF):
    """A MERL table as a model: ``eval``, ``check``, ``plot``, ``render`` like any other.

    ``table`` has shape ``(3, 90, 90, 180)`` (RGB, θh, θd, φd) in 1/sr, negative = missing.
    """

    name = "merl"
    title = "tabulated isotropic BRDF in the MERL format (Matusik et al. 2003)"
    reference = "Matusik, Pfister, Brand, McMillan, A Data-Driven Reflectance Model, ACM TOG 22(3), 2003"
    spec = (
        Param(
            "interpolation",
            "choice",
            "nearest",
            doc="table lookup: nearest bin (as MERL's reader) or trilinear in index space",
            choices=("nearest", "trilinear"),
            fit=False,
        ),
    )

    def __init__(self, table, interpolation: str = "nearest", label: str = "merl", source: str = "") -> None:
        table = np.asarray(table, dtype=np.float64)
        if table.shape != (3,) + SHAPE:
            raise ValueError(f"merl: table must have shape (3, 90, 90, 180), got {table.shape}")
        table = np.where(np.isfinite(table), table, -1.0)
        self.table = table
        self.table.setflags(write=False)
        self.label = label
        self.source = source
        super().__init__(interpolation=interpolation)

    def with_params(self, **changes: Any) -> "MERLBRDF":
        new = dict(self.params)
        new.update(changes)
        return MERLBRDF(self.table, label=self.label, source=self.source, **new)

    def __repr__(self) -> str:
        return f"<MERLBRDF {self.label!r} interpolation={self.params['interpolation']!r}>"

    # -- lookup ------------------------------------------------------------------
    def lookup_nearest(self, theta_h, theta_d, phi_d) -> np.ndarray:
        """MERL's lookup: values of the bins (negative where missing), shape ``(..., 3)``."""
        i = theta_h_index(theta_h)
        j = theta_d_index(theta_d)
        k = phi_d_index(phi_d)
        return np.moveaxis(self.table[:, i, j, k], 0, -1)

    def lookup_trilinear(self, theta_h, theta_d, phi_d) -> np.ndarray:
        """Trilinear interpolation in index space over measured corners (0 where none is)."""
        th = np.asarray(theta_h, dtype=np.float64)
        td = np.asarray(theta_d, dtype=np.float64)
        th, td, pd = np.broadcast_arrays(th, td, fold_phi_d(phi_d))
        ch = np.clip(np.sqrt(np.maximum(th, 0.0) / HALF_PI) * RES_THETA_H - 0.5, 0, RES_THETA_H - 1)
        cd = np.clip(td / HALF_PI * RES_THETA_D - 0.5, 0, RES_THETA_D - 1)
        cp = pd / np.pi * RES_PHI_D - 0.5  # periodic
        i0 = np.minimum(np.floor(ch).astype(np.intp), RES_THETA_H - 2)
        j0 = np.minimum(np.floor(cd).astype(np.intp), RES_THETA_D - 2)
        k0f = np.floor(cp)
        fh, fd, fp = ch - i0, cd - j0, cp - k0f
        k0 = np.mod(k0f.astype(np.intp), RES_PHI_D)
        k1 = np.mod(k0 + 1, RES_PHI_D)
        acc = np.zeros(th.shape + (3,))
        wsum = np.zeros(th.shape)
        for di, wi_ in ((0, 1 - fh), (1, fh)):
            for dj, wj_ in ((0, 1 - fd), (1, fd)):
                for kk, wk_ in ((k0, 1 - fp), (k1, fp)):
                    w = wi_ * wj_ * wk_
                    v = np.moveaxis(self.table[:, i0 + di, j0 + dj, kk], 0, -1)
                    ok = (v >= 0).all(axis=-1)
                    w = np.where(ok, w, 0.0)
                    acc += w[..., None] * np.where(ok[..., None], v, 0.0)
                    wsum += w
        return np.where(wsum[..., None] > 1e-12, acc / np.where(wsum > 1e-12, wsum, 1.0)[..., None], 0.0)

    def eval_rusinkiewicz(self, theta_h, theta_d, phi_d) -> np.ndarray:
        if self.params["interpolation"] == "trilinear":
            return self.lookup_trilinear(theta_h, theta_d, phi_d)
        return np.maximum(self.lookup_nearest(theta_h, theta_d, phi_d), 0.0)


# --------------------------------------------------------------------------- tabulation
def tabulate(model: BRDF, chunk: int = 6) -> np.ndarray:
    """Evaluate an isotropic model at every bin centre: ``(3, 90, 90, 180)``, −1 below the horizon."""
    if isinstance(model, MERLBRDF):
        return np.array(model.table)
    if not getattr(model, "isotropic", True):
        raise ValueError(
            f"{getattr(model, 'name', model)}: the MERL format stores isotropic BRDFs only; "
            "give an isotropic model (e.g. equal alpha_x and alpha_y is still anisotropic by class)"
        )
    th, td, pd = bin_centres()
    out = np.empty((3,) + SHAPE)
    for i0 in range(0, RES_THETA_H, chunk):
        TH, TD, PD = np.meshgrid(th[i0 : i0 + chunk], td, pd, indexing="ij")
        wi, wo = from_rusinkiewicz(TH, np.zeros_like(TH), TD, PD)
        valid = (wi[..., 2] > 0) & (wo[..., 2] > 0)  # a quarter of the bins lie below the horizon
        f = np.broadcast_to(MISSING * SCALES, valid.shape + (3,)).copy()
        f[valid] = np.maximum(np.asarray(model.eval(wi[valid], wo[valid]), dtype=np.float64), 0.0)
        out[:, i0 : i0 + chunk] = np.moveaxis(f, -1, 0)
    return out


def table_rgba(model: BRDF) -> np.ndarray:
    """The table as float32 texels ``(90, 90, 180, 4)`` = [θh][θd][φd][rgba], OpenGL's
    (depth, height, width, components): rgb = each channel clamped at 0 (as :meth:`MERLBRDF.eval`
    does), alpha = 1 where every channel was measured, else 0 (trilinear lookups skip those)."""
    t = tabulate(model)  # (3, 90, 90, 180), negative = missing
    out = np.empty(t.shape[1:] + (4,), dtype=np.float32)
    out[..., :3] = np.moveaxis(np.maximum(t, 0.0), 0, -1)
    out[..., 3] = (t >= 0).all(axis=0)
    return out


def texture3d(model: BRDF) -> np.ndarray:
    """The table as a float32 RGB 3D texture, shape ``(90, 90, 180, 3)``, missing bins 0.

    numpy order [θh][θd][φd][rgb] is OpenGL's (depth, height, width, components):
    upload with ``ctx.texture3d((180, 90, 90), 3, data, dtype="f4")`` and look up
    with ``texcoord = (φd_folded/π, θd/(π/2), sqrt(θh/(π/2)))`` — bin centres at
    ``(k+½)/180``, ``(j+½)/90``, ``(i+½)/90`` — nearest or linear filtering
    (φd repeats, θh and θd clamp to edge).
    """
    rgba = table_rgba(model)
    return np.ascontiguousarray(rgba[..., :3] * rgba[..., 3:])


# --------------------------------------------------------------------------- file I/O
def read_merl_table(path: str | os.PathLike) -> np.ndarray:
    """The ``(3, 90, 90, 180)`` table of a MERL file in 1/sr (scales applied; negative = missing)."""
    path = os.fspath(path)
    size = os.path.getsize(path)  # OSError if it does not exist
    if os.path.isdir(path):
        raise ValueError(f"{path}: is a directory, not a MERL .binary file")
    if size == 0:
        raise ValueError(f"{path}: empty file, not a MERL .binary file")
    if size < _HEADER_BYTES:
        raise ValueError(f"{path}: {size} bytes, too short for the 12-byte MERL header")
    with open(path, "rb") as fh:
        head = fh.read(_HEADER_BYTES)
        dims = tuple(int(d) for d in np.frombuffer(head, dtype="<i4", count=3))
        if dims != SHAPE:
            raise ValueError(
                f"{path}: header says dimensions {dims[0]}x{dims[1]}x{dims[2]}, a MERL .binary file has 90x90x180 "
                "(is it a MERL file?)"
            )
        if size != _FILE_BYTES:
            what = "truncated" if size < _FILE_BYTES else "has trailing data"
            raise ValueError(
                f"{path}: {what}: {size} bytes, a 90x90x180 MERL file has exactly {_FILE_BYTES} bytes"
            )
        data = np.frombuffer(fh.read(), dtype="<f8")
    table = data.reshape((3,) + SHAPE).astype(np.float64) * SCALES[:, None, None, None]
    table = np.where(np.isfinite(table), table, -1.0)
    if not (table >= 0).any():
        raise ValueError(f"{path}: every bin is negative (missing); not usable MERL data")
    return table


def load_merl(path: str | os.PathLike, interpolation: str = "nearest") -> MERLBRDF:
    """Read a MERL ``.binary`` file as a model (``eval``, ``check``, ``plot``, ``render``, ``fit``).

    Malformed files (empty, truncated, wrong dimensions, text) raise a one-line ``ValueError``.
    """
    table = read_merl_table(path)
    label = os.path.basename(os.fspath(path))
    for ext in (".binary", ".bin"):
        if label.endswith(ext):
            label = label[: -len(ext)]
    return MERLBRDF(table, interpolation=interpolation, label=label, source=os.fspath(path))


def write_merl_table(table, path: str | os.PathLike) -> None:
    """Write a ``(3, 90, 90, 180)`` table in 1/sr (negative = missing) as a MERL file."""
    table = np.asarray(table, dtype=np.float64)
    if table.shape != (3,) + SHAPE:
        raise ValueError(f"MERL table must have shape (3, 90, 90, 180), got {table.shape}")
    raw = table / SCALES[:, None, None, None]
    raw = np.where(np.isfinite(raw) & (table >= 0), raw, MISSING)
    from ..fileio import atomic_open

    with atomic_open(path, "wb") as fh:  # temp file + os.replace: a killed write keeps the old file
        fh.write(np.asarray(SHAPE, dtype="<i4").tobytes())
        fh.write(np.ascontiguousarray(raw, dtype="<f8").tobytes())


def save_merl(model: BRDF, path: str | os.PathLike) -> None:
    """Tabulate an isotropic model at the bin centres and write it as a MERL ``.binary`` file.

    The path is checked before the tabulation (a missing folder, a folder given as the file:
    a one-line ``ValueError`` at once), and the file is written atomically.
    """
    from ..fileio import check_output_path

    check_output_path(path, what="MERL file")
    write_merl_table(tabulate(model), path)


__all__ = [
    "MeasuredBRDF",
    "MERLBRDF",
    "table_rgba",
    "load_merl",
    "save_merl",
    "tabulate",
    "texture3d",
    "read_merl_table",
    "write_merl_table",
    "bin_centres",
    "theta_h_index",
    "theta_d_index",
    "phi_d_index",
    "SCALES",
    "SHAPE",
]
