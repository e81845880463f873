"""Energy compensation for multiple scattering between microfacets (Kulla & Conty 2017).

References: C. Kulla, A. Conty, "Revisiting Physically Based Shading at Imageworks",
SIGGRAPH 2017 course "Physically Based Shading in Theory and Practice" (the
energy-compensation lobe and its Fresnel-weighted form); E. Turquin, "Practical
multiple scattering compensation for microfacet models", ILM technical report, 2019
(the same tabulated albedos, used there to scale the single-scattering lobe; we keep
Kulla & Conty's additive lobe because it is reciprocal). The idea goes back to
Kelemen & Szirmay-Kalos, "A Microfacet Based Coupled Specular-Matte BRDF Model with
Importance Sampling", Eurographics 2001.

A single-scattering microfacet lobe with F = 1 reflects only the directional albedo

    E(μ) = ∫ f_ss(wi, wo) cos θi dωi ,   μ = cos θo,

of the light (the rest would bounce again between the facets). The compensation lobe

    f_ms(wi, wo) = (1 − E(μi)) (1 − E(μo)) / (π (1 − E_avg)),   E_avg = 2 ∫₀¹ E(μ) μ dμ,

adds exactly the missing 1 − E(μo) (integrate over wi: 2∫(1 − E(μ)) μ dμ = 1 − E_avg) and is
symmetric in wi, wo, so f_ss + f_ms is reciprocal and white-furnace neutral. For a coloured
Fresnel term the light lost at each extra bounce is coloured too; Kulla & Conty weight the
lobe by the geometric series of the hemispherical Fresnel average F_avg = 2 ∫₀¹ F(μ) μ dμ:

    f_ms,F = f_ms · F_avg² E_avg / (1 − F_avg (1 − E_avg))              (= f_ms when F = 1).

The factor depends on the material only, not on the directions, so reciprocity is kept.

Tables
------
``E`` is tabulated on a grid of μ (33 nodes, uniform on [0, 1], the first node at
μ = 1e-3) by α (33 nodes, uniform on [0, 1]; α = 0 is the mirror, E = 1), for each
distribution (Beckmann, GGX) and each shadowing term (separable Smith,
height-correlated Smith, V-groove), by this project's own quadrature
(:func:`brdfkit.analysis.albedo.albedo`, ``level="fine"``, F = 1, kd = 0) —
:func:`build_tables` rebuilds ``data/multiscatter.npz``. Lookups interpolate linearly
in α and then in μ. ``E_avg`` is the exact moment of the piecewise-linear E(μ), so the
compensation integrates to 1 − E(μo) as given by the table; what remains in a
white furnace is the interpolation error of E (below 0.3 % up to 80°, measured in
tests/test_multiscatter.py).

Anisotropic roughness uses the isotropic table at α = √(αx αy) (an approximation; the
white-furnace figures above are for isotropic surfaces).

The lookup functions use plain arithmetic on arrays or scalars and take the tables as
arguments, so that a compiled kernel can call them unchanged.
"""

from __future__ import annotations

import math
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable

import numpy as np

DATA_PATH = Path(__file__).resolve().with_name("data") / "multiscatter.npz"
DISTRIBUTIONS = ("beckmann", "ggx")
SHADOWINGS = ("smith", "smith-correlated", "v-groove")
N_MU = 33
N_ALPHA = 33
MU_MIN = 1e-3


def mu_grid(n: int = N_MU) -> np.ndarray:
    """The μ nodes of the tables: uniform on [0, 1], the first one moved to μ = 1e-3."""
    mu = np.linspace(0.0, 1.0, n)
    mu[0] = MU_MIN
    return mu


def alpha_grid(n: int = N_ALPHA) -> np.ndarray:
    return np.linspace(0.0, 1.0, n)


def table_key(distribution: str, shadowing: str) -> str:
    return f"E_{distribution}_{shadowing}"


# ---------------------------------------------------------------------------------------------
# lookups (plain arithmetic; tables passed in)
# ---------------------------------------------------------------------------------------------
def interp_uniform(x, values, x0: float, x1: float):
    """Piecewise-linear interpolation of ``values`` given at nodes uniform on [x0, x1] (x clamped)."""
    n = values.shape[-1]
    s = np.clip((x - x0) / (x1 - x0), 0.0, 1.0) * (n - 1)
    i = np.minimum(np.floor(s), n - 2).astype(np.int64)
    t = s - i
    return values[..., i] * (1.0 - t) + values[..., i + 1] * t


def albedo_row(table: np.ndarray, alpha: float) -> np.ndarray:
    """E(μ_j) at roughness ``alpha`` for every μ node: the table interpolated linearly in α."""
    return interp_uniform(np.float64(alpha), table.T, 0.0, 1.0)


def albedo_lookup(row: np.ndarray, mu):
    """E(μ) (or 1 − E(μ)) from a row of :func:`albedo_row` (or 1 − row): linear in μ between the nodes."""
    # the nodes are uniform from 0 to 1 except the first, which sits at MU_MIN: interpolate on the
    # uniform grid with the first value standing for μ = 0 (E is flat there to far below 1e-3)
    return interp_uniform(mu, row, 0.0, 1.0)


def average_albedo(row: np.ndarray) -> float:
    """E_avg = 2 ∫₀¹ E(μ) μ dμ of the piecewise-linear E that :func:`albedo_lookup` returns (exact)."""
    n = row.shape[-1]
    h = 1.0 / (n - 1)
    a = np.arange(n - 1) * h
    b = a + h
    ea, eb = row[:-1], row[1:]
    # ∫_a^b (ea (b − μ) + eb (μ − a))/h · μ dμ = h (ea (2a + b) + eb (a + 2b)) / 6
    return float(2.0 * np.sum(h * (ea * (2 * a + b) + eb * (a + 2 * b)) / 6.0))


def fresnel_average(fresnel: Callable[[np.ndarray], np.ndarray], n: int = 64) -> np.ndarray:
    """F_avg = 2 ∫₀¹ F(μ) μ dμ by Gauss-Legendre (``n`` nodes); ``fresnel(μ)`` gives (n, 3)."""
    x, w = np.polynomial.legendre.leggauss(n)
    mu = 0.5 * (x + 1.0)
    f = np.asarray(fresnel(mu), dtype=np.float64).reshape(n, -1)
    return (f * (mu * w)[:, None]).sum(0)  # 2 · ∫ → the 1/2 of the interval cancels the 2


def fresnel_weight(f_avg, e_avg: float):
    """Kulla & Conty's colour factor F_avg² E_avg / (1 − F_avg (1 − E_avg)) (1 when F_avg = 1)."""
    f_avg = np.asarray(f_avg, dtype=np.float64)
    return f_avg * f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg))


def lobe_scale(e_avg: float) -> float:
    """1 / (π (1 − E_avg)), 0 where the surface is so smooth that nothing is missing."""
    gap = 1.0 - e_avg
    return 1.0 / (math.pi * gap) if gap > 1e-7 else 0.0


def compensation(m_i, m_o, scale):
    """f_ms = scale · (1 − E(μi)) (1 − E(μo)) from the missing energies m = 1 − E; symmetric in wi, wo."""
    return scale * (m_i * m_o)


# ---------------------------------------------------------------------------------------------
# tables
# ---------------------------------------------------------------------------------------------
@lru_cache(maxsize=1)
def _tables() -> dict[str, np.ndarray]:
    with np.load(DATA_PATH) as z:
        return {k: np.asarray(z[k], dtype=np.float64) for k in z.files}


def table(distribution: str, shadowing: str) -> np.ndarray:
    """E(α_k, μ_j), shape (N_ALPHA, N_MU), for a distribution and a shadowing term."""
    t = _tables()
    key = table_key(distribution, shadowing)
    if key not in t:
        raise ValueError(f"multiscatter: no albedo table for {distribution}/{shadowing}")
    return t[key]


def effective_alpha(alpha_x: float, alpha_y: float) -> float:
    return math.sqrt(float(alpha_x) * float(alpha_y))


def setup(p: dict[str, Any], fresnel: Callable[[np.ndarray], np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """What the compensation of one material needs: the missing-energy row 1 − E(μ_j) at its α
    and the RGB factor ``ks · F-weight / (π (1 − E_avg))``, from the microfacet parameters.
    (1 − E is passed on rather than E, so that float32 code does not lose it to cancellation
    where E is within 1e-5 of 1.)"""
    row = albedo_row(table(p["distribution"], p["shadowing"]), effective_alpha(p["alpha_x"], p["alpha_y"]))
    e_avg = average_albedo(row)
    weight = fresnel_weight(fresnel_average(fresnel), e_avg)
    ks = np.broadcast_to(np.asarray(p["ks"], dtype=np.float64), (3,))
    return 1.0 - row, ks * weight * lobe_scale(e_avg)


def multiscatter_term(cos_i, cos_o, missing: np.ndarray, scale: np.ndarray, dtype=np.float64):
    """The RGB compensation lobe, shape ``cos_i.shape + (3,)``, for the row and scale of :func:`setup`."""
    m_i = albedo_lookup(missing, np.asarray(cos_i, dtype=np.float64))
    m_o = albedo_lookup(missing, np.asarray(cos_o, dtype=np.float64))
    return compensation(m_i[..., None], m_o[..., None], scale).astype(dtype, copy=False)


def glsl_uniforms(model: Any) -> dict[str, Any]:
    """``u_ms_missing`` (the 1 − E row, N_MU floats) and ``u_ms_scale`` (RGB) for shaders/microfacet.glsl."""
    from ..models.microfacet import fresnel_term

    p = model.params
    if not p.get("multiscatter"):
        return {"u_ms_missing": [0.0] * N_MU, "u_ms_scale": (0.0, 0.0, 0.0)}
    row, scale = setup(p, lambda mu: fresnel_term(p["fresnel"], mu, p, np.dtype(np.float64)))
    return {"u_ms_missing": [float(x) for x in row], "u_ms_scale": tuple(float(x) for x in scale)}


def build_tables(path: Path = DATA_PATH, level: str = "fine") -> dict[str, np.ndarray]:
    """Tabulate E(μ, α) with this project's quadrature and write them to ``path`` (atomically)."""
    import brdfkit as bk
    from ..analysis.albedo import albedo
    from ..fileio import atomic_open

    mu = mu_grid()
    alphas = alpha_grid()
    theta = np.arccos(mu)
    out: dict[str, np.ndarray] = {"mu": mu, "alpha": alphas}
    for d in DISTRIBUTIONS:
        for s in SHADOWINGS:
            t = np.ones((len(alphas), len(mu)))
            for k, a in enumerate(alphas):
                if a == 0.0:
                    continue  # the mirror: E = 1
                m = bk.model("microfacet", distribution=d, shadowing=s, alpha=float(a), fresnel="none", kd=0.0, ks=1.0)
                t[k] = albedo(m, theta, level=level)[:, 0]
            out[table_key(d, s)] = t
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_open(path, "wb") as fh:
        np.savez_compressed(fh, **out)
    _tables.cache_clear()
    return out


__all__ = [
    "albedo_row", "albedo_lookup", "average_albedo", "fresnel_average", "fresnel_weight", "lobe_scale",
    "compensation", "table", "setup", "multiscatter_term", "glsl_uniforms", "build_tables",
    "mu_grid", "alpha_grid", "DISTRIBUTIONS", "SHADOWINGS",
]
