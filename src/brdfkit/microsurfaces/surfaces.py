"""Explicit microsurfaces: periodic triangle-mesh heightfields with a known slope distribution.

Every surface is one periodic tile, a regular grid of ``nx × ny`` cells on ``[0, Lx] × [0, Ly]``
(each cell split into two triangles), kept in a *base* frame. A world surface is the base tile
under the diagonal map ``(x, y, z) ↦ (x, s_y y, s_z z)`` (``s_y``, ``s_z`` may differ ray by ray,
see :class:`Scales`); straight lines map to straight lines, so rays are traced in the base frame
and only directions and normals are converted (normals by the inverse transpose).

Kinds
-----
* :func:`v_groove` — the symmetric V-groove cavities of Torrance & Sparrow (1967) and Cook &
  Torrance (1982, §"Geometrical attenuation"): grooves along ``y``, facets at ``±angle`` from the
  macro normal. Its masking is the V-groove formula ``min(1, 2 (n·h)(n·w)/(w·h))`` with ``h`` the
  facet that faces ``w`` (in the plane across the grooves; out of it, the same with ``w``
  projected onto that plane, since the surface does not vary along ``y``).
* :func:`gaussian_field` — a random Gaussian heightfield by spectral synthesis: white Gaussian
  noise filtered in the Fourier domain by ``exp(−|k|² ℓ²/8)`` (Gaussian autocorrelation
  ``exp(−r²/ℓ²)``), periodic by construction. Slopes of a Gaussian process are Gaussian, i.e. the
  Beckmann slope density ``P22(x̃, ỹ) = exp(−x̃²/α_x² − ỹ²/α_y²)/(π α_x α_y)`` (Heitz 2014,
  "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), eq. 71;
  Heitz, Hanika, d'Eon & Dachsbacher 2016, "Multiple-Scattering Microfacet BSDFs with the Smith
  Model", §7, validate against such Gaussian surfaces). The triangles' slopes are forward
  differences of the grid heights, so the tile is normalised on *those*: the cell sizes are set
  so that the mean squared triangle slope is exactly ``1/2`` per axis (α = 1) and the mean slope
  is exactly 0 (periodicity). Beckmann with ``α_x, α_y`` is then the map
  ``s_y = α_x/α_y, s_z = α_x``.
* GGX slopes have no Gaussian-process surface: the GGX slope density
  ``1/(π α² (1 + r²/α²)²)`` is a bivariate Student-t with ν = 2, which is a Gaussian scale
  mixture: Beckmann slopes of roughness ``α √W`` with ``1/W ~ Exp(1)`` (``W`` inverse-gamma(1, 1)).
  The GGX microsurface here is that mixture made literal: every ray meets its own tile, the
  Beckmann tile scaled by ``s_z = α_x √W`` with a fresh ``W``. Λ is linear in the slope density
  (Heitz 2014, eq. 72), so ``E_W[Λ_Beckmann(α√W)] = Λ_GGX`` and the mixture's marginal masking is
  Smith's GGX G1 exactly as far as each tile is Smith; the joint masking-shadowing of a mixture is
  *not* the height-correlated Smith G2 of GGX (big-W tiles both mask and shadow more), a
  difference the tests measure and state.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Tile:
    """A periodic grid heightfield in the base frame.

    ``heights`` ``(nx, ny)`` at the grid points ``(i dx, j dy)`` (periodic: the point ``nx`` is
    point 0); ``vertices`` ``(V, 3)`` and ``faces`` ``(F, 3)`` the triangle mesh of one tile with
    the wrapped row/column duplicated; ``normals`` ``(F, 3)`` unit face normals (z > 0).
    """

    heights: np.ndarray
    dx: float
    dy: float
    vertices: np.ndarray
    faces: np.ndarray
    normals: np.ndarray

    @property
    def size(self) -> tuple[float, float]:
        nx, ny = self.heights.shape
        return nx * self.dx, ny * self.dy

    @property
    def zmin(self) -> float:
        return float(self.heights.min())

    @property
    def zmax(self) -> float:
        return float(self.heights.max())

    def slopes(self) -> np.ndarray:
        """The triangles' slopes ``(x̃, ỹ) = (−n_x/n_z, −n_y/n_z)`` (slope space as in Heitz 2014),
        shape ``(F, 2)``; every triangle has the same projected area, so this is the slope sample."""
        n = self.normals
        return np.stack([-n[:, 0] / n[:, 2], -n[:, 1] / n[:, 2]], axis=-1)

    def locate(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Height and face index of the surface above the base-frame points ``(x, y)`` inside the tile."""
        nx, ny = self.heights.shape
        u, v = x / self.dx, y / self.dy
        i = np.clip(np.floor(u).astype(np.int64), 0, nx - 1)
        j = np.clip(np.floor(v).astype(np.int64), 0, ny - 1)
        fu, fv = u - i, v - j
        h = self.heights
        i1, j1 = (i + 1) % nx, (j + 1) % ny
        h00, h10, h11, h01 = h[i, j], h[i1, j], h[i1, j1], h[i, j1]
        lower = fu >= fv  # triangle (00, 10, 11); else (00, 11, 01)
        z = np.where(lower, h00 + fu * (h10 - h00) + fv * (h11 - h10), h00 + fu * (h11 - h01) + fv * (h01 - h00))
        cell = i * ny + j
        face = np.where(lower, cell, cell + nx * ny)
        return z, face


def grid_tile(heights: np.ndarray, dx: float, dy: float) -> Tile:
    """The triangle mesh of a periodic heightfield sampled on an ``nx × ny`` grid."""
    heights = np.asarray(heights, dtype=np.float64)
    nx, ny = heights.shape
    hw = np.pad(heights, ((0, 1), (0, 1)), mode="wrap")  # the wrapped row and column close the tile
    gx, gy = np.meshgrid(np.arange(nx + 1) * dx, np.arange(ny + 1) * dy, indexing="ij")
    vertices = np.stack([gx, gy, hw], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    idx = lambda a, b: (a * (ny + 1) + b).ravel()  # noqa: E731
    v00, v10, v11, v01 = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
    faces = np.concatenate([np.stack([v00, v10, v11], -1), np.stack([v00, v11, v01], -1)]).astype(np.uint32)
    p = vertices[faces]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return Tile(heights, float(dx), float(dy), vertices, faces, n)


def v_groove(angle_deg: float, cells_y: int = 1) -> Tile:
    """One period of symmetric V-grooves along ``y``, facets at ``±angle_deg`` from the normal."""
    if not 0.0 < angle_deg < 90.0:
        raise ValueError(f"v-groove: angle must be in (0, 90) degrees; got {angle_deg!r}")
    t = np.tan(np.radians(angle_deg))
    heights = np.zeros((2, cells_y))
    heights[1, :] = t  # valley at x = 0 (and 2), ridge at x = 1: facet slopes ±tan(angle)
    return grid_tile(heights, 1.0, 1.0)


def gaussian_field(n: int = 512, corr_cells: float = 6.0, seed: int = 0) -> Tile:
    """A periodic Gaussian heightfield, ``n × n`` cells, normalised to triangle slopes of RMS 1/√2 per axis.

    The slopes then follow the isotropic Beckmann density of α = 1 (see the module text);
    ``corr_cells`` is the correlation length ℓ in grid cells.
    """
    if n < 16:
        raise ValueError(f"microsurface: resolution must be at least 16 cells; got {n}")
    rng = np.random.default_rng(seed)
    k = 2.0 * np.pi * np.fft.fftfreq(n)
    kx, ky = np.meshgrid(k, k, indexing="ij")
    spectrum = np.fft.fft2(rng.standard_normal((n, n))) * np.exp(-(kx**2 + ky**2) * corr_cells**2 / 8.0)
    h = np.real(np.fft.ifft2(spectrum))
    vx = np.mean((np.roll(h, -1, 0) - h) ** 2)  # mean squared forward difference along x (per cell)
    vy = np.mean((np.roll(h, -1, 1) - h) ** 2)
    # cell sizes that make the triangle slopes' mean square exactly 1/2 per axis
    return grid_tile(h - h.mean(), np.sqrt(2.0 * vx), np.sqrt(2.0 * vy))


@dataclass(frozen=True)
class Scales:
    """The base → world map ``(x, y, z) ↦ (x, sy·y, sz·z)``, per ray (arrays broadcast to ``(n,)``)."""

    sy: np.ndarray
    sz: np.ndarray

    def to_world_dir(self, d: np.ndarray) -> np.ndarray:
        w = np.stack([d[:, 0], d[:, 1] * self.sy, d[:, 2] * self.sz], axis=-1)
        return w / np.linalg.norm(w, axis=-1, keepdims=True)

    def to_base_dir(self, w: np.ndarray) -> np.ndarray:
        d = np.stack([w[:, 0], w[:, 1] / self.sy, w[:, 2] / self.sz], axis=-1)
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def world_normal(self, n: np.ndarray) -> np.ndarray:
        m = np.stack([n[:, 0], n[:, 1] / self.sy, n[:, 2] / self.sz], axis=-1)  # inverse transpose
        return m / np.linalg.norm(m, axis=-1, keepdims=True)

    def take(self, idx) -> "Scales":
        return Scales(self.sy[idx], self.sz[idx])


def ggx_mixture_weights(n: int, rng: np.random.Generator) -> np.ndarray:
    """``W`` with ``1/W ~ Exp(1)`` (inverse-gamma(1, 1)): Beckmann(α√W) slopes mix to GGX(α) slopes."""
    return 1.0 / rng.standard_exponential(n)


def scales_for(kind: str, n: int, alpha_x: float, alpha_y: float, rng: np.random.Generator) -> Scales:
    """Per-ray base → world maps for ``n`` rays on the surface ``kind``."""
    ones = np.ones(n)
    if kind == "v-groove":
        return Scales(ones, ones)
    sz = alpha_x * ones
    if kind == "ggx":
        sz = sz * np.sqrt(ggx_mixture_weights(n, rng))
    return Scales(ones * (alpha_x / alpha_y), sz)
