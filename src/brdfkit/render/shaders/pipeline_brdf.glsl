// brdfkit renderer: shading with any registered BRDF (the model's GLSL file,
// defining brdf(wi, wo) in the local frame, comes before this file, and
// pipeline_lights.glsl before that). numpy twin: brdfkit/render/lighting.py.
//
//   L_o = Σ_i f_r(wi, wo) · (π · d_cli) · att_i · spot_i · cos θi  +  L_a · ρ̄
//
// A light's diffuse colour d_cli is read as E⊥/π (E⊥ the irradiance it gives
// a surface facing it), so a Lambert surface of albedo kd facing a light of
// colour 1 reflects radiance kd, just as OpenGL's diffuse term with d_cm = kd.
// L_a = scene ambient + Σ att_i spot_i a_cli, reflected with the model's
// directional albedo at normal viewing ρ̄ (computed once, on the CPU, by
// quadrature of the numpy model). The viewer is always local: wo = normalize(-P).

uniform vec3 bkr_ambient_albedo;

vec4 bkr_shade(vec3 P, vec3 n, vec3 t) {
    vec3 b = cross(n, t);
    vec3 v = normalize(-P);
    vec3 wo = vec3(dot(v, t), dot(v, b), dot(v, n));
    vec3 ambient = bkr_scene_ambient;
    vec3 c = vec3(0.0);
    for (int i = 0; i < BKR_MAX_LIGHTS; ++i) {
        if (i >= bkr_num_lights) break;
        float factor;
        vec3 l = bkr_light_vector(i, P, factor);
        ambient += factor * bkr_light_ambient[i];
        vec3 wi = vec3(dot(l, t), dot(l, b), dot(l, n));
        if (wi.z > 0.0 && wo.z > 0.0 && factor > 0.0) {
            c += brdf(wi, wo) * (BK_PI * bkr_light_diffuse[i]) * (factor * wi.z);
        }
    }
    c += ambient * bkr_ambient_albedo;
    return vec4(c, 1.0);
}
