// input.glsl — one tuple row as the kernel reads it: the RGBA32UI texels that hold it (the
// f32 bits, read exactly), the unpacked Row with its bits kept for the f64 frame, the f32
// input vectors with subnormal components rescued (input_vector) and, with f64, the exact
// value of an f32 from its bits (exact64). Rows made on the device (generators.glsl) fill
// the same Row.

#ifndef VKBRDF_INPUT_GLSL
#define VKBRDF_INPUT_GLSL

#include "bindings.glsl"

#if defined(HAS_TANGENTS)
const uint COLUMNS = 13u;
#else
const uint COLUMNS = 10u;
#endif

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

// The bits of N given as exactly (0, 0, 1): the local shading frame, which the peers and
// the bench's scenarios use and the slices and tables generate. make_frame sends such rows
// of isotropic materials to the local frames.
const uvec3 LOCAL_N_BITS = uvec3(0u, 0u, 0x3f800000u);


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

#if defined(HAS_TANGENTS)
// The 4 words at offset `off` (0..3) of the 8 words a, b.
uvec4 window4(uvec4 a, uvec4 b, uint off) {
    return off == 0u ? a
        : off == 1u ? uvec4(a.yzw, b.x)
        : off == 2u ? uvec4(a.zw, b.xy)
        : uvec4(a.w, b.xyz);
}

// Row `row` of 13 columns from the texels that hold it. It starts at float row * 13,
// i.e. at float `off` of texel `first`; its floats end within texel first + 3, and each
// texel fetched holds at least one float of the row, so no fetch leaves the buffer (the
// host rounds it up to whole texels).
Row load_row(uint row) {
    uint start = row * COLUMNS;
    int first = int(start >> 2u);
    uint off = start & 3u;
    uvec4 a = texelFetch(tuple_texels, first);
    uvec4 b = texelFetch(tuple_texels, first + 1);
    uvec4 c = texelFetch(tuple_texels, first + 2);
    uvec4 d = texelFetch(tuple_texels, first + 3);
    uvec4 w0 = window4(a, b, off); // Lx Ly Lz Vx
    uvec4 w1 = window4(b, c, off); // Vy Vz Nx Ny
    uvec4 w2 = window4(c, d, off); // Nz material Tx Ty
    Row r;
    r.l_bits = w0.xyz;
    r.v_bits = uvec3(w0.w, w1.xy);
    r.n_bits = uvec3(w1.zw, w2.x);
    r.material = uintBitsToFloat(w2.y);
    r.t_bits = uvec3(w2.zw, window4(d, d, off).x); // Tz = d[off]
    r.l = input_vector(r.l_bits);
    r.v = input_vector(r.v_bits);
    r.n = input_vector(r.n_bits);
    r.t = input_vector(r.t_bits);
    return r;
}
#else
// The rows of 10 columns as word pairs (row i is pairs 5i to 5i + 4: 10 i words is even),
// over the same bytes as the texels. On lavapipe every load a lane makes from a buffer is
// a loop over the SIMD lanes with a bounds test each, and a texelFetch a call into the
// driver's texel function: five pairs (10 words, no window to select) measured faster
// than three texels (4M tuples, lambert 97 -> 106 M/s as a table kernel and 132 -> 136
// folded; docs/VULKAN.md); 13-column rows, whose start is not always even, keep the texels.
layout(std430, set = 0, binding = BINDING_TUPLES) readonly buffer TuplePairs {
    uvec2 tuple_pairs[];
};

// Row `row` of 10 columns: L, V, N and the material index.
Row load_row(uint row) {
    uint p = row * 5u;
    uvec2 p0 = tuple_pairs[p], p1 = tuple_pairs[p + 1u], p2 = tuple_pairs[p + 2u];
    uvec2 p3 = tuple_pairs[p + 3u], p4 = tuple_pairs[p + 4u];
    Row r;
    r.l_bits = uvec3(p0, p1.x);
    r.v_bits = uvec3(p1.y, p2);
    r.n_bits = uvec3(p3, p4.x);
    r.material = uintBitsToFloat(p4.y);
    r.t_bits = uvec3(0u);
    r.l = input_vector(r.l_bits);
    r.v = input_vector(r.v_bits);
    r.n = input_vector(r.n_bits);
    r.t = vec3(0.0);
    return r;
}
#endif

#if defined(GENERATE_HALF_DIFF) || defined(GENERATE_IMPORTANCE)
// The bits of a row made on the device (normal values: no subnormal to keep).
void set_bits(inout Row r) {
    r.l_bits = floatBitsToUint(r.l);
    r.v_bits = floatBitsToUint(r.v);
    r.n_bits = floatBitsToUint(r.n);
    r.t_bits = floatBitsToUint(r.t);
}
#endif

#if defined(HAS_FLOAT64)
// The exact value of the f32 with bits `b`, subnormals included: through the integer
// mantissa, since a device that flushes f32 subnormals may flush them in a float-to-double
// conversion too (the stress corpus's cosines of 1e-45 are subnormal components).
double exact64(uint b) {
    uint mag = b & 0x7fffffffu;
    double x = (mag >> 23) == 0u ? ldexp(double(mag), -149) : double(uintBitsToFloat(mag));
    return (b & 0x80000000u) != 0u ? -x : x;
}
#endif

#endif
