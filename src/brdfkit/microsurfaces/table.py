"""A whole simulated BRDF table: an isotropic microsurface traced from a grid of incident angles.

For each of ``n_theta`` incident elevations θi (uniform in θ on [0, 89°], azimuth 0; the surface
must be isotropic, so that the azimuth does not matter), ``samples`` paths are traced and binned by
outgoing direction in ``n_u × n_phi`` bins: ``u = sin² θo`` uniform on [0, 1) and the azimuth
difference ``|φo − φi|`` folded onto [0, π] (the mirror symmetry about the plane of incidence).
Each bin has projected solid angle ``∫ cos θo dω = Δu Δφ`` (both mirror halves), so the bin's
BRDF is ``(Σ path weights in the bin / samples) / (Δu Δφ)``. :class:`SimulatedTable` interpolates
these values linearly (θi between grid nodes, ``u`` and the azimuth between bin centres), which
is what ``bk.tabulate`` evaluates to write a MERL or RGL file (``brdfkit measure``).
"""

from __future__ import annotations

from typing import Callable

import numpy as np


class SimulatedTable:
    """The binned BRDF ``values[theta_i, u, phi, rgb]`` with its standard errors, as a model."""

    isotropic = True

    def __init__(self, theta_i: np.ndarray, values: np.ndarray, stderr: np.ndarray, label: str) -> None:
        self.theta_i = np.asarray(theta_i, np.float64)
        self.values = np.asarray(values, np.float64)
        self.stderr = np.asarray(stderr, np.float64)
        self.label = label
        self.name = label
        self.params: dict = {}

    def eval(self, wi, wo) -> np.ndarray:
        """Linearly interpolated simulated BRDF, shape ``(..., 3)``; 0 below the horizon."""
        wi, wo = np.broadcast_arrays(np.asarray(wi, np.float64), np.asarray(wo, np.float64))
        nt, nu, nphi, _ = self.values.shape
        ti = np.arccos(np.clip(wi[..., 2], -1.0, 1.0))
        u = np.clip(1.0 - np.clip(wo[..., 2], 0.0, 1.0) ** 2, 0.0, 1.0)
        dphi = np.abs(np.arctan2(wo[..., 1], wo[..., 0]) - np.arctan2(wi[..., 1], wi[..., 0]))
        dphi = np.where(dphi > np.pi, 2.0 * np.pi - dphi, dphi)
        # fractional indices: θi on the node grid; u and φ at bin centres
        fi = np.interp(ti, self.theta_i, np.arange(nt))
        fu = np.clip(u * nu - 0.5, 0.0, nu - 1.0)
        fp = np.clip(dphi / np.pi * nphi - 0.5, 0.0, nphi - 1.0)
        out = np.zeros(wi.shape[:-1] + (3,))
        for axis_pick in np.ndindex(2, 2, 2):
            idx, w = [], 1.0
            for f, n, b in zip((fi, fu, fp), (nt, nu, nphi), axis_pick):
                lo = np.floor(f).astype(np.int64)
                hi = np.minimum(lo + 1, n - 1)
                t = f - lo
                idx.append(hi if b else lo)
                w = w * (t if b else 1.0 - t)
            out += w[..., None] * self.values[idx[0], idx[1], idx[2]]
        above = (wi[..., 2] > 0) & (wo[..., 2] > 0)
        return np.where(above[..., None], out, 0.0)


def simulate(surface, n_theta: int = 24, n_u: int = 48, n_phi: int = 48, samples: int = 200000,
             bounces: int | None = None, step: Callable[[int], None] | None = None) -> SimulatedTable:
    """Trace ``surface`` (a :class:`~brdfkit.microsurfaces.Microsurface`) into a :class:`SimulatedTable`."""
    for name, v, lo in (("n_theta", n_theta, 2), ("n_u", n_u, 2), ("n_phi", n_phi, 2), ("samples", samples, 100)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo:
            raise ValueError(f"microsurface table: {name} must be an integer >= {lo}; got {v!r}")
    if surface.kind == "v-groove" or surface.alpha_x != surface.alpha_y:
        raise ValueError("microsurface table: only isotropic surfaces (beckmann/ggx with one alpha) tabulate")
    theta = np.radians(np.linspace(0.0, 89.0, n_theta))
    values = np.zeros((n_theta, n_u, n_phi, 3))
    errs = np.zeros_like(values)
    proj = (1.0 / n_u) * (np.pi / n_phi)
    for k, t in enumerate(theta):
        wi = np.array([np.sin(t), 0.0, np.cos(t)])
        p = surface.shoot(wi, samples)
        keep = p.status == 0
        if bounces is not None:
            keep &= p.bounces == bounces
        wo, w = p.wo[keep], p.weight[keep]
        iu = np.minimum((1.0 - np.clip(wo[:, 2], 0, 1) ** 2) * n_u, n_u - 1).astype(np.int64)
        ip = np.minimum(np.abs(np.arctan2(wo[:, 1], wo[:, 0])) / np.pi * n_phi, n_phi - 1).astype(np.int64)
        cell = iu * n_phi + ip
        s1 = np.stack([np.bincount(cell, w[:, c], n_u * n_phi) for c in range(3)], -1)
        s2 = np.stack([np.bincount(cell, w[:, c] ** 2, n_u * n_phi) for c in range(3)], -1)
        mean = s1 / samples
        var = np.maximum(s2 / samples - mean**2, 0.0)
        values[k] = (mean / proj).reshape(n_u, n_phi, 3)
        errs[k] = (np.sqrt(var / samples) / proj).reshape(n_u, n_phi, 3)
        if step:
            step(k + 1)
    label = f"microsurface-{surface.kind}(alpha={surface.alpha_x:g})"
    return SimulatedTable(theta, values, errs, label)
