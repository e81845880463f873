// brdfkit image-based lighting: importance sampling of the BRDF lobes, each routine with
// its solid-angle pdf. numpy twin (the reference, and where each routine's paper is cited):
// brdfkit/analysis/sampling.py; which routine a model gets: brdfkit/render/ibl.py
// (sampler_uniforms, following analysis.sampling.sampler_for).
// Directions in the local shading frame (z = normal). A sample comes back as vec4(wi, ok);
// ok = 0 where the routine cannot produce a direction (a microfacet normal facing away from wo).
// Uses microfacet_d and microfacet_lambda of common.glsl (one source per formula).
// Written in the subset common to GLSL 3.30 and GLSL ES 3.00.

#define BKI_LOBE_NONE 0
#define BKI_LOBE_PHONG 1
#define BKI_LOBE_BLINN 2
#define BKI_LOBE_BECKMANN_H 3
#define BKI_LOBE_GGX_H 4
#define BKI_LOBE_GGX_VISIBLE 5

uniform int bki_lobe;            // one of BKI_LOBE_*
uniform vec2 bki_lobe_params;    // (s, unused) for Phong/Blinn, (alpha_x, alpha_y) for microfacet lobes
uniform float bki_diffuse_prob;  // probability of the cosine-weighted component (1 when bki_lobe = NONE)

// CosineHemisphere (Malley's method): pdf = max(0, cos)/π
vec3 bki_cosine_sample(vec2 u) {
    float r = sqrt(u.x);
    float phi = 2.0 * BK_PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
}

float bki_cosine_pdf(vec3 wi) { return max(wi.z, 0.0) * BK_INV_PI; }

// any orthonormal pair perpendicular to the unit vector r
void bki_frame(vec3 r, out vec3 t, out vec3 b) {
    vec3 a = abs(r.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    t = normalize(a - r * dot(a, r));
    b = cross(r, t);
}

vec4 bki_reflect_valid(vec3 wo, vec3 h) {
    float oh = dot(h, wo);
    return vec4(2.0 * oh * h - wo, oh > 0.0 ? 1.0 : 0.0);
}

// pdf of wi for a half-vector density ph (Walter et al. 2007, eq. 14)
float bki_h_to_wi(float ph, vec3 wo, vec3 h) {
    float oh = dot(h, wo);
    return (oh > 0.0 && h.z > 0.0) ? ph / (4.0 * oh) : 0.0;
}

// PhongLobe(s) around r = reflect(wo): pdf = (s+1)/(2π) max(0, r·wi)^s
vec4 bki_phong_sample(vec3 wo, vec2 u, float s) {
    vec3 r = vec3(-wo.x, -wo.y, wo.z);
    vec3 t, b;
    bki_frame(r, t, b);
    float c = pow(1.0 - u.x, 1.0 / (s + 1.0));
    float sn = sqrt(max(0.0, 1.0 - c * c));
    float phi = 2.0 * BK_PI * u.y;
    return vec4(c * r + sn * cos(phi) * t + sn * sin(phi) * b, 1.0);
}

float bki_phong_pdf(vec3 wo, vec3 wi, float s) {
    float x = max(dot(wi, vec3(-wo.x, -wo.y, wo.z)), 0.0);
    return x > 0.0 ? (s + 1.0) / (2.0 * BK_PI) * pow(x, s) : 0.0;
}

// BlinnLobe(s): h with pdf_h = (s+2)/(2π) (n·h)^(s+1)
vec4 bki_blinn_sample(vec3 wo, vec2 u, float s) {
    float c = pow(1.0 - u.x, 1.0 / (s + 2.0));
    float sn = sqrt(max(0.0, 1.0 - c * c));
    float phi = 2.0 * BK_PI * u.y;
    return bki_reflect_valid(wo, vec3(sn * cos(phi), sn * sin(phi), c));
}

float bki_blinn_pdf(vec3 wo, vec3 wi, float s) {
    vec3 h = bk_half_vector(wi, wo);
    float c = max(h.z, 0.0);
    return bki_h_to_wi((s + 2.0) / (2.0 * BK_PI) * pow(c, s + 1.0), wo, h);
}

// MicrofacetH: h from D(h)(n·h), Beckmann or GGX, anisotropic (Walter et al. 2007, eqs. 28, 35)
vec4 bki_microfacet_h_sample(vec3 wo, vec2 u, int dist, float ax, float ay) {
    float phi = atan(ay * sin(2.0 * BK_PI * u.y), ax * cos(2.0 * BK_PI * u.y));
    float inv_a2 = bk_sqr(cos(phi) / ax) + bk_sqr(sin(phi) / ay);
    float tan2 = dist == BK_BECKMANN ? -log(max(1.0 - u.x, 1e-30)) / inv_a2
                                     : u.x / max(1.0 - u.x, 1e-30) / inv_a2;
    float c = 1.0 / sqrt(1.0 + tan2);
    float sn = sqrt(max(0.0, 1.0 - c * c));
    return bki_reflect_valid(wo, vec3(sn * cos(phi), sn * sin(phi), c));
}

float bki_microfacet_h_pdf(vec3 wo, vec3 wi, int dist, float ax, float ay) {
    vec3 h = bk_half_vector(wi, wo);
    if (h.z <= 0.0) return 0.0;
    return bki_h_to_wi(microfacet_d(dist, h, ax, ay) * h.z, wo, h);
}

// GGXVisible: the distribution of visible normals (Heitz 2018, JCGT 7(4), listing 1)
vec4 bki_ggx_visible_sample(vec3 wo, vec2 u, float ax, float ay) {
    vec3 vh = normalize(vec3(ax * wo.x, ay * wo.y, wo.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 0.0 ? vec3(-vh.y, vh.x, 0.0) / sqrt(lensq) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float phi = 2.0 * BK_PI * u.y;
    float p1 = r * cos(phi);
    float p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2;
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    vec3 h = normalize(vec3(ax * nh.x, ay * nh.y, max(1e-6, nh.z)));
    return bki_reflect_valid(wo, h);
}

float bki_ggx_visible_pdf(vec3 wo, vec3 wi, float ax, float ay) {
    vec3 h = bk_half_vector(wi, wo);
    if (h.z <= 0.0 || dot(h, wo) <= 0.0 || wo.z <= 0.0) return 0.0;
    float g1 = 1.0 / (1.0 + microfacet_lambda(BK_GGX, wo, ax, ay));
    return g1 * microfacet_d(BK_GGX, h, ax, ay) / (4.0 * wo.z);
}

// the model's lobe alone
vec4 bki_lobe_sample(vec3 wo, vec2 u) {
    vec2 q = bki_lobe_params;
    if (bki_lobe == BKI_LOBE_PHONG) return bki_phong_sample(wo, u, q.x);
    if (bki_lobe == BKI_LOBE_BLINN) return bki_blinn_sample(wo, u, q.x);
    if (bki_lobe == BKI_LOBE_BECKMANN_H) return bki_microfacet_h_sample(wo, u, BK_BECKMANN, q.x, q.y);
    if (bki_lobe == BKI_LOBE_GGX_H) return bki_microfacet_h_sample(wo, u, BK_GGX, q.x, q.y);
    if (bki_lobe == BKI_LOBE_GGX_VISIBLE) return bki_ggx_visible_sample(wo, u, q.x, q.y);
    return vec4(bki_cosine_sample(u), 1.0);
}

float bki_lobe_pdf(vec3 wo, vec3 wi) {
    vec2 q = bki_lobe_params;
    if (bki_lobe == BKI_LOBE_PHONG) return bki_phong_pdf(wo, wi, q.x);
    if (bki_lobe == BKI_LOBE_BLINN) return bki_blinn_pdf(wo, wi, q.x);
    if (bki_lobe == BKI_LOBE_BECKMANN_H) return bki_microfacet_h_pdf(wo, wi, BK_BECKMANN, q.x, q.y);
    if (bki_lobe == BKI_LOBE_GGX_H) return bki_microfacet_h_pdf(wo, wi, BK_GGX, q.x, q.y);
    if (bki_lobe == BKI_LOBE_GGX_VISIBLE) return bki_ggx_visible_pdf(wo, wi, q.x, q.y);
    return bki_cosine_pdf(wi);
}

// Mixture: the cosine component with probability bki_diffuse_prob, else the lobe
vec4 bki_brdf_sample(vec3 wo, vec2 u) {
    float pd = bki_diffuse_prob;
    if (u.x < pd) return vec4(bki_cosine_sample(vec2(min(u.x / pd, 0.99999994), u.y)), 1.0);
    return bki_lobe_sample(wo, vec2(min((u.x - pd) / max(1.0 - pd, 1e-30), 0.99999994), u.y));
}

float bki_brdf_pdf(vec3 wo, vec3 wi) {
    float pd = bki_diffuse_prob;
    float p = pd > 0.0 ? pd * bki_cosine_pdf(wi) : 0.0;
    if (pd < 1.0) p += (1.0 - pd) * bki_lobe_pdf(wo, wi);
    return p;
}
