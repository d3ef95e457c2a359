// terms.glsl — the GLSL form of every term of FORMULAS.md §2–§5, one block each, in the
// order of the family lists (src/terms/{d,g,f,k}/mod.rs). A block starts with the line
// `// term <family>/<name>: <citation>`, the term's Rust file (src/terms/<family>/<name>.rs)
// and its CITATION; its functions are named `<name>_...` as the Rust file's forms are
// (tests/term_homes.rs holds the two together). Every function is compiled only when its
// feature is in the batch's FeatureSet (the HAS_* macros), so a GGX + Schlick kernel has no
// erf, no complex Fresnel.
//
// A block holds all of its term's forms: the float32 one every tuple takes, then the two
// that the models' tiny-cosine path takes (FORMULAS.md §1, "Overflow": a cosine below
// TINY_COS, where float32's range no longer holds the factors): `<name>_..._f64` on a device
// with float64, `<name>_..._xf` (m 2^e pairs, ff.glsl) on one without. The two are the same
// formula; models.glsl picks the form, these blocks hold the arithmetic.

#ifndef VKBRDF_TERMS_GLSL
#define VKBRDF_TERMS_GLSL

#include "math.glsl"
#include "ff.glsl"
#include "f_poly_constants.glsl"

// HTSG (htsg.glsl) evaluates the conductor's F: its code is compiled with the model's.
#if defined(HAS_HTSG) && !defined(HAS_F_CONDUCTOR)
#define HAS_F_CONDUCTOR
#endif


// ===================================================================== D (FORMULAS.md §2)
// Arguments: slope2 = (hx/mx)^2 + (hy/my)^2 (= sin2_h / m^2 when isotropic), so that
// tan2_h / m^2 = slope2 / cos_h^2; `norm` is the normalisation constant precomputed in f64
// on the host (src/gpu/layout.rs). Smith's Lambda is the distribution's, in its block.

// term d/gaussian: Torrance & Sparrow 1967
#if defined(HAS_D_GAUSSIAN)
// Torrance & Sparrow 1967, "Theory for Off-Specular Reflection from Roughened Surfaces".
// exp(-(delta/m)^2), delta = angle between n and h. Unnormalised: no 1/pi, no 1/cos_h^4.
float gaussian_d(float cos_h, float sin2_h, float inv_m2) {
    float delta = atan2_positive(sqrt(sin2_h), cos_h);
    return exp_acc(-delta * delta * inv_m2);
}
#if defined(HAS_FLOAT64)
// gaussian_d in f64's range: the angle from float32, the exponential in f64.
double gaussian_d_f64(float cos_h, float sin2_h, float inv_m2) {
    double delta = double(atan2_positive(sqrt(sin2_h), cos_h));
    return exp_f64(-delta * delta * double(inv_m2));
}
#else
// ln gaussian_d as a pair.
vec2 gaussian_ln_d_xf(float cos_h, float sin2_h, float inv_m2) {
    float delta = atan2_positive(sqrt(sin2_h), cos_h);
    return vec2(-delta * delta * inv_m2, 0.0);
}
#endif
#endif

// term d/beckmann: Beckmann 1963; Cook & Torrance 1982
#if defined(HAS_D_BECKMANN)
// Beckmann & Spizzichino 1963, "The Scattering of Electromagnetic Waves from Rough
// Surfaces"; anisotropic form from Walter et al. 2007. exp(-tan2_h/m^2) / (k m^2 cos_h^4):
// includes the 1/cos_h^4 and the convention's 1/k (k = pi modern, 1 Cook–Torrance 1982,
// 4 seed), the latter inside `norm`.
// Formed as norm (e^(-x/2) / cos_h^2)^2, x = tan2_h/m^2: at grazing h, exp(-x) underflows
// to 0 while 1/cos_h^4 overflows, and the direct product would be 0 * inf = NaN; the
// halves stay in range while the value can matter. e^(-x/2) is normal up to x = 174.6,
// and 1/cos_h^2 finite down to cos_h = 1.1e-19 (below, x >= 1e28 for every roughness
// <= 1e4 and the value is 0 either way). Beyond x = 174.6 the exact value is below
// norm e^-x (1 + m^2 x)^2 <= 1e-55 norm (1e4 the largest roughness), 0 to the rule's
// floor of FORMULAS.md §1 even times the largest K the float32 path forms (2.5e29).
// The error: exp_acc's 2 ulp and x's own (its 3 roundings, times x, as S_in carries
// it), then 4 roundings: about the log domain's (exp(-x - 4 ln cos_h)), at one division
// and one exp instead of a division, an exp and two logs (log_cos's branches).
float beckmann_d(float slope2, float cos_h, float sin2_h, float norm) {
    // max: a cos_h^2 flushed to 0 gives x = inf, exp_acc(-inf) = 0, and 0, not 0/0.
    float inv_c2 = 1.0 / max(cos_h * cos_h, FLT_MIN);
    float half_lobe = exp_acc(-0.5 * (slope2 * inv_c2)) * inv_c2;
    return norm * (half_lobe * half_lobe);
}
#if defined(HAS_FLOAT64)
// beckmann_d in f64's range, given cos_h in f64 and ln cos_h: the same log domain, where
// cos_h^4 alone would leave f64's range at cosines of 1e-80.
double beckmann_d_f64(float slope2, double cos_h, double ln_cos_delta, float norm) {
    double c2 = cos_h * cos_h;
    return exp_f64(log_f64(double(norm)) - double(slope2) / c2 - 4.0 * ln_cos_delta);
}
#else
// ln beckmann_d as a pair, given cos_h and ln cos_h as pairs. The exponent is capped at
// 1e30 (a D of e^-1e30 is 0 to any K).
vec2 beckmann_ln_d_xf(float slope2, vec2 cos_h, vec2 ln_cos_delta, float norm) {
    float x = xf_float(xf_div(xf(slope2), xf_mul(cos_h, cos_h)));
    return ff_add(vec2(log_acc(norm) - min(x, 1e30), 0.0), ff_mul_f(ln_cos_delta, -4.0));
}
#endif
#endif

#if defined(HAS_LAMBDA_BECKMANN)
// Smith 1967, "Geometrical Shadowing of a Random Rough Surface"; Lambda for Beckmann as in
// Walter et al. 2007: (erf(a) - 1)/2 + exp(-a^2)/(2 a sqrt(pi)), a = 1/(m tan), written with
// erfc (erf(a) - 1 = -erfc(a)). q2 = m^2 tan^2(w). tan = 0 (w = n) gives Lambda = 0.
float beckmann_lambda(float q2) {
    // a = 1/sqrt(0) would be inf and inf * 0 below NaN; the limit is 0.
    if (q2 == 0.0) {
        return 0.0;
    }
    float a = inversesqrt(q2);
    // For large a both terms are ~exp(-a^2)/(a sqrt(pi)) and cancel: the result is tiny in
    // absolute terms, which is all G = 1/(1 + Lambda) needs.
    return 0.5 * (exp_acc(-a * a) * INV_SQRT_PI / a - erfc_nr(a));
}
#if defined(HAS_FLOAT64)
// beckmann_lambda in f64 for q2 >= 1e14 (a cosine below TINY_COS): a = 1/(m tan) <
// TINY_COS/(1e-7 sin) ~ 1e-8 (roughness >= 1e-7), so exp(-a^2) = 1 and erfc(a) = 1 -
// 2a/sqrt(pi) to O(a^2) < 1e-16 relative, and Lambda = 1/(2 a sqrt(pi)) - 1/2 + a/sqrt(pi).
double beckmann_lambda_f64(double q2) {
    double a = 1.0 / sqrt(q2);
    return 0.5 / (a * double(1.0 / INV_SQRT_PI)) - 0.5 + a * double(INV_SQRT_PI);
}
#else
// 1 + beckmann_lambda as a pair, given sqrt(q2) > 1e8 as a pair (a cosine below TINY_COS):
// sqrt(q2)/(2 sqrt(pi)) + 1/2, the dropped terms below 1e-8 relative.
vec2 beckmann_one_plus_lambda_xf(vec2 sqrt_q2) {
    return xf_add(xf_mul(sqrt_q2, xf(0.5 * INV_SQRT_PI)), xf(0.5));
}
#endif
#endif

// term d/ggx: Trowbridge & Reitz 1975; Walter et al. 2007
#if defined(HAS_D_GGX)
// Walter, Marschner, Li & Torrance 2007, "Microfacet Models for Refraction through Rough
// Surfaces" (GGX; the Trowbridge & Reitz 1975 ellipsoid NDF). m^2 / (pi cos_h^4 (m^2 +
// tan2_h)^2), includes the 1/pi. Written 1/(pi mx my (slope2 + cos_h^2)^2), which has no
// 1/cos_h^4 to overflow and is the anisotropic form too (norm = 1/(pi mx my)).
float ggx_d(float slope2, float cos_h, float norm) {
    float d = slope2 + cos_h * cos_h;
    return norm / (d * d);
}
// No f64 or pair form: D >= 1/(pi m^2 (1/m^2)^2) > 1e-15 for roughness in [1e-7, 1e4], a
// normal float32 at any cosine.

// The certificate of the kernel's local f32 frame (frame64.glsl, frame_scalars_local32):
// whether D moves by at most GGX_LOCAL_FRAME_D_BUDGET (relative) when h turns by that
// frame's bound delta = u (2/c + 1) radians (docs/VULKAN.md, "The local f32 frame"). D's
// slope |d ln D/d theta_h| = 4 |1 - m^2| sin cos/s, s = m^2 cos^2 + sin^2 (at most
// 2 |1 - m^2|/m, at tan theta_h = m); slope x delta <= B squared and times c^2, so that no
// root or division is taken: (4 |1 - m^2| u/B)^2 sin^2 cos^2 (2 + c)^2 <= (s c)^2. The
// operands are the frame's own f32 values, whose few-u errors move the test by a few u of
// B, not the bound. The CPU engine's test is terms/d/ggx.rs's local_frame_ok (its f32
// frame turns h by up to u (4.5/c + 1)).
const float GGX_LOCAL_FRAME_D_BUDGET = 4e-6;
bool ggx_local_frame_ok(float cos_h, float sin2_h, float c, float m2) {
    float k = 4.0 * abs(1.0 - m2) * (F32_UNIT_ROUNDOFF / GGX_LOCAL_FRAME_D_BUDGET);
    float cos2 = cos_h * cos_h;
    float s = m2 * cos2 + sin2_h;
    float a = 2.0 + c;
    return (k * k) * (sin2_h * cos2) * (a * a) <= (s * c) * (s * c);
}
#endif

#if defined(HAS_LAMBDA_GGX)
// Walter et al. 2007: Smith Lambda for GGX, (-1 + sqrt(1 + m^2 tan^2))/2. For q2 <= 1 it is
// rewritten q2 / (2 (1 + sqrt(1 + q2))) (no cancellation at small q2); for q2 > 1 the direct
// form is exact enough and stays finite (inf) when q2 = inf, where the quotient is inf/inf.
float ggx_lambda(float q2) {
    float r = sqrt(1.0 + q2);
    return q2 <= 1.0 ? q2 / (2.0 * (1.0 + r)) : 0.5 * (r - 1.0);
}
// R = sqrt(cos^2 + m^2 sin^2) of a direction w, given cos = n.w and m2_sin2 = m^2 |n x w|^2
// (anisotropic: mx^2 (w.t)^2 + my^2 (w.b)^2): GGX's 1 + Lambda = (cos + R)/(2 cos), a sum
// of positive terms, without Lambda's cancellation at small m^2 tan^2 and without the
// division tan^2 takes (the CPU lanes' form, src/terms/g/smith.rs g_ratio_ggx). For cos
// >= TINY_COS (1e-15) cos^2 is a normal float32; below it the f64 or pair forms take G.
float ggx_lambda_root(float cos_w, float m2_sin2_w) {
    return sqrt(cos_w * cos_w + m2_sin2_w);
}

#if defined(HAS_FLOAT64)
// ggx_lambda in f64 for q2 >= 1e14 (a cosine below TINY_COS), where the subtraction does not
// cancel.
double ggx_lambda_f64(double q2) {
    return 0.5 * (sqrt(1.0 + q2) - 1.0);
}
#else
// 1 + ggx_lambda as a pair, given sqrt(q2) > 1e8 as a pair: sqrt(q2)/2 + 1/2, the dropped
// terms below 1e-8 relative.
vec2 ggx_one_plus_lambda_xf(vec2 sqrt_q2) {
    return xf_add(xf_mul(sqrt_q2, xf(0.5)), xf(0.5));
}
#endif
#endif

// term d/blinn: Blinn 1977
#if defined(HAS_D_BLINN)
// Blinn 1977, "Models of Light Reflection for Computer Synthesized Pictures", normalised so
// that its projected integral is 1: (e+2)/(2 pi) cos_h^e, includes the 1/(2 pi) (in norm).
float blinn_d(float cos_h, float sin2_h, float e, float norm) {
    return norm * exp_acc(e * log_cos(cos_h, sin2_h));
}
#if defined(HAS_FLOAT64)
// blinn_d in f64's range, given ln cos_h in f64.
double blinn_d_f64(double ln_cos_delta, float e, float norm) {
    return exp_f64(log_f64(double(norm)) + double(e) * ln_cos_delta);
}
#else
// ln blinn_d as a pair, given ln cos_h as a pair.
vec2 blinn_ln_d_xf(vec2 ln_cos_delta, float e, float norm) {
    return ff_add(vec2(log_acc(norm), 0.0), ff_mul_f(ln_cos_delta, e));
}
#endif
#endif

// term d/charlie: Estevez & Kulla 2017
#if defined(HAS_D_CHARLIE)
// Estevez & Kulla 2017, "Production Friendly Microfacet Sheen BRDF" (Charlie sheen):
// (2 + 1/m)/(2 pi) sin_h^(1/m), 0 < m <= 1; inv_m = 1/m and norm = (2 + 1/m)/(2 pi) from
// the host. ln sin_h is log_cos of the complementary angle: from cos_h^2 (log1p) where h
// is near grazing, as sin_h next to 1 keeps only its absolute precision, which the
// exponent 1/m (up to 1e7) would multiply. 0 at sin_h = 0 (log of 0 is not needed).
float charlie_d(float cos_h, float sin2_h, float inv_m, float norm) {
    if (sin2_h == 0.0) {
        return 0.0;
    }
    return norm * exp_acc(inv_m * log_cos(sqrt(sin2_h), cos_h * cos_h));
}
#if defined(HAS_FLOAT64)
// charlie_d in f64's range (ln sin_h as charlie_d takes it).
double charlie_d_f64(float cos_h, float sin2_h, float inv_m, float norm) {
    if (sin2_h == 0.0) {
        return 0.0;
    }
    double ln_sin = double(log_cos(sqrt(sin2_h), cos_h * cos_h));
    return exp_f64(log_f64(double(norm)) + double(inv_m) * ln_sin);
}
#else
// ln charlie_d as a pair; ln 0 (sin_h = 0) is XF_LN_ZERO.
vec2 charlie_ln_d_xf(float cos_h, float sin2_h, float inv_m, float norm) {
    if (!(sin2_h > 0.0)) {
        return vec2(XF_LN_ZERO, 0.0);
    }
    vec2 ln_sin = vec2(log_cos(sqrt(sin2_h), cos_h * cos_h), 0.0);
    return ff_add(vec2(log_acc(norm), 0.0), ff_mul_f(ln_sin, inv_m));
}
#endif
#endif

// ===================================================================== G (FORMULAS.md §3)

// term g/none: FORMULAS.md §3
// G = 1: no code (the geometry slot is skipped).

// term g/cook_torrance: Blinn 1977; Cook & Torrance 1982
#if defined(HAS_G_COOK_TORRANCE)
// Blinn 1977 (the V-cavity shadowing/masking), as used by Cook & Torrance 1982, "A
// Reflectance Model for Computer Graphics": min(1, 2 cos_h cos_o / c, 2 cos_h cos_i / c).
float cook_torrance_g(float cos_i, float cos_o, float cos_h, float c) {
    float k = 2.0 * cos_h / c;
    return min(1.0, min(k * cos_o, k * cos_i));
}
#if defined(HAS_FLOAT64)
// cook_torrance_g in f64, from the frame's f64 cosines (the float32 cos_h may be flushed
// to 0 there).
double cook_torrance_g_f64(double cos_i, double cos_o, double cos_h, double c) {
    double t = 2.0 * cos_h / c;
    return min(1.0, min(t * cos_o, t * cos_i));
}
#else
// cook_torrance_g with m 2^e pairs.
vec2 cook_torrance_g_xf(vec2 cos_i, vec2 cos_o, vec2 cos_h, vec2 c) {
    vec2 t = xf_div(xf_mul(xf(2.0), cos_h), c);
    return xf_min(xf(1.0), xf_min(xf_mul(t, cos_o), xf_mul(t, cos_i)));
}
#endif
#endif

// term g/smith: Smith 1967; Walter et al. 2007
#if defined(HAS_G_SMITH)
// Smith 1967, separable form: G1(v) G1(l), G1 = 1 / (1 + Lambda).
float smith_g(float lambda_o, float lambda_i) {
    return 1.0 / ((1.0 + lambda_o) * (1.0 + lambda_i));
}
#if defined(HAS_LAMBDA_GGX)
// smith_g for GGX from each direction's cosine and root R (ggx_lambda_root):
// 1/((1 + Lambda_o)(1 + Lambda_i)) = 4 cos_o cos_i / ((cos_o + R_o)(cos_i + R_i)), one
// division where the Lambda form takes five.
float smith_g_ggx(float cos_o, float r_o, float cos_i, float r_i) {
    return (4.0 * cos_o * cos_i) / ((cos_o + r_o) * (cos_i + r_i));
}
#endif
#if defined(HAS_FLOAT64)
// smith_g in f64.
double smith_g_f64(double lambda_o, double lambda_i) {
    return 1.0 / ((1.0 + lambda_o) * (1.0 + lambda_i));
}
#else
// smith_g from 1 + Lambda per direction as pairs.
vec2 smith_g_xf(vec2 one_plus_lambda_o, vec2 one_plus_lambda_i) {
    return xf_div(xf(1.0), xf_mul(one_plus_lambda_o, one_plus_lambda_i));
}
#endif
#endif

// term g/smith_correlated: Heitz 2014
#if defined(HAS_G_SMITH_CORRELATED)
// Heitz 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs",
// eq. 99 (height-correlated Smith): 1 / (1 + Lambda(v) + Lambda(l)).
float smith_correlated_g(float lambda_o, float lambda_i) {
    return 1.0 / (1.0 + lambda_o + lambda_i);
}
#if defined(HAS_LAMBDA_GGX)
// smith_correlated_g for GGX (see smith_g_ggx): 1/(1 + Lambda_o + Lambda_i) =
// 2 cos_o cos_i / (cos_i R_o + cos_o R_i).
float smith_correlated_g_ggx(float cos_o, float r_o, float cos_i, float r_i) {
    return (2.0 * cos_o * cos_i) / (cos_i * r_o + cos_o * r_i);
}
#endif
#if defined(HAS_FLOAT64)
// smith_correlated_g in f64.
double smith_correlated_g_f64(double lambda_o, double lambda_i) {
    return 1.0 / (1.0 + lambda_o + lambda_i);
}
#else
// smith_correlated_g from 1 + Lambda per direction as pairs, on the tiny-cosine path only:
// 1 + Lambda_o + Lambda_i = (1 + Lambda_o) + (1 + Lambda_i) - 1, and there the larger is
// above 1e8 (one cosine is below TINY_COS), so the -1 is below its precision.
vec2 smith_correlated_g_xf(vec2 one_plus_lambda_o, vec2 one_plus_lambda_i) {
    return xf_div(xf(1.0), xf_add(one_plus_lambda_o, one_plus_lambda_i));
}
#endif
#endif

// term g/smith_fast: Walter et al. 2007
#if defined(HAS_G_SMITH_FAST)
// Walter et al. 2007, eq. 27: rational fit of the Smith–Beckmann G1 (<= 0.35 % error), kept
// as published: it exceeds 1 by up to 6.1e-5 for a in (1.548, 1.6).
float smith_fast_g1(float q2) {
    if (q2 == 0.0) {
        return 1.0; // a = inf: G1 = 1 (and inversesqrt(0) is not needed)
    }
    float a = inversesqrt(q2);
    return a < 1.6 ? (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a) : 1.0;
}
#if defined(HAS_FLOAT64)
// smith_fast_g1 in f64 for a = 1/sqrt(q2) < 1.6, given a.
double smith_fast_g1_f64(double a) {
    return (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
}
#else
// smith_fast_g1 for a < 1e-8 as a pair (a cosine below TINY_COS): 3.535 a to 1e-8 relative.
vec2 smith_fast_g1_xf(vec2 a) {
    return xf_mul(xf(3.535), a);
}
#endif
#endif

// term g/schlick_smith: Schlick 1994; Karis 2013
#if defined(HAS_G_SCHLICK_SMITH)
// Schlick 1994, "An Inexpensive BRDF Model for Physically-based Rendering", with the k of
// Karis 2013, "Real Shading in Unreal Engine 4" (m sqrt(2/pi) Beckmann, m/2 GGX; from the
// host): G1(w) = cos_w / (cos_w + k (1 - cos_w)), one_minus_cos_w formed where cos_w is
// known best (k up to 8e3 multiplies its error). Not cos_w (1 - k) + k, which cancels.
float schlick_smith_g1(float cos_w, float one_minus_cos_w, float k) {
    return cos_w / (cos_w + k * one_minus_cos_w);
}
#if defined(HAS_FLOAT64)
// schlick_smith_g1 in f64.
double schlick_smith_g1_f64(double cos_w, double one_minus_cos_w, double k) {
    return cos_w / (cos_w + k * one_minus_cos_w);
}
#else
// schlick_smith_g1 for cos_w as a pair (1 - cos_w is ~1 there).
vec2 schlick_smith_g1_xf(vec2 cos_w, float one_minus_cos_w, float k) {
    return xf_div(cos_w, xf_add(cos_w, xf(k * one_minus_cos_w)));
}
#endif
#endif

// term g/neubelt: Neubelt & Pettineo 2013
#if defined(HAS_G_NEUBELT)
// Neubelt & Pettineo 2013, "Crafting a Next-Gen Material Pipeline for The Order: 1886"
// (cloth): cos_i cos_o / (cos_i + cos_o - cos_i cos_o), the denominator written
// cos_i + cos_o (1 - cos_i) (non-negative terms: no cancellation near 1).
float neubelt_g(float cos_i, float cos_o) {
    return cos_i * cos_o / (cos_i + cos_o * (1.0 - cos_i));
}
#if defined(HAS_FLOAT64)
// neubelt_g in f64.
double neubelt_g_f64(double cos_i, double cos_o) {
    return cos_i * cos_o / (cos_i + cos_o * (1.0 - cos_i));
}
#else
// neubelt_g with the cosines as pairs; one_minus_cos_i from float32 (an absolute error of
// 6e-8 in a term next to cos_i <= 1).
vec2 neubelt_g_xf(vec2 cos_i, vec2 cos_o, float one_minus_cos_i) {
    return xf_div(xf_mul(cos_i, cos_o), xf_add(cos_i, xf_mul(cos_o, xf(one_minus_cos_i))));
}
#endif
#endif

// ===================================================================== F (FORMULAS.md §4)

// term f/none: FORMULAS.md §4
// F = 1: no code (the Fresnel slot is skipped).

// term f/dielectric: Cook & Torrance 1982
#if defined(HAS_F_DIELECTRIC)
// Cook & Torrance 1982 (exact unpolarised dielectric Fresnel), with the seed's typo fixed:
// g^2 = mu^2 + c^2 - 1, F = 1/2 ((g-c)/(g+c))^2 (1 + ((c(g+c) - 1)/(c(g-c) + 1))^2), F = 1
// under total internal reflection (g^2 < 0). mu2m1 = mu^2 - 1 is formed in f64 on the host;
// g - c is computed as (mu^2 - 1)/(g + c), which does not cancel when mu is near 1.
vec3 dielectric_f(float c, vec3 mu2m1, vec3 mu2m1_lo, double_or_float c_exact) {
#if defined(HAS_FLOAT64)
    // g^2 = mu^2 - 1 + c^2 in f64, from c before its rounding to f32 and mu^2 - 1 to ~48
    // bits: near the critical angle of total internal reflection g^2 -> 0 is a difference
    // of O(1) terms, and in f32 the rounding of c alone (6e-8) moved it by O(1) relative
    // there, F by up to 5e-4 (stress corpus, IOR 0.5).
    dvec3 g2d = dvec3(mu2m1) + dvec3(mu2m1_lo) + c_exact * c_exact;
    if (c_exact < 1e-18) {
        // Below c ~ 1e-18, c^2 and c (g + c) leave float32's normal range, and where c is
        // not a normal float (mirrored grazing tuples, cosines of 1e-45) a GPU flushes it
        // and g to 0: g + c = 0 made 0/0 for an index-matched channel. The same expression
        // in f64 (stress corpus under VKBRDF_EMULATE_FTZ, and on an H200).
        dvec3 gd = sqrt(max(g2d, 0.0));
        dvec3 gpcd = gd + c_exact;
        dvec3 gmcd = (dvec3(mu2m1) + dvec3(mu2m1_lo)) / gpcd;
        dvec3 ad = gmcd / gpcd;
        dvec3 bd = (c_exact * gpcd - 1.0) / (c_exact * gmcd + 1.0);
        vec3 fd = vec3(0.5 * ad * ad * (1.0 + bd * bd));
        return mix(fd, vec3(1.0), lessThan(g2d, dvec3(0.0)));
    }
    vec3 g2 = vec3(g2d);
    vec3 g = vec3(sqrt(max(g2d, 0.0)));
#else
    // c below FLT_MIN (both cosines are then below it; a GPU flushes c to 0): F = 1 -
    // O(c/g) for mu != 1 (mu^2 - 1 is at least ~1e-16 there, and under total internal
    // reflection F = 1), F = 0 for mu = 1 (g = c). The lines below would divide 0 by
    // g + c = 0 for mu = 1 (NaN).
    if (c < FLT_MIN) {
        return mix(vec3(1.0), vec3(0.0), equal(mu2m1, vec3(0.0)));
    }
    // The same sum as a float-float pair per channel (c_exact = c to ~48 bits): without it
    // g^2 near the critical angle is a difference of O(1) floats (see above).
    vec3 g2, g;
    for (int ch = 0; ch < 3; ch++) {
        vec2 g2p = ff_add(vec2(mu2m1[ch], mu2m1_lo[ch]), ff_mul(c_exact, c_exact));
        g2[ch] = ff_round(g2p);
        g[ch] = g2p.x > 0.0 ? ff_round(ff_sqrt(g2p)) : 0.0;
    }
#endif
    vec3 gpc = g + c;                 // >= c > 0
    vec3 gmc = mu2m1 / gpc;           // = g - c
    vec3 a = gmc / gpc;
    vec3 b = (c * gpc - 1.0) / (c * gmc + 1.0); // c (g - c) + 1 >= 1 - c^2 >= 0, and > 0 for mu > 0
    vec3 f = 0.5 * a * a * (1.0 + b * b);
    return mix(f, vec3(1.0), lessThan(g2, vec3(0.0)));
}
#endif

// term f/conductor: Born & Wolf 1999
#if defined(HAS_F_CONDUCTOR)
// Complex helpers for three channels at once: (re, im) pairs.
vec3 cmul_re(vec3 ar, vec3 ai, vec3 br, vec3 bi) { return ar * br - ai * bi; }
vec3 cmul_im(vec3 ar, vec3 ai, vec3 br, vec3 bi) { return ar * bi + ai * br; }

// Principal square root of x + iy per channel (Re >= 0). Takes the root of the larger of
// (|z| + x)/2 and (|z| - x)/2 and derives the other part by division (the direct formulas
// cancel when |x| >> |y|). Branch-free: both candidates are computed and one is selected
// per channel, so lanes never diverge.
void csqrt(vec3 x, vec3 y, out vec3 re, out vec3 im) {
    // |z| scaled by the larger component: sqrt(x^2 + y^2) underflows for |z| < ~1e-19 in
    // f32 (x = cos_t^2 = c^2 of an index-matched conductor at c = 1e-12 gave |z| = 0, cos_t
    // 0.7e-12 instead of 1e-12 and F ~ 1 instead of 0). max(.., 1e-37) keeps z = 0 from 0/0.
    vec3 m = max(max(abs(x), abs(y)), vec3(1e-37));
    vec3 xs = x / m, ys = y / m;
    vec3 r = m * sqrt(xs * xs + ys * ys);
    vec3 sp = sqrt(0.5 * (r + x)); // the real part when x >= 0
    vec3 sn = sqrt(0.5 * (r - x)); // |the imaginary part| when x < 0
    // max(.., 1e-30): sp = 0 only for z = 0 (then y = 0 and the quotient must be 0), and
    // sn = 0 only where x >= 0 selects the other candidate; the guard keeps 0/0 = NaN out
    // of both.
    vec3 im_p = 0.5 * y / max(sp, 1e-30);
    vec3 re_n = 0.5 * abs(y) / max(sn, 1e-30);
    vec3 im_n = mix(sn, -sn, lessThan(y, vec3(0.0)));
    bvec3 neg = lessThan(x, vec3(0.0));
    re = mix(sp, re_n, neg);
    im = mix(im_p, im_n, neg);
}

// Born & Wolf 1999, "Principles of Optics", 7th ed., §13.2: exact Fresnel reflectance of a
// conductor with complex eta = n + ik, unpolarised: (|r_par|^2 + |r_perp|^2)/2 with
// sin2_t = (1 - c^2)/eta^2, cos_t = sqrt(1 - sin2_t), r_par = (eta c - cos_t)/(eta c + cos_t),
// r_perp = (c - eta cos_t)/(c + eta cos_t). |r|^2 is taken as |num|^2/|den|^2 (no complex
// division). With k = 0, n >= 1 it equals dielectric_f.
// cos_t^2 = 1 - sin2_t = (eta^2 - 1 + c^2)/eta^2, with Re(eta^2) - 1 = e2rm1 formed in f64
// on the host: 1 - (1 - c^2)/eta^2 in f32 loses c^2 below ~6e-8 when eta is near 1, and
// F then came out 1 instead of ~0 at grazing c (the stress corpus's eta = 1 conductor).
// The division by eta^2 goes through q = |eta|^2 = n^2 + k^2, one factor at a time: the
// direct 1/|eta^2|^2 = 1/q^2 overflows float32 for |eta| > 4e9, and with extinction 1e10 it
// was inf * 0 = NaN (issue 10). The parser bounds n and k by 1e18, so q <= 2e36.
vec3 conductor_f(float c, vec3 n, vec3 k, vec3 e2rm1) {
    vec3 e2r = n * n - k * k;                   // eta^2
    vec3 e2i = 2.0 * n * k;
    vec3 q = n * n + k * k;                     // |eta|^2 = |eta^2|
    vec3 a = e2r / q, b = e2i / q;              // eta^2 / |eta^2|, components in [-1, 1]
    // eta^2 - 1 + c^2 = ar + i e2i, as (n^2 - k^2 - 1) + c^2, or as (n^2 - k^2) - (1 - c^2)
    // where that form's terms are far smaller (|eta| << 1 near c = 1: the first rounds
    // n^2 - k^2 - 1 to f32 next to 1, and F at n = 1e-6, k = 0, c = 1 came out 9e-5 off).
    float s2 = (1.0 - c) * (1.0 + c);
    vec3 nk = (n - k) * (n + k);
    vec3 ar = mix(e2rm1 + c * c, nk - s2,
                  lessThan(4.0 * (abs(nk) + s2), abs(e2rm1) + c * c));
    vec3 zr = (ar * a + e2i * b) / q;           // (ar + i e2i) / eta^2
    vec3 zi = (1.0 - c) * (1.0 + c) * b / q;    // = (e2i e2r - ar e2i) / q^2, uncancelled
    vec3 ctr, cti;
    csqrt(zr, zi, ctr, cti);                    // cos_t
    vec3 ecr = n * c, eci = k * c;              // eta c
    vec3 pr = ecr - ctr, pi_ = eci - cti;       // eta c - cos_t
    vec3 qr = ecr + ctr, qi = eci + cti;        // eta c + cos_t
    vec3 r_par = (pr * pr + pi_ * pi_) / (qr * qr + qi * qi);
    vec3 ecr2 = cmul_re(n, k, ctr, cti), eci2 = cmul_im(n, k, ctr, cti); // eta cos_t
    vec3 ur = c - ecr2, wr = c + ecr2;
    vec3 r_perp = (ur * ur + eci2 * eci2) / (wr * wr + eci2 * eci2);
    return 0.5 * (r_par + r_perp);
}
#endif

#if defined(HAS_F_CONDUCTOR)
// The metal form (the lanes' conductor::f_lane_metal; pbrt-v3's real FrConductor): with
// w = sqrt(eta^2 - sin^2) = A + iB, F = R_s (|w|^2 c^2 + sin^4)/(|w|^2 c^2 + sin^4 +
// 2cA sin^2), R_s = (|w|^2 + c^2 - 2cA)/(|w|^2 + c^2 + 2cA): A alone, over one division,
// about half conductor_f's arithmetic. R_s's numerator cancels as F0 -> 0, so only a
// material whose every channel is legal for it (FLAG_METAL_FORM: the written bound of
// conductor::metal_form_bound within 48u) takes it. Re(eta^2) = e2rm1 + 1 and nk come
// from the f32 material (two and three roundings, where the lanes round f64 values once).
vec3 conductor_f_metal(float c, vec3 n, vec3 k, vec3 e2rm1) {
    float c2 = c * c;
    float s2 = (1.0 - c) * (1.0 + c);
    vec3 e2ih = n * k;                  // Im(eta^2)/2
    vec3 re = (e2rm1 + 1.0) - s2;        // Re(eta^2 - sin^2)
    vec3 mag = sqrt(re * re + 4.0 * e2ih * e2ih);
    // The root's larger component from the sum that does not cancel, A as Im/2 over it
    // where Re < 0 (metals); t >= sqrt(mag/2), which the legality range keeps >= 7e-3.
    vec3 t = sqrt(0.5 * (mag + abs(re)));
    vec3 a = mix(e2ih / t, t, greaterThanEqual(re, vec3(0.0)));
    vec3 ca2 = 2.0 * c * a;
    vec3 bs = mag + c2;
    vec3 bp = mag * c2 + s2 * s2;
    return (bs - ca2) * bp / ((bs + ca2) * (bp + ca2 * s2));
}

// The fitted interval's centre (35/64, exactly an f32): t = c - CONDUCTOR_POLY_CENTRE is
// exact for c in [CENTRE/2, 2 CENTRE] (Sterbenz) and otherwise rounded once.
const float CONDUCTOR_POLY_CENTRE = 0.546875;
// The least c the polynomial takes (the CPU engine's FAST_MIN_C): the fitted interval
// starts at 0.091875; a lane below takes the metal form.
const float CONDUCTOR_POLY_MIN_C = 0.1;

// A folded conductor's F as its fitted polynomial (f_poly_constants.glsl: the CPU
// engine's conductor::poly, 14 multiply-adds a channel where the metal form takes two
// square roots and a division) at c in [CONDUCTOR_POLY_MIN_C, 1 + a few u], by Horner's
// rule in t, the channels' steps side by side. Without the constants the compiler drops it.
vec3 conductor_f_poly(float c) {
    float t = c - CONDUCTOR_POLY_CENTRE;
    vec3 r = vec3(F_POLY_R14, F_POLY_G14, F_POLY_B14);
    r = r * t + vec3(F_POLY_R13, F_POLY_G13, F_POLY_B13);
    r = r * t + vec3(F_POLY_R12, F_POLY_G12, F_POLY_B12);
    r = r * t + vec3(F_POLY_R11, F_POLY_G11, F_POLY_B11);
    r = r * t + vec3(F_POLY_R10, F_POLY_G10, F_POLY_B10);
    r = r * t + vec3(F_POLY_R9, F_POLY_G9, F_POLY_B9);
    r = r * t + vec3(F_POLY_R8, F_POLY_G8, F_POLY_B8);
    r = r * t + vec3(F_POLY_R7, F_POLY_G7, F_POLY_B7);
    r = r * t + vec3(F_POLY_R6, F_POLY_G6, F_POLY_B6);
    r = r * t + vec3(F_POLY_R5, F_POLY_G5, F_POLY_B5);
    r = r * t + vec3(F_POLY_R4, F_POLY_G4, F_POLY_B4);
    r = r * t + vec3(F_POLY_R3, F_POLY_G3, F_POLY_B3);
    r = r * t + vec3(F_POLY_R2, F_POLY_G2, F_POLY_B2);
    r = r * t + vec3(F_POLY_R1, F_POLY_G1, F_POLY_B1);
    r = r * t + vec3(F_POLY_R0, F_POLY_G0, F_POLY_B0);
    return r;
}
#endif

#if defined(HAS_F_CONDUCTOR) && !defined(HAS_FLOAT64)
// |p|^2 / |q|^2 for complex p, q per channel, both scaled by their largest component
// first: at c below 1e-12 the squares underflow (0/0 = NaN for an index-matched conductor).
vec3 abs2_ratio(vec3 pr, vec3 pi_, vec3 qr, vec3 qi) {
    vec3 m = max(max(abs(pr), abs(pi_)), max(max(abs(qr), abs(qi)), vec3(1e-37)));
    pr /= m; pi_ /= m; qr /= m; qi /= m;
    return (pr * pr + pi_ * pi_) / (qr * qr + qi * qi);
}

// conductor_f for c below 1e-12 without f64 (the f64 frame takes conductor_f_f64 there),
// given c = m 2^e (ff.glsl, xf). Where eta^2 - 1 is within 1e30 c^2 of 0 (index-matched:
// cos_t is then of the order of c, and in float32 c^2 and (eta c)^2 underflow) the
// formula is taken in units of c: u = cos_t/c, u^2 = (e2rm1/c^2 + 1 + i e2i/c^2)/eta^2,
// r_par = |eta - u|^2/|eta + u|^2, r_perp = |1 - eta u|^2/|1 + eta u|^2 (c cancels).
// Elsewhere cos_t is far above c and the float32 formula holds, with its quotients scaled.
vec3 conductor_f_xf(vec2 c_xf, vec3 n, vec3 k, vec3 e2rm1) {
    float c = xf_float(c_xf);
    vec2 c2 = xf_mul(c_xf, c_xf);
    vec3 e2r = n * n - k * k, e2i = 2.0 * n * k, q = n * n + k * k;
    vec3 a = e2r / q, b = e2i / q;
    vec3 A, B;
    bvec3 matched;
    for (int ch = 0; ch < 3; ch++) {
        float ra = xf_float(xf_div(xf(abs(e2rm1[ch])), c2));
        float rb = xf_float(xf_div(xf(abs(e2i[ch])), c2));
        matched[ch] = max(ra, rb) < 1e30;
        A[ch] = (e2rm1[ch] < 0.0 ? -ra : ra) + 1.0;
        B[ch] = e2i[ch] < 0.0 ? -rb : rb;
    }
    // Index-matched channels, in units of c: u = sqrt(A + iB)/eta, the root of A + iB
    // first. Forming u^2 = (A + iB) conj(eta^2)/|eta|^4 overflowed for |eta| near the
    // parser's 1e-6 (|eta|^4 = 1e-24 under A ~ 1e29: NaN for HTSG's bounds material at
    // c = 2.6e-15, stress corpus); 1/eta = conj(eta)/|eta|^2 stays below 1e6.
    vec3 sr, si;
    csqrt(A, B, sr, si);
    vec3 ir = n / q, ii = -k / q;
    vec3 ur = cmul_re(sr, si, ir, ii), ui = cmul_im(sr, si, ir, ii);
    // The principal root (Re u >= 0, as csqrt gives it): -u where the product left Re < 0.
    bvec3 flip = bvec3(ur.x < 0.0 || (ur.x == 0.0 && ui.x < 0.0),
                       ur.y < 0.0 || (ur.y == 0.0 && ui.y < 0.0),
                       ur.z < 0.0 || (ur.z == 0.0 && ui.z < 0.0));
    ur = mix(ur, -ur, flip);
    ui = mix(ui, -ui, flip);
    vec3 par_u = abs2_ratio(n - ur, k - ui, n + ur, k + ui);
    vec3 eur = cmul_re(n, k, ur, ui), eui = cmul_im(n, k, ur, ui); // eta u
    vec3 perp_u = abs2_ratio(1.0 - eur, -eui, 1.0 + eur, eui);
    // The others: conductor_f's lines with c^2 dropped (below 1e-30 of eta^2 - 1).
    vec3 zr = (e2rm1 * a + e2i * b) / q;
    vec3 zi = (1.0 - c) * (1.0 + c) * b / q;
    vec3 ctr, cti;
    csqrt(zr, zi, ctr, cti);
    vec3 ecr = n * c, eci = k * c;
    vec3 par = abs2_ratio(ecr - ctr, eci - cti, ecr + ctr, eci + cti);
    vec3 ecr2 = cmul_re(n, k, ctr, cti), eci2 = cmul_im(n, k, ctr, cti);
    vec3 perp = abs2_ratio(c - ecr2, eci2, c + ecr2, eci2);
    return 0.5 * mix(par + perp, par_u + perp_u, matched);
}
#endif

#if defined(HAS_F_CONDUCTOR) && defined(HAS_FLOAT64)
// conductor_f in f64, for c below 1e-12 (the kernel takes it there): in float32, c^2 and
// (eta c)^2 underflow, and an index-matched conductor (eta = 1, F = 0 exactly) gave
// r_par = 0/0 = NaN at c = 1e-45 (stress corpus). Same formula, line for line.
vec3 conductor_f_f64(double c, vec3 n32, vec3 k32, vec3 e2rm1) {
    dvec3 n = dvec3(n32), k = dvec3(k32);
    dvec3 e2r = n * n - k * k, e2i = 2.0 * n * k, q = n * n + k * k;
    dvec3 a = e2r / q, b = e2i / q;
    // As conductor_f: the form with the smaller terms.
    double s2 = (1.0 - c) * (1.0 + c);
    dvec3 nk = (n - k) * (n + k);
    dvec3 ar = mix(dvec3(e2rm1) + c * c, nk - s2,
                   lessThan(4.0 * (abs(nk) + s2), abs(dvec3(e2rm1)) + c * c));
    dvec3 zr = (ar * a + e2i * b) / q;
    dvec3 zi = (1.0 - c) * (1.0 + c) * b / q;
    // Principal square root of zr + i zi (as csqrt; here q >= 1e-12 and c >= 1.4e-45 keep
    // every square in range, and the max() keeps 0/0 out of the candidate not taken).
    dvec3 r = sqrt(zr * zr + zi * zi);
    dvec3 sp = sqrt(0.5 * (r + zr)), sn = sqrt(0.5 * (r - zr));
    dvec3 im_p = 0.5 * zi / max(sp, dvec3(1e-300));
    dvec3 re_n = 0.5 * abs(zi) / max(sn, dvec3(1e-300));
    dvec3 im_n = mix(sn, -sn, lessThan(zi, dvec3(0.0)));
    bvec3 neg = lessThan(zr, dvec3(0.0));
    dvec3 ctr = mix(sp, re_n, neg), cti = mix(im_p, im_n, neg);
    dvec3 ecr = n * c, eci = k * c;
    dvec3 pr = ecr - ctr, pi_ = eci - cti, qr = ecr + ctr, qi = eci + cti;
    dvec3 r_par = (pr * pr + pi_ * pi_) / (qr * qr + qi * qi);
    dvec3 ecr2 = n * ctr - k * cti, eci2 = n * cti + k * ctr;
    dvec3 ur = c - ecr2, wr = c + ecr2;
    dvec3 r_perp = (ur * ur + eci2 * eci2) / (wr * wr + eci2 * eci2);
    return vec3(0.5 * (r_par + r_perp));
}
#endif

// term f/schlick: Schlick 1994
#if defined(HAS_F_SCHLICK)
// Schlick 1994, "An Inexpensive BRDF Model for Physically-based Rendering":
// F0 + (1 - F0)(1 - c)^5, F0 given or derived from ior/extinction at parse time.
vec3 schlick_f(float c, vec3 f0) {
    float x = 1.0 - c;
    float x2 = x * x;
    return f0 + (1.0 - f0) * (x2 * x2 * x);
}
#endif

// ===================================================================== K (FORMULAS.md §5)

// term k/seed: the seed lecture; Foley et al. 1990
#if defined(HAS_CONV_SEED)
// The seed lecture's glare term (Foley et al. 1990, "Computer Graphics: Principles and
// Practice", 2nd ed., §16.7, R_s = DGF/(N.V)): 1/cos_o.
float seed_k(float cos_i, float cos_o) {
    return 1.0 / cos_o;
}
#if defined(HAS_FLOAT64)
double seed_k_f64(double cos_i, double cos_o) {
    return 1.0 / cos_o;
}
#else
vec2 seed_k_xf(vec2 cos_i, vec2 cos_o) {
    return xf_div(xf(1.0), cos_o);
}
#endif
#endif

// term k/cook_torrance_1982: Cook & Torrance 1982
#if defined(HAS_CONV_CT1982)
// Cook & Torrance 1982: R_s = DGF / (pi (N.L)(N.V)): includes the 1/pi.
float cook_torrance_1982_k(float cos_i, float cos_o) {
    return INV_PI / (cos_i * cos_o); // one division: see modern_k
}
#if defined(HAS_FLOAT64)
// In f64 the product of the cosines cannot underflow (each >= 1e-45).
double cook_torrance_1982_k_f64(double cos_i, double cos_o) {
    return double(INV_PI) / (cos_i * cos_o);
}
#else
vec2 cook_torrance_1982_k_xf(vec2 cos_i, vec2 cos_o) {
    return xf_div(xf(INV_PI), xf_mul(cos_i, cos_o));
}
#endif
#endif

// term k/modern: Walter et al. 2007
#if defined(HAS_CONV_MODERN)
// Walter et al. 2007: 1/(4 cos_i cos_o) (the Jacobian of the half vector), as in Mitsuba 3
// and pbrt-v4. One division of the product: above TINY_COS (1e-15) it is >= 1e-30, a
// normal float32; below, the models form K from the exact cosines instead (models.glsl).
float modern_k(float cos_i, float cos_o) {
    return 0.25 / (cos_i * cos_o);
}
#if defined(HAS_FLOAT64)
// In f64 the product of the cosines cannot underflow (each >= 1e-45).
double modern_k_f64(double cos_i, double cos_o) {
    return 0.25 / (cos_i * cos_o);
}
#else
vec2 modern_k_xf(vec2 cos_i, vec2 cos_o) {
    return xf_div(xf(0.25), xf_mul(cos_i, cos_o));
}
#endif
#endif

#endif
