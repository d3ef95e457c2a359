// frame_fields.glsl — what a tuple's frame is (FORMULAS.md §1): its classification, the
// derived quantities the models read, and the cosine below which they read the exact ones.
// Built by make_frame (frame.glsl); read by models.glsl and htsg.glsl.

#ifndef VKBRDF_FRAME_FIELDS_GLSL
#define VKBRDF_FRAME_FIELDS_GLSL

#include "ff.glsl"

// The classification of a tuple (FORMULAS.md §1): evaluated, invalid (a non-finite or
// zero-length vector, a bad tangent) or below the horizon (the BRDF is 0).
const uint STATUS_VALID = 0u;
const uint STATUS_INVALID = 1u;
const uint STATUS_BELOW_HORIZON = 2u;

// The derived quantities of FORMULAS.md §1 for one valid, above-horizon tuple.
// The *_exact fields: f64 where the device has it, else a float-float pair (hi, lo).
struct Frame {
    vec3 n, l, v, h;   // unit vectors
    float cos_i;       // n.l > 0
    float cos_o;       // n.v > 0
    float cos_h;       // n.h > 0 (cos delta)
    float c;           // v.h > 0, the Fresnel angle cosine
    float sin2_h;      // |n x h|^2, not 1 - cos_h^2 (which cancels near the peak)
    vec3 t, b;         // tangent frame, anisotropic materials only (zero otherwise)
    float hx, hy;      // h.t, h.b: h in the tangent frame (anisotropic materials only)
    float rv, sin2_rv; // r.v and |r x v|^2, r = 2 cos_i n - l (Phong only)
    float sin2_i, sin2_o; // |n x l|^2, |n x v|^2 (Smith's tan^2 numerators)
    double_or_float c_exact; // c before rounding to f32 (f64, or a float-float pair)
#if defined(HAS_FLOAT64)
    double cos_i_exact, cos_o_exact; // cos_i, cos_o before rounding (FORMULAS.md §1,
                       // "Overflow": below TINY_COS the models evaluate from these, in f64)
    double cos_h_exact; // cos_h before rounding (below float32's smallest normal
                       // number the f32 value flushes to 0)
#else
    // The same four in f64's range without f64: m 2^e (ff.glsl, xf), float32 precision.
    vec2 cos_i_xf, cos_o_xf, cos_h_xf, c_xf;
#endif
    vec2 l_tb, v_tb;   // (l.t, l.b), (v.t, v.b) (anisotropic materials only)
};

// FORMULAS.md §1, "Overflow": below this cosine the float32 path no longer holds the
// products the models form (K = 1/(4 cos_i cos_o) leaves float32 below ~1e-19, m^2 tan^2
// at roughness 1e4 below 1e-15, cos^2 becomes subnormal below 1e-19 and a cosine under
// 7e-46 rounds to 0), so the cosine-dependent factors are formed from the frame's exact
// cosines instead: in f64, or as m 2^e (ff.glsl, xf) from the cos_*_xf fields, f64's range
// at float32's precision. Above it every such factor is finite in float32 (K <= 2.5e29,
// m^2 tan^2 <= 1e38 with the parser's roughness <= 1e4). Taken by a vanishing fraction of
// tuples, so the branch costs nothing measurable.
#if defined(HAS_FLOAT64)
const double TINY_COS = 1e-15;
#else
const float TINY_COS = 1e-15;
#endif

#endif
