// ff.glsl — float-float arithmetic for the f32 frame (devices without shaderFloat64, or
// VKBRDF_DISABLE_FLOAT64=1): a value is the unevaluated sum hi + lo of two floats with
// |lo| <= ulp(hi)/2, about 48 bits (Dekker 1971, "A floating-point technique for extending
// the available precision"; Ogita, Rump & Oishi 2005, "Accurate sum and dot product").
//
// The error-free transformations rest on two facts: the rounding error of a float sum is
// itself a float (Knuth's two-sum), and so is that of a product (Dekker's two-product).
// Every intermediate is `precise`: a compiler allowed to reassociate (a + b) - a into b,
// or to contract a*b - p into an fma, would turn each error term into 0 and the pair
// back into a plain float.
//
// Valid for finite operands whose products stay in the normal range (the frame scales its
// inputs by powers of two first); a pair is written vec2(hi, lo).

#ifndef VKBRDF_FF_GLSL
#define VKBRDF_FF_GLSL

#include "math.glsl"

// A value past float32's precision or range: f64 where the device has it, else a
// float-float pair (hi, lo) or m 2^e form.
#if defined(HAS_FLOAT64)
#define double_or_float double
#else
#define double_or_float vec2
#endif

// a + b exactly, as (rounded sum, its error): Knuth's branch-free two-sum.
vec2 two_sum(float a, float b) {
    precise float s = a + b;
    precise float bb = s - a;
    precise float e = (a - (s - bb)) + (b - bb);
    return vec2(s, e);
}

// a + b exactly for |a| >= |b| (or a = 0): Dekker's fast two-sum, renormalising a pair.
vec2 fast_two_sum(float a, float b) {
    precise float s = a + b;
    precise float e = b - (s - a);
    return vec2(s, e);
}

// a = hi + lo exactly, hi and lo of 12 significant bits each (Veltkamp's split), for
// |a| < 2^115 (4097 a must not overflow; the frame's operands are below 4).
vec2 split(float a) {
    precise float c = 4097.0 * a;
    precise float hi = c - (c - a);
    precise float lo = a - hi;
    return vec2(hi, lo);
}

// a * b exactly, as (rounded product, its error), by Dekker's product of the halves: each
// partial product of two 12-bit halves is exact. Not fma(a, b, -a*b): lavapipe compiles
// GLSL fma() to a multiply and an add (the error term came out 0 in the probe of
// tests/f32_frame.rs), and the Vulkan spec does not require fma() to round once; products
// and sums it does require to be correctly rounded.
vec2 two_prod(float a, float b) {
    precise float p = a * b;
    vec2 x = split(a), y = split(b);
    precise float e = ((x.x * y.x - p) + x.x * y.y + x.y * y.x) + x.y * y.y;
    return vec2(p, e);
}

// Sum of two pairs to ~2^-48 relative, also when they cancel (the "accurate" addition:
// both the high and the low parts go through two-sum).
vec2 ff_add(vec2 a, vec2 b) {
    vec2 s = two_sum(a.x, b.x);
    vec2 t = two_sum(a.y, b.y);
    precise float lo = s.y + t.x;
    s = fast_two_sum(s.x, lo);
    precise float lo2 = s.y + t.y;
    return fast_two_sum(s.x, lo2);
}

vec2 ff_neg(vec2 a) {
    return -a;
}

// Product of two pairs (the lo * lo term is below 2^-96 relative and dropped).
vec2 ff_mul(vec2 a, vec2 b) {
    vec2 p = two_prod(a.x, b.x);
    precise float lo = fma(a.x, b.y, fma(a.y, b.x, p.y));
    return fast_two_sum(p.x, lo);
}

// Product of a pair and a float.
vec2 ff_mul_f(vec2 a, float b) {
    vec2 p = two_prod(a.x, b);
    precise float lo = fma(a.y, b, p.y);
    return fast_two_sum(p.x, lo);
}

// a / b for b != 0: the float quotient, corrected by the exact residual a - q b (whose
// error-free product also repairs a division that is not correctly rounded, as on GPUs).
vec2 ff_div(vec2 a, vec2 b) {
    precise float q1 = a.x / b.x;
    vec2 r = ff_add(a, ff_neg(ff_mul_f(b, q1)));
    precise float q2 = r.x / b.x;
    return fast_two_sum(q1, q2);
}

// sqrt(a) for a >= 0: one Newton step on the float root, residual a - s^2 exact.
vec2 ff_sqrt(vec2 a) {
    if (a.x <= 0.0) {
        return vec2(0.0); // the root of 0; the step below would divide 0 by 0
    }
    precise float s = sqrt(a.x);
    vec2 r = ff_add(a, ff_neg(two_prod(s, s)));
    precise float c = r.x / (2.0 * s);
    return fast_two_sum(s, c);
}

// The pair rounded to a float.
float ff_round(vec2 a) {
    precise float s = a.x + a.y;
    return s;
}

// Dot product of two float vectors to ~2^-48 relative of the result itself (Ogita–Rump–Oishi
// Dot2, with the three product errors and two sum errors added by two-sum again): each
// product is an exact pair, so the only error left is the final one, O(u^2) of the largest
// product. Without it a cosine of 1e-8 formed from O(1) components has no correct digit.
vec2 dot_ff(vec3 a, vec3 b) {
    vec2 p0 = two_prod(a.x, b.x), p1 = two_prod(a.y, b.y), p2 = two_prod(a.z, b.z);
    vec2 s = two_sum(p0.x, p1.x);
    vec2 t = two_sum(s.x, p2.x);
    // The five error terms, themselves summed by two-sum: a plain sum would leave an
    // absolute error of u^2 times the largest product (3.5e-15 against cosines of 1e-13).
    vec2 e0 = two_sum(p0.y, p1.y);
    vec2 e1 = two_sum(e0.x, p2.y);
    vec2 e2 = two_sum(e1.x, s.y);
    vec2 e3 = two_sum(e2.x, t.y);
    precise float rest = (e0.y + e1.y) + (e2.y + e3.y);
    vec2 lo = fast_two_sum(e3.x, rest);
    return ff_add(vec2(t.x, 0.0), lo);
}

// a x b of float vectors, each component a_y b_z - a_z b_y as a pair: both products are
// exact pairs and their difference is added by ff_add, so a component that cancels (a
// nearly parallel to b) keeps its relative precision.
void cross_ff(vec3 a, vec3 b, out vec3 hi, out vec3 lo) {
    vec2 x = ff_add(two_prod(a.y, b.z), ff_neg(two_prod(a.z, b.y)));
    vec2 y = ff_add(two_prod(a.z, b.x), ff_neg(two_prod(a.x, b.z)));
    vec2 z = ff_add(two_prod(a.x, b.y), ff_neg(two_prod(a.y, b.x)));
    hi = vec3(x.x, y.x, z.x);
    lo = vec3(x.y, y.y, z.y);
}

// |a|^2 of a pair vector (hi, lo), to ~2^-48 relative (a sum of positives: no cancellation).
vec2 length2_ff3(vec3 hi, vec3 lo) {
    vec2 x = ff_mul(vec2(hi.x, lo.x), vec2(hi.x, lo.x));
    vec2 y = ff_mul(vec2(hi.y, lo.y), vec2(hi.y, lo.y));
    vec2 z = ff_mul(vec2(hi.z, lo.z), vec2(hi.z, lo.z));
    return ff_add(ff_add(x, y), z);
}

// a . b of two pair vectors, each component product a pair, summed by ff_add.
vec2 dot_ff3(vec3 ah, vec3 al, vec3 bh, vec3 bl) {
    vec2 x = ff_mul(vec2(ah.x, al.x), vec2(bh.x, bl.x));
    vec2 y = ff_mul(vec2(ah.y, al.y), vec2(bh.y, bl.y));
    vec2 z = ff_mul(vec2(ah.z, al.z), vec2(bh.z, bl.z));
    return ff_add(ff_add(x, y), z);
}

// a x b of two pair vectors (for the frame's unit vectors held as pairs).
void cross_ff3(vec3 ah, vec3 al, vec3 bh, vec3 bl, out vec3 hi, out vec3 lo) {
    vec2 ax = vec2(ah.x, al.x), ay = vec2(ah.y, al.y), az = vec2(ah.z, al.z);
    vec2 bx = vec2(bh.x, bl.x), by = vec2(bh.y, bl.y), bz = vec2(bh.z, bl.z);
    vec2 x = ff_add(ff_mul(ay, bz), ff_neg(ff_mul(az, by)));
    vec2 y = ff_add(ff_mul(az, bx), ff_neg(ff_mul(ax, bz)));
    vec2 z = ff_add(ff_mul(ax, by), ff_neg(ff_mul(ay, bx)));
    hi = vec3(x.x, y.x, z.x);
    lo = vec3(x.y, y.y, z.y);
}

// a + b of two pair vectors, component by component.
void add_ff3(vec3 ah, vec3 al, vec3 bh, vec3 bl, out vec3 hi, out vec3 lo) {
    for (int k = 0; k < 3; k++) {
        vec2 s = ff_add(vec2(ah[k], al[k]), vec2(bh[k], bl[k]));
        hi[k] = s.x;
        lo[k] = s.y;
    }
}

// The pair vector (hi, lo) divided by the pair d, component by component.
void div_ff3(inout vec3 hi, inout vec3 lo, vec2 d) {
    vec2 x = ff_div(vec2(hi.x, lo.x), d);
    vec2 y = ff_div(vec2(hi.y, lo.y), d);
    vec2 z = ff_div(vec2(hi.z, lo.z), d);
    hi = vec3(x.x, y.x, z.x);
    lo = vec3(x.y, y.y, z.y);
}

// ----------------------------------------------- three-word sums (sharp lobes, f32 frame)
// A running sum of floats in three words, each addition a cascade of two-sums: its error
// is ~n u^3 of the largest partial sum (u = 2^-24), so O(1) terms that cancel to 1e-9 keep
// ~45 bits, where a pair (u^2) keeps ~22.
struct Acc3 {
    float s0, s1, s2;
};

void acc_add(inout Acc3 a, float x) {
    vec2 t = two_sum(a.s0, x);
    vec2 u = two_sum(a.s1, t.y);
    precise float s2 = a.s2 + u.y;
    a.s0 = t.x;
    a.s1 = u.x;
    a.s2 = s2;
}

// Adds x y exactly (both halves of its two-product).
void acc_add_prod(inout Acc3 a, float x, float y) {
    vec2 p = two_prod(x, y);
    acc_add(a, p.x);
    acc_add(a, p.y);
}

// The sum as a pair.
vec2 acc_pair(Acc3 a) {
    vec2 t = two_sum(a.s1, a.s2);
    vec2 r = two_sum(a.s0, t.x);
    precise float lo = r.y + t.y;
    return fast_two_sum(r.x, lo);
}

// a . b of float vectors as its six exact terms (three two-products).
void dot_terms(vec3 a, vec3 b, out float t[6]) {
    for (int k = 0; k < 3; k++) {
        vec2 p = two_prod(a[k], b[k]);
        t[2 * k] = p.x;
        t[2 * k + 1] = p.y;
    }
}

// Component i of a x b as its four exact terms: a_j b_k - a_k b_j, (i, j, k) cyclic.
void cross_terms(vec3 a, vec3 b, int i, out float t[4]) {
    int j = (i + 1) % 3, k = (i + 2) % 3;
    vec2 p = two_prod(a[j], b[k]), q = two_prod(a[k], b[j]);
    t[0] = p.x;
    t[1] = p.y;
    t[2] = -q.x;
    t[3] = -q.y;
}

// ------------------------------------------------- extended range: m 2^e (the f32 frame)
// Where the f64 frame leans on f64's exponent range (FORMULAS.md §1, "Overflow": cosines
// below 1e-15, whose K = 1/(4 cos_i cos_o) leaves float32 and whose G underflows while
// G K stays finite), the f32 frame carries a value as vec2(m, e) = m 2^e, m in [1/2, 1)
// or 0, e an integer held as a float. Every operation rounds m once: float32's relative
// precision, f64's range.

// x >= 0 (subnormal included) as m 2^e. A subnormal is read from its bits, M 2^-149 with
// M its integer mantissa (float(M) is exact and normal): frexp of a subnormal is undefined
// in GLSL, and a device that flushes subnormals (GPUs; lavapipe under VKBRDF_EMULATE_FTZ)
// reads the value itself as 0 in any arithmetic, a scaling by 2^64 included.
vec2 xf(float x) {
    uint b = floatBitsToUint(x) & 0x7fffffffu;
    if (b == 0u) {
        return vec2(0.0);
    }
    int e;
    if (b < 0x00800000u) {
        float m = frexp(float(b), e);
        return vec2(m, float(e) - 149.0);
    }
    float m = frexp(x, e);
    return vec2(m, float(e));
}

// m 2^e renormalised (m finite, >= 0, and normal: products and quotients of two m's are).
vec2 xf_norm(float m, float e) {
    if (m == 0.0) {
        return vec2(0.0);
    }
    int k;
    float f = frexp(m, k);
    return vec2(f, e + float(k));
}

vec2 xf_mul(vec2 a, vec2 b) {
    return xf_norm(a.x * b.x, a.y + b.y);
}

vec2 xf_div(vec2 a, vec2 b) {
    return xf_norm(a.x / b.x, a.y - b.y);
}

vec2 xf_sqrt(vec2 a) {
    // An odd exponent moves one factor 2 into m, so that e/2 is an integer.
    bool odd = mod(a.y, 2.0) != 0.0;
    return xf_norm(sqrt(odd ? 2.0 * a.x : a.x), (odd ? a.y - 1.0 : a.y) * 0.5);
}

// a + b for a, b >= 0: the smaller aligned to the larger (below 2^-30 of it, it does not
// change the float32 result and is dropped, which keeps ldexp's argument in range).
vec2 xf_add(vec2 a, vec2 b) {
    if (a.x == 0.0 || b.y > a.y) {
        vec2 t = a;
        a = b;
        b = t;
    }
    float d = b.y - a.y;
    if (b.x == 0.0 || d < -30.0) {
        return a;
    }
    return xf_norm(a.x + ldexp(b.x, int(d)), a.y);
}

// a < b for m 2^e forms (>= 0).
bool xf_less(vec2 a, vec2 b) {
    return b.x != 0.0 && (a.x == 0.0 || a.y < b.y || (a.y == b.y && a.x < b.x));
}

vec2 xf_min(vec2 a, vec2 b) {
    return xf_less(b, a) ? b : a;
}

// ln(m 2^e) for m > 0 as a pair: e ln2_hi is exact for |e| < 256 (math.glsl's split), and
// two-sum keeps the rest (a float ln of a subnormal cosine, ~-100, is 4e-6 off).
vec2 xf_log_pair(vec2 a) {
    return two_sum(a.y * LN2_HI, log_acc(a.x) + a.y * LN2_LO);
}

// m 2^e rounded to float32: +inf beyond FLT_MAX (the caller saturates and counts it), 0
// below the smallest subnormal. ldexp is applied in two steps below the normal range
// (a subnormal ldexp result is undefined in GLSL; a product by 2^-64 is not).
float xf_float(vec2 a) {
    if (a.x == 0.0 || a.y < -160.0) {
        return 0.0;
    }
    if (a.y > 128.0) {
        return uintBitsToFloat(0x7f800000u);
    }
    if (a.y < -125.0) {
        return ldexp(a.x, int(a.y) + 64) * 5.42101086242752217e-20; // 2^-64
    }
    return ldexp(a.x, int(a.y));
}

// e^x as m 2^e for x = x.hi + x.lo beyond float32's exp range: x = k ln 2 + r, |r| <=
// ln 2 / 2. A pair, because x is ~100 at subnormal cosines and a float x would carry an
// absolute error of 4e-6, the result as much relatively.
vec2 xf_exp(vec2 x) {
    float k = floor(x.x * LOG2E + 0.5);
    float r = (x.x - k * LN2_HI) + (x.y - k * LN2_LO);
    return xf_norm(exp_acc(r), k);
}

// ln 0 as a pair's high word: far below any exponent xf_exp is given, so e^it is 0.
const float XF_LN_ZERO = -1e30;

#endif
