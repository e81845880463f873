// Measured material as a Neural-BRDF network: A. Sztrajman, G. Rainer,
// T. Ritschel, T. Weyrich, "Neural BRDF Representation and Importance
// Sampling", Computer Graphics Forum 40(6), 2021.   numpy: brdfkit/measured/nbrdf.py
//
// The network maps the Rusinkiewicz (1998) half/difference vectors (φh = 0)
//     x = (sin θh, 0, cos θh, sin θd cos φd, sin θd sin φd, cos θd)
// through relu(x·W1 + b1) (21 units), relu(·W2 + b2) (21 units) and
// max(exp(·W3 + b3) − 1, 0) to RGB f_r in 1/sr, φd folded into [0, π) as the
// numpy model does. The angles are measured.glsl's bk_merl_angles (include
// common.glsl, then measured.glsl with its table brdf() renamed, then this file:
// brdfkit.web.api.nbrdf_source).
//
// u_nbrdf holds the 675 weights in the order fc1 (6×21, row-major: input i,
// unit j at 21 i + j), b1, fc2 (21×21), b2, fc3 (21×3), b3, plus one zero:
// 169 vec4 (brdfkit.web.api.nbrdf_weights).

uniform vec4 u_nbrdf[169];

const int BK_NB_B1 = 126;
const int BK_NB_W2 = 147;
const int BK_NB_B2 = 588;
const int BK_NB_W3 = 609;
const int BK_NB_B3 = 672;

float bk_nb_w(int i) { return u_nbrdf[i >> 2][i & 3]; }

vec3 bk_nbrdf_eval(vec3 a) {
    float sh = sin(a.x), chh = cos(a.x);
    float sd = sin(a.y), cd = cos(a.y);
    float x[6];
    x[0] = sh; x[1] = 0.0; x[2] = chh;
    x[3] = sd * cos(a.z); x[4] = sd * sin(a.z); x[5] = cd;
    float h1[21];
    for (int j = 0; j < 21; ++j) {
        float s = bk_nb_w(BK_NB_B1 + j);
        for (int i = 0; i < 6; ++i) s += x[i] * bk_nb_w(21 * i + j);
        h1[j] = max(s, 0.0);
    }
    float h2[21];
    for (int j = 0; j < 21; ++j) {
        float s = bk_nb_w(BK_NB_B2 + j);
        for (int i = 0; i < 21; ++i) s += h1[i] * bk_nb_w(BK_NB_W2 + 21 * i + j);
        h2[j] = max(s, 0.0);
    }
    vec3 z;
    for (int c = 0; c < 3; ++c) {
        float s = bk_nb_w(BK_NB_B3 + c);
        for (int i = 0; i < 21; ++i) s += h2[i] * bk_nb_w(BK_NB_W3 + 3 * i + c);
        z[c] = min(s, 80.0);
    }
    // exp(z) - 1 without cancellation for small z (expm1)
    vec3 e;
    for (int c = 0; c < 3; ++c) {
        float t = z[c];
        e[c] = abs(t) < 1e-3 ? t * (1.0 + t * (0.5 + t / 6.0)) : exp(t) - 1.0;
    }
    return max(e, vec3(0.0));
}

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    return bk_nbrdf_eval(bk_merl_angles(wi, wo));
}
