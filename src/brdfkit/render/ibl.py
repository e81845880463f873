"""Image-based lighting: the GL side's inputs and an independent numpy reference.

The GLSL estimator (``shaders/ibl.glsl`` with ``shaders/ibl_sampling.glsl``) computes,
per pixel,

    L_o(wo) = ∫ f_r(wi, wo) L_env(wi) cos θi dωi

by Monte Carlo with multiple importance sampling (Veach & Guibas 1995, power heuristic)
of the BRDF (the routine :func:`brdfkit.analysis.sampling.sampler_for` picks for the
model, ported to GLSL; cosine-weighted for models without one; for measured materials a
cosine + GGX mixture sized by :func:`measured_lobe`) and of the environment
(its luminance CDF, :meth:`Environment.sampling_tables`), accumulated over passes. The
object does not shadow itself (no visibility test).

:func:`reference_linear` is the same integral by brute force in numpy — every
environment texel split into ``sub × sub`` cells uniform in solid angle, the model's
numpy ``eval`` at each cell centre — on the same G-buffer the GL rasterises; converged
GL renders must agree with it (tests/test_render_ibl.py states the tolerance).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..geometry import normalize
from .environment import Environment, direction_to_texel, row_solid_angles

LOBES = {"none": 0, "phong": 1, "blinn": 2, "beckmann-h": 3, "ggx-h": 4, "ggx-visible": 5}


def sampler_uniforms(model: Any) -> dict[str, Any]:
    """``bki_lobe``, ``bki_lobe_params``, ``bki_diffuse_prob`` for the model's sampler
    (:func:`brdfkit.analysis.sampling.sampler_for`, translated, not re-decided)."""
    from ..analysis import sampling as s
    from .glsl import is_measured

    if is_measured(model):
        # no sampler in analysis/sampling.py for tabulated data: a cosine + GGX mixture sized from
        # the material's own peak (measured_lobe); any positive pdf keeps the estimate unbiased
        a, pd = measured_lobe(model)
        return {"bki_lobe": LOBES["ggx-h"], "bki_lobe_params": (a, a), "bki_diffuse_prob": pd}
    smp = s.sampler_for(model)
    comps, probs = ([smp], [1.0]) if not isinstance(smp, s.Mixture) else (list(smp.components), list(smp._p))
    pd = 0.0
    lobe, params = "none", (0.0, 0.0)
    for c, p in zip(comps, probs):
        if isinstance(c, s.CosineHemisphere):
            pd += float(p)
        elif isinstance(c, s.PhongLobe):
            lobe, params = "phong", (float(c.s), 0.0)
        elif isinstance(c, s.BlinnLobe):
            lobe, params = "blinn", (float(c.s), 0.0)
        elif isinstance(c, s.MicrofacetH):
            lobe = "beckmann-h" if c.distribution == "beckmann" else "ggx-h"
            params = (float(c.alpha_x), float(c.alpha_y))
        elif isinstance(c, s.GGXVisible):
            lobe, params = "ggx-visible", (float(c.alpha_x), float(c.alpha_y))
        else:  # pragma: no cover - a sampler the GLSL does not know: fall back to the cosine
            pd += float(p)
    if lobe == "none":
        pd = 1.0
    return {"bki_lobe": LOBES[lobe], "bki_lobe_params": params, "bki_diffuse_prob": min(max(pd, 0.0), 1.0)}


_LOBE_CACHE: dict[str, tuple[float, float]] = {}


def measured_lobe(model: Any) -> tuple[float, float]:
    """A GGX α and a diffuse probability for sampling a measured material, from its values at
    θo = 20°: the half-width θ½ of the peak around the mirror direction (above the diffuse
    floor, the value 60° away) gives α = tan θ½ / √(√2 − 1) (where a GGX D falls to one half);
    the diffuse probability is π f_floor over that plus the peak's albedo ≈ 4π α² cos² θo (f_peak − f_floor),
    clipped to [0.1, 0.9]."""
    from .glsl import table_key

    key = table_key(model)
    hit = _LOBE_CACHE.get(key)
    if hit is not None:
        return hit
    to = math.radians(20.0)
    wo = np.array([math.sin(to), 0.0, math.cos(to)])
    # the half vector tilted from the normal by δ (in the plane ⟂ to the incidence plane): wi = reflect(wo, h)
    deltas = np.radians(np.array([0.0, 0.25, 0.5, 1, 1.5, 2, 3, 4, 6, 8, 11, 15, 20, 27, 35]))
    h = np.stack([np.zeros_like(deltas), np.sin(deltas), np.cos(deltas)], -1)
    wi = 2 * (h @ wo)[:, None] * h - wo
    ok = wi[:, 2] > 0.05
    far = np.array([[-math.sin(math.radians(60)), 0.0, math.cos(math.radians(60))]])  # 40° from the mirror direction
    f = np.asarray(model.eval(normalize(wi[ok]), np.broadcast_to(wo, (ok.sum(), 3))), dtype=np.float64) @ np.array([0.2126, 0.7152, 0.0722])
    floor = float(np.asarray(model.eval(normalize(far), wo[None]), dtype=np.float64)[0] @ np.array([0.2126, 0.7152, 0.0722]))
    peak = f - min(floor, f.min())
    d = deltas[ok]
    below = np.flatnonzero(peak < 0.5 * peak[0])
    half = d[below[0]] if below.size else d[-1]
    alpha = float(np.clip(math.tan(half) / math.sqrt(math.sqrt(2) - 1), 0.005, 1.0))
    spec = 4 * math.pi * alpha**2 * math.cos(to) ** 2 * max(float(peak[0]), 0.0)
    diff = math.pi * max(floor, 0.0)
    pd = float(np.clip(diff / max(diff + spec, 1e-12), 0.1, 0.9))
    _LOBE_CACHE[key] = (alpha, pd)
    return alpha, pd


def rotation_part(m3: np.ndarray) -> np.ndarray:
    """The rotation of a 3×3 matrix (polar decomposition), so that scaled modelviews keep directions' densities."""
    u, _, vt = np.linalg.svd(np.asarray(m3, dtype=np.float64))
    r = u @ vt
    if np.linalg.det(r) < 0:  # pragma: no cover - a mirroring modelview
        u[:, -1] *= -1
        r = u @ vt
    return r


def eye_to_map(modelview: np.ndarray, env: Environment) -> np.ndarray:
    """Eye-space direction → map-frame direction: the inverse of the modelview's rotation, then the map's."""
    return env.world_to_map() @ rotation_part(np.asarray(modelview)[:3, :3]).T


def env_texture_data(env: Environment) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(RGBA radiance·strength + pdf, marginal CDF (1, H), conditional CDFs (H, W)) as float32."""
    marg, cond, s = env.sampling_tables()
    rgba = np.empty(env.shape + (4,), np.float32)
    rgba[..., :3] = env.rgb * np.float32(1.0)
    rgba[..., 3] = env.sampling_luminance() / np.float32(s)
    return rgba, marg.reshape(1, -1), cond


def camera_rays(projection: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Eye-space unit directions (H, W, 3) through the pixel centres, top row first."""
    w, h = size
    x = (np.arange(w) + 0.5) / w * 2 - 1
    y = 1 - (np.arange(h) + 0.5) / h * 2
    X, Y = np.meshgrid(x, y)
    ndc = np.stack([X, Y, np.ones_like(X), np.ones_like(X)], -1)
    inv = np.linalg.inv(np.asarray(projection, dtype=np.float64))
    p = ndc @ inv.T
    far = p[..., :3] / p[..., 3:4]
    return normalize(far)


def background_radiance(projection: np.ndarray, modelview: np.ndarray, size, env: Environment) -> np.ndarray:
    """The environment seen through each pixel (H, W, 3), top row first."""
    d = camera_rays(projection, size) @ eye_to_map(modelview, env).T
    r, c = direction_to_texel(d, *env.shape)
    return env.rgb[r, c].astype(np.float64) * env.strength


def _cell_directions(env: Environment, sub: int) -> tuple[np.ndarray, np.ndarray]:
    """Map-frame directions (N, 3) of ``sub × sub`` cells per texel (uniform in cos θ and φ), and their
    radiance·solid angle (N, 3)."""
    h, w = env.shape
    edges = np.cos(np.arange(h + 1) * math.pi / h)
    k = (np.arange(sub) + 0.5) / sub
    ct = (edges[:-1, None] + (edges[1:] - edges[:-1])[:, None] * k[None, :]).ravel()  # (h*sub,)
    phi = (((np.arange(w)[:, None] + k[None, :]).ravel()) / w - 0.5) * 2 * math.pi  # (w*sub,)
    st = np.sqrt(np.maximum(0.0, 1 - ct**2))
    d = np.stack(
        [st[:, None] * np.sin(phi)[None, :], np.broadcast_to(ct[:, None], (ct.size, phi.size)),
         -st[:, None] * np.cos(phi)[None, :]], -1,
    )
    om = np.repeat(row_solid_angles(h, w) / (sub * sub), sub)  # per cell row
    rad = np.repeat(np.repeat(env.rgb.astype(np.float64), sub, 0), sub, 1) * env.strength
    return d.reshape(-1, 3), (rad * om[:, None, None]).reshape(-1, 3)


def reference_shade(model: Any, P: np.ndarray, n: np.ndarray, t: np.ndarray, modelview: np.ndarray,
                    env: Environment, sub: int = 3, chunk: int = 4_000_000) -> np.ndarray:
    """Brute-force L_o (N, 3) at eye-space points P with normals n and tangents t (N, 3)."""
    from .lighting import orthonormal_tangent

    n = normalize(np.asarray(n, dtype=np.float64))
    t = orthonormal_tangent(n, np.asarray(t, dtype=np.float64))
    b = np.cross(n, t)
    v = normalize(-np.asarray(P, dtype=np.float64))
    wo = np.stack([(v * t).sum(-1), (v * b).sum(-1), (v * n).sum(-1)], -1)
    d_map, le = _cell_directions(env, sub)
    d_eye = d_map @ eye_to_map(modelview, env)  # rows: (M^T d)ᵀ
    out = np.zeros((len(P), 3))
    per = max(1, chunk // len(d_eye))
    for i in range(0, len(P), per):
        sl = slice(i, i + per)
        wi = np.stack([d_eye @ t[sl].T, d_eye @ b[sl].T, d_eye @ n[sl].T], -1)  # (D, p, 3)
        wi = np.moveaxis(wi, 0, 1)  # (p, D, 3)
        up = wi[..., 2] > 0
        wo_b = np.broadcast_to(wo[sl][:, None, :], wi.shape)
        ok = up & (wo_b[..., 2] > 0)
        f = np.zeros(wi.shape)
        if ok.any():
            f[ok] = np.asarray(model.eval(wi[ok], wo_b[ok]), dtype=np.float64)
        out[sl] = np.einsum("pdc,pd,dc->pc", f, np.where(ok, wi[..., 2], 0.0), le)
    return out


__all__ = ["sampler_uniforms", "eye_to_map", "env_texture_data", "camera_rays", "background_radiance",
           "reference_shade", "rotation_part", "LOBES"]
