// Ashikhmin-Shirley (JGT 2000), anisotropic Phong with coupled diffuse term.
// numpy: brdfkit/models/ashikhmin_shirley.py
//   ρ_s = sqrt((nu+1)(nv+1))/(8π) · (n·h)^(nu cos²φh + nv sin²φh)
//         / (max(h·k, 1e-6) · max(n·wi, n·wo, 1e-6)) · F_schlick(Rs, h·k)
//   ρ_d = 28 Rd/(23π) (1 − Rs)(1 − (1 − n·wi/2)⁵)(1 − (1 − n·wo/2)⁵)
// (n·h)^e = exp(½ (nu hx² + nv hy²) log(1 − s²)/s²), s² = hx² + hy².
// variant ngan (Ngan, Durand & Matusik 2005): kd/π + ks · ρ_s with F_schlick(f0, h·k).
uniform int u_variant;  // 0 paper, 1 ngan
uniform vec3 u_kd;
uniform vec3 u_ks;
uniform vec3 u_f0;
uniform vec3 u_rd;
uniform vec3 u_rs;
uniform float u_nu;
uniform float u_nv;

float ashikhmin_shirley_power(vec3 h, float nu, float nv) {
    float s2 = h.x * h.x + h.y * h.y;
    float t = nu * h.x * h.x + nv * h.y * h.y;
    if (t <= 0.0) return 1.0;
    float lg = s2 < 0.5 ? bk_log1p(-s2) : 2.0 * log(h.z);
    float q = s2 > 0.0 ? lg / s2 : -1.0;
    return exp(0.5 * q * t);
}

// 1 − (1 − x)⁵ = x (5 − 10x + 10x² − 5x³ + x⁴), without the cancellation at small x (grazing)
float ashikhmin_shirley_one_minus_pow5(float x) {
    return x * (5.0 + x * (-10.0 + x * (10.0 + x * (-5.0 + x))));
}

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    vec3 h = bk_half_vector(wi, wo);
    float hk = clamp(dot(wi, h), 0.0, 1.0);
    float ci = wi.z;
    float co = wo.z;
    float lobe = ashikhmin_shirley_power(h, u_nu, u_nv);
    float denom = max(hk, 1e-6) * max(max(ci, co), 1e-6);
    float k = sqrt((u_nu + 1.0) * (u_nv + 1.0)) / (8.0 * BK_PI);
    vec3 spec = (k * lobe / denom) * fresnel_schlick(u_variant == 1 ? u_f0 : u_rs, hk);
    if (u_variant == 1) return u_kd / BK_PI + u_ks * spec;
    float a = ashikhmin_shirley_one_minus_pow5(ci * 0.5);
    float b = ashikhmin_shirley_one_minus_pow5(co * 0.5);
    vec3 diff = (28.0 / (23.0 * BK_PI)) * u_rd * (vec3(1.0) - u_rs) * (a * b);
    return diff + spec;
}
