// frame_local32.glsl — the local f32 frame: a GGX Cook-Torrance lane with N = +z evaluated
// from f32 l and v where D's certificate holds (terms.glsl, ggx_local_frame_ok), on every
// device: the scales of l, v and h come from exact squared lengths, in f64 where the
// device has it and as float-float pairs (ff.glsl) where it does not. make_frame
// (frame.glsl) calls it before the f64 or f32 frame, which takes every lane it does not
// certify. The bound of each quantity: docs/VULKAN.md, "The local frames (N = +z)".

#ifndef VKBRDF_FRAME_LOCAL32_GLSL
#define VKBRDF_FRAME_LOCAL32_GLSL

#include "math.glsl"
#include "ff.glsl"
#include "frame_fields.glsl"
#include "material.glsl"
#include "input.glsl"
#include "terms.glsl"

// A local frame's answer for a lane it leaves to the device's accurate frame (this
// file's, uncertified; frame_local_h64.glsl's, outside its limits).
const uint STATUS_UNCERTIFIED = 3u;

// Below this c a lane leaves the local frames: the f32 one's c is within about u (5 + 1/c)
// (docs/VULKAN.md), at most 21u here, which Cook-Torrance's G and the Fresnel terms read
// with a log-slope of about 1.
const float LOCAL32_MIN_C = 0.0625;
// Below this cos_i, cos_o or cos_h, too: the CPU engine's GRAZING (src/cpu/frame.rs),
// where the models' 1/cos factors stay far inside f32's range and the TINY_COS branches,
// which read the exact cosines, are never taken.
const float LOCAL32_MIN_COS = 1e-4;

// The fields a local frame (this one or frame_local_h64.glsl's) shares from its unit f32
// l and v, with cos_h and c already in f: the cosines, the sines as sums of squares of
// components, and the exact fields the models read only below TINY_COS (never on these
// frames' lanes).
void local_frame_cosines(vec3 l, vec3 v, inout Frame f) {
    f.cos_i = l.z;
    f.cos_o = v.z;
    f.sin2_i = dot(l.xy, l.xy);
    f.sin2_o = dot(v.xy, v.xy);
#if defined(HAS_FLOAT64)
    f.cos_i_exact = double(l.z);
    f.cos_o_exact = double(v.z);
    f.cos_h_exact = double(f.cos_h);
    f.c_exact = double(f.c);
#else
    f.cos_i_xf = xf(l.z);
    f.cos_o_xf = xf(v.z);
    f.cos_h_xf = xf(f.cos_h);
    f.c_xf = xf(f.c);
    f.c_exact = vec2(f.c, 0.0);
#endif
}

#if defined(HAS_COOK_TORRANCE) && defined(HAS_D_GGX) && !defined(NO_LOCAL_FRAME) \
    && !defined(NO_LOCAL32_FRAME)
#define HAS_LOCAL32_FRAME

#if defined(HAS_FLOAT64)
// 1/sqrt(q), q = x.x the squared length of an f32 vector (or of l + v), to within
// u (1 + 1e-6) after its one rounding: q in f64 (exact products, sums to f64's rounding),
// float32's inversesqrt (within 2 ulp, Vulkan's precision table, plus the argument's
// rounding: e <= 5u) and one Newton step in f64 (1.5 e^2 < 2e-13). Outside
// [1e-20, 1e20], 0: the cosine tests then send the lane to the f64 frame. q rounded once
// is returned in length2. `direction`: x is an input direction (L or V), whose squared length
// is near 1 when it was normalised: rsqrt64_input's cubic there, within the same bound.
float inv_length_local32(vec3 x, bool direction, out float length2) {
    dvec3 d = dvec3(x);
    double q = dot(d, d);
    length2 = float(q);
    if (!(q >= 1e-20 && q <= 1e20)) {
        return 0.0;
    }
    return float(direction ? rsqrt64_input(q) : rsqrt64_once(q));
}
#else
// x.x as a pair (hi, lo) to ~2^-36 relative, without f64: each square exact as three
// floats through Veltkamp's split (xh^2, 2 xh xl, xl^2, each product of 12-bit halves
// exact), the large parts added by two-sum, the rest in f32 (their roundings are 2^-12
// and 2^-24 of the sum smaller still).
vec2 length2_local32(vec3 x) {
    vec2 a = split(x.x), b = split(x.y), c = split(x.z);
    precise float a2 = a.x * a.x, b2 = b.x * b.x, c2 = c.x * c.x;
    vec2 s = two_sum(a2, b2);
    vec2 t = two_sum(s.x, c2);
    precise float mid = 2.0 * ((a.x * a.y + b.x * b.y) + c.x * c.y);
    precise float small = (a.y * a.y + b.y * b.y) + c.y * c.y;
    precise float lo = ((s.y + t.y) + mid) + small;
    return fast_two_sum(t.x, lo);
}

// inv_length_local32 of the f64 branch without f64 (inputs or not, the same float-float
// scale): float32's inversesqrt (e <= 5u) and one Newton step y (1 + r/2) whose
// residual r = 1 - q y^2 is formed from the exact pair
// y^2 and the pair q (1 - t.x is exact, t.x being within 1e-5 of 1); the step's last
// addition is the one rounding left: within u (1 + 1e-6). q's high part (within u) is
// returned in length2.
float inv_length_local32(vec3 x, bool direction, out float length2) {
    vec2 q = length2_local32(x);
    length2 = q.x;
    if (!(q.x >= 1e-20 && q.x <= 1e20)) {
        return 0.0;
    }
    float y = inversesqrt(q.x);
    vec2 t = ff_mul(q, two_prod(y, y));
    precise float r = (1.0 - t.x) - t.y;
    precise float y1 = y + y * (0.5 * r);
    return y1;
}
#endif

// Whether material m's lanes may take the local f32 frame: GGX Cook-Torrance, and not the
// dielectric Fresnel term, which reads the exact c near total internal reflection.
bool local32_material(GpuMaterial m) {
    return material_model(m) == MODEL_COOK_TORRANCE && material_distribution(m) == DIST_GGX
        && material_fresnel(m) != FRESNEL_DIELECTRIC;
}

// The frame of a lane of a local32_material with N = +z, in f32, where D's certificate
// and the cosine tests pass; else STATUS_UNCERTIFIED. l and v are the inputs times their
// scales (inv_length_local32), so h = l + v turns by at most u (2/c + 1) radians from the
// exact h; h's scale comes from its exact squared length the same way: cos_h within 2u,
// |n x h|^2 within 6u, c within u (5 + 1/c) of the exact ones, beyond the turn.
uint frame_scalars_local32(Row r, GpuMaterial m, inout Frame f) {
    float ql, qv, qh;
    vec3 l = r.l * inv_length_local32(r.l, true, ql), v = r.v * inv_length_local32(r.v, true, qv);
    // `>=` is false for NaN: no such lane passes.
    if (!(l.z >= LOCAL32_MIN_COS && v.z >= LOCAL32_MIN_COS)) {
        return STATUS_UNCERTIFIED;
    }
    vec3 h = l + v;
    float inv_len = inv_length_local32(h, false, qh);
    f.cos_h = h.z * inv_len;
    f.sin2_h = dot(h.xy, h.xy) * (inv_len * inv_len);
    f.c = 0.5 * (qh * inv_len);
    if (!(f.cos_h >= LOCAL32_MIN_COS && f.c >= LOCAL32_MIN_C
          && ggx_local_frame_ok(f.cos_h, f.sin2_h, f.c, material_roughness2(m).x))) {
        return STATUS_UNCERTIFIED;
    }
    f.h = h * inv_len;
    // make_frame calls this before its normalisations: the unit vectors from here (no
    // model on this frame reads them; set so that no field is left undefined).
    f.l = l;
    f.v = v;
    f.n = vec3(0.0, 0.0, 1.0);
    local_frame_cosines(l, v, f);
    return STATUS_VALID;
}
#endif

#endif
