// Tabulated anisotropic BRDF in the UTIA format: J. Filip, R. Vávra,
// "Template-Based Sampling of Anisotropic BRDFs", Computer Graphics Forum 33(7),
// 2014.   numpy: brdfkit/measured/utia.py (utia_lookup)
//
// The table is u_utia, an RGBA32F 3D texture of 48 x 6 x 288 texels (width =
// φv, height = θv, depth = θi · 48 + φi; brdfkit.render.tables.utia_tables),
// read with texelFetch only. θ steps 15° (0°..75°), φ steps 7.5° (0°..352.5°).
// Quadrilinear in (θi, φi, θv, φv), φ periodic (the corner after 352.5° is 0°),
// θ above 75° extrapolated linearly from the 60° and 75° samples (as the UTIA
// loader), the result clamped at 0; 0 where wi.z <= 0 or wo.z <= 0.
// θ is atan2(|w.xy|, w.z), not acos(w.z) (acos loses small angles in float32).
// Needs common.glsl (bk_atan2, bk_atan2_pos, bk_below, BK_PI).

uniform highp sampler3D u_utia;

const float BK_UTIA_STEP_THETA = BK_PI / 12.0;  // 15°
const float BK_UTIA_STEP_PHI = BK_PI / 24.0;    // 7.5°

// (lower θ index in 0..4, weight of the upper one; above 1 past 75°: extrapolation)
vec2 bk_utia_theta(vec3 w) {
    float u = bk_atan2_pos(length(w.xy), w.z) / BK_UTIA_STEP_THETA;
    float i0 = clamp(floor(u), 0.0, 4.0);
    return vec2(i0, u - i0);
}

// (lower φ index in 0..47, upper index (periodic), weight of the upper one)
vec3 bk_utia_phi(vec3 w) {
    float u = bk_atan2(w.y, w.x) / BK_UTIA_STEP_PHI;
    u = u < 0.0 ? u + 48.0 : u;
    float i0 = floor(u);
    float f = u - i0;
    i0 = mod(i0, 48.0);
    return vec3(i0, mod(i0 + 1.0, 48.0), f);
}

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    vec2 ti = bk_utia_theta(wi), tv = bk_utia_theta(wo);
    vec3 pi_ = bk_utia_phi(wi), pv = bk_utia_phi(wo);
    vec3 acc = vec3(0.0);
    for (int a = 0; a < 2; ++a) {
        float fa = a == 0 ? 1.0 - ti.y : ti.y;
        int ia = int(ti.x) + a;
        for (int b = 0; b < 2; ++b) {
            float fb = b == 0 ? 1.0 - pi_.z : pi_.z;
            int slice = ia * 48 + int(b == 0 ? pi_.x : pi_.y);
            for (int c = 0; c < 2; ++c) {
                float fc = c == 0 ? 1.0 - tv.y : tv.y;
                int ic = int(tv.x) + c;
                for (int d = 0; d < 2; ++d) {
                    float fd = d == 0 ? 1.0 - pv.z : pv.z;
                    int id = int(d == 0 ? pv.x : pv.y);
                    acc += (fa * fb * fc * fd) * texelFetch(u_utia, ivec3(id, ic, slice), 0).rgb;
                }
            }
        }
    }
    return max(acc, 0.0);
}
