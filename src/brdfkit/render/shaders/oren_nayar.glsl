// Oren-Nayar (SIGGRAPH 1994): the qualitative A,B model and the full model with
// C1, C2, C3 and the interreflection term.   numpy: brdfkit/models/oren_nayar.py
// α = max(θi, θo), β = min(θi, θo), Δφ = φo − φi, ρ = kd.
//   qualitative: (ρ/π)(A + B max(0, cos Δφ) sin α tan β)
//   full: (ρ/π) max(0, C1 + cos Δφ C2 tan β + (1 − |cos Δφ|) C3 tan((α+β)/2))
//         + 0.17 (ρ²/π) σ²/(σ² + 0.13) (1 − cos Δφ (2β/π)²)
// cos β and cos α + cos β are floored at 1e-6 in the tangents.
uniform vec3 u_kd;
uniform float u_sigma;
uniform int u_variant;   // 0 qualitative, 1 full

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    float sig2 = u_sigma * u_sigma;
    float si = length(wi.xy);
    float so = length(wo.xy);
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
