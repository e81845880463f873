// brdfkit image-based lighting: an equirectangular environment, its luminance sampling and
// the MIS estimator. Comes after the model's GLSL (brdf(wi, wo) in the local frame),
// pipeline_lights.glsl (bkr_orthonormal_tangent) and ibl_sampling.glsl.
// numpy twins: brdfkit/render/environment.py (map convention, CDFs, pdf) and
// brdfkit/render/ibl.py (the brute-force reference this estimator must converge to).
//
//   L_o(wo) = ∫ f_r(wi, wo) L_env(wi) cos θi dωi            (no shadowing by the object)
//
// Per sample: one direction from the BRDF sampler (pdf p_f) and one from the environment
// (pdf p_e), each weighted by the power heuristic w = p² / (p_f² + p_e²) (Veach & Guibas,
// "Optimally Combining Sampling Techniques for Monte Carlo Rendering", SIGGRAPH 1995).
// Map: row 0 at the zenith (+y), theta = acos(d.y), phi = atan(d.x, -d.z), u = phi/2π + 1/2;
// radiance constant per texel (texelFetch), alpha channel = the sampling pdf of the texel.
// Written in the subset common to GLSL 3.30 and GLSL ES 3.00.

uniform sampler2D bki_env;        // RGBA32F: rgb radiance, a = solid-angle pdf of the texel
uniform sampler2D bki_env_marg;   // R32F, H x 1: cumulative row probabilities
uniform sampler2D bki_env_cond;   // R32F, W x H: cumulative column probabilities per row
uniform mat3 bki_eye_to_map;      // eye-space direction -> map frame (a rotation)
uniform float bki_strength;
uniform int bki_spp;              // samples per pixel in this pass
uniform int bki_pass;             // pass index (decorrelates the random numbers)

uint bki_hash(uint v) {  // PCG-style integer hash (O'Neill 2014; Jarzynski & Olano, JCGT 2020)
    uint s = v * 747796405u + 2891336453u;
    uint w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return (w >> 22u) ^ w;
}

float bki_rand(inout uint state) {
    state = bki_hash(state);
    return float(state >> 8u) * (1.0 / 16777216.0);
}

ivec2 bki_texel_of(vec3 d) {  // (col, row) of a unit map-frame direction
    ivec2 size = textureSize(bki_env, 0);
    float theta = acos(clamp(d.y, -1.0, 1.0));
    float phi = atan(d.x, -d.z);
    int row = clamp(int(floor(theta / BK_PI * float(size.y))), 0, size.y - 1);
    int col = int(floor((phi / (2.0 * BK_PI) + 0.5) * float(size.x)));
    col = col - size.x * int(floor(float(col) / float(size.x)));
    return ivec2(clamp(col, 0, size.x - 1), row);
}

vec4 bki_env_texel(vec3 d_map) { return texelFetch(bki_env, bki_texel_of(d_map), 0); }

// smallest index i in [0, n) with cdf[i] > u (binary search; cdf[n-1] = 1)
int bki_search_marg(float u, int n) {
    int lo = 0;
    int hi = n - 1;
    for (int k = 0; k < 24; ++k) {
        if (lo >= hi) break;
        int mid = (lo + hi) / 2;
        if (texelFetch(bki_env_marg, ivec2(mid, 0), 0).r > u) hi = mid; else lo = mid + 1;
    }
    return lo;
}

int bki_search_cond(float u, int row, int n) {
    int lo = 0;
    int hi = n - 1;
    for (int k = 0; k < 24; ++k) {
        if (lo >= hi) break;
        int mid = (lo + hi) / 2;
        if (texelFetch(bki_env_cond, ivec2(mid, row), 0).r > u) hi = mid; else lo = mid + 1;
    }
    return lo;
}

// a map-frame direction with density (luminance of its texel)/S: a texel by the two CDFs,
// then a point uniform in solid angle inside it (uniform in cos theta and in phi)
vec3 bki_env_sample(vec2 u) {
    ivec2 size = textureSize(bki_env, 0);
    int row = bki_search_marg(u.x, size.y);
    float m0 = row > 0 ? texelFetch(bki_env_marg, ivec2(row - 1, 0), 0).r : 0.0;
    float m1 = texelFetch(bki_env_marg, ivec2(row, 0), 0).r;
    float fu = clamp((u.x - m0) / max(m1 - m0, 1e-30), 0.0, 1.0);
    int col = bki_search_cond(u.y, row, size.x);
    float c0 = col > 0 ? texelFetch(bki_env_cond, ivec2(col - 1, row), 0).r : 0.0;
    float c1 = texelFetch(bki_env_cond, ivec2(col, row), 0).r;
    float fv = clamp((u.y - c0) / max(c1 - c0, 1e-30), 0.0, 1.0);
    float ct0 = cos(float(row) * BK_PI / float(size.y));
    float ct1 = cos(float(row + 1) * BK_PI / float(size.y));
    float ct = mix(ct0, ct1, fu);
    float st = sqrt(max(0.0, 1.0 - ct * ct));
    float phi = ((float(col) + fv) / float(size.x) - 0.5) * 2.0 * BK_PI;
    return vec3(st * sin(phi), ct, -st * cos(phi));
}

float bki_power_weight(float p, float q) {  // p² / (p² + q²), safe for p or q huge
    if (p <= 0.0) return 0.0;
    float r = q / p;
    return 1.0 / (1.0 + r * r);
}

vec3 bkr_ibl_shade(vec3 P, vec3 n, vec3 t, uvec2 pixel) {
    vec3 b = cross(n, t);
    vec3 v = normalize(-P);
    vec3 wo = vec3(dot(v, t), dot(v, b), dot(v, n));
    if (wo.z <= 0.0) return vec3(0.0);
    mat3 to_eye = mat3(t, b, n);
    uint state = bki_hash(pixel.x + bki_hash(pixel.y + bki_hash(uint(bki_pass))));
    vec3 acc = vec3(0.0);
    for (int i = 0; i < bki_spp; ++i) {
        // 1. a direction from the BRDF's sampler
        vec4 s = bki_brdf_sample(wo, vec2(bki_rand(state), bki_rand(state)));
        if (s.w > 0.0 && s.z > 0.0) {
            vec3 wi = normalize(s.xyz);
            float pf = bki_brdf_pdf(wo, wi);
            if (pf > 0.0) {
                vec4 e = bki_env_texel(normalize(bki_eye_to_map * (to_eye * wi)));
                acc += brdf(wi, wo) * e.rgb * (wi.z * bki_power_weight(pf, e.a) / pf);
            }
        }
        // 2. a direction from the environment's luminance
        vec3 dm = bki_env_sample(vec2(bki_rand(state), bki_rand(state)));
        vec3 wi = transpose(to_eye) * (transpose(bki_eye_to_map) * dm);
        if (wi.z > 0.0) {
            vec4 e = bki_env_texel(dm);
            float pf = bki_brdf_pdf(wo, wi);
            acc += brdf(wi, wo) * e.rgb * (wi.z * bki_power_weight(e.a, pf) / e.a);
        }
    }
    return acc * (bki_strength / float(bki_spp));
}
