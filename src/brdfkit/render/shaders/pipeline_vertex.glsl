// brdfkit renderer: the vertex stage. Defines chosen by brdfkit/render/renderer.py:
//   BKR_LIGHT_IN_VERTEX  light here (gouraud / flat); bkr_shade() comes before this file
//   BKR_VERTEX_COLOR     the colour is a vertex attribute (lit on the CPU)
//   BKR_FLAT             the colour is flat: the provoking (last) vertex's, as GL_FLAT
// Normals are transformed by the normal matrix and normalised (GL_NORMALIZE).
// Varyings are interpolated at the centroid of the covered samples, so that MSAA
// never extrapolates a colour or a normal beyond the triangle.

in vec3 in_position;
in vec3 in_normal;
in vec3 in_tangent;
#ifdef BKR_VERTEX_COLOR
in vec4 in_color;
#endif

uniform mat4 bkr_modelview;
uniform mat4 bkr_projection;
uniform mat3 bkr_normal_matrix;

centroid out vec3 v_pos;
centroid out vec3 v_normal;
centroid out vec3 v_tangent;
#ifdef BKR_FLAT
flat out vec4 v_color;
#else
centroid out vec4 v_color;
#endif

void main() {
    vec4 pe = bkr_modelview * vec4(in_position, 1.0);
    vec3 P = pe.xyz / pe.w;
    vec3 n = normalize(bkr_normal_matrix * in_normal);
    vec3 t = mat3(bkr_modelview) * in_tangent;
    v_pos = P;
    v_normal = n;
    v_tangent = t;
#if defined(BKR_LIGHT_IN_VERTEX)
    v_color = bkr_shade(P, n, bkr_orthonormal_tangent(n, t));
#elif defined(BKR_VERTEX_COLOR)
    v_color = in_color;
#else
    v_color = vec4(0.0);
#endif
    gl_Position = bkr_projection * pe;
}
