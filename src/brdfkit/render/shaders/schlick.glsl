// Schlick (Eurographics 1994), single or double slab.   numpy: brdfkit/models/schlick.py
// t = n·h, u = h·wi, v = n·wi, v' = n·wo, w = cos of h's azimuth from +x:
//   S(u) = C + (1 − C)(1 − u)⁵,  Z = r/(1 + (r − 1)t²)²,  A = sqrt(p/(p² − p²w² + w²)) (1 at h = n)
//   D = a/π + b · Z A G(v)G(v')/(4π v v')      (the mirror part c is a delta: omitted)
//   b = 4r(1 − r); a = 0 if r < 0.5 else 1 − b
//   reinjection: + b (1 − G(v)G(v'))/(4π v v')
//   single: f = S D;  double: f = S D + (1 − S) S' D'
// Guarded numerics, as in numpy: with d = r + (1 − r)v (= v/G(v)) and
//   q = r/(1 + (r − 1)t²) = r |Hs|²/(Hs.x² + Hs.y² + r Hs.z²)   (no cancellation for t → 1)
//   b Z A G G'/(4π v v') = (1 − r)/π · A · (q/d)(q/d'),  q ≤ 2 (neither 1/r nor r² is formed);
//   A = 1/hypot(√p·cy, cx/√p) with (cx, cy) h's unit azimuth direction (p is never squared);
//   d floored at 1e-18, each slab capped at 8.5e37 (a quarter of the largest float).
//   r and p are clamped at 1e-37: GL may flush smaller (subnormal) uniforms to 0.
uniform int u_layers;   // 0 single, 1 double
uniform vec3 u_color;
uniform float u_r;
uniform float u_p;
uniform vec3 u_color2;
uniform float u_r2;
uniform float u_p2;
uniform int u_reinjection;

float schlick_hypot(float x, float y) {
    float m = max(abs(x), abs(y));
    if (m == 0.0) return 0.0;
    x /= m;
    y /= m;
    return m * sqrt(x * x + y * y);
}

// b (1 − G G')/(4π v v') = (1 − r)/π · (r/(d v)) (r/(d' v')) · [r + (1 − r)(v + v') − (2 − r) v v']
float schlick_reinjection(float v, float v2, float r) {
    float B = max(r + (1.0 - r) * (v + v2) - (2.0 - r) * v * v2, 0.0);
    float x1 = r / (r + (1.0 - r) * v) / v;
    float x2 = r / (r + (1.0 - r) * v2) / v2;
    return (1.0 - r) / BK_PI * (x1 * x2) * B;
}

float schlick_slab(vec3 Hs, vec2 c, bool at_n, float v, float v2, float r_in, float p_in) {
    float r = max(r_in, 1e-37);
    float p = max(p_in, 1e-37);
    float b = 4.0 * r * (1.0 - r);
    float a = r < 0.5 ? 0.0 : 1.0 - b;
    float q = r * dot(Hs, Hs) / (Hs.x * Hs.x + Hs.y * Hs.y + r * Hs.z * Hs.z);
    float A = 1.0;
    float sp = sqrt(p);
    if (p != 1.0 && !at_n) A = 1.0 / schlick_hypot(sp * c.y, c.x / sp);
    float d1 = max(r + (1.0 - r) * v, 1e-18);
    float d2 = max(r + (1.0 - r) * v2, 1e-18);
    float gloss = b > 0.0 ? (1.0 - r) / BK_PI * A * (q / d1) * (q / d2) : 0.0;
    if (u_reinjection == 1 && b > 0.0) gloss += schlick_reinjection(v, v2, r);
    return min(a / BK_PI + gloss, 8.5e37);
}

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    vec3 Hs = bk_scaled_sum(wi, wo);
    vec3 h = Hs / sqrt(dot(Hs, Hs));
    float u = clamp(dot(wi, h), 0.0, 1.0);
    float l = schlick_hypot(Hs.x, Hs.y);
    bool at_n = l == 0.0;
    vec2 c = at_n ? vec2(1.0, 0.0) : Hs.xy / l;
    float v = wi.z;
    float v2 = wo.z;
    vec3 S = fresnel_schlick(u_color, u);
    vec3 f = S * schlick_slab(Hs, c, at_n, v, v2, u_r, u_p);
    if (u_layers == 1) {
        vec3 S2 = fresnel_schlick(u_color2, u);
        f += (vec3(1.0) - S) * S2 * schlick_slab(Hs, c, at_n, v, v2, u_r2, u_p2);
    }
    return f;
}
