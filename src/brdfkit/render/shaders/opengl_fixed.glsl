// brdfkit renderer: OpenGL's fixed-function lighting equation (OpenGL 2.1 §2.14.1),
// the GLSL twin of brdfkit.opengl.shade. Needs pipeline_lights.glsl before it.
//
//   c = e_cm + a_cm a_cs + Σ att_i spot_i [ a_cm a_cli + (n⊙VP_i) d_cm d_cli
//                                           + f_i (n⊙h_i)^s_rm s_cm s_cli ]
// clamped to [0, 1]; f_i = 1 where n·VP_i > 0; h_i = normalize(VP_i + VE) with
// VE = normalize(-P) for a local viewer, (0, 0, 1) otherwise.

uniform vec4 bkr_mat_ambient;
uniform vec4 bkr_mat_diffuse;
uniform vec4 bkr_mat_specular;
uniform vec4 bkr_mat_emission;
uniform float bkr_mat_shininess;

vec4 bkr_shade(vec3 P, vec3 n, vec3 t) {
    vec3 c = bkr_mat_emission.rgb + bkr_mat_ambient.rgb * bkr_scene_ambient;
    vec3 ve = bkr_local_viewer != 0 ? normalize(-P) : vec3(0.0, 0.0, 1.0);
    for (int i = 0; i < BKR_MAX_LIGHTS; ++i) {
        if (i >= bkr_num_lights) break;
        float factor;
        vec3 vp = bkr_light_vector(i, P, factor);
        vec3 term = bkr_light_ambient[i] * bkr_mat_ambient.rgb;
        float ndotl = dot(n, vp);
        if (ndotl > 0.0) {
            term += ndotl * bkr_light_diffuse[i] * bkr_mat_diffuse.rgb;
            vec3 hv = vp + ve;
            float hl = length(hv);
            float ndoth = hl > 0.0 ? max(dot(n, hv / hl), 0.0) : 0.0;
            // GLSL leaves pow(0, 0) undefined; OpenGL's (n⊙h)^0 is 1
            float s = bkr_mat_shininess > 0.0 ? pow(ndoth, bkr_mat_shininess) : 1.0;
            term += s * bkr_light_specular[i] * bkr_mat_specular.rgb;
        }
        c += factor * term;
    }
    return vec4(clamp(c, 0.0, 1.0), clamp(bkr_mat_diffuse.a, 0.0, 1.0));
}
