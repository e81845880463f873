"""RGL ``.bsdf`` measured materials: reader and evaluation, as Mitsuba 3's ``measured`` plugin.

Reference: J. Dupuy, W. Jakob, "An Adaptive Parameterization for Efficient Material
Acquisition and Rendering", ACM Transactions on Graphics 37(6) (SIGGRAPH Asia 2018),
and its reader in Mitsuba 3, ``src/bsdfs/measured.cpp`` with the warps of
``include/mitsuba/core/distr_2d.h`` (``Marginal2D``). The algorithm below follows
those files; the code is brdfkit's own (numpy, vectorised over direction pairs).

The file is a tensor_file (:mod:`brdfkit.measured.tensor_file`). Fields (float32 unless
said; ``n_phi``/``n_theta`` are the sizes of ``phi_i``/``theta_i``):

=============  =====================================  ================================================
field          shape                                  meaning
=============  =====================================  ================================================
theta_i        (n_theta,)                             elevations of the incident direction (radians,
                                                      increasing) at which the tables were measured
phi_i          (n_phi,)                               its azimuths (radians, increasing); n_phi <= 2 is
                                                      an isotropic material, else the span gives the
                                                      symmetry: reduction = rint(2π / (last − first))
ndf            (Hn, Wn)                               D(m) of the microfacets over (φm, θm) in the
                                                      unit square (rows φ, columns θ)
sigma          (Hs, Ws)                               σ(ω), the projected microfacet area, over (φ, θ)
vndf           (n_phi, n_theta, Hv, Wv)               the visible-normal distribution per incident
                                                      direction; its inverse warp places the samples
luminance      (n_phi, n_theta, H, H)                 the table's luminance (Mitsuba samples it; not
                                                      needed to evaluate: checked, not used)
rgb            (n_phi, n_theta, 3, H, H)              the reflectance samples, or, in spectral files,
spectra        (n_phi, n_theta, n_λ, H, H)            one per wavelength of
wavelengths    (n_λ,)                                 (nm, increasing)
jacobian       (1,) uint8                             1: multiply by D(m) / (4 σ(ωi)) (Dupuy & Jakob
                                                      §4: the samples were divided by it)
description    (n,) uint8                             UTF-8 text
valid          any                                    a mask of the measurement; ignored, as Mitsuba does
=============  =====================================  ================================================

Evaluation of a pair (Mitsuba's names in brackets). brdfkit's ``wi`` points to the light and
``wo`` to the viewer; Mitsuba's ``si.wi`` is brdfkit's ``wo`` and the direction it evaluates
towards is brdfkit's ``wi``. With ``v = wo`` (the direction the tables are parameterised by) and
``l = wi``:

1. anisotropic files with reduction 2 or 4 fold the pair into the measured wedge: with
   ``sy = v.y`` and ``sx = v.x`` (reduction 4) or ``sy`` (reduction 2), both directions' x and y
   are multiplied by ``−sign(sx)`` and ``−sign(sy)`` (the sign of −0 is negative, as
   ``mulsign_neg``), which puts φ(v) in [−π, 0] (2) or [−π, −π/2] (4). Isotropic files
   (n_phi <= 2) are not folded. (Mitsuba 3.9 leaves its ``m_reduction`` uninitialised for them
   and reads it: observed, a fresh process folds by a rotation of π, which changes nothing
   when n_phi = 1 and σ is constant in φ, but after loading a reduction-4 file it mirrors;
   brdfkit follows the code's evident intent.);
2. ``m = normalize(v + l)``; elevations by the stable ``θ = 2 asin(|d − n| / 2)``, azimuths by
   ``atan2``; unit coordinates ``u = (sqrt(θ / (π/2)), (φ + π) / 2π)``, with φm taken relative
   to φv in isotropic files and ``u_m.y`` wrapped into [0, 1);
3. the inverse VNDF warp (``Marginal2D`` with continuous marginal and conditional
   distributions) at ``u_m``, each table linearly interpolated between the slices of the
   measured (φi, θi) (clamped at the ends, a parameter of size 1 not interpolated), each slice
   normalised to integrate to 1 over the bilinear interpolant;
4. the rgb table, bilinear at that sample (the same (φi, θi) interpolation);
5. times ``ndf(u_m) / (4 sigma(u_v))`` when ``jacobian`` is set (bilinear lookups).

That is Mitsuba's ``eval``, which includes the foreshortening cosine of the direction it
evaluates towards (Mitsuba's BSDF contract); brdfkit's f_r is it divided by ``cos θ`` of
brdfkit's ``wi``. Values are clamped at 0 (noise in a table may be negative; and at float32's
largest value, so that an absurd table never gives inf) and computed
in float64 (Mitsuba: float32; they agree to ~1e-5 relative, tested).

Spectral files are converted to linear sRGB once, at load: the spectrum, linear in λ between
the file's wavelengths (clamped beyond them, as Mitsuba interpolates it), is integrated at
5 nm over 360-830 nm against the CIE 1931 2° observer (:mod:`brdfkit.measured.cie`) weighted
by the D65 illuminant, normalised so that a flat spectrum of 1 has Y = 1, and taken to RGB by
the matrix of the sRGB / ITU-R BT.709 primaries (x, y) = (0.64, 0.33), (0.30, 0.60),
(0.15, 0.06) whose white is this D65 (so a flat spectrum gives R = G = B exactly).
"""

from __future__ import annotations

import os

import numpy as np

from .merl import MeasuredBRDF
from .tensor_file import read_tensor_file

#: fields every file has (besides ``rgb``, or ``spectra`` and ``wavelengths``)
REQUIRED = ("theta_i", "phi_i", "ndf", "sigma", "vndf", "luminance", "description", "jacobian")
#: refuse tables whose float64 working copies would exceed this many bytes
MAX_TABLE_BYTES = 4 << 30
#: values are clamped to [0, this]: an absurd table must not give inf in float32
_FLOAT32_MAX = float(np.finfo(np.float32).max)
_CHUNK = 1 << 14  # pairs per block of the vectorised evaluation


# ----------------------------------------------------------------- the unit-square maps
def theta2u(theta):
    """θ in [0, π/2] -> u in [0, 1]: ``sqrt(θ / (π/2))`` (fine cells near the normal)."""
    return np.sqrt(theta * (2.0 / np.pi))


def phi2u(phi):
    """φ in [−π, π] -> u in [0, 1]: ``(φ + π) / 2π``."""
    return (phi + np.pi) * (0.5 / np.pi)


def elevation(d):
    """θ of unit vectors ``d (..., 3)``: ``2 asin(|d − (0, 0, 1)| / 2)``, stable near the normal."""
    dist = np.sqrt(d[..., 0] ** 2 + d[..., 1] ** 2 + (d[..., 2] - 1.0) ** 2)
    return 2.0 * np.arcsin(np.clip(0.5 * dist, -1.0, 1.0))


# ----------------------------------------------------------------- conditional tables
class _Params:
    """Slices and weights of a table conditioned on (φi, θi), per point (Marginal2D's
    ``interpolate_weights``): each parameter linearly interpolated between the two measured
    values around it (weights clamped to [0, 1]); a parameter of size 1 is not interpolated."""

    def __init__(self, phi_values: np.ndarray, theta_values: np.ndarray, phi, theta) -> None:
        ip, wp = _interval(phi_values, phi)
        it, wt = _interval(theta_values, theta)
        npf, nt = len(phi_values), len(theta_values)
        # the (φ, θ) corners: slice index and weight, shape (corners, n); a parameter of size 1
        # has one corner (Mitsuba: stride 0, the second corner the first with weight 0)
        pa = (0, 1) if npf > 1 else (0,)
        tb = (0, 1) if nt > 1 else (0,)
        self.slices = np.stack([(ip + a) * nt + (it + b) for a in pa for b in tb])
        self.weights = np.stack([wp[a] * wt[b] for a in pa for b in tb])

    def lookup(self, table: np.ndarray, index) -> np.ndarray:
        """``table[slice, index]`` interpolated over the corners; ``table`` is ``(slices, k)`` or
        ``(slices, k, channels)`` (then the result is ``(n, channels)``)."""
        extra = (slice(None),) + (None,) * (table.ndim - 2)
        k = table.shape[1]
        flat = table.reshape((-1,) + table.shape[2:])  # a view: a gather by one flat index is ~5x a 2-index one
        out = self.weights[0][extra] * np.take(flat, self.slices[0] * k + index, axis=0)
        for j in range(1, len(self.slices)):
            out += self.weights[j][extra] * np.take(flat, self.slices[j] * k + index, axis=0)
        return out


def _interval(values: np.ndarray, x) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """(lower index, (w0, w1)) of ``x`` among increasing ``values`` (Mitsuba's ``find_interval``)."""
    x = np.asarray(x, dtype=np.float64)
    n = len(values)
    if n == 1:
        return np.zeros(x.shape, dtype=np.intp), (np.ones_like(x), np.zeros_like(x))
    i = np.clip(np.searchsorted(values, x, side="left") - 1, 0, n - 2)
    p0, p1 = values[i], values[i + 1]
    w1 = np.clip((x - p0) / (p1 - p0), 0.0, 1.0)
    return i, (1.0 - w1, w1)


class _Warp:
    """One slice-wise normalised 2D density with continuous marginal/conditional CDFs
    (``Marginal2D<Float, 2, true>`` of Mitsuba), for its inverse mapping.

    ``data`` is ``(slices, h, w)`` over the unit square, x along w (θ), y along h (φ).
    """

    def __init__(self, data: np.ndarray) -> None:
        s, h, w = data.shape
        d = np.asarray(data, dtype=np.float64)
        # conditional CDF along x per row: trapezoids of the bilinear interpolant
        cond = np.cumsum(0.5 / (w - 1) * (d[:, :, :-1] + d[:, :, 1:]), axis=2)  # (s, h, w-1)
        row = cond[:, :, -1]
        marg = np.cumsum(0.5 / (h - 1) * (row[:, :-1] + row[:, 1:]), axis=1)  # (s, h-1)
        norm = 1.0 / marg[:, -1]
        self.h, self.w = h, w
        self.data = (d * norm[:, None, None]).reshape(s, h * w)
        self.cond = (cond * norm[:, None, None]).reshape(s, h * (w - 1))
        self.marg = marg * norm[:, None]

    def invert(self, u: np.ndarray, prm: _Params) -> np.ndarray:
        """The unit-square sample that the warp maps to ``u (n, 2)`` (x, y): Marginal2D's
        ``invert`` (continuous), the bilinear patch's CDFs inverted in x then y."""
        h, w = self.h, self.w
        s = np.clip(u, 0.0, 1.0) * np.array([w - 1.0, h - 1.0])
        px = np.minimum(s[:, 0].astype(np.intp), w - 2)
        py = np.minimum(s[:, 1].astype(np.intp), h - 2)
        fx = s[:, 0] - px
        fy = s[:, 1] - py
        k = py * w + px
        v00, v10 = prm.lookup(self.data, k), prm.lookup(self.data, k + 1)
        v01, v11 = prm.lookup(self.data, k + w), prm.lookup(self.data, k + w + 1)
        c0 = v00 + (v01 - v00) * fy
        c1 = v10 + (v11 - v10) * fy
        # x: the integral over the part of the patch left of fx, plus the CDF before the patch
        x = fx * (c0 + (c1 - c0) * 0.5 * fx) / (w - 1)
        kc = py * (w - 1)
        before = np.maximum(px - 1, 0)
        prev0 = prm.lookup(self.cond, kc + before)
        prev1 = prm.lookup(self.cond, kc + before + (w - 1))
        x = x + np.where(px > 0, prev0 + (prev1 - prev0) * fy, 0.0)
        r0 = prm.lookup(self.cond, kc + (w - 2))
        r1 = prm.lookup(self.cond, kc + (w - 2) + (w - 1))
        x = _safe_div(x, r0 + (r1 - r0) * fy)
        # y: the same along the marginal
        y = fy * (r0 + (r1 - r0) * 0.5 * fy) / (h - 1)
        y = y + np.where(py > 0, prm.lookup(self.marg, np.maximum(py - 1, 0)), 0.0)
        return np.stack([x, y], axis=1)


def _safe_div(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        q = a / b
    return np.where(np.isfinite(q), q, 0.0)


def _bilinear_index(u: np.ndarray, h: int, w: int):
    """(flat index of the lower corner, fx, fy) of ``u (n, 2)`` on an h x w grid (Marginal2D's ``eval``)."""
    s = np.clip(u, 0.0, 1.0) * np.array([w - 1.0, h - 1.0])
    px = np.minimum(s[:, 0].astype(np.intp), w - 2)
    py = np.minimum(s[:, 1].astype(np.intp), h - 2)
    return py * w + px, s[:, 0] - px, s[:, 1] - py


def _bilinear(table: np.ndarray, u: np.ndarray) -> np.ndarray:
    """A plain ``(h, w)`` table bilinear at ``u (n, 2)`` (x along w)."""
    h, w = table.shape
    k, fx, fy = _bilinear_index(u, h, w)
    t = table.reshape(-1)
    a = t[k] + (t[k + 1] - t[k]) * fx
    b = t[k + w] + (t[k + w + 1] - t[k + w]) * fx
    return a + (b - a) * fy


# ----------------------------------------------------------------- spectra -> RGB
def _xyz_to_srgb() -> np.ndarray:
    """XYZ -> linear sRGB for the BT.709 primaries, white = the tabulated D65 (Y = 1)."""
    from . import cie

    prim = np.array([[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]])
    P = np.stack([prim[:, 0] / prim[:, 1], np.ones(3), (1 - prim.sum(axis=1)) / prim[:, 1]])  # columns: XYZ of R, G, B (Y=1)
    white = np.array([(c * cie.D65).sum() for c in (cie.XBAR, cie.YBAR, cie.ZBAR)])
    white /= white[1]
    scale = np.linalg.solve(P, white)
    return np.linalg.inv(P * scale)


def spectral_to_rgb_matrix(wavelengths: np.ndarray) -> np.ndarray:
    """``(3, n_λ)``: linear sRGB of a spectrum given at ``wavelengths`` (see the module docstring)."""
    from . import cie

    lam = cie.WAVELENGTHS
    wl = np.asarray(wavelengths, dtype=np.float64)
    # hat functions of the file's wavelengths at the 5 nm nodes (linear, clamped at the ends)
    hat = np.empty((len(lam), len(wl)))
    eye = np.eye(len(wl))
    for k in range(len(wl)):
        hat[:, k] = np.interp(lam, wl, eye[k]) if len(wl) > 1 else 1.0
    cmf = np.stack([cie.XBAR, cie.YBAR, cie.ZBAR]) * cie.D65  # (3, 95)
    xyz = cmf @ hat / (cie.YBAR * cie.D65).sum()
    return _xyz_to_srgb() @ xyz


# ----------------------------------------------------------------- the file
def _shape_error(path: str, name: str, shape, want: str) -> ValueError:
    return ValueError(f"{path}: field {name!r} has shape {tuple(shape)}, expected {want}")


def _check_layout(path: str, f: dict[str, np.ndarray]) -> tuple[str, int, int]:
    """Mitsuba's structure checks, one line each; returns (table field, n_phi, n_theta)."""
    spectral = "wavelengths" in f
    table = "spectra" if spectral else "rgb"
    for name in REQUIRED + ((table, "wavelengths") if spectral else (table,)):
        if name not in f:
            raise ValueError(f"{path}: not an RGL .bsdf file: field {name!r} is missing")
    for name in ("description", "jacobian"):
        if f[name].dtype != np.uint8 or f[name].ndim != 1:
            raise ValueError(f"{path}: field {name!r} must be a 1-D uint8 array, got {f[name].dtype} {f[name].shape}")
    if f["jacobian"].shape != (1,):
        raise _shape_error(path, "jacobian", f["jacobian"].shape, "(1,)")
    floats = ("theta_i", "phi_i", "ndf", "sigma", "vndf", "luminance", table) + (("wavelengths",) if spectral else ())
    for name in floats:
        if f[name].dtype != np.float32:
            raise ValueError(f"{path}: field {name!r} must be float32, got {f[name].dtype}")
    for name, nd in (("theta_i", 1), ("phi_i", 1), ("wavelengths", 1), ("ndf", 2), ("sigma", 2),
                     ("vndf", 4), ("luminance", 4), (table, 5)):
        if name in f and f[name].ndim != nd:
            raise ValueError(f"{path}: field {name!r} must have {nd} dimension(s), got shape {f[name].shape}")
    n_phi, n_theta = len(f["phi_i"]), len(f["theta_i"])
    if n_phi < 1 or n_theta < 1:
        raise ValueError(f"{path}: phi_i and theta_i must not be empty")
    lead = f"({n_phi}, {n_theta}, ...) to match phi_i and theta_i"
    n_ch = len(f["wavelengths"]) if spectral else 3
    t = f[table].shape
    if t[:2] != (n_phi, n_theta) or t[2] != n_ch or t[3] != t[4]:
        raise _shape_error(path, table, t, f"({n_phi}, {n_theta}, {n_ch}, H, H)")
    for name in ("vndf", "luminance"):
        if f[name].shape[:2] != (n_phi, n_theta):
            raise _shape_error(path, name, f[name].shape, lead)
    if f["luminance"].shape[2:] != t[3:]:
        raise _shape_error(path, "luminance", f["luminance"].shape, f"({n_phi}, {n_theta}, {t[3]}, {t[4]})")
    for name in ("ndf", "sigma", "vndf", table):
        if min(f[name].shape[-2:]) < 2:
            raise _shape_error(path, name, f[name].shape, "at least 2 x 2 samples in its last two dimensions")
    return table, n_phi, n_theta


def _check_values(path: str, f: dict[str, np.ndarray], table: str) -> None:
    for name in ("theta_i", "phi_i", "ndf", "sigma", "vndf", "luminance", table, "wavelengths"):
        if name in f and not np.isfinite(f[name]).all():
            raise ValueError(f"{path}: field {name!r} holds NaN or infinite values")
    for name in ("theta_i", "phi_i", "wavelengths"):
        if name in f and len(f[name]) > 1 and not (np.diff(f[name].astype(np.float64)) > 0).all():
            raise ValueError(f"{path}: field {name!r} must be strictly increasing")
    for name in ("ndf", "sigma", "vndf", "luminance"):
        if (f[name] < 0).any():
            raise ValueError(f"{path}: field {name!r} holds negative values")
    if f["jacobian"][0] and not (f["sigma"] > 0).all():
        raise ValueError(f"{path}: field 'sigma' must be positive (it divides the Jacobian factor)")
    v = f["vndf"]
    if not (v.reshape(v.shape[0] * v.shape[1], -1).sum(axis=1) > 0).all():
        raise ValueError(f"{path}: field 'vndf' has a slice that is zero everywhere (it cannot be normalised)")


def read_rgl(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """The fields of an RGL ``.bsdf`` file, checked as Mitsuba 3 checks them and more
    (finite tables, increasing parameters, positive σ); a one-line ``ValueError`` otherwise."""
    path = os.fspath(path)
    f = read_tensor_file(path)
    table, n_phi, n_theta = _check_layout(path, f)
    work = sum(f[k].size for k in ("ndf", "sigma", "vndf", table)) * 8 * 3
    if work > MAX_TABLE_BYTES:
        raise ValueError(f"{path}: tables of {work >> 20} MiB in memory, more than brdfkit's limit of "
                         f"{MAX_TABLE_BYTES >> 20} MiB")
    _check_values(path, f, table)
    return f


class RGLBRDF(MeasuredBRDF):
    """An RGL ``.bsdf`` material as a model, evaluated as Mitsuba 3's ``measured`` plugin.

    ``fields``: the arrays of the file (:func:`read_rgl`). Attributes: ``isotropic`` (one
    measured azimuth and σ constant in φ: the value depends on φi − φo only), ``reduction``
    (the azimuthal symmetry of an anisotropic file: 1, 2 or 4), ``spectral``, ``jacobian``,
    ``description``, ``resolution`` ``(n_phi, n_theta, H, W)``.
    """

    name = "rgl"
    title = "measured material in the RGL format (Dupuy & Jakob 2018, Mitsuba 3's `measured`)"
    reference = ("Dupuy, Jakob, An Adaptive Parameterization for Efficient Material Acquisition and "
                 "Rendering, ACM TOG 37(6), 2018")
    spec = ()

    def __init__(self, fields: dict[str, np.ndarray], label: str = "rgl", source: str = "") -> None:
        f = fields
        self.label, self.source = label, source
        self.spectral = "wavelengths" in f
        self.description = bytes(f["description"]).decode("utf-8", "replace")
        self.jacobian = bool(f["jacobian"][0])
        self._phi = np.asarray(f["phi_i"], dtype=np.float64)
        self._theta = np.asarray(f["theta_i"], dtype=np.float64)
        n_phi, n_theta = len(self._phi), len(self._theta)
        self.mitsuba_isotropic = n_phi <= 2
        self.reduction = 1
        if not self.mitsuba_isotropic:
            span = float(f["phi_i"][-1]) - float(f["phi_i"][0])
            self.reduction = int(np.rint(2 * np.pi / span))
        sigma = np.asarray(f["sigma"], dtype=np.float64)
        self.isotropic = n_phi == 1 and bool((sigma == sigma[:1]).all())
        self._ndf = np.asarray(f["ndf"], dtype=np.float64)
        self._sigma = sigma
        self._vndf = _Warp(np.asarray(f["vndf"], dtype=np.float64).reshape((n_phi * n_theta,) + f["vndf"].shape[2:]))
        if self.spectral:
            m = spectral_to_rgb_matrix(f["wavelengths"])
            rgb = np.einsum("cl,ptlhw->pthwc", m, np.asarray(f["spectra"], dtype=np.float64))
        else:
            rgb = np.moveaxis(np.asarray(f["rgb"], dtype=np.float64), 2, -1)  # (p, t, h, w, 3)
        h, w = rgb.shape[2:4]
        self.resolution = (n_phi, n_theta, h, w)
        self._rgb = np.ascontiguousarray(rgb.reshape(n_phi * n_theta, h * w, 3))
        super().__init__()

    def __repr__(self) -> str:
        kind = "isotropic" if self.isotropic else f"anisotropic (reduction {self.reduction})"
        return f"<RGLBRDF {self.label!r} {kind} {'spectral' if self.spectral else 'rgb'} {self.resolution}>"

    def _fold(self, v: np.ndarray, l: np.ndarray) -> None:
        """Step 1 of the module docstring, in place on both directions."""
        if self.mitsuba_isotropic or self.reduction < 2:
            return
        sy = v[:, 1].copy()
        sx = v[:, 0].copy() if self.reduction == 4 else sy
        fx = np.where(np.signbit(sx), 1.0, -1.0)
        fy = np.where(np.signbit(sy), 1.0, -1.0)
        for d in (v, l):
            d[:, 0] *= fx
            d[:, 1] *= fy

    def _eval(self, wi, wo, p):
        shape = np.broadcast_shapes(np.shape(wi), np.shape(wo))
        l = np.broadcast_to(wi, shape).reshape(-1, 3)
        v = np.broadcast_to(wo, shape).reshape(-1, 3)
        out = np.empty((len(l), 3))
        for a in range(0, len(l), _CHUNK):  # blocks small enough for the caches
            out[a:a + _CHUNK] = self._eval_flat(l[a:a + _CHUNK], v[a:a + _CHUNK])
        return out.reshape(shape)

    def _eval_flat(self, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
        """Steps 1-5 of the module docstring on ``(n, 3)`` directions above the horizon."""
        l = np.array(wi, dtype=np.float64)
        v = np.array(wo, dtype=np.float64)
        cos_l = l[:, 2].copy()
        self._fold(v, l)
        m = v + l
        m /= np.linalg.norm(m, axis=1, keepdims=True)
        theta_i, phi_i = elevation(v), np.arctan2(v[:, 1], v[:, 0])
        theta_m, phi_m = elevation(m), np.arctan2(m[:, 1], m[:, 0])
        if self.mitsuba_isotropic:
            phi_m = phi_m - phi_i
        u_m = np.stack([theta2u(theta_m), phi2u(phi_m)], axis=1)
        u_m[:, 1] -= np.floor(u_m[:, 1])
        prm = _Params(self._phi, self._theta, phi_i, theta_i)
        sample = self._vndf.invert(u_m, prm)
        h, w = self.resolution[2:]
        k, fx, fy = _bilinear_index(sample, h, w)
        v00, v10 = prm.lookup(self._rgb, k), prm.lookup(self._rgb, k + 1)
        v01, v11 = prm.lookup(self._rgb, k + w), prm.lookup(self._rgb, k + w + 1)
        a = v00 + (v10 - v00) * fx[:, None]
        b = v01 + (v11 - v01) * fx[:, None]
        f = a + (b - a) * fy[:, None]
        if self.jacobian:
            u_i = np.stack([theta2u(theta_i), phi2u(phi_i)], axis=1)
            f *= (_bilinear(self._ndf, u_m) / (4.0 * _bilinear(self._sigma, u_i)))[:, None]
        f = _safe_div(f, cos_l[:, None])
        return np.clip(f, 0.0, _FLOAT32_MAX)


def load_rgl(path: str | os.PathLike) -> RGLBRDF:
    """Read an RGL ``.bsdf`` file as a model (``eval``, ``check``, ``plot``, ``render``, ``fit``).

    Malformed files raise a one-line ``ValueError`` (see :func:`read_rgl`).
    """
    path = os.fspath(path)
    label = os.path.basename(path)
    if label.lower().endswith(".bsdf"):
        label = label[:-5]
    return RGLBRDF(read_rgl(path), label=label, source=path)


__all__ = ["RGLBRDF", "load_rgl", "read_rgl", "spectral_to_rgb_matrix", "elevation", "theta2u", "phi2u"]
