// Microfacet BRDF (Walter, Marschner, Li, Torrance, EGSR 2007; anisotropic D and Λ
// from Heitz, JCGT 2014).   numpy: brdfkit/models/microfacet.py
//   f_r = kd/π + ks · F(c) · D(h) · G(wi, wo) / (4 max(n·wi, 1e-18) max(n·wo, 1e-18))
// h = normalize(wi + wo), c = clamp((wi·h + wo·h)/2, 0, 1).
uniform int u_distribution;   // 0 beckmann, 1 ggx
uniform float u_alpha;        // isotropic shorthand; the shader reads u_alpha_x / u_alpha_y
uniform float u_alpha_x;
uniform float u_alpha_y;
uniform int u_shadowing;      // 0 smith (separable), 1 smith-correlated, 2 v-groove
uniform int u_fresnel;        // 0 conductor, 1 dielectric, 2 schlick, 3 none
uniform vec3 u_eta;
uniform vec3 u_k;
uniform vec3 u_f0;
uniform vec3 u_kd;
uniform vec3 u_ks;
uniform int u_multiscatter;   // 1: add the Kulla-Conty multiple-scattering lobe
// Derived uniforms (brdfkit/terms/multiscatter.py, set by render/glsl.py): the missing energy
// 1 - E(mu_j) of the albedo table at this alpha (nodes uniform in mu on [0, 1]) and
// ks * F-weight / (pi (1 - E_avg)).
#define BK_MS_N 33
uniform float u_ms_missing[BK_MS_N];
uniform vec3 u_ms_scale;

// 1 - E(mu): linear between the row's nodes (numpy: terms/multiscatter.py albedo_lookup).
float microfacet_ms_missing(float mu) {
    float s = clamp(mu, 0.0, 1.0) * float(BK_MS_N - 1);
    int i = min(int(floor(s)), BK_MS_N - 2);
    float t = s - float(i);
    return u_ms_missing[i] * (1.0 - t) + u_ms_missing[i + 1] * t;
}

// Kulla & Conty 2017: scale (1 - E(mu_i)) (1 - E(mu_o)), symmetric in wi and wo.
vec3 microfacet_multiscatter(float cos_i, float cos_o) {
    return u_ms_scale * (microfacet_ms_missing(cos_i) * microfacet_ms_missing(cos_o));
}

vec3 microfacet_fresnel(float c) {
    if (u_fresnel == 0) return fresnel_conductor(c, u_eta, u_k);
    if (u_fresnel == 1) return fresnel_dielectric_cook(c, u_eta);
    if (u_fresnel == 2) return fresnel_schlick(u_f0, c);
    return vec3(1.0);
}

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    float ax = u_alpha_x;
    float ay = u_alpha_y;
    int dist = u_distribution == 1 ? BK_GGX : BK_BECKMANN;
    vec3 h = bk_half_vector(wi, wo);
    float cos_i = wi.z;
    float cos_o = wo.z;
    float lh = dot(wi, h);
    float vh = dot(wo, h);
    float c = clamp(0.5 * (lh + vh), 0.0, 1.0);

    float D = microfacet_d(dist, h, ax, ay);
    float G;
    if (u_shadowing == 0) {
        G = (1.0 / (1.0 + microfacet_lambda(dist, wi, ax, ay)))
          * (1.0 / (1.0 + microfacet_lambda(dist, wo, ax, ay)));
    } else if (u_shadowing == 1) {
        G = 1.0 / (1.0 + microfacet_lambda(dist, wi, ax, ay) + microfacet_lambda(dist, wo, ax, ay));
    } else {
        G = v_groove(h.z, cos_o, cos_i, vh, lh);
    }
    vec3 F = microfacet_fresnel(c);
    float geo = G / (4.0 * max(cos_i, 1e-18) * max(cos_o, 1e-18));
    vec3 spec = min((u_ks * F * D) * geo, vec3(BK_FLT_MAX));
    if (u_multiscatter != 0) spec += microfacet_multiscatter(cos_i, cos_o);
    return spec + u_kd / BK_PI;
}
