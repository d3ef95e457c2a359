// math.glsl — numerical helpers shared by the terms and models (FORMULAS.md §1–§4).
//
// Why our own exp/log: the Vulkan spec only bounds exp() by 3 + 2|x| ULP and log() by an
// absolute 2^-21 near 1; a lobe cos^e with e = 1000 computed as exp(e * log(cos)) would then
// carry an absolute error of ~5e-4 in its exponent. The helpers below are plain f32
// arithmetic (range reduction + short series) and behave the same on every driver. Their
// measured error is pinned by tests/conformance.rs (`math_helpers_are_accurate`).

#ifndef VKBRDF_MATH_GLSL
#define VKBRDF_MATH_GLSL

const float PI = 3.14159265358979323846;
const float INV_PI = 0.31830988618379067154;
const float INV_SQRT_PI = 0.56418958354775628695;
const float LN2_HI = 0.693145751953125;       // ln 2 rounded to 15 bits: k * LN2_HI is exact for |k| < 256
const float LN2_LO = 1.42860682030941723212e-6; // ln 2 - LN2_HI
const float LOG2E = 1.44269504088896340736;
const float FLT_MAX = 3.40282347e38; // the largest finite float32: outputs saturate to it
const float FLT_MIN = 1.17549435e-38; // the smallest normal float32: GPUs flush below it
const float F32_UNIT_ROUNDOFF = 5.96046448e-8; // u = 2^-24: a correctly rounded result is within u relative

// ------------------------------------------------------------------ overflow (FORMULAS.md §1)

// An output value as stored: beyond FLT_MAX (only +inf reaches here: every evaluation path
// turns an exact value beyond FLT_MAX into +inf, and never into NaN) it is FLT_MAX, and the
// tuple is counted as saturated.
float saturate_output(float x, inout bool saturated) {
    if (x > FLT_MAX) {
        saturated = true;
        return FLT_MAX;
    }
    return x;
}

#if defined(HAS_FLOAT64)
// x rounded to float32, +inf when it exceeds FLT_MAX (then saturate_output clamps and counts
// it). Explicit because converting an out-of-range double to float is not defined by GLSL.
float float_or_inf(double x) {
    return x > double(FLT_MAX) ? uintBitsToFloat(0x7f800000u) : float(x);
}

// 1/sqrt(q) for f64 q whose float32 rounding is normal (the callers test a range inside
// [1e-20, 1e20]): float32's inversesqrt of q's rounding (within 2 ulp, the Vulkan
// precision table, plus the argument's rounding: e <= 5u) and one Newton step in f64,
// which takes e to 1.5 e^2 < 2e-13 — enough for a value rounded once to f32 (the local
// frames); frame64.glsl's rsqrt64 takes a second step for f64's last bits. With F64_ROOTS
// (CPU devices, src/gpu/kernel.rs, whose f64 root and division are instructions where a
// GPU emulates them): 1/sqrt(q) in f64, about 1e-16 off (lavapipe, folded mitsuba-ggx
// +1.5-2 %).
double rsqrt64_once(double q) {
#if defined(F64_ROOTS)
    return 1.0 / sqrt(q);
#else
    double y = double(inversesqrt(float(q)));
    return y * (1.5 - 0.5 * q * y * y);
#endif
}

// rsqrt64_once for the squared length q of an input direction, which is within 2^-12 of 1
// whenever the input was normalised (in f32: within a few u): there the Taylor cubic in
// a = q - 1 (exact, Sterbenz), 1 - a/2 + 3a^2/8 - 5a^3/16, whose truncation 35a^4/128 is
// below 1e-15 — no inversesqrt (a root and a division on llvmpipe), no conversion; any
// other q, rsqrt64_once. A subgroup whose lanes are all near unit skips the other side
// (the CPU engine's near-unit scales, src/cpu/frame.rs).
double rsqrt64_input(double q) {
    double a = q - 1.0;
    if (abs(a) <= 1.0 / 4096.0) {
        return 1.0 + a * (-0.5 + a * (0.375 - 0.3125 * a));
    }
    return rsqrt64_once(q);
}
#endif

// ---------------------------------------------------------------- finiteness and normalise

// True when x is +-inf or NaN. A bit test, so no fast-math assumption can fold it away.
bool non_finite(float x) {
    return (floatBitsToUint(x) & 0x7f800000u) == 0x7f800000u;
}

bool any_non_finite(vec3 x) {
    return non_finite(x.x) || non_finite(x.y) || non_finite(x.z);
}

// x / |x| for any finite non-zero x; ok = false for a zero or non-finite x (an invalid
// tuple, FORMULAS.md §1). Divides by the largest |component| first: without that, |x|^2
// underflows to 0 for |x| ~ 1e-20 (0/0 = NaN) and overflows to inf for |x| ~ 1e20
// (x/inf = 0). After scaling, one component is exactly +-1 and |s| lies in [1, sqrt 3].
vec3 safe_normalize(vec3 x, out bool ok) {
    ok = false;
    if (any_non_finite(x)) {
        return vec3(0.0);
    }
    float m = max(max(abs(x.x), abs(x.y)), abs(x.z));
    if (m == 0.0) {
        return vec3(0.0);
    }
    vec3 s = x / m;
    ok = true;
    return s * inversesqrt(dot(s, s));
}

// |a x b|^2: the squared sine of the angle between unit vectors, accurate near 0 where
// 1 - (a.b)^2 cancels to nothing (FORMULAS.md §1, sin2_h).
float cross_length2(vec3 a, vec3 b) {
    vec3 c = cross(a, b);
    return dot(c, c);
}

// -------------------------------------------------------------------- log-domain helpers

// e^x in f32 to about 2 ULP. Cody–Waite reduction x = k ln2 + r, |r| <= ln2/2, then a
// degree-7 Taylor polynomial (truncation < 6e-9 relative) and an exact scaling by 2^k.
float exp_acc(float x) {
#if defined(FAST_MATH)
    // The fast precision variant: the device's own exp (on lavapipe up to 65 ulp off; on
    // GPUs an exp2 instruction), range-limited as below so the result stays defined.
    return x < -87.3 ? 0.0 : exp(min(x, 88.7));
#endif
    // Below ln(FLT_MIN) = -87.34 the result is subnormal or 0; returning 0 there keeps k in
    // the normal exponent range (ldexp of a subnormal result is undefined in GLSL) and maps
    // x = -inf (e.g. -tan2/m^2 at cos_h = 0) to 0 instead of converting inf to an int.
    if (x < -87.3) {
        return 0.0;
    }
    // Above ln(FLT_MAX) the true value overflows f32 anyway.
    if (x > 88.7) {
        return uintBitsToFloat(0x7f800000u);
    }
    float k = floor(x * LOG2E + 0.5);
    float r = (x - k * LN2_HI) - k * LN2_LO;
    float p = 1.0 + r * (1.0 + r * (1.0 / 2.0 + r * (1.0 / 6.0 + r * (1.0 / 24.0
              + r * (1.0 / 120.0 + r * (1.0 / 720.0 + r * (1.0 / 5040.0)))))));
    return ldexp(p, int(k));
}

// ln(1 + y) for |y| <= 0.42 via 2 atanh(s), s = y / (2 + y), |s| <= 0.27: series to s^13
// (truncation s^14 / 15 < 1e-9 relative). Accurate in relative terms even for tiny y,
// where log(1 + y) loses everything to the rounding of 1 + y.
float log1p_small(float y) {
    float s = y / (2.0 + y);
    float s2 = s * s;
    return 2.0 * s * (1.0 + s2 * (1.0 / 3.0 + s2 * (1.0 / 5.0 + s2 * (1.0 / 7.0
                 + s2 * (1.0 / 9.0 + s2 * (1.0 / 11.0 + s2 * (1.0 / 13.0)))))));
}

// ln x for finite x > 0: x = 2^e f with f in [sqrt(1/2), sqrt 2), ln x = e ln2 + ln f, where
// f - 1 is exact (Sterbenz) and ln f comes from log1p_small. About 2 ULP.
float log_acc(float x) {
#if defined(FAST_MATH)
    return log(x); // the fast variant: the device's own log
#endif
    int e;
    float f = frexp(x, e); // f in [0.5, 1)
    if (f < 0.70710678) {
        f *= 2.0;
        e -= 1;
    }
    float fe = float(e);
    return fe * LN2_HI + (log1p_small(f - 1.0) + fe * LN2_LO);
}

#if defined(HAS_FLOAT64)
// ln x for a double x > 0 that may lie below float32's range: x = 2^e f, f in [1/2, 1),
// ln x = e ln 2 + ln f, the sum in f64 (absolute error ~2e-8, from ln f in f32).
double log_f64(double x) {
    int e;
    double f = frexp(x, e);
    return double(e) * 0.69314718055994530942LF + double(log_acc(float(f)));
}

// e^x for a double x whose result may lie beyond float32's range: x = k ln 2 + r with
// |r| <= ln 2 / 2, e^x = 2^k e^r (relative error ~2 ulp of float32).
double exp_f64(double x) {
    // Beyond |x| = 800 the value is 0 or above every float32 and float64 anyway. Without
    // the clamp, x = -1e20 (a lobe cos_h^1e18) leaves r = x - k ln 2 at the size of x's
    // rounding error, thousands, and e^r overflows: the H200, which fuses that product
    // into an FMA, returned inf for a value that is 0.
    x = clamp(x, -800.0LF, 800.0LF);
    double k = floor(x * 1.44269504088896340736LF + 0.5LF);
    double r = x - k * 0.69314718055994530942LF;
    return ldexp(double(exp_acc(float(r))), int(clamp(k, -1100.0LF, 1100.0LF)));
}
#endif

// ln(1 + y) for y > -1.
float log1p_acc(float y) {
    return abs(y) <= 0.42 ? log1p_small(y) : log_acc(1.0 + y);
}

// ln(cos) of an angle given both cos > 0 and sin^2 = |n x w|^2: near the pole cos is
// 1 - sin^2/2 and ln(cos) = ln(1 - sin^2)/2 keeps full relative precision; near the horizon
// cos itself is the accurate number.
float log_cos(float cos_w, float sin2_w) {
#if defined(FAST_MATH)
    // The fast variant: ln cos from cos itself, which near 1 keeps only the absolute
    // precision of cos (the exact path's log1p(-sin^2)/2 keeps the relative one).
    return log(cos_w);
#endif
    return sin2_w < 0.5 ? 0.5 * log1p_acc(-sin2_w) : log_acc(cos_w);
}

// x^e for x >= 0, e >= 0 with pow(0, 0) = 1 (the reference's f64::powf convention); GLSL's
// pow(0, y) is undefined, hence the branch.
float pow_acc(float x, float e) {
    if (x <= 0.0) {
        return e == 0.0 ? 1.0 : 0.0;
    }
    return exp_acc(e * log_acc(x));
}

// atan(y / x) for x >= 0, y >= 0 (an angle in [0, pi/2]). GLSL's atan is only bounded by
// 4096 ULP; here: reduce to t in [0, 1], halve the angle twice with
// atan t = 2 atan(t / (1 + sqrt(1 + t^2))) to |t| <= tan(pi/16) = 0.199, then the Taylor
// series to t^15 (truncation 0.199^17/17 < 1e-13). A few ULP in all.
float atan2_positive(float y, float x) {
#if defined(FAST_MATH)
    return atan(y, x); // the fast variant: the device's own atan2
#endif
    bool swap = y > x;
    float t = swap ? x / y : y / x;
    t = t / (1.0 + sqrt(1.0 + t * t));
    t = t / (1.0 + sqrt(1.0 + t * t));
    float t2 = t * t;
    float a = t * (1.0 - t2 * (1.0 / 3.0 - t2 * (1.0 / 5.0 - t2 * (1.0 / 7.0 - t2 * (1.0 / 9.0
              - t2 * (1.0 / 11.0 - t2 * (1.0 / 13.0 - t2 * (1.0 / 15.0))))))));
    a *= 4.0;
    return swap ? (PI / 2.0 - a) : a;
}

#if defined(HAS_LAMBDA_BECKMANN) || defined(HAS_HTSG)
// erfc(z) for z >= 0. Press, Teukolsky, Vetterling & Flannery 1992, "Numerical Recipes in C",
// 2nd ed., §6.2 `erfcc`: a Chebyshev fit with fractional error < 1.2e-7 everywhere (so it
// stays accurate in relative terms where erfc is tiny, unlike Abramowitz–Stegun 7.1.26,
// whose bound 1.5e-7 is absolute). Evaluated in f32, measured against an f64 erfc
// (tests/conformance.rs, `math_helpers_are_accurate`): relative error <= 5e-7 for z < 1,
// growing as ~2 z^2 u (u = 6e-8) from the rounding of -z^2 in the exponent: 1.8e-6 at
// z = 4, 9e-6 at z = 9 (erfc is below 1e-36 there). beckmann_lambda needs erfc(a) in
// absolute terms next to exp(-a^2)/(a sqrt(pi)), so this costs G less than 1e-7. Beyond
// z = 9.2 the result is 0 (the true value is subnormal in f32).
float erfc_nr(float z) {
    float t = 1.0 / (1.0 + 0.5 * z);
    float p = -z * z - 1.26551223 + t * (1.00002368 + t * (0.37409196 + t * (0.09678418
              + t * (-0.18628806 + t * (0.27886807 + t * (-1.13520398 + t * (1.48851587
              + t * (-0.82215223 + t * 0.17087277))))))));
    return t * exp_acc(p);
}
#endif

#endif
