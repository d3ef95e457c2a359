// frame64.glsl — the frame's scalars in f64, on a device with shaderFloat64 (HAS_FLOAT64):
// cos_i, cos_o, h, cos_h, c, |n x h|^2 and the rest of FORMULAS.md §1 from the exact input
// values, each rounded once to f32 (flushed below FLT_MIN, as a GPU flushes). The f32
// frame of a device without f64 is frame32.glsl; make_frame (frame.glsl) calls one of them.

#ifndef VKBRDF_FRAME64_GLSL
#define VKBRDF_FRAME64_GLSL

#include "math.glsl"
#include "frame_fields.glsl"
#include "material.glsl"
#include "input.glsl"

#if defined(HAS_FLOAT64)

// An f64 value of the frame rounded to f32 as a GPU rounds it: a result below FLT_MIN
// after rounding, 0. GPUs flush f32 subnormals (NVIDIA does, in conversions and
// arithmetic; lavapipe does not), so the f32 copies of the frame's quantities are flushed
// on every device: the code that reads them (and falls back to the f64 ones where they
// vanish) then behaves on lavapipe as on a GPU, and the stress corpus tests it here (its
// cosines of 1e-45 made 0.1 M non-finite outputs on an H200 before). The test is on the
// rounded f32, as a flushing conversion makes it (and in f32, cheaper than in f64).
float f32_of(double x) {
    float y = float(x);
    return abs(y) < FLT_MIN ? 0.0 : y;
}
vec2 f32_of(dvec2 x) {
    return vec2(f32_of(x.x), f32_of(x.y));
}
vec3 f32_of(dvec3 x) {
    return vec3(f32_of(x.x), f32_of(x.y), f32_of(x.z));
}

// 1/sqrt(q) for f64 q > 0 (here 1e-90 <= q <= 4e77: squared lengths of f32 vectors) to
// within a few f64 ulps, without an f64 division or square root (each a long sequence
// of instructions on GPUs, and among llvmpipe's slowest vector operations). q = f 2^e with e even and f
// in [0.5, 2) (exact); float32's inversesqrt of f, within 2 ulp (the Vulkan precision
// table) plus f's rounding, so a relative error e0 <= 3e-7; each Newton step
// y (3 - f y^2)/2 takes e to 1.5 e^2: 1.4e-13, then below f64's rounding (1.1e-16 per
// operation, a few in all): the frame's quantities, rounded once to f32 or read in f64
// by the tiny-cosine paths, are the correctly rounded quotients' to that.
double rsqrt64(double q) {
    // q = f 2^e. The common case (squared lengths of unit-scale vectors, |l + v|^2 of
    // non-mirror pairs) keeps e = 0: float(q) is a normal float32 there, and frexp and
    // ldexp on f64 cost more than the Newton steps on llvmpipe.
    double f = q;
    int e = 0;
    if (!(q >= 1e-30 && q <= 1e30)) {
        f = frexp(q, e); // f in [0.5, 1)
        if ((e & 1) != 0) {
            f *= 2.0;
            e -= 1;
        }
    }
    double y = double(inversesqrt(float(f)));
    y *= 1.5 - 0.5 * f * y * y;
    y *= 1.5 - 0.5 * f * y * y;
    return e == 0 ? y : ldexp(y, -e / 2);
}

// a/|a| in f64 from an input vector's f32 bits (finite and non-zero: checked before).
// Where no component is subnormal, double(float) is exact and exact64's integer path (a
// device may flush a subnormal in the conversion) is skipped: one test of the three.
dvec3 unit64(uvec3 b) {
    // Subnormal: 1 <= magnitude bits <= 0x7fffff (0 wraps around to the largest uint).
    dvec3 d = dvec3(uintBitsToFloat(b));
    if (any(lessThan((b & 0x7fffffffu) - 1u, uvec3(0x007fffffu)))) {
        d = dvec3(exact64(b.x), exact64(b.y), exact64(b.z));
    }
    return d * rsqrt64(dot(d, d));
}

// The cosines into f, and the horizon test on the f64 cosines, as the reference decides
// it: a cosine below 7e-46 rounds to 0 in f32, and testing the f32 value put such tuples
// below the horizon while the reference evaluates them (FORMULAS.md §1: every
// representable cosine). True when both are above the horizon.
bool cosines_f64(double cos_i, double cos_o, inout Frame f) {
    f.cos_i = f32_of(cos_i);
    f.cos_o = f32_of(cos_o);
    f.cos_i_exact = cos_i;
    f.cos_o_exact = cos_o;
    return !(cos_i <= 0.0 || cos_o <= 0.0);
}

// h = normalize(l + v), cos_h and c into f, from unit l, v above the horizon (|l + v| >=
// cos_i + cos_o > 0, so h is well defined); returns h. cos_h = (cos_i + cos_o)/|l + v| and
// c = |l + v|/2: see frame32.glsl.
dvec3 half_vector_f64(dvec3 dl, dvec3 dv, double cos_i, double cos_o, inout Frame f) {
    dvec3 lv = dl + dv;
    double q = dot(lv, lv);
    double inv_len = rsqrt64(q);
    dvec3 h = lv * inv_len;
    f.h = f32_of(h);
    f.cos_h_exact = (cos_i + cos_o) * inv_len;
    double len = q * inv_len;
    f.cos_h = f32_of(f.cos_h_exact);
    f.c = f32_of(0.5 * len);
    f.c_exact = 0.5 * len;
    return h;
}

#if defined(HAS_PHONG)
// Phong's r.v and |r x v|^2 into f, for the mirror direction r of l.
void phong_f64(dvec3 rr, dvec3 dv, inout Frame f) {
    dvec3 rxv = cross(rr, dv);
    f.rv = f32_of(dot(rr, dv));
    f.sin2_rv = f32_of(dot(rxv, rxv));
}
#endif

// frame_scalars_f64 for n = +z exactly: the same scalars (to f64's rounding before their
// one rounding to f32) without N's normalisation and the products with n, which reduce to
// components: cos_i = l.z, |n x l|^2 = l.x^2 + l.y^2, |n x h|^2 = h.x^2 + h.y^2, and
// Phong's r = 2 cos_i n - l = (-l.x, -l.y, l.z).
uint frame_scalars_f64_local(Row r, GpuMaterial m, inout Frame f) {
    dvec3 dl = unit64(r.l_bits), dv = unit64(r.v_bits);
    if (!cosines_f64(dl.z, dv.z, f)) {
        return STATUS_BELOW_HORIZON;
    }
    dvec3 h = half_vector_f64(dl, dv, dl.z, dv.z, f);
    f.sin2_h = f32_of(dot(h.xy, h.xy));
#if defined(HAS_G_SMITH) || defined(HAS_G_SMITH_CORRELATED) || defined(HAS_G_SMITH_FAST) \
    || defined(HAS_G_SCHLICK_SMITH) || defined(HAS_HTSG)
    f.sin2_i = f32_of(dot(dl.xy, dl.xy));
    f.sin2_o = f32_of(dot(dv.xy, dv.xy));
#endif
#if defined(HAS_PHONG)
    if (material_model(m) == MODEL_PHONG) {
        phong_f64(dvec3(-dl.xy, dl.z), dv, f);
    }
#endif
    return STATUS_VALID;
}

// The scalars of the frame for a tuple whose l, v, n (and tangent) make_frame has found
// valid, and the horizon test: STATUS_VALID or STATUS_BELOW_HORIZON.
uint frame_scalars_f64(Row r, GpuMaterial m, inout Frame f) {
    // The frame's scalars in f64 from the raw f32 inputs (the products of f32 values are
    // exact in f64; squares of f32 values, <= 1.2e77, and of subnormals stay in range):
    // - cos_i, cos_o with full f32 relative precision even at grazing angles. In f32,
    //   normalising l and n first leaves each cosine ~1e-7 off in absolute terms: K =
    //   1/(4 cos_i cos_o) is then wrong by O(1) below cos ~1e-6 and the horizon test falls
    //   on the wrong side (the stress corpus's grazing regime).
    // - h, |l + v|, cos_h, c and |n x h|^2: in f32, l + v of two rounded unit vectors
    //   carries ~u absolute error, which near l = -v (grazing mirror geometry) is a relative
    //   error of u/|l + v| in |l + v| and in h's direction: ggx_d, which reads
    //   cos_h^2 + slope2 rather than a logarithm, was 1e-4 off at |l + v| = 2e-3 even at
    //   m = 1, where D is constant (found by tests/vulkan_properties.rs).
    // Cost on lavapipe: 1.1-1.35x the time of a kernel with an unguarded f32 frame
    // (examples/kernel_time.rs, folded materials; docs/VULKAN.md).
    dvec3 dn = unit64(r.n_bits), dl = unit64(r.l_bits), dv = unit64(r.v_bits);
    double cos_i = dot(dn, dl), cos_o = dot(dn, dv);
    if (!cosines_f64(cos_i, cos_o, f)) {
        return STATUS_BELOW_HORIZON;
    }
    dvec3 h = half_vector_f64(dl, dv, cos_i, cos_o, f);
    dvec3 nxh = cross(dn, h);
    f.sin2_h = f32_of(dot(nxh, nxh));
#if defined(HAS_ANISOTROPIC) && defined(HAS_TANGENTS)
    if (is_anisotropic(m)) {
        // h in the tangent frame, built in f64 as in frame32.glsl: with roughness ratios
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
    || defined(HAS_G_SCHLICK_SMITH) || defined(HAS_HTSG)
    dvec3 nxl = cross(dn, dl), nxv = cross(dn, dv); // Smith's tan^2, Schlick-Smith's 1 - cos
    f.sin2_i = f32_of(dot(nxl, nxl));
    f.sin2_o = f32_of(dot(nxv, nxv));
#endif
#if defined(HAS_PHONG)
    if (material_model(m) == MODEL_PHONG) {
        phong_f64(2.0 * cos_i * dn - dl, dv, f);
    }
#endif
    return STATUS_VALID;
}
#endif

#endif
