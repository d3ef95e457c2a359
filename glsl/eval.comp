#version 450
// eval.comp — the BRDF kernel: one invocation per tuple of one chunk.
//
// Compiled once per FeatureSet (src/gpu/kernel.rs): the HAS_* / WRITE_TERMS macros decide
// which models, terms and outputs exist at all. Also injected from Rust (said once there):
// the MODEL_* / DIST_* / GEOM_* / FRESNEL_* / CONV_* / FLAG_* codes, the BINDING_* numbers,
// and USE_SUBGROUP_ARITHMETIC when the device can reduce counts across a subgroup. The
// workgroup size is specialization constant 0.

#extension GL_EXT_samplerless_texture_functions : require

#if defined(USE_SUBGROUP_ARITHMETIC)
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#endif

#include "layout.glsl"
#include "models.glsl"

layout(local_size_x_id = 0) in;

// Rows `Lx Ly Lz Vx Vy Vz Nx Ny Nz material [Tx Ty Tz]` (src/batch.rs), row-major f32,
// read as RGBA32F texels of a uniform texel buffer over the same bytes (the storage-buffer
// binding BINDING_TUPLES is not read by the kernel). On lavapipe a texelFetch of 4 floats
// costs about what one scalar storage-buffer load does (bounds check and address per lane),
// so 3 fetches instead of 10 loads per row (measured: src/gpu/mod.rs, "Input").
// textureBuffer, not samplerBuffer: a sampled image of Dim Buffer draws a SPIR-V warning
// from the validation layer, and texelFetch needs no sampler.
// Read as RGBA32UI, the bits themselves: see input_vector.
layout(set = 0, binding = BINDING_TUPLE_TEXELS) uniform utextureBuffer tuple_texels;
layout(std430, set = 0, binding = BINDING_MATERIALS) readonly buffer Materials {
    GpuMaterial materials[];
};
// n x 3: RGB BRDF.
layout(std430, set = 0, binding = BINDING_BRDF) writeonly buffer Brdf {
    float brdf_out[];
};
#if defined(WRITE_TERMS)
// n x 6: D, G, F_r, F_g, F_b, K.
layout(std430, set = 0, binding = BINDING_TERMS) writeonly buffer Terms {
    float terms_out[];
};
#endif
#if defined(BUCKETED)
// The host uploads a chunk's rows grouped by material (src/gpu/evaluator.rs, bucket_order)
// and puts the outputs back in place: llvmpipe runs a subgroup's lanes in SIMD, and a
// subgroup mixing models executes every model's path (mixed 8-material batch: 3.3x). Row
// i of the chunk as uploaded is row order[i] of the batch's chunk, which only the first
// invalid row's report needs. (Reading the rows in place through order[] instead kept the
// lanes coherent but scattered their loads: 1.5x, not 3.3x.)
layout(std430, set = 0, binding = BINDING_ORDER) readonly buffer Order {
    uint order[];
};
#endif
// Chunk totals; the host sets them to (0, 0, 0xffffffff, 0) before each dispatch.
layout(std430, set = 0, binding = BINDING_COUNTS) buffer Counts {
    uint invalid_count;
    uint below_horizon_count;
    uint first_invalid; // chunk-relative row, 0xffffffff when none
    uint saturated_count; // valid tuples with an output clamped to FLT_MAX
};

layout(push_constant) uniform Params {
    uint tuple_count;    // rows in this chunk
    uint material_count; // rows in the material table
    uint first_row;      // global index of the chunk's first row
    uint grid_width;     // GENERATE_HALF_DIFF: theta_h columns; GENERATE_IMPORTANCE: blocks per point
    uint grid_height;    // GENERATE_HALF_DIFF: theta_d rows; GENERATE_IMPORTANCE: samples per point
    uint spacing;        // GENERATE_HALF_DIFF: 0 theta_h = x^2 pi/2 (MERL), 1 x pi/2;
                         // GENERATE_IMPORTANCE: 0 GGX, 1 Beckmann
} params;

#if defined(HAS_TANGENTS)
const uint COLUMNS = 13u;
#else
const uint COLUMNS = 10u;
#endif

const uint STATUS_VALID = 0u;
const uint STATUS_INVALID = 1u;
const uint STATUS_BELOW_HORIZON = 2u;

// One input row, unpacked.
struct Row {
    vec3 l;
    vec3 v;
    vec3 n;
    float material;
    vec3 t; // 0 without HAS_TANGENTS
    // The f32 bits of L, V, N, T as given: the f64 frame takes their exact values from them.
    uvec3 l_bits, v_bits, n_bits, t_bits;
};

// The 4 words at offset `off` (0..3) of the 8 words a, b.
uvec4 window4(uvec4 a, uvec4 b, uint off) {
    return off == 0u ? a
        : off == 1u ? uvec4(a.yzw, b.x)
        : off == 2u ? uvec4(a.zw, b.xy)
        : uvec4(a.w, b.xyz);
}

// An input vector from its f32 bits, for the f32 arithmetic. GPUs flush f32 subnormals to
// zero in arithmetic (NVIDIA's compute shaders do; lavapipe does not): without this, a
// vector scaled into the subnormal range reads as zero, an invalid tuple, where the
// reference sees a valid direction (FORMULAS.md §1: any length > 0; the stress corpus's
// "denormal" vectors: 0.67 M of 10 M tuples misjudged on an H200). A vector whose largest
// component is below 2^-63 is scaled by 2^64, exactly, since only its direction counts:
// normal components through their exponent field, subnormal ones as float(mantissa) 2^-85,
// both normal. Other vectors are used as read: a subnormal component is then below 2^-63
// of the largest, beneath f32 resolution of the direction (the f64 frame, which reads the
// bits through exact64, keeps even those).
vec3 input_vector(uvec3 b) {
    uvec3 mag = b & 0x7fffffffu;
    uint top = max(mag.x, max(mag.y, mag.z));
    if (top >= (64u << 23)) {
        return uintBitsToFloat(b); // also NaN and Inf, for the invalid test
    }
    vec3 r;
    for (int i = 0; i < 3; i++) {
        float x = (mag[i] >> 23) == 0u
            ? float(mag[i]) * uintBitsToFloat((127u - 85u) << 23)
            : uintBitsToFloat(mag[i] + (64u << 23));
        r[i] = (b[i] & 0x80000000u) != 0u ? -x : x;
    }
    return r;
}

// Row `row` from the texels that hold it. It starts at float row * COLUMNS, i.e. at float
// `off` of texel `first`; its COLUMNS floats end within texel first + 2 (10 columns) or
// first + 3 (13), and each texel fetched holds at least one float of the row, so no fetch
// leaves the buffer (the host rounds it up to whole texels).
Row load_row(uint row) {
    uint start = row * COLUMNS;
    int first = int(start >> 2u);
    uint off = start & 3u;
    uvec4 a = texelFetch(tuple_texels, first);
    uvec4 b = texelFetch(tuple_texels, first + 1);
    uvec4 c = texelFetch(tuple_texels, first + 2);
#if defined(HAS_TANGENTS)
    uvec4 d = texelFetch(tuple_texels, first + 3);
#else
    uvec4 d = uvec4(0u); // 10 columns end within c (off is 0 or 2)
#endif
    uvec4 w0 = window4(a, b, off); // Lx Ly Lz Vx
    uvec4 w1 = window4(b, c, off); // Vy Vz Nx Ny
    uvec4 w2 = window4(c, d, off); // Nz material Tx Ty
    Row r;
    r.l_bits = w0.xyz;
    r.v_bits = uvec3(w0.w, w1.xy);
    r.n_bits = uvec3(w1.zw, w2.x);
    r.material = uintBitsToFloat(w2.y);
#if defined(HAS_TANGENTS)
    r.t_bits = uvec3(w2.zw, window4(d, d, off).x); // Tz = d[off]
#else
    r.t_bits = uvec3(0u);
#endif
    r.l = input_vector(r.l_bits);
    r.v = input_vector(r.v_bits);
    r.n = input_vector(r.n_bits);
    r.t = input_vector(r.t_bits);
    return r;
}

#if defined(GENERATE_HALF_DIFF) || defined(GENERATE_IMPORTANCE)
// The bits of a row made on the device (normal values: no subnormal to keep).
void set_bits(inout Row r) {
    r.l_bits = floatBitsToUint(r.l);
    r.v_bits = floatBitsToUint(r.v);
    r.n_bits = floatBitsToUint(r.n);
    r.t_bits = floatBitsToUint(r.t);
}

// Texel `g` of the half/difference slice (src/table/slice.rs, Rusinkiewicz 1998), made on
// the device instead of read: column i -> x = (i + 1/2)/W, theta_h = x^2 pi/2 (or x pi/2);
// row j -> theta_d = (j + 1/2)/H pi/2; phi_d = 90 degrees, phi_h = 0, n = +z, material 0,
// tangent +x. With phi_d = 90 degrees, d = (0, sin theta_d, cos theta_d), l = R_y(theta_h) d
// and v is l reflected about h = (sin theta_h, 0, cos theta_h): the host's from_half_diff()
// term for term. No tuple is loaded: on lavapipe the loads are about half of the
// kernel's time (see docs/THROUGHPUT.md).
// sin(t pi/2) and cos(t pi/2) for t in [0, 1/2], i.e. angles up to pi/4, by their Taylor
// polynomials to x^11 and x^12: the first omitted terms are below (pi/4)^13/13! = 7e-12
// and (pi/4)^14/14! = 4e-13 relative to the results, so the polynomials are as exact as f32.
vec2 sin_cos_eighth(float t) {
    float x = t * (0.5 * PI);
    float x2 = x * x;
    float s = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0
              * (1.0 - x2 / 110.0)))));
    float c = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0
              * (1.0 - x2 / 90.0 * (1.0 - x2 / 132.0)))));
    return vec2(s, c);
}

// (sin, cos) of theta = u pi/2 for u in [0, 1], given also ubar = 1 - u computed without
// cancellation. Above pi/4 the complement is used (sin theta = cos(ubar pi/2)): forming
// theta, or pi/2 - theta, in f32 would leave ~1e-7 absolute error in the small cosine of
// a grazing angle, where the host's f64 angle has none (measured: 1.5e-5 relative in the
// slice against 7e-6 this way). Neither a range reduction nor the built-in sin/cos (which
// reduce the argument first) is needed.
vec2 sin_cos_quadrant(float u, float ubar) {
    return u <= 0.5 ? sin_cos_eighth(u) : sin_cos_eighth(ubar).yx;
}

// g / w, without an integer division (x86 has no vector one: llvmpipe would divide lane
// by lane): g < 2^24 (MAX_GENERATED_TEXELS on the host) is exact in f32, so the rounded
// quotient is within one of the true one, and the correction makes it exact.
uint quotient(uint g, uint w) {
    uint j = uint(float(g) / float(w));
    return j * w > g ? j - 1u : ((j + 1u) * w <= g ? j + 1u : j);
}

Row half_diff_row(uint g) {
    uint w = params.grid_width;
    uint j = quotient(g, w);
    uint i = g - j * w;
    // Column and row centres x = (i + 1/2)/W, y = (j + 1/2)/H and their complements, each
    // one rounding.
    float fw = float(w), fh = float(params.grid_height);
    float x = (float(i) + 0.5) / fw;
    float xbar = (fw - float(i) - 0.5) / fw;
    float y = (float(j) + 0.5) / fh;
    float ybar = (fh - float(j) - 0.5) / fh;
    // theta_h = u pi/2 with u = x (linear) or x^2 (MERL), 1 - x^2 = (1 - x)(1 + x).
    bool linear = params.spacing != 0u;
    vec2 h = sin_cos_quadrant(linear ? x : x * x, linear ? xbar : xbar * (1.0 + x));
    vec2 d = sin_cos_quadrant(y, ybar);
    Row r;
    r.l = vec3(d.y * h.x, d.x, d.y * h.y);
    float lh = r.l.x * h.x + r.l.z * h.y; // = cos theta_d
    r.v = 2.0 * lh * vec3(h.x, 0.0, h.y) - r.l;
    r.n = vec3(0.0, 0.0, 1.0);
    r.material = 0.0;
    r.t = vec3(1.0, 0.0, 0.0);
    set_bits(r);
    return r;
}
#endif


// Builds the frame of FORMULAS.md §1 and classifies the tuple. The invalid test comes first.
#if defined(HAS_FLOAT64)
// The exact value of the f32 with bits `b`, subnormals included: through the integer
// mantissa, since a device that flushes f32 subnormals may flush them in a float-to-double
// conversion too (the stress corpus's cosines of 1e-45 are subnormal components).
double exact64(uint b) {
    uint mag = b & 0x7fffffffu;
    double x = (mag >> 23) == 0u ? ldexp(double(mag), -149) : double(uintBitsToFloat(mag));
    return (b & 0x80000000u) != 0u ? -x : x;
}

// An f64 value of the frame rounded to f32 as a GPU rounds it: below FLT_MIN, 0. GPUs
// flush f32 subnormals (NVIDIA does, in conversions and arithmetic; lavapipe does not), so
// the f32 copies of the frame's quantities are flushed on every device: the code that
// reads them (and falls back to the f64 ones where they vanish) then behaves on lavapipe
// as on a GPU, and the stress corpus tests it here (its cosines of 1e-45 made 0.1 M
// non-finite outputs on an H200 before).
float f32_of(double x) {
    return abs(x) < double(FLT_MIN) ? 0.0 : float(x);
}
vec2 f32_of(dvec2 x) {
    return vec2(f32_of(x.x), f32_of(x.y));
}
vec3 f32_of(dvec3 x) {
    return vec3(f32_of(x.x), f32_of(x.y), f32_of(x.z));
}

// a/|a| in f64 from an input vector's f32 bits (finite and non-zero: checked before).
dvec3 unit64(uvec3 b) {
    dvec3 d = dvec3(exact64(b.x), exact64(b.y), exact64(b.z));
    return d / sqrt(dot(d, d));
}
#endif

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
#endif

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
    bool lobe = m.kind.x == MODEL_BLINN_PHONG || m.kind.x == MODEL_RTR
        || (m.kind.x == MODEL_COOK_TORRANCE && m.kind.y == DIST_BLINN);
    return lobe && m.lobe.x * sqrt(sin2_h) > 1e6;
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

uint make_frame(Row r, GpuMaterial m, out Frame f) {
    bool ok_l, ok_v, ok_n;
    f.l = safe_normalize(r.l, ok_l);
    f.v = safe_normalize(r.v, ok_v);
    f.n = safe_normalize(r.n, ok_n);
    f.t = vec3(0.0);
    f.b = vec3(0.0);
    f.hx = 0.0;
    f.hy = 0.0;
    f.rv = 0.0;
    f.sin2_rv = 0.0;
    f.sin2_i = 0.0;
    f.sin2_o = 0.0;
    f.l_tb = vec2(0.0);
    f.v_tb = vec2(0.0);
    f.c_exact = double_or_float(0.0);
#if defined(HAS_FLOAT64)
    f.cos_i_exact = 0.0;
    f.cos_o_exact = 0.0;
    f.cos_h_exact = 0.0;
#else
    f.cos_i_xf = vec2(0.0);
    f.cos_o_xf = vec2(0.0);
    f.cos_h_xf = vec2(0.0);
    f.c_xf = vec2(0.0);
#endif
    if (!(ok_l && ok_v && ok_n)) {
        return STATUS_INVALID;
    }
#if defined(HAS_ANISOTROPIC)
    if (is_anisotropic(m)) {
#if defined(HAS_TANGENTS)
        bool ok_t;
        vec3 t = safe_normalize(r.t, ok_t);
        // |T - n(n.T)| = |n x t| |T|: the tuple is invalid when |n x t| <= 1e-12 (FORMULAS.md
        // §1), tested squared. `precise`: a compiler that contracts a*b - c*d into an FMA
        // (NVIDIA's does) leaves n x n at ~1e-8 instead of 0, and every tangent parallel
        // to the normal passed as valid (the stress corpus on an H200: 0.24 M of 10 M
        // tuples). Where the device has f64 the test is made there, from the exact inputs,
        // as the reference makes it.
        precise vec3 nxt = cross(f.n, t);
        precise float s2 = dot(nxt, nxt);
#if defined(HAS_FLOAT64)
        dvec3 nxt64 = cross(unit64(r.n_bits), unit64(r.t_bits));
        bool parallel = dot(nxt64, nxt64) <= 1e-24LF;
#else
        // Without f64: in make_frame's f32 branch, from N x T exact to a pair.
        bool parallel = false;
#endif
        if (!ok_t || parallel) {
            return STATUS_INVALID;
        }
        // b = n x t / |n x t| and t = b x n: the same frame as t = normalize(T - n(n.T)),
        // b = n x t, but built from cross products. Gram–Schmidt's subtraction leaves t
        // tilted out of the tangent plane by ~u/|n x t| (when T is near N), and h, which lies
        // mostly along n, would turn that tilt into an error of h.t; b x n is perpendicular
        // to n to within u whatever the error of b.
        f.b = nxt * inversesqrt(s2);
        f.t = cross(f.b, f.n);
#else
        return STATUS_INVALID; // anisotropic material, batch without tangents
#endif
    }
#endif
#if defined(HAS_FLOAT64)
    // The frame's scalars in f64 from the raw f32 inputs (the products of f32 values are
    // exact in f64; squares of f32 values, <= 1.2e77, and of subnormals stay in range):
    // - cos_i, cos_o with full f32 relative precision even at grazing angles. In f32,
    //   normalising l and n first leaves each cosine ~1e-7 off in absolute terms: K =
    //   1/(4 cos_i cos_o) is then wrong by O(1) below cos ~1e-6 and the horizon test falls
    //   on the wrong side (the stress corpus's grazing regime).
    // - h, |l + v|, cos_h, c and |n x h|^2: in f32, l + v of two rounded unit vectors
    //   carries ~u absolute error, which near l = -v (grazing mirror geometry) is a relative
    //   error of u/|l + v| in |l + v| and in h's direction: D_GGX, which reads
    //   cos_h^2 + slope2 rather than a logarithm, was 1e-4 off at |l + v| = 2e-3 even at
    //   m = 1, where D is constant (found by tests/vulkan_properties.rs).
    // Cost on lavapipe: 1.05-1.4x the f32 frame's time (examples/kernel_time.rs).
    dvec3 dn = unit64(r.n_bits), dl = unit64(r.l_bits), dv = unit64(r.v_bits);
    double cos_i = dot(dn, dl), cos_o = dot(dn, dv);
    f.cos_i = f32_of(cos_i);
    f.cos_o = f32_of(cos_o);
    f.cos_i_exact = cos_i;
    f.cos_o_exact = cos_o;
    // The horizon test on the f64 cosines, as the reference decides it: a cosine below
    // 7e-46 rounds to 0 in f32, and testing the f32 value put such tuples below the horizon
    // while the reference evaluates them (FORMULAS.md §1: every representable cosine).
    if (cos_i <= 0.0 || cos_o <= 0.0) {
        return STATUS_BELOW_HORIZON;
    }
    // |l + v| >= cos_i + cos_o > 0 here, so h is well defined.
    dvec3 lv = dl + dv;
    double len = sqrt(dot(lv, lv));
    dvec3 h = lv / len;
    f.h = f32_of(h);
    // cos_h = (cos_i + cos_o)/|l + v| and c = |l + v|/2: see the f32 branch.
    f.cos_h_exact = (cos_i + cos_o) / len;
    f.cos_h = f32_of(f.cos_h_exact);
    f.c = f32_of(0.5 * len);
    f.c_exact = 0.5 * len;
    dvec3 nxh = cross(dn, h);
    f.sin2_h = f32_of(dot(nxh, nxh));
#if defined(HAS_ANISOTROPIC) && defined(HAS_TANGENTS)
    if (is_anisotropic(m)) {
        // h in the tangent frame, built in f64 as in the f32 branch: with roughness ratios
        // up to 1e4, (h.b/m_y)^2 turns an f32 error of ~1e-7 in h.b into 3e-2 in D (Ward
        // and Beckmann near the peak, stress corpus).
        dvec3 nxt = cross(dn, unit64(r.t_bits));
        dvec3 b = nxt / sqrt(dot(nxt, nxt));
        dvec3 t = cross(b, dn);
        f.hx = f32_of(dot(h, t));
        f.hy = f32_of(dot(h, b));
        f.l_tb = f32_of(dvec2(dot(dl, t), dot(dl, b)));
        f.v_tb = f32_of(dvec2(dot(dv, t), dot(dv, b)));
    }
#endif
#if defined(HAS_G_SMITH) || defined(HAS_G_SMITH_CORRELATED) || defined(HAS_G_SMITH_FAST) \
    || defined(HAS_G_SCHLICK_SMITH)
    dvec3 nxl = cross(dn, dl), nxv = cross(dn, dv); // Smith's tan^2, Schlick-Smith's 1 - cos
    f.sin2_i = f32_of(dot(nxl, nxl));
    f.sin2_o = f32_of(dot(nxv, nxv));
#endif
#if defined(HAS_PHONG)
    if (m.kind.x == MODEL_PHONG) {
        dvec3 rr = 2.0 * cos_i * dn - dl;
        dvec3 rxv = cross(rr, dv);
        f.rv = f32_of(dot(rr, dv));
        f.sin2_rv = f32_of(dot(rxv, rxv));
    }
#endif
#else
    // No f64: the same scalars from the raw inputs with float-float pairs (ff.glsl), which
    // carry ~48 bits where the f64 branch carries 53 (each reason as there):
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
    // cos_h = (cos_i + cos_o)/|l + v| and c = |l + v|/2, as in the f64 branch: dot(n, h)
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
        // b = N x T/|N x T| and t = b x n as pair vectors (the f64 branch's construction).
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
    || defined(HAS_G_SCHLICK_SMITH)
    cross_ff3(n_hi, n_lo, l_hi, l_lo, x_hi, x_lo);
    f.sin2_i = ff_round(length2_ff3(x_hi, x_lo));
    cross_ff3(n_hi, n_lo, v_hi, v_lo, x_hi, x_lo);
    f.sin2_o = ff_round(length2_ff3(x_hi, x_lo));
#endif
#if defined(HAS_PHONG)
    if (m.kind.x == MODEL_PHONG) {
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
        if (m.lobe.x * sqrt(f.sin2_rv) > 1e6) {
            f.sin2_rv = sin2_rv_sharp(ns, ls, vs);
        }
    }
#endif
#endif
    return STATUS_VALID;
}

#if defined(HAS_MEASURED)
#include "measured.glsl"
#endif

Eval evaluate(Frame f, GpuMaterial m) {
    switch (m.kind.x) {
#if defined(HAS_LAMBERT)
    case MODEL_LAMBERT: return model_lambert(m);
#endif
#if defined(HAS_PHONG)
    case MODEL_PHONG: return model_phong(f, m);
#endif
#if defined(HAS_BLINN_PHONG)
    case MODEL_BLINN_PHONG: return model_blinn_phong(f, m);
#endif
#if defined(HAS_RTR)
    case MODEL_RTR: return model_rtr(f, m);
#endif
#if defined(HAS_WARD)
    case MODEL_WARD: return model_ward(f, m);
#endif
#if defined(HAS_COOK_TORRANCE)
    case MODEL_COOK_TORRANCE: return model_cook_torrance(f, m);
#endif
    default: return eval_zero();
    }
}

#if defined(GENERATE_IMPORTANCE)
// ============================================================ importance-sampled integrals
// The albedo and split-sum DFG tables (src/table/albedo.rs, which states the method and
// its accuracy): invocation g integrates SAMPLES_PER_BLOCK samples of one (mu, alpha)
// point, making each sample's l on the device, and writes the block's sums of
// x = f cos_i / pdf(l) and x (1 - c)^5; the host adds the blocks in f64. Push constants:
// grid_width = blocks per point, grid_height = samples per point N, spacing = lobe
// (0 GGX by its visible normals, 1 Beckmann by D cos_h). Per point, 4 texels of the input
// (the host's f64 sampling constants, rounded once): (v, G1(v)), (t1, s), (t2, alpha),
// (v_h, material).
const uint SAMPLES_PER_BLOCK = 256u;

// (sin, cos) of 2 pi u for u in [0, 1): the quadrant q = floor(4u) by exact f32
// arithmetic, the rest by sin_cos_quadrant.
vec2 sin_cos_turn(float u) {
    float q = floor(4.0 * u);
    float t = 4.0 * u - q; // exact: 4u is exact and q is its integer part
    vec2 sc = sin_cos_quadrant(t, 1.0 - t);
    return q == 0.0 ? sc : q == 1.0 ? vec2(sc.y, -sc.x) : q == 2.0 ? -sc : vec2(-sc.y, sc.x);
}

void importance_block(uint g) {
    uint blocks = params.grid_width;
    uint n = params.grid_height;
    uint p = quotient(g, blocks);
    uint b = g - p * blocks;
    vec4 t0 = uintBitsToFloat(texelFetch(tuple_texels, int(4u * p)));
    vec4 t1 = uintBitsToFloat(texelFetch(tuple_texels, int(4u * p + 1u)));
    vec4 t2 = uintBitsToFloat(texelFetch(tuple_texels, int(4u * p + 2u)));
    vec4 t3 = uintBitsToFloat(texelFetch(tuple_texels, int(4u * p + 3u)));
    vec3 v = t0.xyz;
    float g1 = t0.w, s = t1.w, alpha = t2.w;
    uint mi = min(uint(t3.w), params.material_count - 1u);
    GpuMaterial m = materials[mi];
    bool ggx = params.spacing == 0u;
    float sum = 0.0, sum5 = 0.0;
    uint first = b * SAMPLES_PER_BLOCK;
    uint last = min(first + SAMPLES_PER_BLOCK, n);
    for (uint k = first; k < last; k++) {
        // Hammersley point k of n: ((k + 1/2)/n, radical inverse of k).
        float u1 = (float(k) + 0.5) / float(n);
        float u2 = float(bitfieldReverse(k)) * (1.0 / 4294967296.0);
        vec2 phi = sin_cos_turn(u2); // (sin, cos)
        vec3 h;
        if (ggx) {
            // Heitz 2018, "Sampling the GGX Distribution of Visible Normals", listing 1.
            float r = sqrt(u1);
            float p1 = r * phi.y;
            float p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * phi.x;
            float p3 = sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0));
            vec3 nh = p1 * t1.xyz + p2 * t2.xyz + p3 * t3.xyz;
            h = normalize(vec3(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0)));
        } else {
            // D cos_h: tan^2 = -alpha^2 ln(1 - u1), by log1p (u1 is as small as 1/(2n)).
            float tan2 = alpha * alpha * -log1p_acc(-u1);
            float cos_t = inversesqrt(1.0 + tan2);
            float sin_t = sqrt(tan2) * cos_t;
            h = vec3(sin_t * phi.y, sin_t * phi.x, cos_t);
        }
        vec3 l = 2.0 * dot(v, h) * h - v;
        if (!(l.z > 0.0)) {
            continue; // below the horizon: f = 0 (a NaN l from a degenerate h too)
        }
        Row r;
        r.l = l;
        r.v = v;
        r.n = vec3(0.0, 0.0, 1.0);
        r.material = 0.0;
        r.t = vec3(0.0);
        set_bits(r);
        Frame f;
        if (make_frame(r, m, f) != STATUS_VALID) {
            continue;
        }
        Eval e = evaluate(f, m);
        // pdf(l) from the same f32 frame and D as f, so that D cancels consistently:
        // GGX G1(v) D / (4 cos_o), Beckmann D cos_h / (4 c).
        float pdf = ggx ? g1 * e.d / (4.0 * f.cos_o) : e.d * f.cos_h / (4.0 * f.c);
        float x = e.brdf.r * (f.cos_i / pdf);
        if (non_finite(x)) {
            continue; // pdf underflowed to 0: the host drops such samples too
        }
        float w = 1.0 - clamp(f.c, 0.0, 1.0);
        float w2 = w * w;
        sum += x;
        sum5 += x * (w2 * w2 * w);
    }
    brdf_out[3u * g] = sum;
    brdf_out[3u * g + 1u] = sum5;
    brdf_out[3u * g + 2u] = 0.0;
}
#endif

// The chunk row that uploaded row `row` came from (see Order).
uint original_row(uint row) {
#if defined(BUCKETED)
    return order[row];
#else
    return row;
#endif
}

// Evaluates row `row` of the chunk, stores its outputs and counts it.
void evaluate_row(uint row) {
    // The batch validated every index; the clamp only keeps a corrupted buffer from
    // reading outside the table.
#if defined(GENERATE_HALF_DIFF)
    Row r = half_diff_row(params.first_row + row);
#else
    Row r = load_row(row);
#endif
    uint mi = min(uint(r.material), params.material_count - 1u);
    GpuMaterial m = materials[mi];
    Frame f;
    uint status = make_frame(r, m, f);
    Eval e = status == STATUS_VALID ? evaluate(f, m) : eval_zero();
#if defined(HAS_MEASURED)
    if (status == STATUS_VALID && m.kind.x == MODEL_MEASURED) {
        e = model_measured(r, m);
    }
#endif
    // FORMULAS.md §1, "Overflow": an output beyond FLT_MAX (here +inf) is stored as FLT_MAX
    // and the tuple counted as saturated. Every output counts, the terms too whether or not
    // they are written, so the count does not depend on the request (as on the reference).
    bool saturated = false;
    e.brdf.r = saturate_output(e.brdf.r, saturated);
    e.brdf.g = saturate_output(e.brdf.g, saturated);
    e.brdf.b = saturate_output(e.brdf.b, saturated);
    e.d = saturate_output(e.d, saturated);
    e.g = saturate_output(e.g, saturated);
    e.f.r = saturate_output(e.f.r, saturated);
    e.f.g = saturate_output(e.f.g, saturated);
    e.f.b = saturate_output(e.f.b, saturated);
    e.k = saturate_output(e.k, saturated);
    brdf_out[row * 3u] = e.brdf.r;
    brdf_out[row * 3u + 1u] = e.brdf.g;
    brdf_out[row * 3u + 2u] = e.brdf.b;
#if defined(WRITE_TERMS)
    terms_out[row * 6u] = e.d;
    terms_out[row * 6u + 1u] = e.g;
    terms_out[row * 6u + 2u] = e.f.r;
    terms_out[row * 6u + 3u] = e.f.g;
    terms_out[row * 6u + 4u] = e.f.b;
    terms_out[row * 6u + 5u] = e.k;
#endif

    // Counts, only where there is something to count: the block runs for the invocations
    // whose tuple is invalid, below the horizon or saturated, and llvmpipe skips it altogether when a
    // subgroup has none (the usual case). Subgroup operations inside it reduce over those
    // active invocations only, so one atomic per subgroup, not per tuple (below-horizon
    // tuples are common: per-tuple atomics would serialise on one address). Measured on
    // lavapipe, 4M tuples with nothing to count: Lambert without loads and stores 148 ->
    // ~270 M/s against a reduction over every invocation; the whole kernel 1.1-1.3x
    // (`examples/kernel_time.rs`); with half the tuples below the horizon, no change.
    // Deliberately not a workgroup reduction in shared memory: that needs barrier(), and
    // llvmpipe runs any shader with a barrier through coroutines, which made the whole
    // kernel 2.7x slower on lavapipe (measured: 280 vs 103 ms for 4M tuples of a
    // load-and-store kernel).
    if (status != STATUS_VALID || saturated) {
        bool invalid = status == STATUS_INVALID;
        bool below = status == STATUS_BELOW_HORIZON;
#if defined(USE_SUBGROUP_ARITHMETIC)
        // The three counts in one reduction, 10 bits each (a subgroup has at most 128
        // invocations): invalid, below-horizon << 10, saturated << 20; and the first invalid
        // row only when there is one (n_invalid is uniform over the active invocations).
        uint packed = subgroupAdd(invalid ? 1u : below ? 0x400u : 0x100000u);
        uint n_invalid = packed & 0x3ffu;
        uint n_below = (packed >> 10u) & 0x3ffu;
        uint n_saturated = packed >> 20u;
        uint first = 0xffffffffu;
        if (n_invalid != 0u) {
            first = subgroupMin(invalid ? original_row(row) : 0xffffffffu);
        }
        if (subgroupElect()) {
            if (n_invalid != 0u) {
                atomicAdd(invalid_count, n_invalid);
                atomicMin(first_invalid, first);
            }
            if (n_below != 0u) {
                atomicAdd(below_horizon_count, n_below);
            }
            if (n_saturated != 0u) {
                atomicAdd(saturated_count, n_saturated);
            }
        }
#else
        if (invalid) {
            atomicAdd(invalid_count, 1u);
            atomicMin(first_invalid, original_row(row));
        } else if (below) {
            atomicAdd(below_horizon_count, 1u);
        } else {
            atomicAdd(saturated_count, 1u);
        }
#endif
    }
}

void main() {
    uint row = gl_GlobalInvocationID.x;
    // Out-of-range invocations of the last workgroup simply stop: the counts' subgroup
    // operations reduce over the invocations still active.
    if (row < params.tuple_count) {
#if defined(GENERATE_IMPORTANCE)
        importance_block(params.first_row + row);
#else
        evaluate_row(row);
#endif
    }
}
