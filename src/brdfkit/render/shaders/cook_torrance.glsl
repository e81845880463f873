// Cook-Torrance (ACM TOG 1982), as the lecture writes it.   numpy: brdfkit/models/cook_torrance.py
//   f_r = kd/π + ks · (F/π) · D · G / ((n·l)(n·v)),  l = wi, v = wo, h = normalize(l + v)
//   D = exp(−(tan α/m)²)/(m² cos⁴α)  (no 1/π),  F exact dielectric at c = v·h,
//   G = min(1, 2(n·h)(n·v)/(v·h), 2(n·h)(n·l)/(l·h)); cosines floored at 1e-18 in the divisor.
uniform vec3 u_kd;
uniform vec3 u_ks;
uniform float u_m;
uniform vec3 u_ior;

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    vec3 h = bk_half_vector(wi, wo);
    float n_l = wi.z;
    float n_v = wo.z;
    float l_h = dot(wi, h);
    float v_h = dot(wo, h);
    float c = clamp(0.5 * (l_h + v_h), 0.0, 1.0);

    float D = beckmann_unnormalized(h, u_m, u_m);
    float G = v_groove(h.z, n_v, n_l, v_h, l_h);
    vec3 F = fresnel_dielectric_cook(c, u_ior);
    float geo = G / (max(n_l, 1e-18) * max(n_v, 1e-18));
    vec3 spec = min((u_ks * (F / BK_PI) * D) * geo, vec3(BK_FLT_MAX));
    return spec + u_kd / BK_PI;
}
