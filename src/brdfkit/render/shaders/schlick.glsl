// Schlick (Eurographics 1994), single or double slab.   numpy: brdfkit/models/schlick.py
// t = n·h, u = h·wi, v = n·wi, v' = n·wo, w² = hx²/(hx² + hy²):
//   S(u) = C + (1 − C)(1 − u)⁵,  Z = r/(1 + (r − 1)t²)²,  A = sqrt(p/(p² − p²w² + w²)) (1 at h = n)
//   (1 + (r − 1)t² is evaluated as (Hx² + Hy² + r Hz²)/|H|², which does not cancel for small r)
//   D = a/π + b · Z A / (4π (r + (1−r)v)(r + (1−r)v'))      (the mirror part c is a delta: omitted)
//   b = 4r(1 − r); a = 0 if r < 0.5 else 1 − b
//   single: f = S D;  double: f = S D + (1 − S) S' D'
uniform int u_layers;   // 0 single, 1 double
uniform vec3 u_color;
uniform float u_r;
uniform float u_p;
uniform vec3 u_color2;
uniform float u_r2;
uniform float u_p2;

float schlick_slab(vec3 Hs, float w2, bool at_n, float v, float v2, float r, float p) {
    float b = 4.0 * r * (1.0 - r);
    float a = r < 0.5 ? 0.0 : 1.0 - b;
    float q = (Hs.x * Hs.x + Hs.y * Hs.y + r * Hs.z * Hs.z) / dot(Hs, Hs);
    float z = r / (q * q);
    float A = 1.0;
    if (p != 1.0 && !at_n) A = sqrt(p / (p * p - p * p * w2 + w2));
    float gg = 1.0 / ((r + (1.0 - r) * v) * (r + (1.0 - r) * v2));
    return a / BK_PI + b * z * A * gg / (4.0 * BK_PI);
}

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    vec3 Hs = bk_scaled_sum(wi, wo);
    vec3 h = Hs / sqrt(dot(Hs, Hs));
    float u = clamp(dot(wi, h), 0.0, 1.0);
    float s2 = h.x * h.x + h.y * h.y;
    bool at_n = s2 == 0.0;
    float w2 = at_n ? 1.0 : h.x * h.x / s2;
    float v = wi.z;
    float v2 = wo.z;
    vec3 S = fresnel_schlick(u_color, u);
    vec3 f = S * schlick_slab(Hs, w2, at_n, v, v2, u_r, u_p);
    if (u_layers == 1) {
        vec3 S2 = fresnel_schlick(u_color2, u);
        f += (vec3(1.0) - S) * S2 * schlick_slab(Hs, w2, at_n, v, v2, u_r2, u_p2);
    }
    return f;
}
