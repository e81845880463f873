// Measured material in the RGL format: J. Dupuy, W. Jakob, "An Adaptive
// Parameterization for Efficient Material Acquisition and Rendering", ACM TOG
// 37(6), 2018, evaluated as Mitsuba 3's `measured` plugin.
//   numpy: brdfkit/measured/rgl.py (RGLBRDF: its docstring has the steps 1-5
//   this file follows, and the names below are its names)
//
// The tables come from brdfkit.render.tables.rgl_tables (every texture RGBA32F
// or R32F, read with texelFetch only: no filtering, no coordinate rounding):
//   u_rgl_warp   3D, (Wv, Hv, slices): r = the VNDF, each slice normalised to
//                integrate to 1 over its bilinear interpolant; g (x < Wv − 1) =
//                its conditional CDF along x per row; b = the marginal CDF of
//                row y (y < Hv − 1, the same at every x)
//   u_rgl_rgb    3D, (W, H, slices): rgb = the reflectance samples (spectral
//                files converted to linear sRGB at load, as numpy does)
//   u_rgl_ndf    2D, (Wn, Hn): D(m);   u_rgl_sigma  2D: σ(ω)
//   u_rgl_axes   2D, (max(n_phi, n_theta), 2): row 0 = phi_i, row 1 = theta_i
// slice = i_phi · n_theta + i_theta. Ints: u_rgl_n_phi, u_rgl_n_theta,
// u_rgl_isotropic (Mitsuba's: n_phi <= 2), u_rgl_reduction (1, 2, 4),
// u_rgl_jacobian (0/1).
// Needs common.glsl (bk_atan2, bk_atan2_pos, bk_below, BK_PI, BK_FLT_MAX).

uniform highp sampler3D u_rgl_warp;
uniform highp sampler3D u_rgl_rgb;
uniform highp sampler2D u_rgl_ndf;
uniform highp sampler2D u_rgl_sigma;
uniform highp sampler2D u_rgl_axes;
uniform int u_rgl_n_phi;
uniform int u_rgl_n_theta;
uniform int u_rgl_isotropic;
uniform int u_rgl_reduction;
uniform int u_rgl_jacobian;

// θ of a unit vector: 2 asin(|d − n| / 2), stable near the normal (rgl.elevation)
float bk_rgl_elevation(vec3 d) {
    float s = 0.5 * length(vec3(d.xy, d.z - 1.0));
    s = clamp(s, 0.0, 1.0);
    return 2.0 * bk_atan2_pos(s, sqrt((1.0 - s) * (1.0 + s)));
}

// the unit-square coordinates (rgl.theta2u, rgl.phi2u)
float bk_rgl_theta2u(float theta) { return sqrt(theta * (2.0 / BK_PI)); }
float bk_rgl_phi2u(float phi) { return (phi + BK_PI) * (0.5 / BK_PI); }

bool bk_rgl_signbit(float x) { return (floatBitsToUint(x) >> 31) != 0u; }

// (lower index, weight of the upper one) of x among the row's increasing values
// (Mitsuba's find_interval: the last index with value < x, clamped to [0, n − 2];
// the weight clamped to [0, 1]); a parameter of size 1: (0, 0)
vec2 bk_rgl_interval(int row, int n, float x) {
    if (n == 1) return vec2(0.0);
    int lo = 0, hi = n;  // first index with value >= x, by bisection
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (texelFetch(u_rgl_axes, ivec2(mid, row), 0).r < x) lo = mid + 1; else hi = mid;
    }
    int i = clamp(lo - 1, 0, n - 2);
    float p0 = texelFetch(u_rgl_axes, ivec2(i, row), 0).r;
    float p1 = texelFetch(u_rgl_axes, ivec2(i + 1, row), 0).r;
    return vec2(float(i), clamp((x - p0) / (p1 - p0), 0.0, 1.0));
}

// the four (φi, θi) corners: slices and weights (rgl._Params; a parameter of size 1
// gives its second corner weight 0)
struct BkRglCorners { ivec4 slice; vec4 weight; };

BkRglCorners bk_rgl_corners(float phi, float theta) {
    vec2 p = bk_rgl_interval(0, u_rgl_n_phi, phi);
    vec2 t = bk_rgl_interval(1, u_rgl_n_theta, theta);
    int ip = int(p.x), it = int(t.x);
    int ip1 = min(ip + 1, u_rgl_n_phi - 1), it1 = min(it + 1, u_rgl_n_theta - 1);
    BkRglCorners c;
    c.slice = ivec4(ip * u_rgl_n_theta + it, ip * u_rgl_n_theta + it1,
                    ip1 * u_rgl_n_theta + it, ip1 * u_rgl_n_theta + it1);
    c.weight = vec4((1.0 - p.y) * (1.0 - t.y), (1.0 - p.y) * t.y, p.y * (1.0 - t.y), p.y * t.y);
    return c;
}

// a texel of the warp table interpolated over the corners (rgl._Params.lookup)
vec4 bk_rgl_warp_at(BkRglCorners c, int x, int y) {
    vec4 v = c.weight.x * texelFetch(u_rgl_warp, ivec3(x, y, c.slice.x), 0);
    v += c.weight.y * texelFetch(u_rgl_warp, ivec3(x, y, c.slice.y), 0);
    v += c.weight.z * texelFetch(u_rgl_warp, ivec3(x, y, c.slice.z), 0);
    v += c.weight.w * texelFetch(u_rgl_warp, ivec3(x, y, c.slice.w), 0);
    return v;
}

vec3 bk_rgl_rgb_at(BkRglCorners c, int x, int y) {
    vec3 v = c.weight.x * texelFetch(u_rgl_rgb, ivec3(x, y, c.slice.x), 0).rgb;
    v += c.weight.y * texelFetch(u_rgl_rgb, ivec3(x, y, c.slice.y), 0).rgb;
    v += c.weight.z * texelFetch(u_rgl_rgb, ivec3(x, y, c.slice.z), 0).rgb;
    v += c.weight.w * texelFetch(u_rgl_rgb, ivec3(x, y, c.slice.w), 0).rgb;
    return v;
}

float bk_rgl_safe_div(float a, float b) {
    float q = a / b;
    return (isnan(q) || isinf(q)) ? 0.0 : q;
}

// the inverse of the VNDF warp at u (Mitsuba's Marginal2D::invert, continuous;
// rgl._Warp.invert): the bilinear patch's CDFs inverted in x, then in y
vec2 bk_rgl_invert(vec2 u, BkRglCorners c) {
    ivec3 size = textureSize(u_rgl_warp, 0);
    int w = size.x, h = size.y;
    vec2 s = clamp(u, 0.0, 1.0) * vec2(float(w - 1), float(h - 1));
    int px = min(int(s.x), w - 2), py = min(int(s.y), h - 2);
    float fx = s.x - float(px), fy = s.y - float(py);
    float v00 = bk_rgl_warp_at(c, px, py).r, v10 = bk_rgl_warp_at(c, px + 1, py).r;
    float v01 = bk_rgl_warp_at(c, px, py + 1).r, v11 = bk_rgl_warp_at(c, px + 1, py + 1).r;
    float c0 = v00 + (v01 - v00) * fy;
    float c1 = v10 + (v11 - v10) * fy;
    float x = fx * (c0 + (c1 - c0) * 0.5 * fx) / float(w - 1);
    if (px > 0) {
        float prev0 = bk_rgl_warp_at(c, px - 1, py).g, prev1 = bk_rgl_warp_at(c, px - 1, py + 1).g;
        x += prev0 + (prev1 - prev0) * fy;
    }
    vec4 e0 = bk_rgl_warp_at(c, w - 2, py), e1 = bk_rgl_warp_at(c, w - 2, py + 1);
    float r0 = e0.g, r1 = e1.g;
    x = bk_rgl_safe_div(x, r0 + (r1 - r0) * fy);
    float y = fy * (r0 + (r1 - r0) * 0.5 * fy) / float(h - 1);
    if (py > 0) y += bk_rgl_warp_at(c, 0, py - 1).b;
    return vec2(x, y);
}

// a plain 2D table bilinear at u (rgl._bilinear; x along the width)
float bk_rgl_bilinear(highp sampler2D t, vec2 u) {
    ivec2 size = textureSize(t, 0);
    vec2 s = clamp(u, 0.0, 1.0) * vec2(float(size.x - 1), float(size.y - 1));
    int px = min(int(s.x), size.x - 2), py = min(int(s.y), size.y - 2);
    float fx = s.x - float(px), fy = s.y - float(py);
    float a = mix(texelFetch(t, ivec2(px, py), 0).r, texelFetch(t, ivec2(px + 1, py), 0).r, fx);
    float b = mix(texelFetch(t, ivec2(px, py + 1), 0).r, texelFetch(t, ivec2(px + 1, py + 1), 0).r, fx);
    return a + (b - a) * fy;
}

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    vec3 l = wi, v = wo;  // v: the direction the tables are parameterised by
    float cos_l = l.z;
    // 1. fold an anisotropic pair into the measured wedge
    if (u_rgl_isotropic == 0 && u_rgl_reduction >= 2) {
        float sy = v.y;
        float sx = u_rgl_reduction == 4 ? v.x : sy;
        vec2 f = vec2(bk_rgl_signbit(sx) ? 1.0 : -1.0, bk_rgl_signbit(sy) ? 1.0 : -1.0);
        v.xy *= f;
        l.xy *= f;
    }
    // 2. the half vector and the unit-square coordinates
    vec3 m = normalize(v + l);
    float theta_i = bk_rgl_elevation(v), phi_i = bk_atan2(v.y, v.x);
    float theta_m = bk_rgl_elevation(m), phi_m = bk_atan2(m.y, m.x);
    if (u_rgl_isotropic != 0) phi_m -= phi_i;
    vec2 u_m = vec2(bk_rgl_theta2u(theta_m), bk_rgl_phi2u(phi_m));
    u_m.y -= floor(u_m.y);
    // 3. the inverse VNDF warp, 4. the rgb table bilinear at that sample
    BkRglCorners c = bk_rgl_corners(phi_i, theta_i);
    vec2 sample_ = bk_rgl_invert(u_m, c);
    ivec3 size = textureSize(u_rgl_rgb, 0);
    vec2 s = clamp(sample_, 0.0, 1.0) * vec2(float(size.x - 1), float(size.y - 1));
    int px = min(int(s.x), size.x - 2), py = min(int(s.y), size.y - 2);
    float fx = s.x - float(px), fy = s.y - float(py);
    vec3 a = mix(bk_rgl_rgb_at(c, px, py), bk_rgl_rgb_at(c, px + 1, py), fx);
    vec3 b = mix(bk_rgl_rgb_at(c, px, py + 1), bk_rgl_rgb_at(c, px + 1, py + 1), fx);
    vec3 f = a + (b - a) * fy;
    // 5. the Jacobian factor D(m) / (4 σ(v))
    if (u_rgl_jacobian != 0) {
        vec2 u_i = vec2(bk_rgl_theta2u(theta_i), bk_rgl_phi2u(phi_i));
        f *= bk_rgl_bilinear(u_rgl_ndf, u_m) / (4.0 * bk_rgl_bilinear(u_rgl_sigma, u_i));
    }
    // Mitsuba's value includes cos θ of wi: f_r is it divided by that
    f = vec3(bk_rgl_safe_div(f.r, cos_l), bk_rgl_safe_div(f.g, cos_l), bk_rgl_safe_div(f.b, cos_l));
    return clamp(f, 0.0, BK_FLT_MAX);
}
