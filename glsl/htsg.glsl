// htsg.glsl — the kernel's form of src/terms/htsg.rs.
// model htsg: He, Torrance, Sillion & Greenberg 1991
//
// FORMULAS.md §8 in f32 on either frame (the f64 frame and the f32 one give it the same
// scalars; only ln cos below TINY_COS comes from each frame's own extended form). The
// material's packing (src/gpu/layout.rs, gpu_material): fresnel0.rgb = n, fresnel1.rgb = k,
// scale.yzw = n^2 - k^2 - 1 (the conductor's), lobe.x = tau/(2 sigma0), lobe.y = sigma0/tau,
// specular.rgb = T = 2 pi tau / lambda per channel (f64, rounded once), diffuse.rgb = a/pi.
//
// Rearranged so that no factor leaves float32's range where the value does not:
// - S1(x) = A/(e^{-x^2} + A), A = x sqrt(pi)(1 + erf x) (Lambda's 1/x removed), and S1/cos
//   theta formed without dividing by cos: tau sqrt(pi)(1 + erf x)/(2 sigma0 sin (e^{-x^2} + A));
// - ln K(theta) = ln(sin erfc x) - ln cos, so that R = (K_i + K_r)/sqrt(8 pi) is never formed
//   (K ~ 1/cos reaches 1e45);
// - G D = 16 c^4 (T/4)^2 w^2 sum e^{-g} g^(m-1)/(m! m) e^{-a/m} with w = 2 pi sigma/lambda, so
//   that G = (4c^2/(cos_i + cos_r))^2, which overflows at grazing while D underflows, is
//   not a factor of f in the series' range (g <= 18.5).

#ifndef VKBRDF_HTSG_GLSL
#define VKBRDF_HTSG_GLSL

#include "math.glsl"
#include "ff.glsl"
#include "frame_fields.glsl"
#include "material.glsl"
#include "models.glsl"

#if defined(HAS_HTSG)

const float SQRT_PI = 1.77245385090551602730;
// ln sqrt(8 pi).
const float LN_SQRT_8PI = 1.61208571304069586;
// The sentinel of ln K = ln 0 (normal incidence, or S1 = 1 to f32 precision).
const float HTSG_LN_ZERO = -1e30;

// S1(theta)/cos theta (htsg_q) and ln K(theta) (htsg_ln_k) for one direction, given its
// cosine, |n x w|^2 and ln cos.
void htsg_direction(float cos_w, float sin2_w, float ln_cos_w, float half_cot,
                    out float q, out float ln_k) {
    float sin_w = sqrt(sin2_w);
    // x = tau cot theta/(2 sigma0) > 4.5: 1 - S1 < e^{-x^2}/(2x sqrt(pi)) < 1e-10, below f32's
    // resolution of S1, and K = tan theta erfc(x) < 2.2e-8 (tan theta <= 2 tau/(9 sigma0) <=
    // 111 there): against another K it moves R by less than 2e-4 of a value R >= 1e-4, and
    // with R < 1e-4 alone sigma = sigma0 to f32 precision (htsg_sigma), so K is taken as 0.
    // Tested as a product: x itself divides by sin, which is 0 at normal incidence.
    if (half_cot * cos_w > 4.5 * sin_w) {
        q = 1.0 / cos_w;
        ln_k = HTSG_LN_ZERO;
        return;
    }
    // Here sin_w >= half_cot cos_w / 4.5 > 0 unless cos_w flushed to 0 (then sin_w = 1).
    float x = half_cot * cos_w / sin_w;
    float e = erfc_nr(x);
    float one_plus_erf = 2.0 - e;
    float den = exp_acc(-x * x) + x * SQRT_PI * one_plus_erf;
    q = SQRT_PI * one_plus_erf * half_cot / (sin_w * den);
    ln_k = log_acc(sin_w * e) - ln_cos_w;
}

// sigma = sigma0/sqrt(1 + z^2), z e^{z^2/2} = R, from ln R. Newton on ln z + z^2/2 = ln R
// from z = R (R <= 1) or sqrt(2 ln(1 + R)): five steps meet f32's precision over the whole
// range (1.1e-7 of sigma, measured against f64 over ln R in [-9.3, 104]); Westin's start
// sqrt(2 ln R) needs a dozen just above R = 1, where it is near 0.
float htsg_sigma(float sigma0, float ln_r) {
    // z < 1e-4: sigma = sigma0 (1 - z^2/2) rounds to sigma0.
    if (ln_r < -9.3) {
        return sigma0;
    }
    float z = ln_r <= 0.0 ? exp_acc(ln_r) : sqrt(2.0 * (ln_r + log1p_acc(exp_acc(-ln_r))));
    for (int it = 0; it < 5; it++) {
        float h = log_acc(z) + 0.5 * z * z - ln_r;
        z -= z * h / (1.0 + z * z);
    }
    return sigma0 * inversesqrt(1.0 + z * z);
}

// The series of Eq. 78 divided by g: sum_{m>=1} e^{-g} g^(m-1)/(m! m) e^{-a/m} for g <= 18.5.
// The weights q_m = e^{-g} g^(m-1)/m! grow by g/(m+1) (relative rounding ~m u at the
// peak, m ~ g); the sum stops once the tail's bound q_m g/(m (1 - g/(m+1))) (e^{-a/m} <= 1)
// is below 2^-25 of it, by m = 60 at g = 18.5.
float htsg_series_over_g(float g, float a) {
    float q = exp_acc(-g);
    float sum = 0.0;
    for (int m = 1; m <= 80; m++) {
        float mf = float(m);
        q /= mf;
        float w = q / mf;
        sum += w * exp_acc(-a / mf);
        q *= g;
        if (mf > g && (w * g / (1.0 - g / (mf + 1.0)) <= sum * 3e-8 || q == 0.0)) {
            break;
        }
    }
    return sum;
}

// ln cos_i (incident) or ln cos_r: from the f32 cosine above TINY_COS, else from the
// frame's extended form (the f32 value is 0 below FLT_MIN on a GPU).
float htsg_ln_cos(Frame f, bool incident) {
    float cos_w = incident ? f.cos_i : f.cos_o;
    if (cos_w >= TINY_COS) {
        return log_acc(cos_w);
    }
#if defined(HAS_FLOAT64)
    return float(log_f64(incident ? f.cos_i_exact : f.cos_o_exact));
#else
    return ff_round(xf_log_pair(incident ? f.cos_i_xf : f.cos_o_xf));
#endif
}

// G = (|l + v|^2 / n.(l + v))^2 = (4c^2/(cos_i + cos_r))^2. Below TINY_COS the f32 cosines
// may be flushed to 0 (c too, at a grazing mirror geometry, where 0/0 made NaN), so the
// quotient is formed from the frame's extended forms: f64, or m 2^e.
float htsg_g(Frame f, float s2, float ns) {
    if (ns >= TINY_COS) {
        return (s2 / ns) * (s2 / ns);
    }
#if defined(HAS_FLOAT64)
    double q = 4.0 * f.c_exact * f.c_exact / (f.cos_i_exact + f.cos_o_exact);
    return float_or_inf(q * q);
#else
    vec2 q = xf_div(xf_mul(xf(4.0), xf_mul(f.c_xf, f.c_xf)), xf_add(f.cos_i_xf, f.cos_o_xf));
    return xf_float(xf_mul(q, q));
#endif
}

Eval model_htsg(Frame f, GpuMaterial m) {
    float half_cot = m.lobe.x;
    float q_i, q_o, ln_k_i, ln_k_o;
    htsg_direction(f.cos_i, f.sin2_i, htsg_ln_cos(f, true), half_cot, q_i, ln_k_i);
    htsg_direction(f.cos_o, f.sin2_o, htsg_ln_cos(f, false), half_cot, q_o, ln_k_o);
    float k_hi = max(ln_k_i, ln_k_o), k_lo = min(ln_k_i, ln_k_o);
    float ln_r = k_hi <= 0.5 * HTSG_LN_ZERO ? HTSG_LN_ZERO
        : k_hi + log1p_acc(exp_acc(k_lo - k_hi)) - LN_SQRT_8PI;
    // sigma/tau, so that w = 2 pi sigma/lambda = T sigma/tau.
    float ratio = htsg_sigma(m.lobe.y, ln_r);
    float ns = f.cos_i + f.cos_o;
    float s2 = 4.0 * f.c * f.c;
    float vxy2 = s2 * f.sin2_h;
    Eval e;
    e.k = q_i * q_o * INV_PI;
    e.g = htsg_g(f, s2, ns);
    e.f = frame_conductor_f(f, m);
    for (int ch = 0; ch < 3; ch++) {
        float t = m.specular[ch];
        float norm = 0.0625 * t * t;
        float wv = t * ratio;
        float g = wv * ns * wv * ns;
        float a = 0.25 * vxy2 * t * t;
        float d, gd;
        if (g > 18.5) {
            d = norm * exp_acc(-a / g) / g;
            gd = e.g * d;
        } else {
            float s = norm * htsg_series_over_g(g, a);
            d = g * s;
            gd = s2 * s2 * wv * wv * s;
        }
        if (ch == 1) {
            e.d = d;
        }
        e.brdf[ch] = e.f[ch] * gd * e.k + m.diffuse[ch];
    }
    return e;
}

#endif

#endif
