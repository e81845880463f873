// Measured (tabulated) isotropic BRDF: a MERL table (Matusik, Pfister, Brand,
// McMillan, "A Data-Driven Reflectance Model", ACM TOG 22(3), 2003) looked up
// in a 3D texture.   numpy: brdfkit/measured/merl.py (MERLBRDF)
//
// The table is u_table, an RGBA32F 3D texture of 180 x 90 x 90 texels (width
// = φd, height = θd, depth = θh), NEAREST filtering, read with texelFetch at
// integer bin indices (no filtering or texture-coordinate rounding involved):
//   rgb = max(value, 0) per channel (f_r in 1/sr, MERL's channel scales
//         already applied), alpha = 1 where every channel was measured, else 0.
// The angles are Rusinkiewicz's (1998) half/difference angles, computed as
// merl.symmetric_half_diff does: the same for (wi, wo) and (wo, wi), φd
// folded into [0, π). MERL's bins (floor, clamped to the last bin):
//   θh: sqrt(θh / (π/2)) · 90,   θd: θd / (π/2) · 90,   φd: φd / π · 180.
// u_interpolation: 0 = nearest (MERL's reader), 1 = trilinear in index space
// over the measured corners (θh, θd clamped, φd periodic), as
// MERLBRDF.lookup_trilinear.
// Needs common.glsl (bk_atan01, bk_below, BK_PI, BK_HALF_PI) before it.

uniform highp sampler3D u_table;
uniform int u_interpolation;

const float BK_MERL_TH = 90.0;
const float BK_MERL_TD = 90.0;
const float BK_MERL_PD = 180.0;

// atan2(y, x) for y >= 0, in [0, π], with the accurate bk_atan01
float bk_merl_atan2_upper(float y, float x) {
    float ax = abs(x);
    if (ax == 0.0 && y == 0.0) return 0.0;
    float r = y <= ax ? bk_atan01(y / ax) : BK_HALF_PI - bk_atan01(ax / y);
    return x < 0.0 ? BK_PI - r : r;
}

// The half/difference geometry of merl.symmetric_half_diff, rearranged to be
// well conditioned in float32 and bit-for-bit the same for (wi, wo) and
// (wo, wi): with s = wi + wo, d = wi − wo and h = s / |s|,
//   q.x = sin θh = |h.xy|,  q.y = cos θh = h.z,
//   q.zw = d rotated into the half-vector frame (x, y; its z is 0 for unit
//          vectors), the sign chosen so that y > 0 (or y = 0, x >= 0): φd
//          folded into [0, π) (the swap negates d exactly);
//   |s| = 2 cos θd and |d| = 2 sin θd (bk_merl_lengths).
// Not from angles: no acos(h.z), which loses the small θh near the specular peak.
vec4 bk_merl_half_diff(vec3 wi, vec3 wo) {
    vec3 s = wi + wo;
    vec3 d = wi - wo;
    vec3 h = s / max(length(s), 1e-30);
    float r = length(h.xy);
    float ch = r > 0.0 ? h.x / r : 1.0;    // cos φh
    float sh = r > 0.0 ? h.y / r : 0.0;    // sin φh
    // rotate d by −φh about z, then by −θh about y (cos θh = h.z, sin θh = r)
    float x0 = ch * d.x + sh * d.y;
    float vy = -sh * d.x + ch * d.y;
    float vx = h.z * x0 - r * d.z;
    if (vy < 0.0 || (vy == 0.0 && vx < 0.0)) {
        vx = -vx;
        vy = -vy;
    }
    return vec4(r, h.z, vx, vy);
}

vec2 bk_merl_lengths(vec3 wi, vec3 wo) { return vec2(length(wi + wo), length(wi - wo)); }

// (θh, θd, φd folded into [0, π)) from bk_merl_half_diff: atan2 throughout
// (θd = atan2(|wi − wo|, |wi + wo|), half the angle between wi and wo)
vec3 bk_merl_angles(vec3 wi, vec3 wo) {
    vec4 q = bk_merl_half_diff(wi, wo);
    vec2 l = bk_merl_lengths(wi, wo);
    float theta_h = bk_merl_atan2_upper(q.x, q.y);
    float theta_d = bk_merl_atan2_upper(l.y, l.x);
    float phi_d = bk_merl_atan2_upper(q.w, q.z);
    // fold into [0, π): π (up to float32 rounding) is φd = 0
    if (phi_d >= BK_PI - 2.5e-7) phi_d = 0.0;
    return vec3(theta_h, theta_d, phi_d);
}

vec3 bk_merl_nearest(vec3 a) {
    int i = int(clamp(floor(sqrt(max(a.x, 0.0) / BK_HALF_PI) * BK_MERL_TH), 0.0, BK_MERL_TH - 1.0));
    int j = int(clamp(floor(a.y / BK_HALF_PI * BK_MERL_TD), 0.0, BK_MERL_TD - 1.0));
    int k = int(clamp(floor(a.z / BK_PI * BK_MERL_PD), 0.0, BK_MERL_PD - 1.0));
    return texelFetch(u_table, ivec3(k, j, i), 0).rgb;
}

vec3 bk_merl_trilinear(vec3 a) {
    float ch = clamp(sqrt(max(a.x, 0.0) / BK_HALF_PI) * BK_MERL_TH - 0.5, 0.0, BK_MERL_TH - 1.0);
    float cd = clamp(a.y / BK_HALF_PI * BK_MERL_TD - 0.5, 0.0, BK_MERL_TD - 1.0);
    float cp = a.z / BK_PI * BK_MERL_PD - 0.5;
    int i0 = min(int(floor(ch)), 88);
    int j0 = min(int(floor(cd)), 88);
    float k0f = floor(cp);
    float fh = ch - float(i0);
    float fd = cd - float(j0);
    float fp = cp - k0f;
    int k0 = int(k0f);
    if (k0 < 0) k0 += 180;
    if (k0 > 179) k0 -= 180;
    int k1 = k0 == 179 ? 0 : k0 + 1;
    vec3 acc = vec3(0.0);
    float wsum = 0.0;
    for (int di = 0; di < 2; ++di) {
        float wh = di == 0 ? 1.0 - fh : fh;
        for (int dj = 0; dj < 2; ++dj) {
            float wd = dj == 0 ? 1.0 - fd : fd;
            for (int dk = 0; dk < 2; ++dk) {
                float w = wh * wd * (dk == 0 ? 1.0 - fp : fp);
                vec4 v = texelFetch(u_table, ivec3(dk == 0 ? k0 : k1, j0 + dj, i0 + di), 0);
                w *= v.a;  // 0 where the bin was not measured
                acc += w * v.rgb;
                wsum += w;
            }
        }
    }
    return wsum > 1e-12 ? acc / wsum : vec3(0.0);
}

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    vec3 a = bk_merl_angles(wi, wo);
    return u_interpolation == 1 ? bk_merl_trilinear(a) : bk_merl_nearest(a);
}
