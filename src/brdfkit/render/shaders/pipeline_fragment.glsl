// brdfkit renderer: the fragment stage. Defines chosen by brdfkit/render/renderer.py:
//   BKR_LIGHT_IN_FRAGMENT  Phong shading: light here with the interpolated normal
//   BKR_GBUFFER            write eye-space position, normal, tangent (lit on the CPU)
//   BKR_IBL                image-based lighting with the interpolated normal (ibl.glsl)
//   otherwise              the interpolated (or flat) vertex colour
// The alpha written is coverage (1); the material's alpha is not used for blending.

centroid in vec3 v_pos;
centroid in vec3 v_normal;
centroid in vec3 v_tangent;
#ifdef BKR_FLAT
flat in vec4 v_color;
#else
centroid in vec4 v_color;
#endif

#ifdef BKR_GBUFFER
layout(location = 0) out vec4 o_pos;
layout(location = 1) out vec4 o_normal;
layout(location = 2) out vec4 o_tangent;
#else
layout(location = 0) out vec4 o_color;
#endif

void main() {
#if defined(BKR_GBUFFER)
    o_pos = vec4(v_pos, 1.0);
    o_normal = vec4(normalize(v_normal), 1.0);
    o_tangent = vec4(v_tangent, 1.0);
#elif defined(BKR_IBL)
    vec3 n = normalize(v_normal);
    o_color = vec4(bkr_ibl_shade(v_pos, n, bkr_orthonormal_tangent(n, v_tangent), uvec2(gl_FragCoord.xy)), 1.0);
#elif defined(BKR_LIGHT_IN_FRAGMENT)
    vec3 n = normalize(v_normal);
    o_color = vec4(bkr_shade(v_pos, n, bkr_orthonormal_tangent(n, v_tangent)).rgb, 1.0);
#else
    o_color = vec4(v_color.rgb, 1.0);
#endif
}
