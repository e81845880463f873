// Oren-Nayar (SIGGRAPH 1994): the qualitative A,B model and the full model with
// C1, C2, C3 and the interreflection term.   numpy: brdfkit/models/oren_nayar.py
// α = max(θi, θo), β = min(θi, θo), Δφ = φo − φi, ρ = kd.
//   qualitative: (ρ/π)(A + B max(0, cos Δφ) sin α tan β)
//   full: (ρ/π) max(0, C1 + cos Δφ C2 tan β + (1 − |cos Δφ|) C3 tan((α+β)/2))
//         + 0.17 (ρ²/π) σ²/(σ² + 0.13) (1 − cos Δφ (2β/π)²)
// cos β and cos α + cos β are floored at 1e-6 in the tangents.
//   eon (Portsmouth, Kutz & Hill 2025; numpy: brdfkit/models/eon.py), r = min(σ, 1):
//       (ρ/π) A (1 + r s/t) + (ρ_ms/π) A r (c1 − G(θi)/π)(c1 − G(θo)/π)/(c1 − c2)
//       A = 1/(1 + c1 r), s = wi·wo − μi μo, t = max(μi, μo) (floored at 1e-6) if s > 0 else 1,
//       G(θ) = sin θ (θ − sin θ cos θ) + (2/3)(sin θ cos θ (1 + sin θ + sin²θ)/(1 + sin θ) − sin θ),
//       ρ_ms = ρ² Ē/(1 − ρ(1 − Ē)), Ē = A (1 + c2 r), c1 = 1/2 − 2/(3π), c2 = 2/3 − 28/(15π)
uniform vec3 u_kd;
uniform float u_sigma;
uniform int u_variant;   // 0 qualitative, 1 full, 2 eon

const float EON_C1 = 0.5 - 2.0 / (3.0 * BK_PI);
const float EON_C2 = 2.0 / 3.0 - 28.0 / (15.0 * BK_PI);

// G(θ) of the FON albedo E = A + (B/π) G (eon.fon_g)
float eon_fon_g(float st, float ct, float theta) {
    float tail = st * ct * (1.0 + st + st * st) / (1.0 + st);
    return st * (theta - st * ct) + (2.0 / 3.0) * (tail - st);
}

// f_EON, RGB (oren_nayar.eon)
vec3 eon_brdf(vec3 wi, vec3 wo, float si, float so) {
    float r = min(u_sigma, 1.0);
    float A = 1.0 / (1.0 + EON_C1 * r);
    float s = wi.x * wo.x + wi.y * wo.y;
    float t = s > 0.0 ? max(max(wi.z, wo.z), 1e-6) : 1.0;
    float single = A * max(1.0 + r * (s / t), 0.0);  // >= 1 - r in exact arithmetic (eon.fon_single)
    float li = max(EON_C1 - eon_fon_g(si, wi.z, bk_atan2_pos(si, wi.z)) / BK_PI, 0.0);
    float lo = max(EON_C1 - eon_fon_g(so, wo.z, bk_atan2_pos(so, wo.z)) / BK_PI, 0.0);
    float shape = A * r * li * lo / (EON_C1 - EON_C2);
    float e_avg = A * (1.0 + EON_C2 * r);
    vec3 rho_ms = u_kd * u_kd * e_avg / (1.0 - u_kd * (1.0 - e_avg));
    return u_kd / BK_PI * single + rho_ms / BK_PI * shape;
}

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    float sig2 = u_sigma * u_sigma;
    float si = length(wi.xy);
    float so = length(wo.xy);
    if (u_variant == 2) return eon_brdf(wi, wo, si, so);
    float ci = wi.z;
    float co = wo.z;
    vec2 pi_ = si > 0.0 ? wi.xy / si : vec2(0.0);
    vec2 po_ = so > 0.0 ? wo.xy / so : vec2(0.0);
    float cos_dphi = clamp(dot(pi_, po_), -1.0, 1.0);
    float sin_a = max(si, so);
    float cos_a = min(ci, co);
    float sin_b = min(si, so);
    float cos_b = max(ci, co);
    float tan_b = sin_b / max(cos_b, 1e-6);

    if (u_variant == 0) {
        float A = 1.0 - 0.5 * sig2 / (sig2 + 0.33);
        float B = 0.45 * sig2 / (sig2 + 0.09);
        float g = A + B * max(cos_dphi, 0.0) * sin_a * tan_b;
        return (u_kd / BK_PI) * g;
    }
    float ti = bk_atan2_pos(si, ci);
    float to = bk_atan2_pos(so, co);
    float alpha = max(ti, to);
    float beta = min(ti, to);
    float two_b_pi = 2.0 * beta / BK_PI;
    float C1 = 1.0 - 0.5 * sig2 / (sig2 + 0.33);
    float k2 = 0.45 * sig2 / (sig2 + 0.09);
    float C2 = cos_dphi >= 0.0 ? k2 * sin_a : k2 * (sin_a - two_b_pi * two_b_pi * two_b_pi);
    float C3 = 0.125 * sig2 / (sig2 + 0.09) * bk_sqr(4.0 * alpha * beta / (BK_PI * BK_PI));
    float tan_half = (sin_a + sin_b) / max(cos_a + cos_b, 1e-6);
    float g1 = C1 + cos_dphi * C2 * tan_b + (1.0 - abs(cos_dphi)) * C3 * tan_half;
    g1 = max(g1, 0.0);
    float g2 = 0.17 * sig2 / (sig2 + 0.13) * (1.0 - cos_dphi * two_b_pi * two_b_pi);
    return (u_kd / BK_PI) * g1 + (u_kd * u_kd / BK_PI) * g2;
}
