"""Writing any model as an RGL ``.bsdf`` file: Dupuy & Jakob's adaptive parameterization, built
from the model itself.

References: J. Dupuy, W. Jakob, "An Adaptive Parameterization for Efficient Material
Acquisition and Rendering", ACM TOG 37(6), 2018 (§4: the parameterization; §5: the
acquisition pipeline, whose steps a model replaces here by evaluations), and J. Dupuy,
E. Heitz, J.-C. Iehl, P. Poulin, V. Ostromoukhov, "Extracting Microfacet-based BRDF Parameters
from Arbitrary Materials with Power Iterations", Computer Graphics Forum 34(4) (EGSR 2015),
for the NDF. The fields are those Mitsuba 3's ``measured`` plugin reads
(``src/bsdfs/measured.cpp``; :mod:`brdfkit.measured.rgl` reads them as it does).

Unit square: ``u = (sqrt(θ / (π/2)), (φ + π) / 2π)`` for every table over directions.

Steps (brdfkit's ``wo``, the viewer, is the direction ``v`` the tables are parameterised by;
``wi``, the light, is ``l``; f_r is the model):

1. **Backscattering** ``b(ω) = Y(f_r(ω, ω))`` (Y: the luminance of linear sRGB, 0.2126 R +
   0.7152 G + 0.0722 B; Dupuy & Jakob measure one wavelength, 532 nm) at the nodes of the NDF
   grid (``ndf_resolution`` elevations; for anisotropic models as many azimuths over [−π, π]).
2. **NDF by power iteration** (Dupuy et al. 2015, their eq. for retro-reflection): for a
   microfacet surface, ``f_r(ω, ω) = F D(ω) G1(ω) / (4 cos²θ)`` with ``G1(ω) = cos θ / σ(ω)``
   (shadowing equals masking when the two directions coincide), so
   ``D(ω) ∝ cos θ · b(ω) · σ[D](ω)`` with ``σ[D](ω) = ∫ ⟨ω, m⟩₊ D(m) dm``: D is the dominant
   eigenvector of a positive linear operator. Iterate ``D ← cos θ · b · σ[D]`` (rescaled to a
   maximum of 1) from ``D = 1`` until it changes by less than 1e-6 (at most 64 steps), then
   normalise ``∫ D(m) cos θm dm = 1`` (σ of the normal is 1). D is the bilinear interpolant of
   its nodes in the unit square (as the reader interpolates it); σ[D] is integrated on a grid
   twice as fine, in closed form over the azimuth for isotropic models. Values below 1e-6 of
   the maximum are raised to it (a Beckmann tail underflows float32; the reader divides by D).
3. **σ**, the projected area ``σ(ω) = ∫ ⟨ω, m⟩₊ D(m) dm``, on the same grid (field ``sigma``).
4. **Incident elevations** ``theta_i``: ``n_theta`` values equally spaced in σ between the
   normal and 89° (Dupuy & Jakob: σ measures the projected area the measurement sees); azimuths
   ``phi_i``: one (0) for an isotropic model; else ``n_phi`` over the wedge [−π, −π + 2π/r] of
   the model's symmetry r (4: mirror-symmetric in x and in y; 2: under a rotation by π; 1:
   none), which the reader folds every pair into.
5. **VNDF** per incident direction ``v`` (field ``vndf``), the density of the visible normals in
   the unit square: ``⟨v, m⟩₊ D(m) / σ(v) · 2π² u_x sin θm`` (the last factor is dω/du).
6. **Samples** (fields ``rgb``, ``luminance``): the ``resolution × resolution`` grid of points
   ``s`` of the unit square, carried by the VNDF warp (``Marginal2D.sample``, the inverse of what
   the reader applies) to a normal ``m``; ``l`` is ``v`` reflected about ``m``, and the sample is
   ``f_r(l, v) cos θl · 4 σ(v) / D(m)`` (0 where ``l`` is below the horizon) with D and σ the
   bilinear lookups of the written tables: the reader multiplies by ``D(m) / (4 σ(v))``
   (``jacobian`` = 1) and so returns f_r exactly at every sample. ``luminance`` is the samples'
   Y (Mitsuba samples it; raised to 1e-6 of each slice's maximum so that no slice is zero).

The interpolation between samples, and between the measured incident directions, is the
tabulation error; :func:`brdfkit.measured.tabulation.tabulate` measures it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .rgl import _bilinear, elevation, phi2u, theta2u

#: linear sRGB -> luminance Y
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
#: relative floor of D and of each luminance slice
FLOOR = 1e-6
#: largest incident elevation tabulated (the reader clamps beyond it)
THETA_MAX = np.radians(89.0)
#: default resolutions (Dupuy & Jakob's files: 32 x 32 samples per table)
DEFAULTS = dict(resolution=64, n_theta=32, n_phi=None, ndf_resolution=64)
#: default number of incident azimuths per quarter turn of an anisotropic model
PHI_PER_QUARTER = 10
_POWER_STEPS, _POWER_TOL = 64, 1e-6
_CHUNK = 1 << 14


# ----------------------------------------------------------------- directions
def u2theta(u):
    return np.square(u) * (np.pi / 2)


def u2phi(u):
    return (2.0 * np.asarray(u) - 1.0) * np.pi


def direction(theta, phi) -> np.ndarray:
    """Unit vectors ``(..., 3)`` of elevation θ and azimuth φ."""
    st = np.sin(theta)
    return np.stack(np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)), axis=-1)


def _clamp_up(d: np.ndarray, zmin: float = 1e-4) -> np.ndarray:
    """``d`` with its z raised to ``zmin`` and renormalised (a model is 0 on the horizon)."""
    out = np.array(d, dtype=np.float64)
    out[..., 2] = np.maximum(out[..., 2], zmin)
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


def luminance(rgb: np.ndarray) -> np.ndarray:
    return np.asarray(rgb, dtype=np.float64) @ LUMINANCE


def _evaluate(model, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """f_r ``(n, 3)`` in float64, non-finite and negative values taken as 0."""
    out = np.empty((len(wi), 3))
    for a in range(0, len(wi), _CHUNK):
        f = np.asarray(model.eval(wi[a:a + _CHUNK], wo[a:a + _CHUNK]), dtype=np.float64)
        out[a:a + _CHUNK] = np.broadcast_to(f, (len(f), 3)) if f.ndim == 2 else f[:, None]
    return np.maximum(np.nan_to_num(out, nan=0.0, posinf=0.0, neginf=0.0), 0.0)


# ----------------------------------------------------------------- the NDF and sigma
def _lerp_matrix(n_nodes: int, u: np.ndarray) -> np.ndarray:
    """``(len(u), n_nodes)``: linear-interpolation weights of the nodes ``k/(n_nodes-1)`` at ``u``."""
    x = np.clip(u, 0.0, 1.0) * (n_nodes - 1)
    i = np.minimum(x.astype(np.intp), n_nodes - 2)
    f = x - i
    out = np.zeros((len(u), n_nodes))
    out[np.arange(len(u)), i] = 1.0 - f
    out[np.arange(len(u)), i + 1] = f
    return out


def _azimuthal_cosine_integral(theta: np.ndarray, theta_m: np.ndarray) -> np.ndarray:
    """``∫₀^{2π} max(0, cos θ cos θm + sin θ sin θm cos φ) dφ`` for every (θ, θm) (closed form)."""
    a = np.cos(theta)[:, None] * np.cos(theta_m)[None, :]
    b = np.sin(theta)[:, None] * np.sin(theta_m)[None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        phi0 = np.arccos(np.clip(-a / b, -1.0, 1.0))
    part = 2.0 * (a * phi0 + b * np.sin(phi0))
    return np.where(a >= b, 2 * np.pi * a, np.where(a <= -b, 0.0, part))


class _SigmaOperator:
    """``σ[D]`` at the nodes, for D given at the same nodes (bilinear in the unit square).

    Isotropic (``h == 2``, D constant in φ): a matrix over the elevations, the azimuth integrated
    in closed form. Anisotropic: the fine quadrature points and weights, applied in blocks."""

    def __init__(self, h: int, w: int, isotropic: bool, sub: int = 2) -> None:
        self.h, self.w, self.isotropic = h, w, isotropic
        fx = (np.arange(sub * (w - 1)) + 0.5) / (sub * (w - 1))  # midpoints of the fine cells
        theta_f = u2theta(fx)
        wx = np.pi * fx * np.sin(theta_f) / (sub * (w - 1))  # dθ sinθ = π u sinθ du
        self.lx = _lerp_matrix(w, fx)
        self.node_theta = u2theta(np.arange(w) / (w - 1))
        if isotropic:
            k = _azimuthal_cosine_integral(self.node_theta, theta_f)  # (w, fine)
            self.matrix = (k * wx[None, :]) @ self.lx  # (w, w)
            return
        fy = (np.arange(sub * (h - 1)) + 0.5) / (sub * (h - 1))
        self.ly = _lerp_matrix(h, fy)
        phi_f = u2phi(fy)
        m = direction(theta_f[None, :], phi_f[:, None])  # (fy, fx, 3)
        wy = 2 * np.pi / (sub * (h - 1))
        self.m = m.reshape(-1, 3)
        self.weight = (np.broadcast_to(wx[None, :] * wy, m.shape[:2])).reshape(-1)
        uy = np.arange(h) / (h - 1)
        self.nodes = direction(self.node_theta[None, :], u2phi(uy)[:, None]).reshape(-1, 3)

    def __call__(self, d: np.ndarray) -> np.ndarray:
        """σ at the nodes, ``(h, w)``, of D at the nodes ``(h, w)``."""
        if self.isotropic:
            s = self.matrix @ d[0]
            return np.broadcast_to(s, (self.h, self.w)).copy()
        fine = (self.ly @ d @ self.lx.T).reshape(-1) * self.weight  # D·dω at the fine points
        out = np.empty(len(self.nodes))
        step = max(1, (1 << 22) // len(self.m))
        for a in range(0, len(self.nodes), step):
            cos = np.maximum(self.nodes[a:a + step] @ self.m.T, 0.0)
            out[a:a + step] = cos @ fine
        return out.reshape(self.h, self.w)


@dataclass
class NDF:
    """The NDF table ``ndf (h, w)``, σ at the same nodes, and how the power iteration ended."""

    ndf: np.ndarray
    sigma: np.ndarray
    steps: int
    change: float
    operator: _SigmaOperator


def backscatter_nodes(h: int, w: int, isotropic: bool) -> np.ndarray:
    """The directions ``(h, w, 3)`` of the NDF grid's nodes (isotropic: every row at φ = 0)."""
    theta = u2theta(np.arange(w) / (w - 1))
    phi = np.zeros(h) if isotropic else u2phi(np.arange(h) / (h - 1))
    return direction(theta[None, :], phi[:, None])


def power_iteration_ndf(model, resolution: int = 64, isotropic: bool = True) -> NDF:
    """Step 2 of the module docstring: the NDF (and σ) of ``model`` from its backscattering."""
    h, w = (2, resolution) if isotropic else (resolution, resolution)
    nodes = backscatter_nodes(h, w, isotropic)
    flat = _clamp_up(nodes.reshape(-1, 3), 1e-3)  # the horizon's nodes just above it
    b = luminance(_evaluate(model, flat, flat))
    weight = (np.maximum(b, 0.0) * flat[:, 2]).reshape(h, w)  # cos θ · b
    if not (weight > 0).any():
        raise ValueError("the model reflects nothing back towards any direction (its backscattering is 0): "
                         "an NDF cannot be derived from it")
    op = _SigmaOperator(h, w, isotropic)
    d = np.ones((h, w))
    change, steps = np.inf, 0
    for steps in range(1, _POWER_STEPS + 1):
        new = weight * op(d)
        new /= new.max()
        change = float(np.abs(new - d).max())
        d = new
        if change < _POWER_TOL:
            break
    d = np.maximum(d, FLOOR * d.max())
    d /= op(d)[0, 0]  # σ(normal) = ∫ D cos θm dm = 1
    return NDF(ndf=d, sigma=op(d), steps=steps, change=change, operator=op)


# ----------------------------------------------------------------- incident directions
def theta_samples(ndf: NDF, n_theta: int) -> np.ndarray:
    """``n_theta`` elevations in [0, 89°], equally spaced in σ (the table's σ, averaged over the
    azimuth, linear between its nodes in the unit square as the reader interpolates it)."""
    fine = np.linspace(0.0, THETA_MAX, 1024)
    row = ndf.sigma.mean(axis=0)
    s = np.interp(theta2u(fine), np.arange(len(row)) / (len(row) - 1), row)
    s = np.minimum.accumulate(s)  # σ decreases with θ; guard against quadrature ripples
    target = np.linspace(s[0], s[-1], n_theta)
    theta = np.interp(target[::-1], s[::-1], fine[::-1])[::-1]
    theta[0], theta[-1] = 0.0, THETA_MAX
    return np.maximum.accumulate(theta)


def phi_samples(n_phi: int, reduction: int) -> np.ndarray:
    """The incident azimuths: ``[0]`` (isotropic, ``n_phi == 1``) or ``n_phi`` over [−π, −π + 2π/r]."""
    if n_phi == 1:
        return np.zeros(1)
    return np.linspace(-np.pi, -np.pi + 2 * np.pi / reduction, n_phi)


def symmetry_reduction(model, n: int = 2000, seed: int = 7, rtol: float = 1e-6) -> int:
    """4 when ``model`` is mirror-symmetric in x and in y, 2 when symmetric under a rotation by π,
    else 1 (checked numerically on ``n`` random pairs: the reader folds pairs accordingly)."""
    rng = np.random.default_rng(seed)

    def dirs():
        z = rng.uniform(0.05, 1.0, n)
        p = rng.uniform(-np.pi, np.pi, n)
        s = np.sqrt(1 - z * z)
        return np.stack([s * np.cos(p), s * np.sin(p), z], axis=1)

    wi, wo = dirs(), dirs()
    f = _evaluate(model, wi, wo)
    scale = np.abs(f).max() + 1e-300

    def same(sx, sy):
        k = np.array([sx, sy, 1.0])
        return bool(np.abs(_evaluate(model, wi * k, wo * k) - f).max() <= rtol * scale)

    if same(-1.0, 1.0) and same(1.0, -1.0):
        return 4
    return 2 if same(-1.0, -1.0) else 1


# ----------------------------------------------------------------- the VNDF and its warp
def vndf_slice(ndf_table: np.ndarray, v: np.ndarray, sigma_v: float, h: int, w: int, isotropic: bool) -> np.ndarray:
    """Step 5: the VNDF of incident direction ``v`` on an ``h x w`` grid of the unit square."""
    ux = np.arange(w) / (w - 1)
    uy = np.arange(h) / (h - 1)
    theta, phi = u2theta(ux)[None, :], u2phi(uy)[:, None]
    if isotropic:  # the table's azimuths are relative to φ(v)
        phi = phi + np.arctan2(v[1], v[0])
    m = direction(theta, phi)
    u = np.stack(np.broadcast_arrays(ux[None, :], uy[:, None]), axis=-1).reshape(-1, 2)
    d = _bilinear(ndf_table, u).reshape(h, w)
    jac = 2 * np.pi ** 2 * ux[None, :] * np.sin(theta)
    return np.maximum(m @ v, 0.0) * d / sigma_v * jac


def warp_sample(data: np.ndarray, s: np.ndarray) -> np.ndarray:
    """The point of the unit square that the (normalised, bilinear) density ``data (h, w)`` warps
    the uniform point ``s (n, 2)`` (x, y) to: Mitsuba's ``Marginal2D::sample`` (continuous), the
    inverse of :meth:`brdfkit.measured.rgl._Warp.invert` (marginal in y first, then x given y)."""
    h, w = data.shape
    d = np.asarray(data, dtype=np.float64)
    cond = np.concatenate([np.zeros((h, 1)), np.cumsum(0.5 / (w - 1) * (d[:, :-1] + d[:, 1:]), axis=1)], axis=1)
    rows = cond[:, -1]
    marg = np.concatenate([[0.0], np.cumsum(0.5 / (h - 1) * (rows[:-1] + rows[1:]))])
    # y: the marginal's CDF, piecewise quadratic
    ty = np.clip(s[:, 1], 0.0, 1.0) * marg[-1]
    py = np.clip(np.searchsorted(marg, ty, side="left") - 1, 0, h - 2)
    r0, r1 = rows[py], rows[py + 1]
    fy = _solve_quadratic_cdf(r0, r1, (ty - marg[py]) * (h - 1))
    # x: the conditional of the row interpolated at fy
    c = cond[py] * (1.0 - fy)[:, None] + cond[py + 1] * fy[:, None]  # (n, w) cumulative
    tx = np.clip(s[:, 0], 0.0, 1.0) * c[:, -1]
    px = np.clip((c < tx[:, None]).sum(axis=1) - 1, 0, w - 2)
    n = np.arange(len(s))
    c0 = d[py, px] * (1.0 - fy) + d[py + 1, px] * fy
    c1 = d[py, px + 1] * (1.0 - fy) + d[py + 1, px + 1] * fy
    fx = _solve_quadratic_cdf(c0, c1, (tx - c[n, px]) * (w - 1))
    return np.stack([(px + fx) / (w - 1), (py + fy) / (h - 1)], axis=1)


def _solve_quadratic_cdf(a: np.ndarray, b: np.ndarray, target: np.ndarray) -> np.ndarray:
    """``t`` in [0, 1] with ``a t + (b − a) t² / 2 = target`` (the integral of a linear density),
    in the form stable for ``a ≈ b``."""
    disc = np.maximum(a * a + 2.0 * (b - a) * target, 0.0)
    den = a + np.sqrt(disc)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(den > 0, 2.0 * target / den, 0.0)
    return np.clip(np.nan_to_num(t), 0.0, 1.0)


# ----------------------------------------------------------------- the file
@dataclass
class RGLTables:
    """The fields of the file (:attr:`fields`) and facts about how they were built."""

    fields: dict
    isotropic: bool
    reduction: int
    ndf_steps: int
    ndf_change: float


def rgl_tables(model, *, resolution: int = 64, n_theta: int = 32, n_phi: int | None = None,
               ndf_resolution: int = 64, isotropic: bool | None = None, description: str = "",
               progress: Callable[[int, int], None] | None = None) -> RGLTables:
    """The RGL fields of ``model`` (steps 1-6 of the module docstring). ``isotropic``: None
    takes the model's own attribute. ``progress(done, total)`` is called per incident direction."""
    iso = bool(getattr(model, "isotropic", False)) if isotropic is None else bool(isotropic)
    reduction = 1 if iso else symmetry_reduction(model)
    if n_phi is None:
        n_phi = 1 if iso else PHI_PER_QUARTER * (4 // reduction) + 1
    ndf = power_iteration_ndf(model, ndf_resolution, iso)
    # the reader sees the float32 tables: every lookup below uses them, rounded the same way
    ndf32 = ndf.ndf.astype(np.float32).astype(np.float64)
    sigma32 = ndf.sigma.astype(np.float32).astype(np.float64)
    theta_i = theta_samples(ndf, n_theta).astype(np.float32).astype(np.float64)
    phi_i = phi_samples(n_phi, reduction).astype(np.float32).astype(np.float64)
    h = w = resolution
    grid = np.stack(np.meshgrid(np.arange(w) / (w - 1), np.arange(h) / (h - 1)), axis=-1).reshape(-1, 2)
    vndf = np.empty((n_phi, n_theta, h, w))
    rgb = np.empty((n_phi, n_theta, 3, h, w))
    total = n_phi * n_theta
    for a, phi in enumerate(phi_i):
        for b, theta in enumerate(theta_i):
            v = direction(theta, phi)
            u_v = np.array([[theta2u(theta), phi2u(phi)]])
            sigma_v = float(_bilinear(sigma32, u_v)[0])
            vndf[a, b] = vndf_slice(ndf32, v, sigma_v, h, w, iso).astype(np.float32)
            u_m = warp_sample(vndf[a, b], grid)
            theta_m, phi_m = u2theta(u_m[:, 0]), u2phi(u_m[:, 1])
            m = direction(theta_m, phi_m + (phi if iso else 0.0))
            l = 2.0 * (m @ v)[:, None] * m - v
            up = l[:, 2] > 0
            vals = np.zeros((len(l), 3))
            if up.any():
                f = _evaluate(model, l[up] / np.linalg.norm(l[up], axis=1, keepdims=True),
                              np.broadcast_to(v, (int(up.sum()), 3)))
                jac = 4.0 * sigma_v / _bilinear(ndf32, u_m[up])
                vals[up] = f * (l[up, 2] * jac)[:, None]
            rgb[a, b] = vals.T.reshape(3, h, w)
            if progress is not None:
                progress(a * n_theta + b + 1, total)
    lum = np.maximum(np.einsum("c,ptchw->pthw", LUMINANCE, rgb), 0.0)
    peak = lum.reshape(n_phi, n_theta, -1).max(axis=2)
    lum = np.maximum(lum, np.where(peak > 0, FLOOR * peak, 1.0)[:, :, None, None])
    fields = {
        "description": description,
        "jacobian": np.array([1], np.uint8),
        "theta_i": theta_i.astype(np.float32),
        "phi_i": phi_i.astype(np.float32),
        "ndf": ndf32.astype(np.float32),
        "sigma": sigma32.astype(np.float32),
        "vndf": vndf.astype(np.float32),
        "luminance": lum.astype(np.float32),
        "rgb": rgb.astype(np.float32),
    }
    return RGLTables(fields=fields, isotropic=iso, reduction=reduction, ndf_steps=ndf.steps,
                     ndf_change=ndf.change)


__all__ = ["rgl_tables", "RGLTables", "power_iteration_ndf", "NDF", "warp_sample", "vndf_slice",
           "theta_samples", "phi_samples", "symmetry_reduction", "direction", "DEFAULTS"]
