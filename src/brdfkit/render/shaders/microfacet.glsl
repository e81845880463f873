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
// Multiple scattering (Kulla & Conty 2017; numpy: brdfkit/terms/multiscatter.py):
//   f_ms = ks · F_avg² E_avg / (1 − F_avg (1 − E_avg)) · (1 − E(μi)) (1 − E(μo)) / (π (1 − E_avg))
// with 1 − E(α, μ) bilinear in the table (α first, then μ; nodes uniform on [0, 1]), 1 − E_avg
// linear in α, F_avg = 2 ∫ F(μ) μ dμ by the same 16 Gauss-Legendre nodes as numpy.
// The tables (BK_MS_*) are generated into multiscatter_tables.glsl by `python -m brdfkit.render.generate`;
// brdfkit.render.glsl puts that file in place of the next line (GLSL has no #include).
// @include multiscatter_tables.glsl

float microfacet_ms_at(int k) {  // element k of the flat 1 - E table
    vec4 v = BK_MS_MISSING4[k / 4];
    return v[k - 4 * (k / 4)];
}

float microfacet_ms_avg_at(int k) {
    vec4 v = BK_MS_MISSING_AVG4[k / 4];
    return v[k - 4 * (k / 4)];
}

int microfacet_ms_table() {  // index of (distribution, shadowing), as DISTRIBUTIONS x SHADOWINGS
    return (u_distribution == 1 ? 3 : 0) + u_shadowing;
}

// 1 - E(alpha, mu): linear in alpha between table rows, then linear in mu
float microfacet_ms_missing(int tab, float alpha, float mu) {
    float sa = clamp(alpha, 0.0, 1.0) * float(BK_MS_N - 1);
    int ia = min(int(floor(sa)), BK_MS_N - 2);
    float ta = sa - float(ia);
    float sm = clamp(mu, 0.0, 1.0) * float(BK_MS_N - 1);
    int im = min(int(floor(sm)), BK_MS_N - 2);
    float tm = sm - float(im);
    int r0 = (tab * BK_MS_N + ia) * BK_MS_N + im;
    int r1 = r0 + BK_MS_N;
    float a0 = microfacet_ms_at(r0) * (1.0 - ta) + microfacet_ms_at(r1) * ta;
    float a1 = microfacet_ms_at(r0 + 1) * (1.0 - ta) + microfacet_ms_at(r1 + 1) * ta;
    return a0 * (1.0 - tm) + a1 * tm;
}

float microfacet_ms_missing_avg(int tab, float alpha) {
    float sa = clamp(alpha, 0.0, 1.0) * float(BK_MS_N - 1);
    int ia = min(int(floor(sa)), BK_MS_N - 2);
    float ta = sa - float(ia);
    int k = tab * BK_MS_N + ia;
    return microfacet_ms_avg_at(k) * (1.0 - ta) + microfacet_ms_avg_at(k + 1) * ta;
}

vec3 microfacet_fresnel(float c);

vec3 microfacet_fresnel_avg() {
    vec3 s = vec3(0.0);
    for (int k = 0; k < BK_MS_FAVG_N; ++k) s += BK_MS_FAVG_W[k] * BK_MS_FAVG_MU[k] * microfacet_fresnel(BK_MS_FAVG_MU[k]);
    return 2.0 * s;
}

vec3 microfacet_multiscatter(float cos_i, float cos_o, float ax, float ay) {
    int tab = microfacet_ms_table();
    float alpha = sqrt(ax * ay);
    float gap = microfacet_ms_missing_avg(tab, alpha);  // 1 - E_avg
    if (gap <= 1e-7) return vec3(0.0);
    vec3 favg = microfacet_fresnel_avg();
    vec3 weight = favg * favg * (1.0 - gap) / (1.0 - favg * gap);
    float m = microfacet_ms_missing(tab, alpha, cos_i) * microfacet_ms_missing(tab, alpha, cos_o);
    return u_ks * weight * (m / (BK_PI * gap));
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
    if (u_multiscatter != 0) spec += microfacet_multiscatter(cos_i, cos_o, ax, ay);
    return spec + u_kd / BK_PI;
}
