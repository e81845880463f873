"""Measured samples for fitting: weighted (ωi, ωo, f) triples of a measured material.

Used by :func:`brdfkit.measured.optimise.fit` and :mod:`brdfkit.measured.metrics`.

A few thousand (θh, θd, φd) samples (:func:`sample`), uniform in MERL's index space (the
square-root θh mapping puts many of them in the specular peak), with random φh; both
directions within ``max_theta_deg`` (80°, as Ngan et al. 2005) of the normal. From a MERL
table the samples are bin centres of measured bins and the values are the table's; from
any other model the model is evaluated. Each sample carries the weight
``sin θh · dθh/du · sin θd cos θd`` (the Jacobian of the half/difference parameterisation,
dωi dωo = 4 cos θd dωh dωd with dωh = sin θh dθh dφh, dωd = sin θd dθd dφd, over the
sampling density; the constant 4 cancels in the normalisation; θh = u² π/2 so
dθh/du = π u), so every metric estimates an integral over pairs of directions (ωi, ωo),
normalised by the integral of the weight. :func:`table` takes every measured bin instead,
:func:`subsample` a random subset of samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..geometry import from_rusinkiewicz
from ..models.base import BRDF
from .merl import HALF_PI, MERLBRDF, RES_PHI_D, RES_THETA_D, RES_THETA_H, bin_centres


@dataclass
class Samples:
    """Measured samples: directions, values (N, 3) in 1/sr, weights (N,) with mean 1."""

    wi: np.ndarray
    wo: np.ndarray
    f: np.ndarray
    w: np.ndarray
    source: str = ""
    #: False for anisotropic data (UTIA, anisotropic RGL): a fitted model's x/y pairs are then left untied
    isotropic: bool = True

    @property
    def cos_i(self) -> np.ndarray:
        return self.wi[:, 2]

    def __len__(self) -> int:
        return len(self.w)


def resolve_source(measured: Any) -> BRDF:
    """The data to fit: any source :func:`brdfkit.sources.resolve` takes (a measured material, a MERL
    or other measured file, a fit's JSON, a model name or object)."""
    from ..sources import resolve

    return resolve(measured)


def _source_label(model: BRDF) -> str:
    return getattr(model, "label", None) or getattr(model, "name", "model")


def sample(measured: Any, n: int = 3000, seed: int = 0, max_theta_deg: float = 80.0) -> Samples:
    """``n`` weighted samples of a measured material / model (see the module docstring)."""
    model = resolve_source(measured)
    # φh is drawn uniformly on [0, 2π) below, so anisotropic data (UTIA, anisotropic RGL) are sampled as well
    if not (0 < max_theta_deg <= 90):
        raise ValueError(f"max_theta_deg must be in (0, 90], got {max_theta_deg}")
    if n < 16:
        raise ValueError(f"need at least 16 samples, got {n}")
    rng = np.random.default_rng(seed)
    cos_max = math.cos(math.radians(max_theta_deg)) if max_theta_deg < 90 else 0.0
    is_table = isinstance(model, MERLBRDF)
    _, centre_td, centre_pd = bin_centres()
    wi_l, wo_l, f_l, w_l = [], [], [], []
    have = 0
    for _round in range(20):
        m = max(4 * n, 4096)
        if is_table:
            i = rng.integers(0, RES_THETA_H, m)
            j = rng.integers(0, RES_THETA_D, m)
            k = rng.integers(0, RES_PHI_D, m)
            u = (i + 0.5) / RES_THETA_H  # θh's bin centre in index space (θh = u² π/2 below)
            td, pd = centre_td[j], centre_pd[k]
        else:
            u = rng.random(m)
            td = rng.random(m) * HALF_PI
            pd = rng.random(m) * np.pi
        th = u * u * HALF_PI
        ph = rng.random(m) * 2 * np.pi
        # reciprocity: half of the samples with wi and wo swapped (φd + π)
        pd = pd + np.pi * (rng.random(m) < 0.5)
        wi, wo = from_rusinkiewicz(th, ph, td, pd)
        ok = (wi[:, 2] > cos_max) & (wo[:, 2] > cos_max)
        if is_table:
            v = np.moveaxis(model.table[:, i, j, k], 0, -1)
            ok &= (v >= 0).all(axis=-1)
        idx = np.flatnonzero(ok)[: n - have]
        if idx.size == 0:
            continue
        if is_table:
            fv = v[idx]
        else:
            fv = np.asarray(model.eval(wi[idx], wo[idx]), dtype=np.float64)
        wts = np.sin(th[idx]) * (np.pi * u[idx]) * np.sin(td[idx]) * np.cos(td[idx])
        wi_l.append(wi[idx])
        wo_l.append(wo[idx])
        f_l.append(fv)
        w_l.append(wts)
        have += idx.size
        if have >= n:
            break
    if have < 16:
        raise ValueError(f"{_source_label(model)}: too few measured samples within {max_theta_deg}° ({have})")
    w = np.concatenate(w_l)
    f = np.concatenate(f_l)
    if not np.isfinite(f).all():
        raise ValueError(f"{_source_label(model)}: measured values are not finite")
    return Samples(np.concatenate(wi_l), np.concatenate(wo_l), f, w / w.mean(), _source_label(model),
                   bool(getattr(model, "isotropic", True)))


def table(measured: Any, max_theta_deg: float = 80.0) -> Samples:
    """Every measured bin as a sample (``samples="table"``): MERL's 90 × 90 × 180 bin centres with
    both directions within ``max_theta_deg`` of the normal, φh = 0 for isotropic data (uniformly
    random φh per bin, seed 0, for anisotropic data such as UTIA),
    weighted as :func:`sample` weights them. From a MERL table the values are the table's (bins
    marked missing are left out); from any other isotropic model (a built-in material) the model
    is evaluated at the bin centres."""
    model = resolve_source(measured)
    if not (0 < max_theta_deg <= 90):
        raise ValueError(f"max_theta_deg must be in (0, 90], got {max_theta_deg}")
    cos_max = math.cos(math.radians(max_theta_deg)) if max_theta_deg < 90 else 0.0
    th, td, pd = bin_centres()
    I, J, K = np.meshgrid(np.arange(RES_THETA_H), np.arange(RES_THETA_D), np.arange(RES_PHI_D), indexing="ij")
    I, J, K = I.ravel(), J.ravel(), K.ravel()
    # isotropic data: φh = 0; anisotropic data: φh drawn uniformly per bin (fixed seed), so every azimuth counts
    if getattr(model, "isotropic", True):
        ph = np.zeros(I.size)
    else:
        ph = np.random.default_rng(0).random(I.size) * 2 * np.pi
    wi, wo = from_rusinkiewicz(th[I], ph, td[J], pd[K])
    ok = (wi[:, 2] > cos_max) & (wo[:, 2] > cos_max)
    if isinstance(model, MERLBRDF):
        v = np.moveaxis(model.table[:, I, J, K], 0, -1)
        ok &= (v >= 0).all(axis=-1)
        idx = np.flatnonzero(ok)
        fv = np.ascontiguousarray(v[idx], dtype=np.float64)
    else:
        idx = np.flatnonzero(ok)
        fv = np.asarray(model.eval(wi[idx], wo[idx]), dtype=np.float64)
    if idx.size < 16:
        raise ValueError(f"{_source_label(model)}: too few measured bins within {max_theta_deg}° ({idx.size})")
    if not np.isfinite(fv).all():
        raise ValueError(f"{_source_label(model)}: measured values are not finite")
    u = (I[idx] + 0.5) / RES_THETA_H
    w = np.sin(th[I[idx]]) * (np.pi * u) * np.sin(td[J[idx]]) * np.cos(td[J[idx]])
    return Samples(np.ascontiguousarray(wi[idx]), np.ascontiguousarray(wo[idx]), fv, w / w.mean(),
                   _source_label(model), bool(getattr(model, "isotropic", True)))


def subsample(data: Samples, n: int, seed: int = 0) -> Samples:
    """A uniformly random subset of ``n`` of ``data``'s samples, weights kept (renormalised to mean 1):
    the same integral estimated from fewer points, for the multi-start search of a table-scale fit."""
    if n >= len(data):
        return data
    rng = np.random.default_rng(seed)
    idx = np.sort(rng.choice(len(data), size=n, replace=False))
    w = data.w[idx]
    return Samples(data.wi[idx], data.wo[idx], data.f[idx], w / w.mean(), data.source, data.isotropic)


__all__ = ["Samples", "resolve_source", "sample", "table", "subsample"]
