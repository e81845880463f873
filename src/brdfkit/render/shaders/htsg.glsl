// He, Torrance, Sillion, Greenberg (SIGGRAPH 1991): physical-optics reflection from a
// rough Gaussian surface; eval = directional diffuse + uniform diffuse kd/π (the
// specular delta is not a finite value).   numpy: brdfkit/models/htsg.py (read its
// docstring for the equations, errata and the evaluation of the series).
//
//   ρ_dd = F · |v|⁴ · S_i/c_i · S_o/c_o / π · (2πσ/λ)² (πτ/(2λ))² · Σ(g, T)/g
//   g = (2πσ/λ)² (c_i + c_o)²,  T = (πτ/λ)² |wi_xy + wo_xy|²,  |v|² = |wi + wo|²
//   Σ(g, T) = Σ_{m≥1} e^(−g) g^m/(m!·m) e^(−T/m)
//   σ = σ0/sqrt(1 + W((K_i + K_o)²/(8π))),  K = tan θ erfc(τ/(2σ0 tan θ))
//   S/c = (1 − ½ erfc a)/(c (1 − ½ erfc a) + σ0 s e^(−a²)/(√π τ)),  a = τ c/(2σ0 s)
//   F = exact conductor Fresnel at cos = |wi + wo|/2
//
// float32 evaluation of ln(Σ/g): the asymptotic form (g >= 40, T/g <= 0.5 g^0.55)
// with the exact coefficients Q_1..Q_6 of the numpy module, else the windowed
// direct sum around the saddle point m* in log space, each term from Stirling's
// series written as −m·(x − log1p x), x = (g − m)/m, so that nothing cancels
// (ln m! alone would lose 1e-2 absolute at m ~ 1e4 in float32).
uniform float u_sigma0;
uniform float u_tau;
uniform vec3 u_eta;
uniform vec3 u_k;
uniform vec3 u_wavelengths;
uniform vec3 u_kd;
uniform vec3 u_ks;  // scale of the directional-diffuse (and specular) part

// W(z) for z = exp(lz) >= 0 (principal branch), Newton on w + ln w = lz
float htsg_lambertw_from_log(float lz) {
    if (lz < -30.0) return exp(lz);  // W(z) = z (1 − z + …), z < 1e-13
    float w = lz <= 1.0 ? bk_log1p(exp(lz)) : lz - log(lz);
    for (int i = 0; i < 5; ++i) {
        w = w - (w + bk_log(w) - lz) * w / (w + 1.0);
    }
    return w;
}

// S(θ)/cos θ (eqs. 24-25 with the e^(−a²) erratum)
float htsg_shadowing_over_cos(float c, float sigma0, float tau) {
    c = clamp(c, 0.0, 1.0);
    float s = sqrt(max(0.0, (1.0 - c) * (1.0 + c)));
    float ea = 0.0;
    float ec = 0.0;
    if (s > 0.0) {
        float a = min(tau * c / (2.0 * sigma0 * s), 1e10);
        ea = exp(-a * a);
        ec = bk_erfc_pos(a);
    }
    float den = c * (1.0 - 0.5 * ec) + sigma0 * s * ea / (1.77245385090551602730 * tau);
    return (1.0 - 0.5 * ec) / max(den, 1e-30);
}

// K = tan θ · erfc(τ/(2σ0 tan θ)) (eq. 82)
float htsg_K(float c, float sigma0, float tau) {
    c = clamp(c, 0.0, 1.0);
    float s = sqrt(max(0.0, (1.0 - c) * (1.0 + c)));
    float t = s / max(c, 1e-30);
    if (t <= 0.0) return 0.0;
    return t * bk_erfc_pos(tau / (2.0 * sigma0 * t));
}

// x − log1p(x) for x >= −1 without cancellation; q = 1 + x (= g/m) passed exactly
float htsg_phi(float x, float q) {
    if (x < -0.5) return x - log(q);
    if (x > 0.5) return x - log(q);
    float z = x / (2.0 + x);   // x − 2z = x·z, so x − 2 atanh(z) = x·z − 2z³·tail(z²)
    float z2 = z * z;
    return x * z - 2.0 * z * z2 * bk_atanh_tail(z2);
}

const float HTSG_LNFACT[17] = float[17](0.0, 0.0, 0.693147180559945, 1.7917594692280554, 3.178053830347945, 4.787491742782047, 6.579251212010102, 8.525161361065415, 10.604602902745249, 12.801827480081467, 15.104412573075514, 17.502307845873887, 19.987214495661885, 22.55216385312342, 25.191221182738683, 27.89927138384089, 30.671860106080672);

// ln of the m-th term of Σ/g: (m−1) ln g − g − ln m! − ln m − T/m
float htsg_log_term(float m, float g, float lg, float T) {
    if (m <= 16.0) {
        return (m - 1.0) * lg - g - HTSG_LNFACT[int(m)] - bk_log(m) - T / m;
    }
    // Stirling: ln m! = m ln m − m + ½ ln(2π m) + 1/(12m) − 1/(360m³) (+ < 1e-10 here)
    float lm = log(m);
    float inv = 1.0 / m;
    float st = inv / 12.0 - inv * inv * inv / 360.0;
    float x = (g - m) / m;
    return -m * htsg_phi(x, g / m) - lg - 0.91893853320467274178 - 1.5 * lm - st - T / m;
}

// exact asymptotic coefficients Q_n(a) (brdfkit.models.htsg.asymptotic_coefficients)
float htsg_q1(float a) {
    float p = 0.5;
    p = p * a + -2.0;
    p = p * a + 1.0;
    return p;
}

float htsg_q2(float a) {
    float p = -0.8333333333333334;
    p = p * a + 5.0;
    p = p * a + -7.0;
    p = p * a + 1.5;
    return p;
}

float htsg_q3(float a) {
    float p = 2.0416666666666665;
    p = p * a + -17.333333333333332;
    p = p * a + 43.5;
    p = p * a + -33.0;
    p = p * a + 4.333333333333333;
    return p;
}

float htsg_q4(float a) {
    float p = -6.075;
    p = p * a + 68.66666666666667;
    p = p * a + -260.8333333333333;
    p = p * a + 385.0;
    p = p * a + -191.0;
    p = p * a + 17.75;
    return p;
}

float htsg_q5(float a) {
    float p = 20.334722222222222;
    p = p * a + -292.53333333333336;
    p = p * a + 1533.5416666666667;
    p = p * a + -3571.3333333333335;
    p = p * a + 3604.5;
    p = p * a + -1297.0;
    p = p * a + 92.2;
    return p;
}

float htsg_q6(float a) {
    float p = -73.66924603174603;
    p = p * a + 1304.5333333333333;
    p = p * a + -8902.091666666667;
    p = p * a + 29343.666666666668;
    p = p * a + -48036.166666666664;
    p = p * a + 36137.0;
    p = p * a + -10063.0;
    p = p * a + 574.5;
    return p;
}

// ln(Σ(g, T)/g)
float htsg_log_series_ratio(float g, float T) {
    g = max(g, 1e-30);
    T = max(T, 0.0);
    float a = T / g;
    float lg = log(g);
    if (g >= 40.0 && a <= 0.5 * exp(0.55 * lg)) {
        float eps = 1.0 / g;
        float corr = htsg_q6(a) * eps;
        corr = (corr + htsg_q5(a)) * eps;
        corr = (corr + htsg_q4(a)) * eps;
        corr = (corr + htsg_q3(a)) * eps;
        corr = (corr + htsg_q2(a)) * eps;
        corr = (corr + htsg_q1(a)) * eps;
        return -a - 2.0 * lg + corr;
    }
    // saddle point m* = g exp(W(2T/g²)/2) and width σ_m of the summand
    float w = T > 0.0 ? htsg_lambertw_from_log(log(2.0 * T) - 2.0 * lg) : 0.0;
    float mstar = max(g * exp(0.5 * w), 1.0);
    float sig = 1.0 / sqrt(1.0 / mstar + 2.0 * T / (mstar * mstar * mstar));
    float lo = max(floor(mstar - 6.0 * sig - 1.0), 1.0);
    float hi = ceil(mstar + 7.0 * sig + 4.0);
    float mc = clamp(floor(mstar + 0.5), lo, hi);
    float lc = htsg_log_term(mc, g, lg, T);
    int n = int(min(hi - lo, 8191.0)) + 1;
    float acc = 0.0;
    for (int i = 0; i < n; ++i) {
        float m = lo + float(i);
        acc += exp(htsg_log_term(m, g, lg, T) - lc);
    }
    return lc + log(acc);
}

float htsg_channel(float lam_nm, float eta, float k, float sigma, float vz, float vxy2, float cos_local,
                   float geo) {
    float lam = lam_nm * 1e-3;  // µm
    float k2 = bk_sqr(2.0 * BK_PI * sigma / lam);
    float g = k2 * vz * vz;
    float T = bk_sqr(BK_PI * u_tau / lam) * vxy2;
    float ratio = exp(htsg_log_series_ratio(g, T));
    float F = fresnel_conductor1(cos_local, eta, k);
    return F * geo * k2 * bk_sqr(BK_PI * u_tau / (2.0 * lam)) * ratio;
}

vec3 brdf(vec3 wi, vec3 wo) {
    if (bk_below(wi, wo)) return vec3(0.0);
    vec3 kd = u_kd / BK_PI;
    if (u_sigma0 <= 0.0) return kd;
    float ci = clamp(wi.z, 0.0, 1.0);
    float co = clamp(wo.z, 0.0, 1.0);
    float vx = wi.x + wo.x;
    float vy = wi.y + wo.y;
    float vz = ci + co;
    float vxy2 = vx * vx + vy * vy;
    float v2 = vxy2 + vz * vz;
    // effective roughness (eqs. 80-83): (z0/σ0)² = W((K_i + K_o)²/(8π))
    float kk = htsg_K(ci, u_sigma0, u_tau) + htsg_K(co, u_sigma0, u_tau);
    float w = kk > 0.0 ? htsg_lambertw_from_log(2.0 * log(kk) - 3.22417142752923640 /* ln 8π */) : 0.0;
    float sigma = u_sigma0 / sqrt(1.0 + w);
    float si = htsg_shadowing_over_cos(ci, u_sigma0, u_tau);
    float so = htsg_shadowing_over_cos(co, u_sigma0, u_tau);
    float geo = v2 * v2 * si * so / BK_PI;
    float cos_local = clamp(0.5 * sqrt(v2), 0.0, 1.0);
    vec3 dd = vec3(htsg_channel(u_wavelengths.r, u_eta.r, u_k.r, sigma, vz, vxy2, cos_local, geo),
                   htsg_channel(u_wavelengths.g, u_eta.g, u_k.g, sigma, vz, vxy2, cos_local, geo),
                   htsg_channel(u_wavelengths.b, u_eta.b, u_k.b, sigma, vz, vxy2, cos_local, geo));
    return max(u_ks * dd + kd, vec3(0.0));
}
