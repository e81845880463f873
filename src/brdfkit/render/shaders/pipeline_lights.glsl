// brdfkit renderer: the lights, with OpenGL's attenuation and spotlight rules
// (OpenGL 2.1 §2.14.1). Shared by the fixed-function material (opengl_fixed.glsl)
// and the BRDF materials (pipeline_brdf.glsl). numpy twins: brdfkit.opengl.light_vector
// and brdfkit.render.lighting.orthonormal_tangent.
// Everything in eye space (the eye at the origin, looking down -z).
// Written in the subset common to GLSL 3.30 and GLSL ES 3.00 (the caller adds #version).

precision highp float;
precision highp int;

#define BKR_MAX_LIGHTS 8

uniform int bkr_num_lights;
uniform vec4 bkr_light_position[BKR_MAX_LIGHTS];        // xyzw; w = 0: directional, toward the light
uniform vec3 bkr_light_ambient[BKR_MAX_LIGHTS];
uniform vec3 bkr_light_diffuse[BKR_MAX_LIGHTS];
uniform vec3 bkr_light_specular[BKR_MAX_LIGHTS];
uniform vec3 bkr_light_attenuation[BKR_MAX_LIGHTS];     // constant, linear, quadratic
uniform vec3 bkr_light_spot_direction[BKR_MAX_LIGHTS];  // unit
uniform float bkr_light_spot_exponent[BKR_MAX_LIGHTS];
uniform float bkr_light_spot_cos_cutoff[BKR_MAX_LIGHTS]; // -2.0: not a spotlight (cutoff 180)
uniform vec3 bkr_scene_ambient;                          // light model ambient
uniform int bkr_local_viewer;

// Unit vector from the surface point P toward light i; `factor` receives
// attenuation (positional lights only) times the spotlight factor.
vec3 bkr_light_vector(int i, vec3 P, out float factor) {
    vec4 lp = bkr_light_position[i];
    vec3 vp;
    factor = 1.0;
    if (lp.w != 0.0) {
        vec3 d = lp.xyz / lp.w - P;
        float dist = length(d);
        vp = dist > 0.0 ? d / dist : vec3(0.0);
        vec3 k = bkr_light_attenuation[i];
        factor = 1.0 / (k.x + k.y * dist + k.z * dist * dist);
    } else {
        vp = normalize(lp.xyz);
    }
    float cc = bkr_light_spot_cos_cutoff[i];
    if (cc > -1.5) {
        float cs = -dot(vp, bkr_light_spot_direction[i]);
        float e = bkr_light_spot_exponent[i];
        float spot = cs >= cc ? (e > 0.0 ? pow(max(cs, 0.0), e) : 1.0) : 0.0;
        factor *= spot;
    }
    return vp;
}

// The tangent made orthogonal to the unit normal n (Gram-Schmidt); any
// perpendicular where the given tangent is parallel to n.
vec3 bkr_orthonormal_tangent(vec3 n, vec3 t) {
    vec3 u = t - n * dot(n, t);
    float l = length(u);
    if (l > 1e-6) return u / l;
    vec3 a = abs(n.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    return normalize(a - n * dot(n, a));
}
