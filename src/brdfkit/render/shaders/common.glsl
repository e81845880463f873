// brdfkit common GLSL: constants, accurate math helpers and the shared
// Fresnel (F), distribution (D) and shadowing (G) terms, mirroring the numpy
// functions in brdfkit/terms/*.py one for one (same names, same clamps).
//
// Written in the subset common to GLSL 3.30 and GLSL ES 3.00: no #version
// line (the caller prepends it), no #include, no double, explicit float
// literals, no implicit int->float conversion. Every model file
// (<module>.glsl) is appended to this file and defines
//     vec3 brdf(vec3 wi, vec3 wo)
// in the local shading frame (normal +z, tangent +x), wi toward the light,
// wo toward the viewer, returning f_r in 1/sr without the cosine and vec3(0)
// where wi.z <= 0 or wo.z <= 0.
//
// Some GL implementations (Mesa's llvmpipe among them) evaluate acos/asin
// with ~1e-4 absolute error and atan with ~2e-5 relative error, so the
// models use bk_atan / bk_acos below (about 2e-7 relative in float32), and
// erf, which GLSL lacks, is bk_erf.

precision highp float;
precision highp int;

#define BK_PI 3.14159265358979323846
#define BK_INV_PI 0.31830988618379067154
#define BK_HALF_PI 1.57079632679489661923
#define BK_INV_SQRT_PI 0.56418958354775628695

// ---------------------------------------------------------------------------
// math helpers
// ---------------------------------------------------------------------------

// arctangent of x in [0, 1]: x * P(x^2), P a degree-8 polynomial fitted
// (least squares with Lawson reweighting, float64) to atan(x)/x on [0, 1];
// float32 relative error about 1.3e-7.
float bk_atan01(float x) {
    float t = x * x;
    float p = 0.002903552493080497;
    p = p * t - 0.016283007338643074;
    p = p * t + 0.043039366602897644;
    p = p * t - 0.0753367617726326;
    p = p * t + 0.10654677450656891;
    p = p * t - 0.14207133650779724;
    p = p * t + 0.19993053376674652;
    p = p * t - 0.3333309292793274;
    p = p * t + 1.0;
    return x * p;
}

// arctangent of any finite x
float bk_atan(float x) {
    float ax = abs(x);
    float r = ax <= 1.0 ? bk_atan01(ax) : BK_HALF_PI - bk_atan01(1.0 / ax);
    return x < 0.0 ? -r : r;
}

// arccosine of x in [-1, 1] (clamped): acos x = 2 atan(sqrt((1-x)/(1+x))),
// accurate near x = ±1 where acos is steep.
float bk_acos(float x) {
    float ax = min(abs(x), 1.0);
    float r = 2.0 * bk_atan01(sqrt((1.0 - ax) / (1.0 + ax)));
    return x < 0.0 ? BK_PI - r : r;
}

// atan2(y, x) in [−π, π] as numpy's arctan2 away from the origin (there: 0), the sign of
// y's zero kept (atan2(−0, x < 0) = −π); from bk_atan01: GL's atan(y, x) is 2e-5 off on llvmpipe
float bk_atan2(float y, float x) {
    float ax = abs(x), ay = abs(y);
    if (ax == 0.0 && ay == 0.0) return 0.0;
    float r = ay <= ax ? bk_atan01(ay / ax) : BK_HALF_PI - bk_atan01(ax / ay);
    if (x < 0.0) r = BK_PI - r;
    return (floatBitsToUint(y) >> 31) != 0u ? -r : r;
}

// complementary error function for x >= 0: the Chebyshev-fitted form of
// Numerical Recipes (Press et al., 2nd ed., §6.2, fractional error < 1.2e-7).
float bk_erfc_pos(float x) {
    float t = 1.0 / (1.0 + 0.5 * x);
    float p = 0.17087277;
    p = p * t - 0.82215223;
    p = p * t + 1.48851587;
    p = p * t - 1.13520398;
    p = p * t + 0.27886807;
    p = p * t - 0.18628806;
    p = p * t + 0.09678418;
    p = p * t + 0.37409196;
    p = p * t + 1.00002368;
    p = p * t - 1.26551223;
    return t * exp(-x * x + p);
}

float bk_erf(float x) {
    float r = 1.0 - bk_erfc_pos(abs(x));
    return x < 0.0 ? -r : r;
}

float bk_erfc(float x) {
    return x >= 0.0 ? bk_erfc_pos(x) : 2.0 - bk_erfc_pos(-x);
}

float bk_sqr(float x) { return x * x; }

// the horizon test every brdf() starts with
bool bk_below(vec3 wi, vec3 wo) { return wi.z <= 0.0 || wo.z <= 0.0; }

// wi + wo divided by its largest absolute component: the half vector's direction with
// a length in [1, √3], safe to normalise at grazing angles (brdfkit.geometry.scaled_sum).
// Callers have wi.z + wo.z > 0, so the divisor is positive.
vec3 bk_scaled_sum(vec3 wi, vec3 wo) {
    vec3 H = wi + wo;
    return H / max(max(abs(H.x), abs(H.y)), abs(H.z));
}

// normalize(wi + wo), robust at grazing angles (brdfkit.geometry.half_vector)
vec3 bk_half_vector(vec3 wi, vec3 wo) {
    vec3 s = bk_scaled_sum(wi, wo);
    return s / sqrt(dot(s, s));
}

// ---------------------------------------------------------------------------
// Fresnel (terms/fresnel.py)
// ---------------------------------------------------------------------------

// Exact dielectric Fresnel in Cook & Torrance's (1982, eq. 8) form, relative
// index n; 1 under total internal reflection:
//   F = ½ (g−c)²/(g+c)² · (1 + (c(g+c)−1)²/(c(g−c)+1)²),  g² = n² + c² − 1.
// Evaluated without cancellation: g² = (n−1)(n+1) + c² for n >= 1 and
// n² − (1−c)(1+c) for n < 1, and g − c = (n−1)(n+1)/(g + c).
float fresnel_dielectric_cook1(float c, float n) {
    c = clamp(c, 0.0, 1.0);
    float n2m1 = (n - 1.0) * (n + 1.0);
    if (n2m1 == 0.0) return 0.0;  // n = 1: no interface
    float g2 = n >= 1.0 ? n2m1 + c * c : n * n - (1.0 - c) * (1.0 + c);
    if (g2 < 0.0) return 1.0;
    float g = sqrt(g2);
    float gpc = g + c;
    if (gpc <= 0.0) return 1.0;  // g = c = 0: grazing at the critical angle
    float gmc = n2m1 / gpc;
    float a = gmc / gpc;
    float num = c * gpc - 1.0;
    float den = c * gmc + 1.0;
    float r = num / den;
    return clamp(0.5 * a * a * (1.0 + r * r), 0.0, 1.0);
}

vec3 fresnel_dielectric_cook(float c, vec3 n) {
    return vec3(fresnel_dielectric_cook1(c, n.r),
                fresnel_dielectric_cook1(c, n.g),
                fresnel_dielectric_cook1(c, n.b));
}

// complex helpers: vec2(re, im)
vec2 bk_cmul(vec2 a, vec2 b) { return vec2(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x); }
vec2 bk_cdiv(vec2 a, vec2 b) {
    // Smith's algorithm: no overflow/underflow of |b|^2
    if (abs(b.x) >= abs(b.y)) {
        float r = b.y / b.x;
        float d = b.x + b.y * r;
        return vec2((a.x + a.y * r) / d, (a.y - a.x * r) / d);
    }
    float r = b.x / b.y;
    float d = b.x * r + b.y;
    return vec2((a.x * r + a.y) / d, (a.y * r - a.x) / d);
}
vec2 bk_csqrt(vec2 z) {
    // principal square root, cancellation-free
    float m = length(z);
    if (m == 0.0) return vec2(0.0);
    if (z.x >= 0.0) {
        float t = sqrt(0.5 * (m + z.x));
        return vec2(t, z.y / (2.0 * t));
    }
    float t = sqrt(0.5 * (m - z.x));
    return vec2(abs(z.y) / (2.0 * t), z.y < 0.0 ? -t : t);
}
float bk_cabs2(vec2 z) { return dot(z, z); }

// Exact unpolarised Fresnel reflectance of a conductor, index η = eta + i k:
// cos²θt = 1 − sin²θi/η², r_s = (c − η cos θt)/(c + η cos θt),
// r_p = (η c − cos θt)/(η c + cos θt), F = (|r_s|² + |r_p|²)/2.
// Evaluated without cancellation (η ≈ 1, grazing, c ≈ 1): with q = (η−1)(η+1),
//   cos²θt = (q + c²)/η² for |η| >= 1, (η² − (1−c)(1+c))/η² for |η| < 1,
//   r_s = −q/(c + η cos θt)²,
//   r_p = q ((η² + 1)c² − 1) / (η² (η c + cos θt)²).
float fresnel_conductor1(float c, float eta, float k) {
    c = clamp(c, 0.0, 1.0);
    vec2 e = vec2(eta, k);
    vec2 e2 = bk_cmul(e, e);
    vec2 q = bk_cmul(e - vec2(1.0, 0.0), e + vec2(1.0, 0.0));
    vec2 num = bk_cabs2(e) >= 1.0 ? q + vec2(c * c, 0.0) : e2 - vec2((1.0 - c) * (1.0 + c), 0.0);
    vec2 cos_t = bk_csqrt(bk_cdiv(num, e2));
    vec2 ds = vec2(c, 0.0) + bk_cmul(e, cos_t);
    vec2 dp = e * c + cos_t;
    float ds2 = bk_cabs2(ds);
    float dp2 = bk_cabs2(dp);
    float q2 = bk_cabs2(q);
    if (ds2 <= 0.0 || dp2 <= 0.0) return q2 > 0.0 ? 1.0 : 0.0;
    float rs2 = q2 / (ds2 * ds2);
    vec2 b = (e2 + vec2(1.0, 0.0)) * (c * c) - vec2(1.0, 0.0);
    float rp2 = q2 * bk_cabs2(b) / (bk_cabs2(e2) * dp2 * dp2);
    return clamp(0.5 * (rs2 + rp2), 0.0, 1.0);
}

vec3 fresnel_conductor(float c, vec3 eta, vec3 k) {
    return vec3(fresnel_conductor1(c, eta.r, k.r),
                fresnel_conductor1(c, eta.g, k.g),
                fresnel_conductor1(c, eta.b, k.b));
}

// Schlick (1994): F0 + (1 − F0)(1 − c)^5
vec3 fresnel_schlick(vec3 f0, float c) {
    float m = 1.0 - clamp(c, 0.0, 1.0);
    float m2 = m * m;
    return f0 + (vec3(1.0) - f0) * (m2 * m2 * m);
}

float fresnel_schlick1(float f0, float c) {
    float m = 1.0 - clamp(c, 0.0, 1.0);
    float m2 = m * m;
    return f0 + (1.0 - f0) * (m2 * m2 * m);
}

// normal-incidence reflectance ((n − 1)/(n + 1))²
vec3 f0_from_ior(vec3 n) {
    vec3 r = (n - vec3(1.0)) / (n + vec3(1.0));
    return r * r;
}

// ---------------------------------------------------------------------------
// Microfacet distributions D and Smith Λ (terms/distributions.py)
// ---------------------------------------------------------------------------
// h, w: local unit vectors; ax, ay: roughness along +x / +y (ax == ay for
// isotropic). D is evaluated as exp(−e − 4 ln h_z) so it underflows to 0
// instead of 0/0; every D is 0 for h_z <= 0.

const int BK_BECKMANN = 0;
const int BK_GGX = 1;

// Normalised Beckmann (Walter et al. 2007, eq. 25; anisotropic Heitz 2014, eq. 71):
// exp(−(h_x²/α_x² + h_y²/α_y²)/h_z²) / (π α_x α_y h_z⁴)
float beckmann(vec3 h, float ax, float ay) {
    if (h.z <= 0.0) return 0.0;
    float e = (bk_sqr(h.x / ax) + bk_sqr(h.y / ay)) / (h.z * h.z);
    return exp(-e - 4.0 * log(h.z)) / (ax * ay) / BK_PI;
}

// Beckmann without the 1/π (Cook & Torrance 1982, eq. 4, from a half vector)
float beckmann_unnormalized(vec3 h, float ax, float ay) {
    if (h.z <= 0.0) return 0.0;
    float e = (bk_sqr(h.x / ax) + bk_sqr(h.y / ay)) / (h.z * h.z);
    return exp(-e - 4.0 * log(h.z)) / (ax * ay);
}

// The lecture's / Cook & Torrance's (1982, eq. 4) D from cos α = n·h:
// exp(−(tan α / m)²) / (m² cos⁴ α), no 1/π.
float beckmann_cook(float cos_h, float m) {
    float c = clamp(cos_h, -1.0, 1.0);
    if (c <= 0.0) return 0.0;
    float t2 = (1.0 - c * c) / (c * c);
    return exp(-t2 / (m * m) - 4.0 * log(c)) / (m * m);
}

// GGX / Trowbridge-Reitz (Walter et al. 2007, eq. 33; anisotropic Heitz 2014, eq. 85):
// 1 / (π α_x α_y (h_x²/α_x² + h_y²/α_y² + h_z²)²)
float ggx(vec3 h, float ax, float ay) {
    if (h.z <= 0.0) return 0.0;
    float q = bk_sqr(h.x / ax) + bk_sqr(h.y / ay) + h.z * h.z;
    return 1.0 / (BK_PI * ax * ay * q * q);
}

float microfacet_d(int dist, vec3 h, float ax, float ay) {
    return dist == BK_GGX ? ggx(h, ax, ay) : beckmann(h, ax, ay);
}

// s = sqrt(w_x² α_x² + w_y² α_y²), so that α(w) tan θ = s / w_z (Heitz 2014, eq. 80)
float projected_roughness_tan(vec3 w, float ax, float ay) {
    return sqrt(bk_sqr(w.x * ax) + bk_sqr(w.y * ay));
}

// Exact Smith Λ of Beckmann, for w.z > 0 (Walter et al. 2007, eq. 27; Heitz 2014, eq. 72):
// a = w_z / s, Λ = (exp(−a²)/(a √π) − erfc(a)) / 2, clamped at 0; Λ = 0 for s = 0.
// A subnormal w.z counts as the smallest normal float (terms/distributions.py: lambda_floor).
float bk_lambda_floor(float z) {
    return z > 0.0 ? max(z, 1.17549435e-38) : z;
}

float beckmann_lambda(vec3 w, float ax, float ay) {
    float s = projected_roughness_tan(w, ax, ay);
    if (s <= 0.0) return 0.0;
    float a = bk_lambda_floor(w.z) / s;
    float lam = 0.5 * (exp(-a * a) / (a * 1.77245385090551602730) - bk_erfc_pos(a));
    return max(lam, 0.0);
}

// Exact Smith Λ of GGX, for w.z > 0 (Walter et al. 2007, eq. 34; Heitz 2014, eq. 86):
// (−1 + sqrt(1 + α² tan²θ))/2 evaluated as s² / (2 w_z (sqrt(w_z² + s²) + w_z)).
float ggx_lambda(vec3 w, float ax, float ay) {
    float s = projected_roughness_tan(w, ax, ay);
    float z = bk_lambda_floor(w.z);
    return (s * s) / (2.0 * z * (sqrt(z * z + s * s) + z));
}

float microfacet_lambda(int dist, vec3 w, float ax, float ay) {
    return dist == BK_GGX ? ggx_lambda(w, ax, ay) : beckmann_lambda(w, ax, ay);
}

// ---------------------------------------------------------------------------
// Masking-shadowing G (terms/shadowing.py)
// ---------------------------------------------------------------------------

// Torrance-Sparrow / Cook-Torrance (1982, eq. 6) V-groove:
// min(1, 2(n·h)(n·v)/(v·h), 2(n·h)(n·l)/(l·h)); negative cosines count as 0,
// a zero v·h or l·h leaves its term out.
float v_groove(float n_h, float n_v, float n_l, float v_h, float l_h) {
    n_h = max(n_h, 0.0);
    n_v = max(n_v, 0.0);
    n_l = max(n_l, 0.0);
    v_h = max(v_h, 0.0);
    l_h = max(l_h, 0.0);
    float g = 1.0;
    if (v_h > 0.0) g = min(g, 2.0 * n_h * n_v / v_h);
    if (l_h > 0.0) g = min(g, 2.0 * n_h * n_l / l_h);
    return max(g, 0.0);
}

// Smith masking G1(w) = χ⁺(w·h) / (1 + Λ(w)); 0 for w.z <= 0 (Λ = ∞).
float smith_g1(vec3 w, float ax, float ay, int dist, vec3 h) {
    if (w.z <= 0.0 || dot(w, h) <= 0.0) return 0.0;
    return 1.0 / (1.0 + microfacet_lambda(dist, w, ax, ay));
}

// separable Smith G1(wi) G1(wo) (Walter et al. 2007, eq. 23)
float smith_g_separable(vec3 wi, vec3 wo, float ax, float ay, int dist, vec3 h) {
    return smith_g1(wi, ax, ay, dist, h) * smith_g1(wo, ax, ay, dist, h);
}

// height-correlated Smith χ⁺(wi·h) χ⁺(wo·h) / (1 + Λ(wi) + Λ(wo)) (Heitz 2014, eq. 99)
float smith_g_correlated(vec3 wi, vec3 wo, float ax, float ay, int dist, vec3 h) {
    if (wi.z <= 0.0 || wo.z <= 0.0 || dot(wi, h) <= 0.0 || dot(wo, h) <= 0.0) return 0.0;
    return 1.0 / (1.0 + microfacet_lambda(dist, wi, ax, ay) + microfacet_lambda(dist, wo, ax, ay));
}

// atan2(y, x) for y >= 0, x >= 0 (not both 0): the polar angle of a direction
// from (sin θ, cos θ), accurate near 0 and near π/2.
float bk_atan2_pos(float y, float x) {
    return y <= x ? bk_atan01(y / x) : BK_HALF_PI - bk_atan01(x / y);
}

#define BK_FLT_MAX 3.402823466e+38

// The tail of the atanh series: (atanh(z) − z)/z³ = 1/3 + z²/5 + … + z¹⁶/19 for |z| <= 1/3
// (truncation < 1e-10 relative), as a polynomial in z2 = z².
float bk_atanh_tail(float z2) {
    float p = 1.0 / 19.0;
    p = p * z2 + 1.0 / 17.0;
    p = p * z2 + 1.0 / 15.0;
    p = p * z2 + 1.0 / 13.0;
    p = p * z2 + 1.0 / 11.0;
    p = p * z2 + 1.0 / 9.0;
    p = p * z2 + 1.0 / 7.0;
    p = p * z2 + 1.0 / 5.0;
    p = p * z2 + 1.0 / 3.0;
    return p;
}

// log(1 + x) for x in [-0.5, 0.5] without cancellation: 2 atanh(z), z = x/(2 + x),
// |z| <= 1/3; plain log elsewhere.
float bk_log1p(float x) {
    if (abs(x) > 0.5) return log(1.0 + x);
    float z = x / (2.0 + x);
    float z2 = z * z;
    return 2.0 * z * (1.0 + z2 * bk_atanh_tail(z2));
}

// Natural log accurate near 1: GL implementations compute log/log2 with an
// *absolute* error (llvmpipe: 1.6e-7 at x ≈ 1), which pow(x, s) with a large
// s turns into a large relative error (1 % at s = 1e5). For x in [0.5, 1.5]
// x − 1 is exact and bk_log1p is accurate to ~1e-7 relative.
float bk_log(float x) {
    if (x >= 0.5 && x <= 1.5) return bk_log1p(x - 1.0);
    return log(x);
}

// x^s for x >= 0 (0^0 = 1, 0^s = 0), accurate for large s: exp(s·ln x).
float bk_pow(float x, float s) {
    if (x > 0.0) return exp(s * bk_log(x));
    return s == 0.0 ? 1.0 : 0.0;
}
