"""Importance sampling of BRDF lobes, with the pdf of each routine, and a χ² test of the pair.

Every sampler maps uniform numbers ``u`` (N, 2) in [0, 1)² and a viewing direction ``wo``
(3,) to directions ``wi`` (N, 3) on the unit sphere, and gives the solid-angle density
``pdf(wo, wi)`` of what it samples. Samples that the routine cannot turn into a
direction (e.g. a microfacet normal facing away from wo) come back as NaN rows; the pdf
then integrates to the probability of a valid sample (< 1). Samples below the horizon are
valid directions where the BRDF is zero.

Routines
--------
``CosineHemisphere``      pdf = max(0, cos θ)/π (Malley's method).
``PhongLobe(s)``          around r = reflect(wo): pdf = (s+1)/(2π) max(0, r·wi)^s
                          (Lafortune & Willems 1994).
``BlinnLobe(s)``          h with pdf_h = (s+2)/(2π) (n·h)^(s+1), wi = reflect(wo, h);
                          pdf = pdf_h / (4 |wo·h|) (Walter et al. 2007, eq. 14).
``MicrofacetH(d, αx, αy)`` h from D(h)(n·h), D Beckmann or GGX, anisotropic
                          (Walter et al. 2007, eqs. 28, 35; Ward's half-vector sampling is the
                          Beckmann case, Walter 2005 "Notes on the Ward BRDF").
``GGXVisible(αx, αy)``    h from the distribution of visible normals
                          D_wo(h) = G1(wo) max(0, wo·h) D(h) / cos θo (Heitz 2018,
                          "Sampling the GGX Distribution of Visible Normals", JCGT 7(4));
                          pdf = G1(wo) D(h) / (4 cos θo).
``Mixture``               one-sample mixture of the above by weights.

:func:`sampler_for` builds the sampler of a registered model from its parameters;
:func:`chi2_test` checks a sampler against its pdf (as Mitsuba 3's ``ChiSquareTest`` and
pbrt-v4's sampling tests do); :func:`albedo_mc` estimates the albedo with it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..geometry import frame_from_normal, half_vector, reflect, spherical_to_vector
from .albedo import _gl

_INV_PI = 1.0 / math.pi


class Sampler:
    """Base class: ``sample(wo, u) -> wi`` and ``pdf(wo, wi) -> density``."""

    def sample(self, wo: np.ndarray, u: np.ndarray) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    def pdf(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError


class CosineHemisphere(Sampler):
    def sample(self, wo, u):
        r = np.sqrt(u[:, 0])
        phi = 2 * math.pi * u[:, 1]
        return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0.0, 1 - u[:, 0]))], -1)

    def pdf(self, wo, wi):
        return np.maximum(wi[..., 2], 0.0) * _INV_PI


@dataclass
class PhongLobe(Sampler):
    s: float

    def sample(self, wo, u):
        r = reflect(wo)
        t, b = frame_from_normal(r)
        c = np.power(1 - u[:, 0], 1.0 / (self.s + 1))  # 1 − u avoids 0^(1/(s+1)) issues
        sn = np.sqrt(np.maximum(0.0, 1 - c * c))
        phi = 2 * math.pi * u[:, 1]
        return c[:, None] * r + (sn * np.cos(phi))[:, None] * t + (sn * np.sin(phi))[:, None] * b

    def pdf(self, wo, wi):
        x = np.maximum(wi @ reflect(wo), 0.0)
        return (self.s + 1) / (2 * math.pi) * np.where(x > 0, np.power(x, self.s), 0.0)


@dataclass
class BlinnLobe(Sampler):
    s: float

    def sample(self, wo, u):
        c = np.power(1 - u[:, 0], 1.0 / (self.s + 2))
        sn = np.sqrt(np.maximum(0.0, 1 - c * c))
        phi = 2 * math.pi * u[:, 1]
        h = np.stack([sn * np.cos(phi), sn * np.sin(phi), c], -1)
        return _valid_reflection(wo, h)

    def pdf(self, wo, wi):
        h = half_vector(wi, wo)
        c = np.maximum(h[..., 2], 0.0)
        ph = (self.s + 2) / (2 * math.pi) * np.power(c, self.s + 1)
        return _h_to_wi(ph, wo, h)


def _valid_reflection(wo: np.ndarray, h: np.ndarray) -> np.ndarray:
    oh = h @ wo
    wi = reflect(wo, h)
    wi[oh <= 0] = np.nan  # h faces away from wo: no reflection (the pdf does not count it)
    return wi


def _h_to_wi(ph: np.ndarray, wo: np.ndarray, h: np.ndarray) -> np.ndarray:
    oh = h @ wo
    ok = (oh > 0) & (h[..., 2] > 0)
    return np.where(ok, ph / (4 * np.where(ok, oh, 1.0)), 0.0)


@dataclass
class MicrofacetH(Sampler):
    distribution: str
    alpha_x: float
    alpha_y: float

    def _d_cos(self, h: np.ndarray) -> np.ndarray:
        """D(h) (n·h) for h in the upper hemisphere."""
        ax, ay = self.alpha_x, self.alpha_y
        c = np.maximum(h[..., 2], 1e-150)
        e = (h[..., 0] / ax) ** 2 + (h[..., 1] / ay) ** 2
        with np.errstate(all="ignore"):
            if self.distribution == "beckmann":
                d = np.exp(-e / (c * c)) / (math.pi * ax * ay * c**4)
            else:
                d = 1.0 / (math.pi * ax * ay * (e + c * c) ** 2)
            d = np.nan_to_num(d, nan=0.0, posinf=0.0)
        return np.where(h[..., 2] > 0, d * c, 0.0)

    def sample(self, wo, u):
        ax, ay = self.alpha_x, self.alpha_y
        # azimuth of the slope distribution: tan φ = (αy/αx) tan(2π u2), same quadrant
        phi = np.arctan2(ay * np.sin(2 * math.pi * u[:, 1]), ax * np.cos(2 * math.pi * u[:, 1]))
        inv_a2 = np.cos(phi) ** 2 / ax**2 + np.sin(phi) ** 2 / ay**2
        u1 = u[:, 0]
        if self.distribution == "beckmann":
            tan2 = -np.log1p(-u1) / inv_a2
        else:
            tan2 = u1 / np.maximum(1 - u1, 1e-300) / inv_a2
        c = 1 / np.sqrt(1 + tan2)
        sn = np.sqrt(np.maximum(0.0, 1 - c * c))
        h = np.stack([sn * np.cos(phi), sn * np.sin(phi), c], -1)
        return _valid_reflection(wo, h)

    def pdf(self, wo, wi):
        h = half_vector(wi, wo)
        return _h_to_wi(self._d_cos(h), wo, h)


@dataclass
class GGXVisible(Sampler):
    alpha_x: float
    alpha_y: float

    def _g1(self, w: np.ndarray) -> np.ndarray:
        z2 = np.maximum(w[..., 2] ** 2, 1e-300)
        a2t2 = ((w[..., 0] * self.alpha_x) ** 2 + (w[..., 1] * self.alpha_y) ** 2) / z2
        return 2.0 / (1.0 + np.sqrt(1.0 + a2t2))

    def sample(self, wo, u):
        ax, ay = self.alpha_x, self.alpha_y
        # Heitz 2018, listing 1: stretch, sample the projected hemisphere, unstretch
        vh = np.array([ax * wo[0], ay * wo[1], wo[2]])
        vh /= np.linalg.norm(vh)
        lensq = vh[0] ** 2 + vh[1] ** 2
        t1 = np.array([-vh[1], vh[0], 0.0]) / math.sqrt(lensq) if lensq > 0 else np.array([1.0, 0.0, 0.0])
        t2 = np.cross(vh, t1)
        r = np.sqrt(u[:, 0])
        phi = 2 * math.pi * u[:, 1]
        p1 = r * np.cos(phi)
        p2 = r * np.sin(phi)
        s = 0.5 * (1.0 + vh[2])
        p2 = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - p1 * p1)) + s * p2
        nh = p1[:, None] * t1 + p2[:, None] * t2 + np.sqrt(np.maximum(0.0, 1 - p1 * p1 - p2 * p2))[:, None] * vh
        h = np.stack([ax * nh[:, 0], ay * nh[:, 1], np.maximum(1e-12, nh[:, 2])], -1)
        h /= np.linalg.norm(h, axis=-1, keepdims=True)
        return _valid_reflection(wo, h)

    def pdf(self, wo, wi):
        h = half_vector(wi, wo)
        d_cos = MicrofacetH("ggx", self.alpha_x, self.alpha_y)._d_cos(h)
        c = np.maximum(h[..., 2], 1e-300)
        oh = h @ wo
        ok = (h[..., 2] > 0) & (oh > 0) & (wo[2] > 0)
        # D_wo(h) = G1(wo) (wo·h) D(h) / cos θo;  pdf = D_wo / (4 wo·h) = G1(wo) D(h) / (4 cos θo)
        val = self._g1(wo) * (d_cos / c) / (4 * max(wo[2], 1e-300))
        return np.where(ok, val, 0.0)


@dataclass
class Mixture(Sampler):
    """One-sample mixture: component k with probability weights[k] / sum(weights)."""

    components: Sequence[Sampler]
    weights: Sequence[float]

    def __post_init__(self) -> None:
        w = np.asarray(self.weights, dtype=np.float64)
        if w.ndim != 1 or len(w) != len(self.components) or np.any(w < 0) or not w.sum() > 0:
            raise ValueError("Mixture: weights must be non-negative, one per component, not all zero")
        self._p = w / w.sum()

    def sample(self, wo, u):
        cdf = np.cumsum(self._p)
        k = np.minimum(np.searchsorted(cdf, u[:, 0], side="right"), len(cdf) - 1)
        lo = np.concatenate([[0.0], cdf[:-1]])[k]
        u0 = np.clip((u[:, 0] - lo) / np.maximum(self._p[k], 1e-300), 0.0, np.nextafter(1.0, 0.0))
        uu = np.stack([u0, u[:, 1]], -1)
        out = np.empty((len(u), 3))
        for j, comp in enumerate(self.components):
            m = k == j
            if np.any(m):
                out[m] = comp.sample(wo, uu[m])
        return out

    def pdf(self, wo, wi):
        return sum(p * c.pdf(wo, wi) for p, c in zip(self._p, self.components) if p > 0)


# ---------------------------------------------------------------------------------------------
def _lum(v: Any) -> float:
    a = np.broadcast_to(np.asarray(v, dtype=np.float64), (3,))
    return float(a @ np.array([0.2126, 0.7152, 0.0722]))


def sampler_for(model: Any) -> Sampler:
    """The importance sampler of a registered model (a cosine-weighted fallback otherwise)."""
    name = getattr(model, "name", "")
    p = getattr(model, "params", {}) or {}
    diffuse = CosineHemisphere()

    def mix(kd: float, lobe: Sampler, ks: float) -> Sampler:
        if kd <= 0 and ks <= 0:
            return diffuse
        return Mixture([diffuse, lobe], [max(kd, 0.0), max(ks, 0.0)])

    if name == "phong":
        return mix(_lum(p["kd"]), PhongLobe(float(p["shininess"])), _lum(p["ks"]))
    if name == "blinn-phong":
        return mix(_lum(p["kd"]), BlinnLobe(float(p["shininess"])), _lum(p["ks"]))
    if name == "cook-torrance":
        return mix(_lum(p["kd"]), MicrofacetH("beckmann", float(p["m"]), float(p["m"])), _lum(p["ks"]))
    if name == "ward":
        return mix(_lum(p["kd"]), MicrofacetH("beckmann", float(p["alpha_x"]), float(p["alpha_y"])), _lum(p["ks"]))
    if name == "microfacet":
        ax, ay = float(p["alpha_x"]), float(p["alpha_y"])
        lobe = GGXVisible(ax, ay) if p.get("distribution") == "ggx" else MicrofacetH("beckmann", ax, ay)
        return mix(_lum(p.get("kd", 0.0)), lobe, _lum(p.get("ks", 1.0)))
    return diffuse


def _as_wo(wo: Any) -> np.ndarray:
    wo = np.asarray(wo, dtype=np.float64)
    if wo.shape != (3,) or not np.all(np.isfinite(wo)) or wo[2] <= 0:
        raise ValueError("sampling: wo must be a finite (3,) vector above the horizon")
    return wo / np.linalg.norm(wo)


def chi2_test(
    sampler: Sampler,
    wo,
    *,
    n: int = 200_000,
    res: tuple[int, int] = (24, 64),
    seed: int = 0,
    sub: int = 6,
    min_expected: float = 5.0,
) -> dict[str, Any]:
    """Pearson χ² goodness of fit of ``sampler.sample`` against ``sampler.pdf``.

    The upper hemisphere (where a BRDF lives) is cut into ``res`` bins uniform in
    (cos θ, φ); the expected count of a bin is ``n`` × the integral of the pdf over it
    (Gauss-Legendre, ``sub``² nodes per bin). Everything else — samples below the
    horizon and samples the routine could not produce — forms one more bin whose expected
    count is ``n`` minus the rest, so a pdf of the wrong total mass fails too. (Below the
    horizon a half-vector pdf has an integrable 1/(wo·h) singularity at wi = −wo that a
    fixed bin rule cannot integrate.) Bins expecting fewer than ``min_expected`` samples
    are pooled. Returns ``{"p_value", "chi2", "dof", "observed_upper", "expected_upper",
    "stray"}``; a correct sampler gives a p-value uniform in [0, 1], a wrong one ≈ 0.
    """
    from scipy.stats import chi2 as chi2_dist

    wo = _as_wo(wo)
    rng = np.random.default_rng(seed)
    wi = sampler.sample(wo, rng.random((n, 2)))
    ok = np.all(np.isfinite(wi), axis=-1)
    wi = wi[ok]
    wi = wi / np.linalg.norm(wi, axis=-1, keepdims=True)
    up = wi[:, 2] > 0
    wi = wi[up]
    zb = np.linspace(0.0, 1.0, res[0] + 1)
    pb = np.linspace(0.0, 2 * math.pi, res[1] + 1)
    obs, _, _ = np.histogram2d(
        np.clip(wi[:, 2], 0, 1), np.mod(np.arctan2(wi[:, 1], wi[:, 0]), 2 * math.pi), bins=[zb, pb]
    )
    x, w = _gl(sub)  # Gauss-Legendre on [0, 1]
    z = (zb[:-1, None] + np.diff(zb)[:, None] * x).ravel()
    wz = (np.diff(zb)[:, None] * w).ravel()
    ph = (pb[:-1, None] + np.diff(pb)[:, None] * x).ravel()
    wp = (np.diff(pb)[:, None] * w).ravel()
    Z, P = np.meshgrid(z, ph, indexing="ij")
    st = np.sqrt(np.maximum(0.0, 1 - Z**2))
    dirs = np.stack([st * np.cos(P), st * np.sin(P), Z], -1).reshape(-1, 3)
    with np.errstate(all="ignore"):
        dens = sampler.pdf(wo, dirs).reshape(Z.shape) * wz[:, None] * wp[None, :]
    exp = dens.reshape(res[0], sub, res[1], sub).sum(axis=(1, 3)).ravel() * n
    obs = obs.ravel()
    rest_obs = float(n - obs.sum())
    rest_exp = float(n - exp.sum())
    small = exp < min_expected
    o = np.concatenate([obs[~small], [obs[small].sum(), rest_obs]])
    e = np.concatenate([exp[~small], [exp[small].sum(), max(rest_exp, 0.0)]])
    keep = e > 1e-9
    stray = float(o[~keep].sum())  # samples where the pdf says none can be
    o, e = o[keep], e[keep]
    stat = float(np.sum((o - e) ** 2 / e))
    dof = max(1, len(o) - 1)
    p = float(chi2_dist.sf(stat, dof)) if stray == 0 else 0.0
    return {
        "p_value": p,
        "chi2": stat,
        "dof": dof,
        "observed_upper": int(obs.sum()),
        "expected_upper": float(exp.sum()),
        "stray": stray,
    }


def albedo_mc(model: Any, theta_o: float, *, n: int = 200_000, seed: int = 0, sampler: Sampler | None = None):
    """Monte Carlo a(wo) = E[f(wi, wo) cos θi / pdf(wi)] with the model's sampler.

    Returns ``(mean (3,), standard error (3,))``.
    """
    if not 0 <= theta_o < math.pi / 2:
        raise ValueError("albedo_mc: theta_o must lie in [0, π/2)")
    wo = spherical_to_vector(theta_o, 0.0)
    s = sampler or sampler_for(model)
    rng = np.random.default_rng(seed)
    wi = s.sample(wo, rng.random((n, 2)))
    ok = np.all(np.isfinite(wi), axis=-1) & (np.nan_to_num(wi[:, 2]) > 0)
    est = np.zeros((n, 3))
    if np.any(ok):
        w = wi[ok]
        pdf = s.pdf(wo, w)
        f = np.asarray(model.eval(w, wo), dtype=np.float64)
        est[ok] = np.where(pdf[:, None] > 0, f * w[:, 2:3] / np.where(pdf > 0, pdf, 1.0)[:, None], 0.0)
    return est.mean(0), est.std(0) / math.sqrt(n)


__all__ = [
    "Sampler",
    "CosineHemisphere",
    "PhongLobe",
    "BlinnLobe",
    "MicrofacetH",
    "GGXVisible",
    "Mixture",
    "sampler_for",
    "chi2_test",
    "albedo_mc",
]
