// Measured material as a Neural-BRDF network: A. Sztrajman, G. Rainer,
// T. Ritschel, T. Weyrich, "Neural BRDF Representation and Importance
// Sampling", Computer Graphics Forum 40(6), 2021.   numpy: brdfkit/measured/nbrdf.py
//
// The network maps the Rusinkiewicz (1998) half/difference vectors (φh = 0)
//     x = (sin θh, 0, cos θh, sin θd cos φd, sin θd sin φd, cos θd)
// through relu(x·W1 + b1) (21 units), relu(·W2 + b2) (21 units) and
// max(exp(·W3 + b3) − 1, 0) to RGB f_r in 1/sr, φd folded into [0, π) as the
// numpy model does. x is built from vectors, not angles (numpy takes sin/cos of
// its float64 angles; float32 sin/cos of float32 angles would differ by ~1e-4
// after the network): the half vector's (|h.xy|, h.z) and the difference
// vector in the half-vector frame, measured.glsl's bk_merl_half_diff (include
// common.glsl, then measured.glsl with its table brdf() renamed, then this
// file: brdfkit.web.api.nbrdf_source).
//
// u_nbrdf holds the weights in 4x4 blocks (brdfkit.web.api.nbrdf_blocks: the
// 21 units padded to 24 = 6 groups of 4), read only at constant indices (the
// macros unroll the layers): a dynamic index into a uniform array costs a
// gather per pixel in a software renderer.

uniform vec4 u_nbrdf[211];

#define BK_NB_M4(i) mat4(u_nbrdf[i], u_nbrdf[(i) + 1], u_nbrdf[(i) + 2], u_nbrdf[(i) + 3])
// layer 1, group k: inputs (x0, x2, x3, x4) = xa, x5, bias
#define BK_NB_L1(k) max(BK_NB_M4(6 * (k)) * xa + u_nbrdf[6 * (k) + 4] * x5 + u_nbrdf[6 * (k) + 5], 0.0)
// layer 2, group k, from the 6 groups a0..a5 of layer 1
#define BK_NB_L2(k) max(u_nbrdf[180 + (k)] + BK_NB_M4(36 + 24 * (k)) * a0 + BK_NB_M4(40 + 24 * (k)) * a1 \
    + BK_NB_M4(44 + 24 * (k)) * a2 + BK_NB_M4(48 + 24 * (k)) * a3 + BK_NB_M4(52 + 24 * (k)) * a4 \
    + BK_NB_M4(56 + 24 * (k)) * a5, 0.0)

// exp(t) − 1 without the cancellation of exp(t) − 1 for small |t| (expm1):
// Taylor to t^8 below 1/4 (truncation < 1e-9 relative), else exp
vec3 bk_nb_expm1(vec3 t) {
    vec3 p = t * (1.0 + t * (1.0 / 2.0 + t * (1.0 / 6.0 + t * (1.0 / 24.0 + t * (1.0 / 120.0
        + t * (1.0 / 720.0 + t * (1.0 / 5040.0 + t * (1.0 / 40320.0))))))));
    return mix(exp(t) - 1.0, p, lessThan(abs(t), vec3(0.25)));
}

// the network at x = (xa.x, 0, xa.yzw, x5): RGB f_r in 1/sr
vec3 bk_nbrdf_network(vec4 xa, float x5) {
    vec4 a0 = BK_NB_L1(0), a1 = BK_NB_L1(1), a2 = BK_NB_L1(2), a3 = BK_NB_L1(3), a4 = BK_NB_L1(4), a5 = BK_NB_L1(5);
    vec4 b0 = BK_NB_L2(0), b1 = BK_NB_L2(1), b2 = BK_NB_L2(2), b3 = BK_NB_L2(3), b4 = BK_NB_L2(4), b5 = BK_NB_L2(5);
    vec4 z = u_nbrdf[210] + BK_NB_M4(186) * b0 + BK_NB_M4(190) * b1 + BK_NB_M4(194) * b2
        + BK_NB_M4(198) * b3 + BK_NB_M4(202) * b4 + BK_NB_M4(206) * b5;
    return max(bk_nb_expm1(min(z.xyz, vec3(80.0))), vec3(0.0));
}

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    vec4 q = bk_merl_half_diff(wi, wo);   // sin θh, cos θh, (d.x, d.y) in the half frame
    vec2 l = bk_merl_lengths(wi, wo);     // 2 cos θd, 2 sin θd (unit vectors)
    float n = length(l);                  // 2; |wi + wo|^2 + |wi − wo|^2 = 2 (|wi|^2 + |wo|^2)
    // sin θd (cos φd, sin φd) = d.xy / 2, cos θd = |wi + wo| / 2
    return bk_nbrdf_network(vec4(q.x, q.y, q.zw / n), l.x / n);
}
