"""EON: the energy-preserving Oren-Nayar BRDF (the scalar terms of ``oren-nayar`` ``variant="eon"``).

Reference: J. Portsmouth, P. Kutz and S. Hill, "EON: A Practical Energy-Preserving
Rough Diffuse BRDF", Journal of Computer Graphics Techniques (JCGT) 14(1), 2025,
http://jcgt.org/published/0014/01/06/ (arXiv:2410.18026). The diffuse lobe of
OpenPBR Surface 1.1 (``base_diffuse_roughness``), of MaterialX 1.39's
``oren_nayar_diffuse_bsdf`` with ``energy_compensation = true``, and of the glTF
draft ``KHR_materials_diffuse_roughness``.

The model is registered as a variant of :mod:`brdfkit.models.oren_nayar` (the class,
its parameters and the mapping from ``sigma`` live there); this module holds the
paper's formulas, one small scalar function per term, compiled by the engine and
run uncompiled by the reference engine (:mod:`brdfkit.engine`). Their GLSL twins are
in ``render/shaders/oren_nayar.glsl``.

Formulas (ρ the single-scattering albedo = kd, r ∈ [0, 1] the roughness,
μi = cos θi, μo = cos θo):

1. The single-scattering lobe is Fujii's "FON" form of the qualitative
   Oren-Nayar model (Y. Fujii, https://mimosa-pudica.net/improved-oren-nayar.html,
   as the EON paper restates it)::

       f_ss = (ρ/π) · A · (1 + r · s/t)
       s    = wi·wo − μi μo  (= sin θi sin θo cos Δφ)
       t    = max(μi, μo) if s > 0, else 1
       A    = 1 / (1 + (1/2 − 2/(3π)) r),   B = r A   (f_ss = (ρ/π)(A + B s/t))

2. Its directional albedo, in closed form (derived in the paper)::

       E_FON(μ) = A + (B/π) · G(θ)
       G(θ)     = sin θ (θ − sin θ cos θ) + (2/3) (tan θ (1 − sin³θ) − sin θ)

   and its cosine-weighted average over the hemisphere::

       Ē_FON = 2 ∫₀¹ E_FON(μ) μ dμ = A (1 + (2/3 − 28/(15π)) r)

   The paper also gives a polynomial fit of G/π in 1 − μ (coefficients
   0.0571085289, 0.491881867, −0.332181442, 0.0714429953) for shaders that avoid
   the arccosine: :func:`fon_albedo_approx`. The kernel uses the closed form.

3. The paper's multiple-scattering compensation (after Kelemen &
   Szirmay-Kalos 2001 and Kulla & Conty 2017) adds the energy the single-scattering
   lobe loses, re-scattered with the albedo of the multiple bounces::

       f_ms = (ρ_ms/π) · (1 − E_FON(μi)) (1 − E_FON(μo)) / (1 − Ē_FON)
       ρ_ms = ρ² Ē_FON / (1 − ρ (1 − Ē_FON))

       f_EON = f_ss + f_ms

   Its directional albedo is ρ E_FON(μ) + ρ_ms (1 − E_FON(μ)): exactly 1 for ρ = 1
   at every angle (the white furnace), which the tests check by quadrature.

Numerics. 1 − E_FON(μ) = A r (c1 − G/π) and 1 − Ē_FON = A r (c1 − c2), with
c1 = 1/2 − 2/(3π), c2 = 2/3 − 28/(15π), so the compensation factor is computed as
A r (c1 − G(θi)/π)(c1 − G(θo)/π)/(c1 − c2): no 0/0 at r = 0 (where f_EON is
exactly Lambert, ρ/π). tan θ (1 − sin³θ) is written sin θ cos θ (1 + sin θ + sin²θ)/(1 + sin θ),
finite up to the horizon (G(π/2) = π/2 − 2/3, i.e. E_FON = 1 at grazing). s is
wix·wox + wiy·woy (no cancellation), and t is floored at 1e-6 (COS_FLOOR): f_ss
diverges like 1/max(μi, μo) when both directions approach the horizon at the same
azimuth, as the qualitative model's tan β does; the floor changes values only
within 0.00006° of the horizon.
"""

from __future__ import annotations

import math

from ..engine import jit

#: 1/2 − 2/(3π): FON's A = 1/(1 + c1 r), and c1 = G(π/2)/π
FON_C1 = 0.5 - 2.0 / (3.0 * math.pi)
#: 2/3 − 28/(15π): Ē_FON = A (1 + c2 r)
FON_C2 = 2.0 / 3.0 - 28.0 / (15.0 * math.pi)
#: the paper's polynomial fit of G(θ)/π in (1 − μ): g1, g2, g3, g4
FON_G_FIT = (0.0571085289, 0.491881867, -0.332181442, 0.0714429953)
#: floor on t = max(μi, μo) in s/t
COS_FLOOR = 1e-6


@jit
def fon_a(r):
    """FON's A = 1/(1 + (1/2 − 2/(3π)) r); B = r A."""
    return 1.0 / (1.0 + FON_C1 * r)


@jit
def fon_g(sin_t, cos_t, theta):
    """G(θ) = sin θ (θ − sin θ cos θ) + (2/3)(tan θ (1 − sin³θ) − sin θ), of E_FON = A + (B/π) G."""
    tail = sin_t * cos_t * (1.0 + sin_t + sin_t * sin_t) / (1.0 + sin_t)  # tan θ (1 − sin³θ), finite at π/2
    return sin_t * (theta - sin_t * cos_t) + (2.0 / 3.0) * (tail - sin_t)


@jit
def fon_single(r, s, mu_i, mu_o):
    """A (1 + r s/t): the FON single-scattering lobe without ρ/π (t = max(μi, μo) if s > 0, else 1).

    1 + r s/t ≥ 1 − r ≥ 0 in exact arithmetic (s ≥ −1, r ≤ 1); at r = 1 and wi = −wo on the
    horizon, s rounds below −1 (−1.2e-8 in float32): floored at 0."""
    t = max(max(mu_i, mu_o), COS_FLOOR) if s > 0.0 else 1.0
    return fon_a(r) * max(1.0 + r * (s / t), 0.0)


@jit
def eon_loss(g):
    """(1 − E_FON(μ)) / (A r) = c1 − G/π, floored at 0 (directions a rounding off unit length)."""
    return max(FON_C1 - g / math.pi, 0.0)


@jit
def eon_ms_shape(r, g_i, g_o):
    """(1 − E_FON(μi))(1 − E_FON(μo))/(1 − Ē_FON) = A r (c1 − Gi/π)(c1 − Go/π)/(c1 − c2)."""
    return fon_a(r) * r * eon_loss(g_i) * eon_loss(g_o) / (FON_C1 - FON_C2)


@jit
def eon_avg_albedo(r):
    """Ē_FON = A (1 + (2/3 − 28/(15π)) r), the cosine-weighted mean of E_FON."""
    return fon_a(r) * (1.0 + FON_C2 * r)


@jit
def eon_rho_ms(rho, e_avg):
    """ρ_ms = ρ² Ē/(1 − ρ(1 − Ē)): the albedo of the multiply scattered light."""
    return rho * rho * e_avg / (1.0 - rho * (1.0 - e_avg))


@jit
def eon_channel(rho, single, ms_shape, e_avg):
    """f_EON of one channel: (ρ/π) A(1 + r s/t) + (ρ_ms/π) · the compensation shape."""
    return rho / math.pi * single + eon_rho_ms(rho, e_avg) / math.pi * ms_shape


# -- closed forms for tests, exports and documentation (numpy-free scalars) ----------------------
def fon_albedo(mu: float, r: float) -> float:
    """E_FON(μ) = A + (B/π) G(θ), the exact directional albedo of the FON lobe (ρ = 1)."""
    mu = min(max(mu, 0.0), 1.0)
    st = math.sqrt(max(1.0 - mu * mu, 0.0))
    g = fon_g.py_func(st, mu, math.atan2(st, mu))
    a = 1.0 / (1.0 + FON_C1 * r)
    return a + r * a * g / math.pi


def fon_albedo_approx(mu: float, r: float) -> float:
    """The paper's fast E_FON: (1 + r·Ĝ/π)/(1 + c1 r) with its quartic fit Ĝ/π in m = 1 − μ."""
    m = 1.0 - mu
    g1, g2, g3, g4 = FON_G_FIT
    g_over_pi = m * (g1 + m * (g2 + m * (g3 + m * g4)))
    return (1.0 + r * g_over_pi) / (1.0 + FON_C1 * r)


def eon_albedo(mu: float, r: float, rho: float) -> float:
    """Directional albedo of f_EON: ρ E_FON(μ) + ρ_ms (1 − E_FON(μ)) (= 1 for ρ = 1)."""
    e = fon_albedo(mu, r)
    e_avg = (1.0 + FON_C2 * r) / (1.0 + FON_C1 * r)
    rho_ms = rho * rho * e_avg / (1.0 - rho * (1.0 - e_avg))
    return rho * e + rho_ms * (1.0 - e)


__all__ = [
    "FON_C1", "FON_C2", "FON_G_FIT", "fon_a", "fon_g", "fon_single", "eon_loss", "eon_ms_shape",
    "eon_avg_albedo", "eon_rho_ms", "eon_channel", "fon_albedo", "fon_albedo_approx", "eon_albedo",
]
