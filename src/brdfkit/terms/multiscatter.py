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
(:func:`brdfkit.analysis.albedo.albedo`, ``level="fine"``, F = 1, kd = 0):
``python -m brdfkit.analysis.multiscatter_tables`` rebuilds ``data/multiscatter.npz``
(:func:`brdfkit.analysis.multiscatter_tables.build_tables`). Lookups interpolate linearly
in α and then in μ. ``E_avg`` is the exact moment of the piecewise-linear E(μ), so the
compensation integrates to 1 − E(μo) as given by the table; what remains in a
white furnace is the interpolation error of E (below 0.3 % up to 80°, measured in
tests/test_multiscatter.py).

Anisotropic roughness uses the isotropic table at α = √(αx αy) (an approximation; the
white-furnace figures above are for isotropic surfaces).

The lookup functions use plain arithmetic on arrays or scalars and take the tables as
arguments, so that a compiled kernel can call them unchanged. The GLSL twin
(``shaders/microfacet.glsl``) reads the same tables as constant arrays (1 − E, so that
float32 does not lose it where E is within 1e-5 of 1) from ``shaders/multiscatter_tables.glsl``,
whose text is :func:`glsl_tables` (written by ``python -m brdfkit.render.generate``), and
computes the row, E_avg and F_avg itself (16 Gauss-Legendre nodes, as here): no uniforms
beyond the model's parameters, so WebGL pages need nothing extra.

This module imports no other part of brdfkit but the engine: the tables are built elsewhere
(:mod:`brdfkit.analysis.multiscatter_tables`), the GLSL file written by :mod:`brdfkit.render.generate`.
"""

from __future__ import annotations

import math
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..engine import jit

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


@jit
def lookup_uniform(values, off, n, x):
    """``values[off : off + n]`` (nodes uniform on [0, 1]) interpolated linearly at ``x`` (clamped).

    The per-direction lookup of the compiled microfacet kernel: the row of missing energies
    1 − E(μ_j) travels in the kernel's parameter array at offset ``off``.
    """
    s = min(max(x, 0.0), 1.0) * float(n - 1)  # float(): the float32 twin's cast (engine/precision.py)
    i = min(int(math.floor(s)), n - 2)
    t = s - float(i)
    return values[off + i] * (1.0 - t) + values[off + i + 1] * t


def albedo_lookup(row: np.ndarray, mu):
    """E(μ) (or 1 − E(μ)) from a row of :func:`albedo_row` (or 1 − row): linear in μ between the nodes.

    The nodes are uniform from 0 to 1 except the first, which sits at MU_MIN: the lookup is on
    the uniform grid with the first value standing for μ = 0 (E is flat there to far below 1e-3).
    Evaluated by the kernel's own scalar :func:`lookup_uniform`.
    """
    row = np.ascontiguousarray(row, dtype=np.float64)
    mu = np.asarray(mu, dtype=np.float64)
    flat = [lookup_uniform(row, 0, row.shape[-1], float(m)) for m in mu.reshape(-1)]
    return np.asarray(flat, dtype=np.float64).reshape(mu.shape)


def average_albedo(row: np.ndarray) -> float:
    """E_avg = 2 ∫₀¹ E(μ) μ dμ of the piecewise-linear E that :func:`albedo_lookup` returns (exact)."""
    n = row.shape[-1]
    h = 1.0 / (n - 1)
    a = np.arange(n - 1) * h
    b = a + h
    ea, eb = row[:-1], row[1:]
    # ∫_a^b (ea (b − μ) + eb (μ − a))/h · μ dμ = h (ea (2a + b) + eb (a + 2b)) / 6
    return float(2.0 * np.sum(h * (ea * (2 * a + b) + eb * (a + 2 * b)) / 6.0))


FAVG_NODES = 16  # Gauss-Legendre nodes of F_avg (the GLSL twin uses the same ones)


def fresnel_average(fresnel: Callable[[np.ndarray], np.ndarray], n: int = FAVG_NODES) -> np.ndarray:
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


@jit
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


def reload_tables() -> None:
    """Forget the tables read so far: the next lookup reads :data:`DATA_PATH` again (after a rebuild)."""
    _tables.cache_clear()


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


def _glsl_array(kind: str, name: str, items: list[str]) -> str:
    out, cur = [], ""
    for tok in items:
        if cur and len(cur) + len(tok) + 1 > 110:
            out.append(cur)
            cur = ""
        cur += tok + ","
    out.append(cur.rstrip(","))
    return f"const {kind} {name}[{len(items)}] = {kind}[{len(items)}](\n    " + "\n    ".join(out) + ");\n"


def _glsl_float(z: float) -> str:
    t = f"{float(z):.9g}"
    return t if ("." in t or "e" in t or "n" in t) else t + ".0"  # GLSL ES has no int -> float conversion


def glsl_tables() -> str:
    """The GLSL constants of ``shaders/multiscatter_tables.glsl`` (which microfacet.glsl includes): 1 − E per
    table (distribution-major, then shadowing, then α, then μ), 1 − E_avg per table and α, and the F_avg
    quadrature nodes, from the shipped tables (:func:`table`)."""
    miss, avg = [], []
    for d in DISTRIBUTIONS:
        for sh in SHADOWINGS:
            t = table(d, sh)
            miss.append(1.0 - t)
            avg.append([1.0 - average_albedo(row) for row in t])
    miss_a = np.concatenate([m.ravel() for m in miss])
    avg_a = np.concatenate([np.asarray(a) for a in avg])
    x, w = np.polynomial.legendre.leggauss(FAVG_NODES)

    def arr(name: str, v: np.ndarray) -> str:
        return _glsl_array("float", name, [_glsl_float(z) for z in v])

    def arr4(name: str, v: np.ndarray) -> str:
        # packed four to a vec4: Mesa compiles a constant array of n vec4 far faster than one of 4n floats
        v = np.concatenate([v, np.zeros((-len(v)) % 4)])
        items = [f"vec4({','.join(_glsl_float(z) for z in v[i:i + 4])})" for i in range(0, len(v), 4)]
        return _glsl_array("vec4", name, items)

    return (
        f"#define BK_MS_N {N_MU}\n#define BK_MS_FAVG_N {FAVG_NODES}\n"
        + arr4("BK_MS_MISSING4", miss_a) + arr4("BK_MS_MISSING_AVG4", avg_a)
        + arr("BK_MS_FAVG_MU", 0.5 * (x + 1.0)) + arr("BK_MS_FAVG_W", 0.5 * w)
    )


__all__ = [
    "albedo_row", "albedo_lookup", "average_albedo", "fresnel_average", "fresnel_weight", "lobe_scale",
    "compensation", "lookup_uniform", "table", "table_key", "reload_tables", "setup", "glsl_tables",
    "mu_grid", "alpha_grid", "DATA_PATH", "DISTRIBUTIONS", "SHADOWINGS",
]
