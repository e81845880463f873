// Blinn-Phong (Blinn 1977; normalisation (s+8)/(8π), Real-Time Rendering 3rd ed. §7.6).
// numpy: brdfkit/models/blinn_phong.py
// h = normalize(wi + wo) (the sum rescaled by its largest component first),
// (the lobe is computed from 1 − n·h, see below)
//   f_r = kd/π + ks·lobe,
//   normalized: lobe = (s+8)/(8π) · (n·h)^s
//   raw:        lobe = (n·h)^s / max(n·wi, 1e-4)
uniform vec3 u_kd;
uniform vec3 u_ks;
uniform float u_shininess;
uniform int u_normalized;

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    vec3 H = bk_scaled_sum(wi, wo);
    // (n·h)^s = exp(s·log1p(−(1 − n·h))) with 1 − n·h = (Hx² + Hy²)/(|H|(|H| + Hz)):
    // no cancellation, so large s keeps its accuracy (n·h itself is only good to an ulp).
    float len = sqrt(dot(H, H));
    float one_minus_nh = min((H.x * H.x + H.y * H.y) / (len * (len + H.z)), 1.0);
    float s = u_shininess;
    // near the peak from 1 − n·h; far from it (n·h < 0.5) n·h itself is the accurate one
    float lobe = one_minus_nh <= 0.5 ? exp(s * bk_log1p(-one_minus_nh)) : bk_pow(H.z / len, s);
    if (u_normalized != 0) {
        lobe *= (s + 8.0) / (8.0 * BK_PI);
    } else {
        lobe /= max(wi.z, 1e-4);
    }
    return u_kd / BK_PI + u_ks * lobe;
}
