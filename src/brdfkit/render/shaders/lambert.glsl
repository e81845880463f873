// Lambert (Photometria, 1760): f_r = kd / π.   numpy: brdfkit/models/lambert.py
uniform vec3 u_kd;

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    return u_kd / BK_PI;
}
