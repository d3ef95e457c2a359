// frame32.glsl — the frame's scalars without f64 (a device without shaderFloat64, or
// VKBRDF_DISABLE_FLOAT64=1): the same quantities as frame64.glsl from the raw inputs with
// float-float pairs (ff.glsl) and m 2^e forms (xf), with three-word sums where a lobe is
// sharper than pairs resolve. make_frame (frame.glsl) calls it.

#ifndef VKBRDF_FRAME32_GLSL
#define VKBRDF_FRAME32_GLSL

#include "ff.glsl"
#include "frame_fields.glsl"
#include "material.glsl"
#include "input.glsl"

#if !defined(HAS_FLOAT64)
// a 2^k with max |a_i| in [1, 2) (a finite and non-zero: checked before). A power of two:
// exact, so the frame's pairs see the inputs themselves; without it the squares of
// components near 1e-30 or 1e30 leave float32's range.
vec3 scale_pow2(vec3 a) {
    float m = max(max(abs(a.x), abs(a.y)), abs(a.z));
    if (m < 1.1754944e-38) {
        // A subnormal largest component has no exponent field to read: bring it into
        // the normal range first (exact, a power of two).
        a *= 18446744073709551616.0; // 2^64
        m *= 18446744073709551616.0;
    }
    int e = int((floatBitsToUint(m) >> 23) & 0xffu) - 127;
    return ldexp(a, ivec3(-e));
}

// a 2^(boost - e) with 2^e <= max |a_i| < 2^(e + 1), from the f32 bits of a (finite and
// non-zero: checked before), by integer arithmetic: component i is M 2^X (M the integer
// mantissa, hidden bit included; a subnormal's X is -149) and becomes float(M) 2^(X +
// boost - e), exact. GPUs flush f32 subnormals to zero in arithmetic and in the inputs of
// arithmetic (NVIDIA does; VKBRDF_EMULATE_FTZ=1 makes lavapipe do it too), so a subnormal
// component of a vector whose largest one is normal (the stress corpus's tiny cosines,
// N along an axis and 1e-45 the component of L along it) reads as 0 in scale_pow2 and in
// every product formed from it: the cosine is then 0, the tuple below the horizon. With a
// boost of 2^60 every component down to 2^-149 of the largest lands in the normal range,
// and products of two such vectors stay below 2^123.
vec3 scaled_bits(uvec3 b, int boost) {
    uvec3 mag = b & 0x7fffffffu;
    uint top = max(mag.x, max(mag.y, mag.z));
    int e = top >= 0x00800000u ? int(top >> 23) - 127 : findMSB(top) - 149;
    vec3 a;
    for (int i = 0; i < 3; i++) {
        bool normal = mag[i] >= 0x00800000u;
        uint m = normal ? (mag[i] & 0x007fffffu) | 0x00800000u : mag[i];
        int x = (normal ? int(mag[i] >> 23) - 150 : -149) + boost - e;
        // Below 2^-126 after the boost the component is flushed (or subnormal) anyway; the
        // test keeps ldexp's exponent in range.
        float c = x < -150 ? 0.0 : ldexp(float(m), x);
        a[i] = (b[i] & 0x80000000u) != 0u ? -c : c;
    }
    return a;
}

// The boost of scaled_bits for the tiny-cosine and tiny-|l + v| paths (see there).
const int TINY_BOOST = 60;

// A cosine N.W/(|N||W|) of the scaled inputs ns, ws (|N||W| = lengths as a pair): the pair
// (float-float where the dot product is above 2^-80, else its float32 rounding, 0 below
// FLT_MIN), its m 2^e form, and whether it is > 0 (the horizon test, made on the exact
// dot product's sign as the reference makes it). Where the dot product of the scaled
// inputs is below 2^-80 it is formed again from the inputs' bits boosted by 2^60 each
// (scaled_bits): under flush-to-zero the scaled inputs lose components below 2^-126 of
// the largest and every product below 2^-126, an absolute error of ~2^-123 that is all
// of a cosine of 1e-38 or 1e-45 (its sign too); above 2^-80 it is below 2^-43 relative.
vec2 frame_cosine(vec3 ns, vec3 ws, uvec3 n_bits, uvec3 w_bits, vec2 lengths, out vec2 cos_xf,
                  out bool above) {
    vec2 d = dot_ff(ns, ws);
    if (abs(d.x) >= 8.2718061e-25) { // 2^-80
        vec2 c = ff_div(d, lengths);
        above = c.x > 0.0;
        cos_xf = xf(ff_round(c));
        return c;
    }
    d = dot_ff(scaled_bits(n_bits, TINY_BOOST), scaled_bits(w_bits, TINY_BOOST));
    above = d.x > 0.0; // the pair's hi is 0 only for an exact 0
    cos_xf = above ? xf_div(xf(d.x), xf(ff_round(lengths))) - vec2(0.0, float(2 * TINY_BOOST))
                   : vec2(0.0);
    return vec2(xf_float(cos_xf), 0.0);
}

// |l + v| for unit l, v, from the scaled inputs L, V, their lengths and lv = l + v as a
// pair vector (the reference's construction, src/reference/frame.rs): |l + v|^2 =
// 2 (1 + l.v) with p = L.V exact to a pair, q = |L||V|. For p >= 0, 1 + l.v = 1 + p/q;
// for p < 0 that sum cancels near l = -v (grazing mirror geometry), and Lagrange's
// identity |L|^2|V|^2 - (L.V)^2 = |L x V|^2 turns it into |L x V|^2/(q (q - p)), a
// quotient of positives. Where |L x V| is small its terms are scaled by 2^k (exact): lv
// is returned scaled and k set, |l + v| = result 2^-k (k = 0 for |L x V| >= 2^-30). Where
// |L x V| is below 2^-100 (|l + v| below ~1e-30: mirrored directions with components of
// 1e-38 or 1e-45) it would be lost to flush-to-zero and h be NaN; |l + v| then comes from
// lv itself, formed again from the inputs' bits boosted by 2^60 (scaled_bits): the tiny
// components that make it up are below 2^-126 of the largest, and the unit vectors of
// the frame have lost them under flush-to-zero (exact mirrors summed to lv = 0).
vec2 lv_length(vec3 ls, vec3 vs, vec2 nl, vec2 nv, uvec3 l_bits, uvec3 v_bits,
               inout vec3 lv_hi, inout vec3 lv_lo, out float k) {
    k = 0.0;
    vec2 p = dot_ff(ls, vs);
    vec2 q = ff_mul(nl, nv);
    if (p.x >= 0.0) {
        return ff_sqrt(ff_mul_f(ff_add(vec2(1.0, 0.0), ff_div(p, q)), 2.0));
    }
    vec3 x_hi, x_lo;
    cross_ff(ls, vs, x_hi, x_lo);
    float xm = max(max(abs(x_hi.x), abs(x_hi.y)), abs(x_hi.z));
    if (xm >= 7.8886091e-31) { // 2^-100
        // Below |L x V| = 2^-30 its square and the products below leave the range where a
        // two-product is exact under flush-to-zero (its partial products below 2^-126 are
        // flushed: an absolute error of ~2^-124, 1e-4 relative at |l + v| = 5e-19), so
        // L x V is scaled by 2^k first (exact) and |l + v| 2^k returned, lv scaled alike.
        if (xm < 9.3132257e-10) { // 2^-30
            int j = 127 - int((floatBitsToUint(xm) >> 23) & 0xffu);
            k = float(j);
            x_hi = ldexp(x_hi, ivec3(j));
            x_lo = ldexp(x_lo, ivec3(j));
            lv_hi = ldexp(lv_hi, ivec3(j));
            lv_lo = ldexp(lv_lo, ivec3(j));
        }
        vec2 lxv = ff_sqrt(length2_ff3(x_hi, x_lo));
        return ff_sqrt(ff_mul_f(ff_mul(ff_div(lxv, q), ff_div(lxv, ff_add(q, -p))), 2.0));
    }
    vec3 lb_hi = scaled_bits(l_bits, TINY_BOOST), lb_lo = vec3(0.0);
    vec3 vb_hi = scaled_bits(v_bits, TINY_BOOST), vb_lo = vec3(0.0);
    div_ff3(lb_hi, lb_lo, nl);
    div_ff3(vb_hi, vb_lo, nv);
    add_ff3(lb_hi, lb_lo, vb_hi, vb_lo, lv_hi, lv_lo); // (l + v) 2^60
    float m = max(max(abs(lv_hi.x), abs(lv_hi.y)), abs(lv_hi.z));
    if (m == 0.0) {
        return vec2(0.0); // l = -v exactly: below the horizon, and never read
    }
    // m >= 2^-90 here (|l + v| >= cos_i + cos_o >= 2^-150): a normal number.
    int j = 127 - int((floatBitsToUint(m) >> 23) & 0xffu);
    k = float(TINY_BOOST + j);
    lv_hi = ldexp(lv_hi, ivec3(j));
    lv_lo = ldexp(lv_lo, ivec3(j));
    return ff_sqrt(length2_ff3(lv_hi, lv_lo));
}


// 1/|A| for a scaled input A (|A|^2 = s, |A| = len as pairs) in three words (w0, w1, w2):
// the pair r0 = 1/len and one Newton step r0 (1 + rho/2), rho = 1 - |A|^2 r0^2 summed
// from its exact terms (r0.lo^2 included: it is of the order of rho itself).
vec3 inverse_length3(vec3 a, vec2 len) {
    vec2 r0 = ff_div(vec2(1.0, 0.0), len);
    float sq[6];
    dot_terms(a, a, sq);
    vec2 h2 = two_prod(r0.x, r0.x), hl = two_prod(2.0 * r0.x, r0.y), l2 = two_prod(r0.y, r0.y);
    float r2[6] = float[6](h2.x, h2.y, hl.x, hl.y, l2.x, l2.y);
    Acc3 acc = Acc3(-1.0, 0.0, 0.0);
    for (int i = 0; i < 6; i++) {
        for (int j = 0; j < 6; j++) {
            acc_add_prod(acc, sq[i], r2[j]);
        }
    }
    float rho = -acc_pair(acc).x;
    return vec3(r0, r0.x * rho * 0.5);
}

#if defined(HAS_BLINN_PHONG) || defined(HAS_RTR) || defined(HAS_D_BLINN)
// |n x h|^2 for a lobe cos_h^e so sharp that the pair frame's |n x h| (error ~2^-48
// absolute) is not enough: with e = 1e18 the lobe lives at |n x h| ~ 1e-9, where e |n x h|^2
// then came out 1e-5 off relative (stress corpus, near-peak). n x (l + v) = (N x L)/|L| +
// (N x V)/|V|, the cross products exact (four terms each) and 1/|L|, 1/|V| in three words
// (inverse_length3), summed in three words: O(1) terms that cancel, to ~2^-70.
float sin2_h_sharp(vec3 ns, vec3 ls, vec3 vs, vec2 nn, vec2 nl, vec2 nv, vec2 lv_len) {
    vec3 rl = inverse_length3(ls, nl), rv = inverse_length3(vs, nv);
    vec3 x_hi, x_lo;
    for (int i = 0; i < 3; i++) {
        float a[4], b[4];
        cross_terms(ns, ls, i, a);
        cross_terms(ns, vs, i, b);
        Acc3 acc = Acc3(0.0, 0.0, 0.0);
        for (int j = 0; j < 4; j++) {
            for (int w = 0; w < 3; w++) {
                acc_add_prod(acc, a[j], rl[w]);
                acc_add_prod(acc, b[j], rv[w]);
            }
        }
        vec2 xi = acc_pair(acc);
        x_hi[i] = xi.x;
        x_lo[i] = xi.y;
    }
    // n x h = that / (|N| |l + v|), in pairs to the one final rounding (each float rounding
    // on the way costs e |n x h|^2 u, up to 1e-6 at the lobe's edge).
    vec2 d = ff_mul(nn, lv_len);
    return ff_round(ff_div(length2_ff3(x_hi, x_lo), ff_mul(d, d)));
}

// Whether the tuple's material is a lobe cos_h^e sharp enough for sin2_h_sharp: its
// relative error e |n x h| 2^-47 would exceed ~1e-8.
bool sharp_h_lobe(GpuMaterial m, float sin2_h) {
    uint model = material_model(m);
    bool lobe = model == MODEL_BLINN_PHONG || model == MODEL_RTR
        || (model == MODEL_COOK_TORRANCE && material_distribution(m) == DIST_BLINN);
    return lobe && material_exponent(m) * sqrt(sin2_h) > 1e6;
}
#endif

#if defined(HAS_PHONG)
// |r x v|^2, r = 2 cos_i n - l, for a Phong lobe as sharp as above (the same failure, at
// r ~ v). r x v = (2 (N.L)(N x V) - |N|^2 (L x V)) / (|N|^2 |L| |V|): the bracket W is a
// polynomial in the inputs, summed from its exact terms in three words, and |r x v|^2 =
// |W|^2 / (|N|^4 |L|^2 |V|^2).
float sin2_rv_sharp(vec3 ns, vec3 ls, vec3 vs) {
    float nl[6], nn[6];
    dot_terms(ns, ls, nl);
    dot_terms(ns, ns, nn);
    vec3 w_hi, w_lo;
    for (int i = 0; i < 3; i++) {
        float nxv[4], lxv[4];
        cross_terms(ns, vs, i, nxv);
        cross_terms(ls, vs, i, lxv);
        Acc3 acc = Acc3(0.0, 0.0, 0.0);
        for (int a = 0; a < 6; a++) {
            for (int b = 0; b < 4; b++) {
                acc_add_prod(acc, 2.0 * nl[a], nxv[b]);
                acc_add_prod(acc, -nn[a], lxv[b]);
            }
        }
        vec2 wi = acc_pair(acc);
        w_hi[i] = wi.x;
        w_lo[i] = wi.y;
    }
    vec2 n2 = dot_ff(ns, ns);
    vec2 d = ff_mul(ff_mul(n2, n2), ff_mul(dot_ff(ls, ls), dot_ff(vs, vs)));
    return ff_round(ff_div(length2_ff3(w_hi, w_lo), d));
}
#endif

// The scalars of the frame for a tuple whose l, v, n (and tangent) make_frame has found
// valid, the tangent-parallel test and the horizon test: STATUS_VALID, STATUS_INVALID or
// STATUS_BELOW_HORIZON.
uint frame_scalars_f32(Row r, GpuMaterial m, inout Frame f) {
    // No f64: the same scalars from the raw inputs with float-float pairs (ff.glsl), which
    // carry ~48 bits where frame64.glsl carries 53 (each reason as there):
    // - cos_i, cos_o = N.L/(|N||L|), the dot product exact before its one rounding (the
    //   products of f32 inputs are exact pairs), as the reference forms them;
    // - |l + v| from 1 + l.v, by Lagrange's identity where l.v < 0 (see lv_length);
    // - l, v, n, h and the tangent frame as pair vectors, so that h's direction, |n x h|^2,
    //   h.t, h.b and r.v keep their relative precision near l = -v, near the peak and at
    //   roughness ratios up to 1e4 (three words where a lobe is sharper: sin2_h_sharp);
    // - the cosines, cos_h and c also as m 2^e (xf) for the models' TINY_COS branches,
    //   which need f64's exponent range, not its precision.
    vec3 ls = scale_pow2(r.l), vs = scale_pow2(r.v), ns = scale_pow2(r.n);
    vec2 nl = ff_sqrt(dot_ff(ls, ls)), nv = ff_sqrt(dot_ff(vs, vs));
    vec2 nn2 = dot_ff(ns, ns);
    vec2 nn = ff_sqrt(nn2);
#if defined(HAS_ANISOTROPIC) && defined(HAS_TANGENTS)
    // The tangent-parallel test of FORMULAS.md §1, |n x t| <= 1e-12, as |N x T|^2 <=
    // 1e-24 |N|^2 |T|^2 on the scaled inputs, N x T exact to a pair (cross_ff: two-products
    // and two-sums, every operation `precise`): a tangent that is an exact multiple of N
    // gives exactly 0, as in the reference, whatever the device contracts. Not the shared
    // s2 above: cross() and dot() are built-ins, which `precise` does not keep from being
    // contracted into FMAs (the f32 frame on an H200 counted 0.91 M invalid tuples of 10 M
    // where the reference counts 1.15 M). Made before the horizon test, as the reference
    // makes it; N x T is the b of the tangent frame below.
    vec3 b_hi = vec3(0.0), b_lo = vec3(0.0);
    vec2 nxt2 = vec2(0.0);
    if (is_anisotropic(m)) {
        vec3 ts = scale_pow2(r.t);
        cross_ff(ns, ts, b_hi, b_lo);
        nxt2 = length2_ff3(b_hi, b_lo);
        if (ff_round(nxt2) <= 1e-24 * ff_round(nn2) * ff_round(dot_ff(ts, ts))) {
            return STATUS_INVALID;
        }
    }
#endif
    // The horizon test on the exact dot products' signs, as the reference decides it: a
    // cosine below 7e-46 rounds to 0 in f32, and below FLT_MIN a GPU flushes it to 0.
    bool above_i, above_o;
    vec2 cos_i = frame_cosine(ns, ls, r.n_bits, r.l_bits, ff_mul(nn, nl), f.cos_i_xf, above_i);
    vec2 cos_o = frame_cosine(ns, vs, r.n_bits, r.v_bits, ff_mul(nn, nv), f.cos_o_xf, above_o);
    f.cos_i = ff_round(cos_i);
    f.cos_o = ff_round(cos_o);
    if (!(above_i && above_o)) {
        return STATUS_BELOW_HORIZON;
    }
    vec3 l_hi = ls, l_lo = vec3(0.0), v_hi = vs, v_lo = vec3(0.0), n_hi = ns, n_lo = vec3(0.0);
    div_ff3(l_hi, l_lo, nl);
    div_ff3(v_hi, v_lo, nv);
    div_ff3(n_hi, n_lo, nn);
    vec3 h_hi, h_lo;
    add_ff3(l_hi, l_lo, v_hi, v_lo, h_hi, h_lo); // l + v, made unit below
    // |l + v| = lv_len 2^-k: k = 0 but where |l + v| < ~1e-15 (see lv_length).
    float k;
    vec2 lv_len = lv_length(ls, vs, nl, nv, r.l_bits, r.v_bits, h_hi, h_lo, k);
    // cos_h = (cos_i + cos_o)/|l + v| and c = |l + v|/2, as in frame64.glsl: dot(n, h)
    // and dot(v, h) would inherit h's direction error, which grows as 1/|l + v|.
    vec2 lv_xf = xf(ff_round(lv_len)) - vec2(0.0, k);
    f.c_xf = lv_xf - vec2(0.0, 1.0);
    // Cosines or |l + v| near or below float32's normal range (grazing tuples with
    // components of 1e-38 or 1e-45): their squares and quotients leave float32, and cos_h
    // and c come from the m 2^e forms instead (float32 precision, which is all that is
    // left of a subnormal cosine).
    if (k == 0.0 && min(f.cos_i, f.cos_o) >= 1e-30) {
        f.cos_h = ff_round(ff_div(ff_add(cos_i, cos_o), lv_len));
        f.cos_h_xf = xf(f.cos_h);
    } else {
        f.cos_h_xf = xf_div(xf_add(f.cos_i_xf, f.cos_o_xf), lv_xf);
        f.cos_h = xf_float(f.cos_h_xf);
    }
    if (k == 0.0) {
        f.c_exact = 0.5 * lv_len;
        f.c = ff_round(f.c_exact);
    } else {
        f.c = xf_float(f.c_xf);
        f.c_exact = vec2(f.c, 0.0);
    }
    div_ff3(h_hi, h_lo, lv_len);
    f.h = h_hi + h_lo;
    vec3 x_hi, x_lo;
    cross_ff3(n_hi, n_lo, h_hi, h_lo, x_hi, x_lo);
    f.sin2_h = ff_round(length2_ff3(x_hi, x_lo));
#if defined(HAS_BLINN_PHONG) || defined(HAS_RTR) || defined(HAS_D_BLINN)
    if (k == 0.0 && sharp_h_lobe(m, f.sin2_h)) {
        f.sin2_h = sin2_h_sharp(ns, ls, vs, nn, nl, nv, lv_len);
    }
#endif
#if defined(HAS_ANISOTROPIC) && defined(HAS_TANGENTS)
    if (is_anisotropic(m)) {
        // b = N x T/|N x T| and t = b x n as pair vectors (frame64.glsl's construction).
        vec3 t_hi, t_lo;
        div_ff3(b_hi, b_lo, ff_sqrt(nxt2)); // N x T from the parallel test above
        cross_ff3(b_hi, b_lo, n_hi, n_lo, t_hi, t_lo);
        f.hx = ff_round(dot_ff3(h_hi, h_lo, t_hi, t_lo));
        f.hy = ff_round(dot_ff3(h_hi, h_lo, b_hi, b_lo));
        f.l_tb = vec2(ff_round(dot_ff3(l_hi, l_lo, t_hi, t_lo)),
                      ff_round(dot_ff3(l_hi, l_lo, b_hi, b_lo)));
        f.v_tb = vec2(ff_round(dot_ff3(v_hi, v_lo, t_hi, t_lo)),
                      ff_round(dot_ff3(v_hi, v_lo, b_hi, b_lo)));
    }
#endif
#if defined(HAS_G_SMITH) || defined(HAS_G_SMITH_CORRELATED) || defined(HAS_G_SMITH_FAST) \
    || defined(HAS_G_SCHLICK_SMITH) || defined(HAS_HTSG)
    cross_ff3(n_hi, n_lo, l_hi, l_lo, x_hi, x_lo);
    f.sin2_i = ff_round(length2_ff3(x_hi, x_lo));
    cross_ff3(n_hi, n_lo, v_hi, v_lo, x_hi, x_lo);
    f.sin2_o = ff_round(length2_ff3(x_hi, x_lo));
#endif
#if defined(HAS_PHONG)
    if (material_model(m) == MODEL_PHONG) {
        // r = 2 cos_i n - l as a pair vector.
        vec3 r_hi, r_lo;
        vec2 ci2 = ff_mul_f(cos_i, 2.0);
        for (int i = 0; i < 3; i++) {
            vec2 ri = ff_add(ff_mul(ci2, vec2(n_hi[i], n_lo[i])), -vec2(l_hi[i], l_lo[i]));
            r_hi[i] = ri.x;
            r_lo[i] = ri.y;
        }
        f.rv = ff_round(dot_ff3(r_hi, r_lo, v_hi, v_lo));
        cross_ff3(r_hi, r_lo, v_hi, v_lo, x_hi, x_lo);
        f.sin2_rv = ff_round(length2_ff3(x_hi, x_lo));
        // As sharp_h_lobe, for r.v (Phong).
        if (material_exponent(m) * sqrt(f.sin2_rv) > 1e6) {
            f.sin2_rv = sin2_rv_sharp(ns, ls, vs);
        }
    }
#endif
    return STATUS_VALID;
}
#endif

#endif
