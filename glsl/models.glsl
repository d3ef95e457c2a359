// models.glsl — the reflection models of FORMULAS.md §6, built from the terms of terms.glsl.
// Each model returns the BRDF (1/sr, no cosine) and its terms; non-microfacet models report
// D = the specular lobe per unit c_spec (0 for lambert) and G = F = K = 1. Every model is
// compiled only when the batch uses it (HAS_* macros from the FeatureSet).

#ifndef VKBRDF_MODELS_GLSL
#define VKBRDF_MODELS_GLSL

#include "frame_fields.glsl"
#include "material.glsl"
#include "terms.glsl"

// One tuple's result: the BRDF and the term columns D, G, F_rgb, K.
struct Eval {
    vec3 brdf;
    float d;
    float g;
    vec3 f;
    float k;
};

// The all-zero result of an invalid or below-horizon tuple (FORMULAS.md §1).
Eval eval_zero() {
    Eval e;
    e.brdf = vec3(0.0);
    e.d = 0.0;
    e.g = 0.0;
    e.f = vec3(0.0);
    e.k = 0.0;
    return e;
}

// A non-microfacet model: c_diff/pi + c_spec * lobe, D = lobe, G = F = K = 1.
Eval eval_lobe(GpuMaterial m, float lobe) {
    Eval e;
    e.brdf = m.diffuse.rgb + m.specular.rgb * lobe;
    e.d = lobe;
    e.g = 1.0;
    e.f = vec3(1.0);
    e.k = 1.0;
    return e;
}

#if defined(HAS_FLOAT64)
// A non-microfacet model whose lobe was formed in f64: c_diff/pi + c_spec * lobe in f64,
// each output rounded once (+inf beyond FLT_MAX, saturated by the caller).
Eval eval_lobe_f64(GpuMaterial m, double lobe) {
    Eval e;
    dvec3 brdf = dvec3(m.diffuse.rgb) + dvec3(m.specular.rgb) * lobe;
    e.brdf = vec3(float_or_inf(brdf.x), float_or_inf(brdf.y), float_or_inf(brdf.z));
    e.d = float_or_inf(lobe);
    e.g = 1.0;
    e.f = vec3(1.0);
    e.k = 1.0;
    return e;
}
#endif

#if !defined(HAS_FLOAT64)
// eval_lobe_f64 without f64: c_diff/pi + c_spec * lobe with lobe = m 2^e, each output
// rounded once (+inf beyond FLT_MAX, saturated by the caller).
Eval eval_lobe_xf(GpuMaterial m, vec2 lobe) {
    Eval e;
    for (int ch = 0; ch < 3; ch++) {
        e.brdf[ch] = m.diffuse[ch] + xf_float(xf_mul(xf(m.specular[ch]), lobe));
    }
    e.d = xf_float(lobe);
    e.g = 1.0;
    e.f = vec3(1.0);
    e.k = 1.0;
    return e;
}
#endif

// ln cos_h for the lobes cos_h^e. Where the f32 cos_h is not a normal number (cosines of
// 1e-45 make it ~1e-45, and GPUs flush that to 0: make_frame's f32_of), from the f64
// cos_h: ln of 0 would give cos_h^1 = 1 instead of 1e-45 (RTR at e = 1, stress corpus).
float ln_cos_h(Frame f) {
#if defined(HAS_FLOAT64)
    if (f.cos_h < FLT_MIN) {
        return float(log_f64(f.cos_h_exact));
    }
#else
    // The same from the m 2^e form: under flush-to-zero the f32 cos_h is 0 here, and
    // log_acc(0) is a finite wrong number (RTR at e = 1 came out 3.6e-3, not 7e-46).
    if (f.cos_h < FLT_MIN) {
        return ff_round(xf_log_pair(f.cos_h_xf));
    }
#endif
    return log_cos(f.cos_h, f.sin2_h);
}

// (hx/mx)^2 + (hy/my)^2, i.e. tan2_h / m^2 times cos_h^2 (isotropic: sin2_h / m^2).
float slope2_h(Frame f, GpuMaterial m) {
#if defined(HAS_ANISOTROPIC)
    if (is_anisotropic(m)) {
        vec2 inv = material_inv_roughness2(m);
        return f.hx * f.hx * inv.x + f.hy * f.hy * inv.y;
    }
#endif
    return f.sin2_h * material_inv_roughness2(m).x;
}

#if defined(HAS_G_SMITH) || defined(HAS_G_SMITH_CORRELATED) || defined(HAS_G_SMITH_FAST)
// m^2 |n x w|^2, anisotropic mx^2 (w.t)^2 + my^2 (w.b)^2: m2_tan2's numerator.
float m2_sin2(GpuMaterial m, vec2 w_tb, float sin2_w) {
#if defined(HAS_ANISOTROPIC)
    if (is_anisotropic(m)) {
        vec2 m2 = material_roughness2(m);
        return m2.x * w_tb.x * w_tb.x + m2.y * w_tb.y * w_tb.y;
    }
#endif
    return material_roughness2(m).x * sin2_w;
}

#if defined(HAS_LAMBDA_GGX)
// GGX's roots R = sqrt(cos^2 + m2_sin2) of v and l (ggx_lambda_root): the two Smith forms'
// operands, (R_o, R_i).
vec2 roots_ggx(Frame f, GpuMaterial m) {
    return vec2(ggx_lambda_root(f.cos_o, m2_sin2(m, f.v_tb, f.sin2_o)),
                ggx_lambda_root(f.cos_i, m2_sin2(m, f.l_tb, f.sin2_i)));
}
#endif

// m^2 tan^2(w) = m^2 |n x w|^2 / (n.w)^2, anisotropic (mx^2 (w.t)^2 + my^2 (w.b)^2) / (n.w)^2
// (FORMULAS.md §3): the argument of Smith's Lambda and of the smith-fast fit. w.t, w.b and
// |n x w|^2 come from make_frame (in f64 where the device has it: with roughness ratios
// up to 1e4 the f32 tangent frame's error put G 3e-4 off at grazing, stress corpus).
float m2_tan2(GpuMaterial m, vec2 w_tb, float sin2_w, float cos_w) {
    return m2_sin2(m, w_tb, sin2_w) / (cos_w * cos_w);
}
#endif

#if defined(HAS_G_SMITH) || defined(HAS_G_SMITH_CORRELATED)
// Smith's Lambda for the material's distribution (Beckmann or GGX; the material validation
// rejects smith* with gaussian or blinn).
float distribution_lambda(GpuMaterial m, float q2) {
#if defined(HAS_LAMBDA_BECKMANN)
    if (material_distribution(m) == DIST_BECKMANN) {
        return beckmann_lambda(q2);
    }
#endif
#if defined(HAS_LAMBDA_GGX)
    return ggx_lambda(q2);
#else
    return 0.0;
#endif
}
#endif

#if defined(HAS_LAMBERT)
// Lambert 1760, "Photometria": c_diff / pi (the 1/pi is folded into m.diffuse). D = 0.
Eval model_lambert(GpuMaterial m) {
    return eval_lobe(m, 0.0);
}
#endif

#if defined(HAS_PHONG)
// Lewis 1994, "Making Shaders More Physically Plausible" (Phong 1975, modified and
// normalised): c_diff/pi + c_spec (e+2)/(2 pi) max(0, r.v)^e, r = 2 cos_i n - l.
// ln(r.v) comes from |r x v|^2 (log_cos), not from r.v itself: near the peak r.v = 1 - x
// carries an absolute error of ~1e-7 that e = 1000 would turn into 1e-4 relative. r.v and
// |r x v|^2 come from make_frame (in f64 where the device has it: in f32, r.v in the lobe's
// tail, where it is small, was 7e-4 off relative).
Eval model_phong(Frame f, GpuMaterial m) {
    float e = material_exponent(m);
    // pow(0, e): 0, or 1 for e = 0 (GLSL leaves pow(0, y) undefined).
    float p = f.rv > 0.0 ? exp_acc(e * log_cos(f.rv, f.sin2_rv)) : (e == 0.0 ? 1.0 : 0.0);
    return eval_lobe(m, material_norm(m) * p);
}
#endif

#if defined(HAS_BLINN_PHONG)
// Blinn 1977 as written in the seed lecture: c_diff/pi + c_spec cos_h^e / (pi cos_i)
// (not reciprocal; the 1/pi is in material_norm(m)).
Eval model_blinn_phong(Frame f, GpuMaterial m) {
    float p = exp_acc(material_exponent(m) * ln_cos_h(f));
#if defined(HAS_FLOAT64)
    // 1/cos_i overflows float32 (or cos_i rounded to 0, and 0/0 = NaN) below TINY_COS.
    if (f.cos_i_exact < TINY_COS) {
        // The f32 lobe p = cos_h^e can underflow here while p / cos_i is O(1) or large:
        // cos_h itself below float32's smallest normal (l ⟂ v at cosines 1e-45 and 1e-38:
        // cos_h = 7e-39, f = 1.6e6 at e = 1), or cos_h^e below it (e = 100, cos_h = 0.36).
        // The quotient is then formed in the log domain, ln cos_h from the f64 cosine where
        // the f32 one is not a normal number.
        if (p < 1.1754944e-38 && material_exponent(m) > 0.0) {
            double ln_cos = f.cos_h >= FLT_MIN ? double(log_cos(f.cos_h, f.sin2_h))
                                               : log_f64(f.cos_h_exact);
            double ln_q = double(material_exponent(m)) * ln_cos - log_f64(f.cos_i_exact);
            return eval_lobe_f64(m, double(material_norm(m)) * exp_f64(ln_q));
        }
        // The product in f64: scale p in f32 is subnormal, flushed on GPUs, for p ~ 1e-38.
        return eval_lobe_f64(m, double(material_norm(m)) * double(p) / f.cos_i_exact);
    }
#else
    // The same two cases in m 2^e form (the f32 frame).
    if (f.cos_i < TINY_COS) {
        if (p < 1.1754944e-38 && material_exponent(m) > 0.0) {
            vec2 ln_cos_h = f.cos_h >= 1.1754944e-38 ? vec2(log_cos(f.cos_h, f.sin2_h), 0.0)
                                                     : xf_log_pair(f.cos_h_xf);
            vec2 ln_q = ff_add(ff_mul_f(ln_cos_h, material_exponent(m)), -xf_log_pair(f.cos_i_xf));
            return eval_lobe_xf(m, xf_mul(xf(material_norm(m)), xf_exp(ln_q)));
        }
        // scale p as m 2^e: the float product is below FLT_MIN where p is just above it
        // (cos_h = 1.4e-38 at cosines of 1e-38), and a GPU flushes it to 0.
        return eval_lobe_xf(m, xf_div(xf_mul(xf(material_norm(m)), xf(p)), f.cos_i_xf));
    }
#endif
    return eval_lobe(m, material_norm(m) * p / f.cos_i);
}
#endif

#if defined(HAS_RTR)
// Akenine-Möller, Haines & Hoffman 2008, "Real-Time Rendering", 3rd ed., §5.5 (the seed's
// shading equation): c_diff/pi + c_spec (e+8)/(8 pi) cos_h^e, the (e+8)/(8 pi) in
// material_norm(m).
Eval model_rtr(Frame f, GpuMaterial m) {
    return eval_lobe(m, material_norm(m) * exp_acc(material_exponent(m) * ln_cos_h(f)));
}
#endif

#if defined(HAS_WARD)
// Ward 1992, "Measuring and Modeling Anisotropic Reflection":
// c_diff/pi + c_spec exp(-((hx/mx)^2 + (hy/my)^2)/hz^2) / (4 pi mx my sqrt(cos_i cos_o));
// 1/(4 pi mx my) is material_norm(m).
Eval model_ward(Frame f, GpuMaterial m) {
    float x = exp_acc(-slope2_h(f, m) / (f.cos_h * f.cos_h));
#if defined(HAS_FLOAT64)
    // 1/sqrt(cos_i cos_o) overflows float32 below TINY_COS, or a cosine rounded to 0 gives
    // inversesqrt(0) = inf; in f64 the product of two cosines >= 1.4e-45 is normal.
    if (min(f.cos_i_exact, f.cos_o_exact) < TINY_COS) {
        return eval_lobe_f64(m, double(material_norm(m)) * double(x) / sqrt(f.cos_i_exact * f.cos_o_exact));
    }
#else
    if (min(f.cos_i, f.cos_o) < TINY_COS) {
        // scale x as m 2^e, as in model_blinn_phong (the scale is ~1e-9 at roughness 1e4).
        return eval_lobe_xf(m, xf_div(xf_mul(xf(material_norm(m)), xf(x)),
                                      xf_sqrt(xf_mul(f.cos_i_xf, f.cos_o_xf))));
    }
#endif
    // Where exp underflows to 0 the lobe is 0; the guard keeps 0 * inf (cos_i, cos_o both
    // ~1e-38) from becoming NaN. One inversesqrt per cosine: their product cannot overflow.
    float lobe = x == 0.0 ? 0.0 : material_norm(m) * x * inversesqrt(f.cos_i) * inversesqrt(f.cos_o);
    return eval_lobe(m, lobe);
}
#endif

#if defined(HAS_COOK_TORRANCE) && defined(HAS_FLOAT64)
// Smith's Lambda in f64 for direction w with n.w = cos_w (f64): float32's for cos_w >=
// TINY_COS; below it from q2 = m^2 tan^2 in f64 (in float32 it is +inf, Lambda +inf and G 0,
// where the exact G is as small as 1e-45 and G K is finite).
double distribution_lambda_f64(GpuMaterial m, vec2 w_tb, float sin2_w, double cos_w) {
    if (cos_w >= TINY_COS) {
#if defined(HAS_G_SMITH) || defined(HAS_G_SMITH_CORRELATED)
        return double(distribution_lambda(m, m2_tan2(m, w_tb, sin2_w, float(cos_w))));
#else
        return 0.0;
#endif
    }
#if defined(HAS_G_SMITH) || defined(HAS_G_SMITH_CORRELATED) || defined(HAS_G_SMITH_FAST)
    double q2 = double(m2_sin2(m, w_tb, sin2_w)) / (cos_w * cos_w);
#else
    double q2 = 0.0;
#endif
#if defined(HAS_LAMBDA_BECKMANN)
    if (material_distribution(m) == DIST_BECKMANN) {
        return beckmann_lambda_f64(q2);
    }
#endif
#if defined(HAS_LAMBDA_GGX)
    return ggx_lambda_f64(q2);
#else
    return 0.0;
#endif
}

// G1 of Walter et al. 2007's rational fit (smith_fast_g1) in f64 for one direction.
double fast_g1_f64(GpuMaterial m, vec2 w_tb, float sin2_w, double cos_w) {
#if defined(HAS_G_SMITH_FAST)
    if (cos_w >= TINY_COS) {
        return double(smith_fast_g1(m2_tan2(m, w_tb, sin2_w, float(cos_w))));
    }
    return smith_fast_g1_f64(cos_w / sqrt(double(m2_sin2(m, w_tb, sin2_w)))); // a < 1.6
#else
    return 1.0;
#endif
}

// D in f64 (log domain) for a tuple with min(cos_i, cos_o) < TINY_COS whose f32 D is not
// a normal number: K is then as large as 1e90, and D = 1e-38 (a sharp lobe, a Beckmann tail)
// still makes an O(1e6) BRDF. GPUs flush such a D to 0 (NVIDIA does; lavapipe keeps a
// subnormal D with fewer bits), which lost the specular term altogether (stress corpus on
// an H200). The slope and angle come from the f32 frame; only the range is f64's.
double d_f64(Frame f, GpuMaterial m) {
    double ln_cos = f.cos_h >= FLT_MIN ? double(log_cos(f.cos_h, f.sin2_h)) : log_f64(f.cos_h_exact);
    switch (material_distribution(m)) {
#if defined(HAS_D_GAUSSIAN)
    case DIST_GAUSSIAN: return gaussian_d_f64(f.cos_h, f.sin2_h, material_inv_roughness2(m).x);
#endif
#if defined(HAS_D_BECKMANN)
    case DIST_BECKMANN: return beckmann_d_f64(slope2_h(f, m), f.cos_h_exact, ln_cos, material_norm(m));
#endif
#if defined(HAS_D_BLINN)
    case DIST_BLINN: return blinn_d_f64(ln_cos, material_exponent(m), material_norm(m));
#endif
#if defined(HAS_D_CHARLIE)
    case DIST_CHARLIE: return charlie_d_f64(f.cos_h, f.sin2_h, material_exponent(m), material_norm(m));
#endif
    default: // GGX: its D is a normal float32 at any cosine (terms.glsl)
        return 0.0;
    }
}

// G and K in f64 for a tuple with min(cos_i, cos_o) < TINY_COS, where float32 overflows K
// and underflows G although their product stays finite (FORMULAS.md §1, "Overflow").
void microfacet_gk_f64(Frame f, GpuMaterial m, uint convention, out double g, out double k) {
    double ci = f.cos_i_exact, co = f.cos_o_exact;
    g = 1.0;
    switch (material_geometry(m)) {
#if defined(HAS_G_COOK_TORRANCE)
    case GEOM_COOK_TORRANCE: g = cook_torrance_g_f64(ci, co, f.cos_h_exact, f.c_exact); break;
#endif
#if defined(HAS_G_SMITH)
    case GEOM_SMITH:
        g = smith_g_f64(distribution_lambda_f64(m, f.v_tb, f.sin2_o, co),
                        distribution_lambda_f64(m, f.l_tb, f.sin2_i, ci));
        break;
#endif
#if defined(HAS_G_SMITH_CORRELATED)
    case GEOM_SMITH_CORRELATED:
        g = smith_correlated_g_f64(distribution_lambda_f64(m, f.v_tb, f.sin2_o, co),
                                   distribution_lambda_f64(m, f.l_tb, f.sin2_i, ci));
        break;
#endif
#if defined(HAS_G_SMITH_FAST)
    case GEOM_SMITH_FAST:
        g = fast_g1_f64(m, f.v_tb, f.sin2_o, co) * fast_g1_f64(m, f.l_tb, f.sin2_i, ci);
        break;
#endif
#if defined(HAS_G_SCHLICK_SMITH)
    case GEOM_SCHLICK_SMITH: { // 1 - cos as the float32 path forms it (model_cook_torrance)
        double k = double(material_schlick_k(m));
        double omc_o = double(f.sin2_o) / (1.0 + co), omc_i = double(f.sin2_i) / (1.0 + ci);
        g = schlick_smith_g1_f64(co, omc_o, k) * schlick_smith_g1_f64(ci, omc_i, k);
        break;
    }
#endif
#if defined(HAS_G_NEUBELT)
    case GEOM_NEUBELT: g = neubelt_g_f64(ci, co); break;
#endif
    default: break;
    }
    k = 1.0;
    switch (convention) {
#if defined(HAS_CONV_SEED)
    case CONV_SEED: k = seed_k_f64(ci, co); break;
#endif
#if defined(HAS_CONV_CT1982)
    case CONV_CT1982: k = cook_torrance_1982_k_f64(ci, co); break;
#endif
#if defined(HAS_CONV_MODERN)
    case CONV_MODERN: k = modern_k_f64(ci, co); break;
#endif
    default: break;
    }
}
#endif

#if defined(HAS_COOK_TORRANCE) && !defined(HAS_FLOAT64)
// The TINY_COS helpers of the f64 branch above, in m 2^e form (the f32 frame): 1 + Lambda
// (Smith) for direction w with n.w = cos_w < TINY_COS, where q2 = m^2 tan^2 leaves
// float32 (the distribution's *_one_plus_lambda_xf, from sqrt(q2) > 1e8).
vec2 one_plus_lambda_tiny_xf(GpuMaterial m, vec2 w_tb, float sin2_w, vec2 cos_w) {
#if defined(HAS_G_SMITH) || defined(HAS_G_SMITH_CORRELATED) || defined(HAS_G_SMITH_FAST)
    vec2 sq = xf_div(xf(sqrt(m2_sin2(m, w_tb, sin2_w))), cos_w); // sqrt(q2)
#else
    vec2 sq = vec2(0.0);
#endif
#if defined(HAS_LAMBDA_BECKMANN)
    if (material_distribution(m) == DIST_BECKMANN) {
        return beckmann_one_plus_lambda_xf(sq);
    }
#endif
#if defined(HAS_LAMBDA_GGX)
    return ggx_one_plus_lambda_xf(sq);
#else
    return xf(1.0);
#endif
}

// 1 + Lambda for either cosine: float32's above TINY_COS.
vec2 one_plus_lambda_xf(GpuMaterial m, vec2 w_tb, float sin2_w, float cos_w, vec2 cos_w_xf) {
    if (cos_w >= TINY_COS) {
#if defined(HAS_G_SMITH) || defined(HAS_G_SMITH_CORRELATED)
        return xf(1.0 + distribution_lambda(m, m2_tan2(m, w_tb, sin2_w, cos_w)));
#else
        return xf(1.0);
#endif
    }
    return one_plus_lambda_tiny_xf(m, w_tb, sin2_w, cos_w_xf);
}

// Walter et al.'s G1 fit for either cosine: below TINY_COS a = cos_w/sqrt(m^2 sin^2) <
// 1e-8 (smith_fast_g1_xf).
vec2 fast_g1_xf(GpuMaterial m, vec2 w_tb, float sin2_w, float cos_w, vec2 cos_w_xf) {
#if defined(HAS_G_SMITH_FAST)
    if (cos_w >= TINY_COS) {
        return xf(smith_fast_g1(m2_tan2(m, w_tb, sin2_w, cos_w)));
    }
    return smith_fast_g1_xf(xf_div(cos_w_xf, xf(sqrt(m2_sin2(m, w_tb, sin2_w)))));
#else
    return xf(1.0);
#endif
}

// d_f64 in m 2^e form (the f32 frame): D where its float32 value is not a normal number
// and K is beyond float32 (a D of 1e-38 times a K of 1e45 is the BRDF).
vec2 d_xf(Frame f, GpuMaterial m) {
    vec2 ln_cos = f.cos_h >= FLT_MIN ? vec2(log_cos(f.cos_h, f.sin2_h), 0.0)
                                     : xf_log_pair(f.cos_h_xf);
    vec2 ln_d = vec2(XF_LN_ZERO, 0.0);
    switch (material_distribution(m)) {
#if defined(HAS_D_GAUSSIAN)
    case DIST_GAUSSIAN: ln_d = gaussian_ln_d_xf(f.cos_h, f.sin2_h, material_inv_roughness2(m).x); break;
#endif
#if defined(HAS_D_BECKMANN)
    case DIST_BECKMANN: ln_d = beckmann_ln_d_xf(slope2_h(f, m), f.cos_h_xf, ln_cos, material_norm(m)); break;
#endif
#if defined(HAS_D_BLINN)
    case DIST_BLINN: ln_d = blinn_ln_d_xf(ln_cos, material_exponent(m), material_norm(m)); break;
#endif
#if defined(HAS_D_CHARLIE)
    case DIST_CHARLIE: ln_d = charlie_ln_d_xf(f.cos_h, f.sin2_h, material_exponent(m), material_norm(m)); break;
#endif
    default: // GGX: its D is a normal float32 at any cosine (terms.glsl)
        break;
    }
    // Beyond e^-200 the product with any K (<= 1e90) is 0 in float32; xf_exp's range
    // reduction needs a finite argument.
    return ln_d.x < -200.0 ? vec2(0.0) : xf_exp(ln_d);
}

// microfacet_gk_f64 in m 2^e form.
void microfacet_gk_xf(Frame f, GpuMaterial m, uint convention, out vec2 g, out vec2 k) {
    vec2 ci = f.cos_i_xf, co = f.cos_o_xf;
    g = xf(1.0);
    switch (material_geometry(m)) {
#if defined(HAS_G_COOK_TORRANCE)
    // cos_h from its m 2^e form: the float one is subnormal (few bits) or flushed here.
    case GEOM_COOK_TORRANCE: g = cook_torrance_g_xf(ci, co, f.cos_h_xf, f.c_xf); break;
#endif
#if defined(HAS_G_SMITH)
    case GEOM_SMITH:
        g = smith_g_xf(one_plus_lambda_xf(m, f.v_tb, f.sin2_o, f.cos_o, co),
                       one_plus_lambda_xf(m, f.l_tb, f.sin2_i, f.cos_i, ci));
        break;
#endif
#if defined(HAS_G_SMITH_CORRELATED)
    case GEOM_SMITH_CORRELATED:
        g = smith_correlated_g_xf(one_plus_lambda_xf(m, f.v_tb, f.sin2_o, f.cos_o, co),
                                  one_plus_lambda_xf(m, f.l_tb, f.sin2_i, f.cos_i, ci));
        break;
#endif
#if defined(HAS_G_SMITH_FAST)
    case GEOM_SMITH_FAST:
        g = xf_mul(fast_g1_xf(m, f.v_tb, f.sin2_o, f.cos_o, co),
                   fast_g1_xf(m, f.l_tb, f.sin2_i, f.cos_i, ci));
        break;
#endif
#if defined(HAS_G_SCHLICK_SMITH)
    case GEOM_SCHLICK_SMITH: { // 1 - cos as the float32 path forms it (model_cook_torrance)
        float k = material_schlick_k(m);
        g = xf_mul(schlick_smith_g1_xf(co, f.sin2_o / (1.0 + f.cos_o), k),
                   schlick_smith_g1_xf(ci, f.sin2_i / (1.0 + f.cos_i), k));
        break;
    }
#endif
#if defined(HAS_G_NEUBELT)
    case GEOM_NEUBELT: g = neubelt_g_xf(ci, co, 1.0 - f.cos_i); break;
#endif
    default: break;
    }
    k = xf(1.0);
    switch (convention) {
#if defined(HAS_CONV_SEED)
    case CONV_SEED: k = seed_k_xf(ci, co); break;
#endif
#if defined(HAS_CONV_CT1982)
    case CONV_CT1982: k = cook_torrance_1982_k_xf(ci, co); break;
#endif
#if defined(HAS_CONV_MODERN)
    case CONV_MODERN: k = modern_k_xf(ci, co); break;
#endif
    default: break;
    }
}
#endif

#if defined(HAS_F_CONDUCTOR)
// The conductor's F at the frame's c, in the form each range of c needs: below c = 1e-12
// from the frame's f64 (or m 2^e) c, where c^2 leaves float32's range.
vec3 frame_conductor_f(Frame f, GpuMaterial m) {
#if defined(HAS_FLOAT64)
    if (f.c_exact < 1e-12) {
        return conductor_f_f64(f.c_exact, m.fresnel0.rgb, m.fresnel1.rgb, material_fresnel_lo(m));
    }
#else
    if (xf_less(f.c_xf, xf(1e-12))) {
        return conductor_f_xf(f.c_xf, m.fresnel0.rgb, m.fresnel1.rgb, material_fresnel_lo(m));
    }
#endif
#if !defined(NO_METAL_FORM)
    // A folded conductor with a fitted polynomial (a specialization constant: without it
    // the branch is compiled out); lanes below its interval take the metal form. NO_F_POLY
    // (a kernel_time variant) turns it off, for measuring.
#if !defined(NO_F_POLY)
    if (MATERIAL_F_POLY && f.c >= CONDUCTOR_POLY_MIN_C) {
        return conductor_f_poly(f.c);
    }
#endif
    // A material-uniform branch: a batch's lanes of one material all take the same side.
    vec3 fr;
    if (material_metal_form(m)) {
        fr = conductor_f_metal(f.c, m.fresnel0.rgb, m.fresnel1.rgb, material_fresnel_lo(m));
    } else {
        fr = conductor_f(f.c, m.fresnel0.rgb, m.fresnel1.rgb, material_fresnel_lo(m));
    }
    return fr;
#else
    return conductor_f(f.c, m.fresnel0.rgb, m.fresnel1.rgb, material_fresnel_lo(m));
#endif
}
#endif

#if defined(HAS_COOK_TORRANCE)
// Cook & Torrance 1982, "A Reflectance Model for Computer Graphics":
// d c_diff/pi + s c_spec (x) D G F K (d c_diff/pi is m.diffuse, s c_spec is m.specular).
Eval model_cook_torrance(Frame f, GpuMaterial m) {
    uint fresnel = material_fresnel(m);
    uint convention = material_convention(m);
    Eval e;

    e.d = 0.0;
    switch (material_distribution(m)) {
#if defined(HAS_D_GAUSSIAN)
    case DIST_GAUSSIAN: e.d = gaussian_d(f.cos_h, f.sin2_h, material_inv_roughness2(m).x); break;
#endif
#if defined(HAS_D_BECKMANN)
    case DIST_BECKMANN: e.d = beckmann_d(slope2_h(f, m), f.cos_h, f.sin2_h, material_norm(m)); break;
#endif
#if defined(HAS_D_GGX)
    case DIST_GGX: e.d = ggx_d(slope2_h(f, m), f.cos_h, material_norm(m)); break;
#endif
#if defined(HAS_D_BLINN)
    case DIST_BLINN: e.d = blinn_d(f.cos_h, f.sin2_h, material_exponent(m), material_norm(m)); break;
#endif
#if defined(HAS_D_CHARLIE)
    case DIST_CHARLIE: e.d = charlie_d(f.cos_h, f.sin2_h, material_exponent(m), material_norm(m)); break;
#endif
    default: break;
    }

    e.g = 1.0;
    switch (material_geometry(m)) {
#if defined(HAS_G_COOK_TORRANCE)
    case GEOM_COOK_TORRANCE: e.g = cook_torrance_g(f.cos_i, f.cos_o, f.cos_h, f.c); break;
#endif
#if defined(HAS_G_SMITH)
    case GEOM_SMITH:
#if defined(HAS_LAMBDA_GGX)
        if (material_distribution(m) == DIST_GGX) {
            vec2 r = roots_ggx(f, m);
            e.g = smith_g_ggx(f.cos_o, r.x, f.cos_i, r.y);
            break;
        }
#endif
        e.g = smith_g(distribution_lambda(m, m2_tan2(m, f.v_tb, f.sin2_o, f.cos_o)),
                      distribution_lambda(m, m2_tan2(m, f.l_tb, f.sin2_i, f.cos_i)));
        break;
#endif
#if defined(HAS_G_SMITH_CORRELATED)
    case GEOM_SMITH_CORRELATED:
#if defined(HAS_LAMBDA_GGX)
        if (material_distribution(m) == DIST_GGX) {
            vec2 r = roots_ggx(f, m);
            e.g = smith_correlated_g_ggx(f.cos_o, r.x, f.cos_i, r.y);
            break;
        }
#endif
        e.g = smith_correlated_g(distribution_lambda(m, m2_tan2(m, f.v_tb, f.sin2_o, f.cos_o)),
                                distribution_lambda(m, m2_tan2(m, f.l_tb, f.sin2_i, f.cos_i)));
        break;
#endif
#if defined(HAS_G_SMITH_FAST)
    case GEOM_SMITH_FAST:
        e.g = smith_fast_g1(m2_tan2(m, f.v_tb, f.sin2_o, f.cos_o)) * smith_fast_g1(m2_tan2(m, f.l_tb, f.sin2_i, f.cos_i));
        break;
#endif
#if defined(HAS_G_SCHLICK_SMITH)
    case GEOM_SCHLICK_SMITH: {
        // k = lobe.w (isotropic only, see gpu_material). 1 - cos = |n x w|^2/(1 + cos), from
        // make_frame's sin2 (accurate in both frames): 1 - f.cos_i in f32 is off by up to
        // 6e-8 absolute near normal incidence, an error k (up to 8e3) multiplies.
        float omc_o = f.sin2_o / (1.0 + f.cos_o), omc_i = f.sin2_i / (1.0 + f.cos_i);
        e.g = schlick_smith_g1(f.cos_o, omc_o, material_schlick_k(m)) * schlick_smith_g1(f.cos_i, omc_i, material_schlick_k(m));
        break;
    }
#endif
#if defined(HAS_G_NEUBELT)
    case GEOM_NEUBELT: e.g = neubelt_g(f.cos_i, f.cos_o); break;
#endif
    default: break;
    }

    e.f = vec3(1.0);
    switch (fresnel) {
#if defined(HAS_F_DIELECTRIC)
    case FRESNEL_DIELECTRIC: e.f = dielectric_f(f.c, m.fresnel0.rgb, material_fresnel_lo(m), f.c_exact); break;
#endif
#if defined(HAS_F_CONDUCTOR)
    case FRESNEL_CONDUCTOR: e.f = frame_conductor_f(f, m); break;
#endif
#if defined(HAS_F_SCHLICK)
    case FRESNEL_SCHLICK: e.f = schlick_f(f.c, m.fresnel0.rgb); break;
#endif
    default: break;
    }

    e.k = 1.0;
    switch (convention) {
#if defined(HAS_CONV_SEED)
    case CONV_SEED: e.k = seed_k(f.cos_i, f.cos_o); break;
#endif
#if defined(HAS_CONV_CT1982)
    case CONV_CT1982: e.k = cook_torrance_1982_k(f.cos_i, f.cos_o); break;
#endif
#if defined(HAS_CONV_MODERN)
    case CONV_MODERN: e.k = modern_k(f.cos_i, f.cos_o); break;
#endif
    default: break;
    }

    // K last: D G F <= D is finite, so an overflow here means the exact product exceeds
    // FLT_MAX (before the colour). A zero factor wins: without f64, K is +inf when both
    // cosines are ~1e-38, and 0 * inf would be NaN.
    vec3 dgf = (e.d * e.g) * e.f;
    vec3 spec = mix(dgf * e.k, vec3(0.0), equal(dgf, vec3(0.0)));
    e.brdf = m.diffuse.rgb + m.specular.rgb * spec;
#if defined(HAS_FLOAT64)
    // Below TINY_COS, G and K in f64 (float32 overflows K and underflows G); and where the
    // float32 product overflowed (a sharp lobe at grazing, or before a colour < 1 could
    // bring it back in range), the product again in f64, where it cannot: the output is then
    // +inf only if the exact value exceeds FLT_MAX (saturated by the caller).
    bool tiny = min(f.cos_i_exact, f.cos_o_exact) < TINY_COS;
    if (tiny || any_non_finite(e.brdf)) {
        double d64 = double(e.d), g64 = double(e.g), k64 = double(e.k);
        if (tiny) {
            microfacet_gk_f64(f, m, convention, g64, k64);
            e.g = float(g64);
            e.k = float_or_inf(k64);
            if (e.d < FLT_MIN && material_distribution(m) != DIST_GGX) {
                d64 = d_f64(f, m);
            }
        }
        dvec3 b = dvec3(m.diffuse.rgb)
            + dvec3(m.specular.rgb) * ((d64 * g64 * k64) * dvec3(e.f));
        e.brdf = vec3(float_or_inf(b.x), float_or_inf(b.y), float_or_inf(b.z));
    }
#else
    // The same in m 2^e form (the f32 frame).
    bool tiny = min(f.cos_i, f.cos_o) < TINY_COS;
    if (tiny || any_non_finite(e.brdf)) {
        vec2 gx = xf(e.g), kx = xf(e.k);
        if (tiny) {
            microfacet_gk_xf(f, m, convention, gx, kx);
            e.g = xf_float(gx);
            e.k = xf_float(kx);
        }
        vec2 dx = tiny && e.d < FLT_MIN && material_distribution(m) != DIST_GGX ? d_xf(f, m) : xf(e.d);
        vec2 dgk = xf_mul(xf_mul(dx, gx), kx);
        for (int ch = 0; ch < 3; ch++) {
            e.brdf[ch] = m.diffuse[ch] + xf_float(xf_mul(xf(m.specular[ch]), xf_mul(dgk, xf(e.f[ch]))));
        }
    }
#endif
    return e;
}
#endif


#endif
