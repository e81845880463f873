// Phong (CACM 1975) / Lewis (CGF 1994).   numpy: brdfkit/models/phong.py
// r = reflect(wi) about n = +z, x = r·wo:
//   f_r = kd/π + ks·lobe,
//   normalized: lobe = (s+2)/(2π) · x^s        (0 where x <= 0, also for s = 0)
//   raw:        lobe = x^s / max(n·wi, 1e-4)
uniform vec3 u_kd;
uniform vec3 u_ks;
uniform float u_shininess;
uniform int u_normalized;

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    float rv = wi.z * wo.z - wi.x * wo.x - wi.y * wo.y;
    float s = u_shininess;
    float lobe = rv > 0.0 ? bk_pow(min(rv, 1.0), s) : 0.0;
    if (u_normalized != 0) {
        lobe *= (s + 2.0) / (2.0 * BK_PI);
    } else {
        lobe /= max(wi.z, 1e-4);
    }
    return u_kd / BK_PI + u_ks * lobe;
}
