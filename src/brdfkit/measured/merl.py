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

import math

import numpy as np

from ..engine import jit, vectorize
from ..geometry import from_rusinkiewicz, half_vector, half_vector_c
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
@jit
def theta_h_bin(theta_h):
    """MERL's θh bin: ``floor(sqrt(θh/(π/2)) · 90)``, 0 for θh ≤ 0, clamped to 89 (an int)."""
    u = math.sqrt(max(theta_h, 0.0) / (0.5 * math.pi)) * RES_THETA_H
    return int(min(max(math.floor(u), 0.0), RES_THETA_H - 1.0))


@jit
def theta_d_bin(theta_d):
    """MERL's θd bin: ``floor(θd/(π/2) · 90)`` clamped to [0, 89]."""
    return int(min(max(math.floor(theta_d / (0.5 * math.pi) * RES_THETA_D), 0.0), RES_THETA_D - 1.0))


@jit
def fold_phi(phi_d):
    """φd folded into [0, π) (reciprocity: φd and φd + π are the same configuration).

    Values within 1e-9 of π are snapped to 0, so that an in-plane pair and its
    swap (φd = 0 and φd = π up to rounding) fall into the same bin.
    """
    pd = phi_d % math.pi
    if pd > math.pi - 1e-9:
        return 0.0
    return pd


@jit
def phi_d_bin(phi_d):
    """MERL's φd bin: ``floor(fold(φd)/π · 180)`` clamped to [0, 179]."""
    return int(min(max(math.floor(fold_phi(phi_d) / math.pi * RES_PHI_D), 0.0), RES_PHI_D - 1.0))


# array forms over the same scalar sources, compiled lazily on first use (nothing at import)
_fold_v = vectorize(fold_phi, 1)
_th_v = vectorize(theta_h_bin, 1)
_td_v = vectorize(theta_d_bin, 1)
_pd_v = vectorize(phi_d_bin, 1)


def theta_h_index(theta_h) -> np.ndarray:
    """Array form of :func:`theta_h_bin`."""
    return _th_v(np.asarray(theta_h, dtype=np.float64)).astype(np.intp)


def theta_d_index(theta_d) -> np.ndarray:
    """Array form of :func:`theta_d_bin`."""
    return _td_v(np.asarray(theta_d, dtype=np.float64)).astype(np.intp)


def fold_phi_d(phi_d) -> np.ndarray:
    """Array form of :func:`fold_phi`."""
    return _fold_v(np.asarray(phi_d, dtype=np.float64))


def phi_d_index(phi_d) -> np.ndarray:
    """Array form of :func:`phi_d_bin`."""
    return _pd_v(np.asarray(phi_d, dtype=np.float64)).astype(np.intp)


def bin_centres() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(θh (90,), θd (90,), φd (180,))`` at the bin centres in index space."""
    th = ((np.arange(RES_THETA_H) + 0.5) / RES_THETA_H) ** 2 * HALF_PI
    td = (np.arange(RES_THETA_D) + 0.5) / RES_THETA_D * HALF_PI
    pd = (np.arange(RES_PHI_D) + 0.5) / RES_PHI_D * np.pi
    return th, td, pd


def symmetric_half_diff(wi, wo) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(θh, θd, φd folded into [0, π))``, bit-for-bit the same for ``(wi, wo)`` and ``(wo, wi)``.

    Mathematically the angles of :func:`brdfkit.geometry.to_rusinkiewicz` (φd
    folded); computed symmetrically (:func:`symmetric_half_diff_c`, the scalar source)
    so that a pair and its swap always fall into the same MERL bin, even on a bin
    boundary (a table is then exactly reciprocal).
    """
    wi = np.asarray(wi, dtype=np.float64)
    wo = np.asarray(wo, dtype=np.float64)
    wi, wo = np.broadcast_arrays(wi, wo)
    shape = wi.shape[:-1]
    out = np.empty((3, int(np.prod(shape, dtype=np.int64))))
    _half_diff_many(np.ascontiguousarray(wi).reshape(-1, 3), np.ascontiguousarray(wo).reshape(-1, 3), out)
    return out[0].reshape(shape), out[1].reshape(shape), out[2].reshape(shape)


@jit
def symmetric_half_diff_c(ix, iy, iz, ox, oy, oz):
    """The scalar form of :func:`symmetric_half_diff`: ``(θh, θd, φd folded)`` of one pair.

    Built from ``wi + wo`` and the difference of the two directions in the half-vector
    frame, so ``(wi, wo)`` and ``(wo, wi)`` give bit-identical angles.
    """
    hx, hy, hz = half_vector_c(ix, iy, iz, ox, oy, oz)
    # cos/sin of φh and θh straight from h (no atan2/cos/sin round trip); φh = 0 at h = n
    st = math.sqrt(hx * hx + hy * hy)
    ct = hz
    # θh = atan2(sin, cos), not acos(h_z): acos loses half the digits near the normal (an ulp of
    # h_z moves θh by ~1e-8 there), where the specular peaks of measured materials lie
    theta_h = math.atan2(st, ct)
    if st > 0.0:
        ch = hx / st
        sh = hy / st
    else:
        ch = 1.0
        sh = 0.0
    # rotate by −φh about z, then by −θh about y
    xa = ch * ix + sh * iy
    yi = -sh * ix + ch * iy
    xi = ct * xa - st * iz
    zi = st * xa + ct * iz
    xb = ch * ox + sh * oy
    yo = -sh * ox + ch * oy
    xo = ct * xb - st * oz
    zo = st * xb + ct * oz
    theta_d = math.acos(min(max(0.5 * (zi + zo), -1.0), 1.0))
    vx = xi - xo  # 2·(dx, dy); the swap negates it exactly
    vy = yi - yo
    if vy < 0.0 or (vy == 0.0 and vx < 0.0):
        vx = -vx
        vy = -vy
    return theta_h, theta_d, fold_phi(math.atan2(vy, vx))


@jit
def merl_nearest(table, theta_h, theta_d, phi_d):
    """MERL's lookup (its reader's bins) in a flat ``(3·90·90·180,)`` table, missing bins as 0."""
    q = (theta_h_bin(theta_h) * RES_THETA_D + theta_d_bin(theta_d)) * RES_PHI_D + phi_d_bin(phi_d)
    return max(table[q], 0.0), max(table[N_BINS + q], 0.0), max(table[2 * N_BINS + q], 0.0)


@jit
def merl_trilinear(table, theta_h, theta_d, phi_d):
    """Trilinear interpolation in index space over the measured corners (0 where none is).

    Samples sit at their bin centres in index space: θh and θd clamped at the ends, φd
    periodic with period π; a corner counts only where all three channels were measured.
    """
    ch = min(max(math.sqrt(max(theta_h, 0.0) / (0.5 * math.pi)) * RES_THETA_H - 0.5, 0.0), RES_THETA_H - 1.0)
    cd = min(max(theta_d / (0.5 * math.pi) * RES_THETA_D - 0.5, 0.0), RES_THETA_D - 1.0)
    cp = fold_phi(phi_d) / math.pi * RES_PHI_D - 0.5
    i0 = min(int(math.floor(ch)), RES_THETA_H - 2)
    j0 = min(int(math.floor(cd)), RES_THETA_D - 2)
    k0f = math.floor(cp)
    fh = ch - i0
    fd = cd - j0
    fp = cp - k0f
    k0 = int(k0f) % RES_PHI_D
    k1 = (k0 + 1) % RES_PHI_D
    a0 = 0.0
    a1 = 0.0
    a2 = 0.0
    wsum = 0.0
    for di in range(2):
        wi_ = fh if di == 1 else 1.0 - fh
        for dj in range(2):
            wj_ = fd if dj == 1 else 1.0 - fd
            for dk in range(2):
                wk_ = fp if dk == 1 else 1.0 - fp
                kk = k1 if dk == 1 else k0
                q = ((i0 + di) * RES_THETA_D + (j0 + dj)) * RES_PHI_D + kk
                v0 = table[q]
                v1 = table[N_BINS + q]
                v2 = table[2 * N_BINS + q]
                if v0 >= 0.0 and v1 >= 0.0 and v2 >= 0.0:
                    w = wi_ * wj_ * wk_
                    a0 += w * v0
                    a1 += w * v1
                    a2 += w * v2
                    wsum += w
    if wsum > 1e-12:
        return a0 / wsum, a1 / wsum, a2 / wsum
    return 0.0, 0.0, 0.0


@jit
def merl_kernel(wix, wiy, wiz, wox, woy, woz, p, c):
    """A MERL table per pair (engine protocol, :mod:`brdfkit.engine`).

    ``p`` = the flat ``(3, 90, 90, 180)`` table in 1/sr (negative = missing); ``c`` = [interpolation
    (0 nearest, 1 trilinear)].
    """
    th, td, pd = symmetric_half_diff_c(wix, wiy, wiz, wox, woy, woz)
    if c[0] == 1:
        return merl_trilinear(p, th, td, pd)
    return merl_nearest(p, th, td, pd)


@jit
def _half_diff_many(wi, wo, out):
    for j in range(wi.shape[0]):
        a, b, c = symmetric_half_diff_c(wi[j, 0], wi[j, 1], wi[j, 2], wo[j, 0], wo[j, 1], wo[j, 2])
        out[0, j] = a
        out[1, j] = b
        out[2, j] = c


@jit
def _lookup_many(table, th, td, pd, trilinear, out):
    for j in range(th.shape[0]):
        if trilinear:
            r, g, b = merl_trilinear(table, th[j], td[j], pd[j])
        else:
            r, g, b = merl_nearest(table, th[j], td[j], pd[j])
        out[j, 0] = r
        out[j, 1] = g
        out[j, 2] = b


# --------------------------------------------------------------------------- the model
class MeasuredBRDF(BRDF):
    """Base of tabulated / learned isotropic BRDFs given in Rusinkiewicz angles.

    Subclasses implement ``eval_rusinkiewicz(theta_h, theta_d, phi_d)`` → ``(..., 3)``
    (float64 angles, non-negative values). Not in the analytic-model registry.
    """

    isotropic = True
    measured = True
    #: tables and networks keep float64 computation also for float32 input (engine/precision.py is for analytic kernels)
    kernel_float32 = False

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
    kernel = staticmethod(merl_kernel)

    def kernel_args(self):
        key = "_kernel_args"
        if key not in self._cache:
            c = np.array([self.spec[0].choices.index(self.params["interpolation"])], dtype=np.int64)
            self._cache[key] = (np.ascontiguousarray(self.table, dtype=np.float64).reshape(-1), c)
        return self._cache[key]

    def lookup_nearest(self, theta_h, theta_d, phi_d) -> np.ndarray:
        """MERL's lookup: values of the bins (negative where missing), shape ``(..., 3)``."""
        i = theta_h_index(theta_h)
        j = theta_d_index(theta_d)
        k = phi_d_index(phi_d)
        return np.moveaxis(self.table[:, i, j, k], 0, -1)

    def _lookup(self, theta_h, theta_d, phi_d, trilinear: bool) -> np.ndarray:
        th, td, pd = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (theta_h, theta_d, phi_d)))
        shape = th.shape
        out = np.empty((th.size, 3))
        flat = self.kernel_args()[0]
        _lookup_many(flat, th.ravel().copy(), td.ravel().copy(), pd.ravel().copy(), trilinear, out)
        return out.reshape(shape + (3,))

    def lookup_trilinear(self, theta_h, theta_d, phi_d) -> np.ndarray:
        """Trilinear interpolation in index space over measured corners (0 where none is), :func:`merl_trilinear`."""
        return self._lookup(theta_h, theta_d, phi_d, True)

    def eval_rusinkiewicz(self, theta_h, theta_d, phi_d) -> np.ndarray:
        return self._lookup(theta_h, theta_d, phi_d, self.params["interpolation"] == "trilinear")


# --------------------------------------------------------------------------- tabulation
#: (x, y) parameter pairs whose equality makes an anisotropic-class model isotropic in value
_XY_PAIRS = (("alpha_x", "alpha_y"), ("nu", "nv")) + tuple((f"cx_{k}", f"cy_{k}") for k in (1, 2, 3))


def _anisotropic_message(model: BRDF) -> str:
    """save_merl's one-line refusal of an anisotropic model, saying what to give instead."""
    name = getattr(model, "name", None) or type(model).__name__
    params = getattr(model, "params", {}) or {}
    spec = {q.name for q in getattr(type(model), "spec", ())}
    head = f"{name}: the MERL format stores isotropic BRDFs only, and this {name} is anisotropic"
    if "alpha" in spec:  # microfacet: one roughness makes the instance isotropic
        return f"{head}; give one roughness, alpha=... (the isotropic parameter), instead of alpha_x and alpha_y"
    pairs = [(x, y) for x, y in _XY_PAIRS if x in params and y in params]
    equal = [f"{x} = {y}" for x, y in pairs if np.array_equal(np.asarray(params[x]), np.asarray(params[y]))]
    if pairs and len(equal) == len(pairs):
        return (f"{head} by class even with {', '.join(equal)} (it has no isotropic parameter); tabulate an "
                "isotropic model instead, e.g. microfacet with alpha=... (its isotropic roughness), or "
                "bk.fit an isotropic model to it first")
    return f"{head}; tabulate an isotropic model (e.g. microfacet with alpha=..., its isotropic roughness)"


def tabulate(model: BRDF, chunk: int = 6) -> np.ndarray:
    """Evaluate an isotropic model at every bin centre: ``(3, 90, 90, 180)``, −1 below the horizon."""
    if isinstance(model, MERLBRDF):
        return np.array(model.table)
    if not getattr(model, "isotropic", True):
        raise ValueError(_anisotropic_message(model))
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
