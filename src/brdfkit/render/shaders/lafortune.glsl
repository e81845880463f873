// Lafortune, Foo, Torrance & Greenberg, SIGGRAPH 1997, eq. (4)-(6).
// numpy: brdfkit/models/lafortune.py
//   d_k = cx_k·wi.x·wo.x + cy_k·wi.y·wo.y + cz_k·wi.z·wo.z
//   f_r = kd/π + Σ_{k <= lobes} ks_k · max(0, d_k)^n_k
// max(0, d)^n = exp(min(n·ln d, 60)) for d > 0, else 0 (the cap keeps |C| > 1 finite).
uniform vec3 u_kd;
uniform int u_lobes;
uniform vec3 u_ks_1;
uniform float u_cx_1;
uniform float u_cy_1;
uniform float u_cz_1;
uniform float u_n_1;
uniform vec3 u_ks_2;
uniform float u_cx_2;
uniform float u_cy_2;
uniform float u_cz_2;
uniform float u_n_2;
uniform vec3 u_ks_3;
uniform float u_cx_3;
uniform float u_cy_3;
uniform float u_cz_3;
uniform float u_n_3;

float lafortune_dot(vec3 wi, vec3 wo, float cx, float cy, float cz) {
    return cx * wi.x * wo.x + cy * wi.y * wo.y + cz * wi.z * wo.z;
}

float lafortune_lobe(float d, float n) {
    if (d <= 0.0) return 0.0;
    return exp(min(n * bk_log(d), 60.0));
}

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    vec3 f = u_kd / BK_PI;
    f += u_ks_1 * lafortune_lobe(lafortune_dot(wi, wo, u_cx_1, u_cy_1, u_cz_1), u_n_1);
    if (u_lobes >= 2) f += u_ks_2 * lafortune_lobe(lafortune_dot(wi, wo, u_cx_2, u_cy_2, u_cz_2), u_n_2);
    if (u_lobes >= 3) f += u_ks_3 * lafortune_lobe(lafortune_dot(wi, wo, u_cx_3, u_cy_3, u_cz_3), u_n_3);
    return f;
}
