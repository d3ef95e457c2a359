// frame_local_h64.glsl — the local frame of a Beckmann Cook-Torrance lane with N = +z on a
// device with f64: the scales of l and v and the half vector in f64, each value the models
// read rounded once, as the f64 local frame (frame64.glsl) forms them — but with one Newton
// step a scale instead of two, l and v themselves in f32, and no flush tests. Beckmann's D
// has no certificate for the f32 local frame (its slope grows without bound in the tails,
// docs/VULKAN.md), so this frame's bound holds on every lane without one: no lane of a
// subgroup leaves for another frame but the grazing ones. make_frame (frame.glsl) calls it
// before the f64 local frame, which takes the lanes it leaves. The bound of each
// quantity: docs/VULKAN.md, "The local frames (N = +z)".

#ifndef VKBRDF_FRAME_LOCAL_H64_GLSL
#define VKBRDF_FRAME_LOCAL_H64_GLSL

#include "math.glsl"
#include "frame_fields.glsl"
#include "material.glsl"
#include "input.glsl"

#if defined(HAS_FLOAT64) && defined(HAS_COOK_TORRANCE) && defined(HAS_D_BECKMANN) \
    && !defined(NO_LOCAL_FRAME) && !defined(NO_LOCAL_H64_FRAME)
#define HAS_LOCAL_H64_FRAME

// frame_scalars_local_h64's answer for a lane it leaves to the f64 local frame.
const uint STATUS_NOT_LOCAL_H64 = 4u;

// Below these cosines (cos_i, cos_o, cos_h) and this c the lane takes the f64 local frame:
// the local f32 frame's limits (frame_local32.glsl), the CPU engine's GRAZING, where the
// models' 1/cos factors stay far inside f32's range and the TINY_COS branches, which read
// the f64 cosines, are never taken; and c >= 1/16, where h's f64 direction keeps the
// scales' 2e-13 below 4e-12 (tan theta_d <= 1/c).
const float LOCAL_H64_MIN_COS = 1e-4;
const float LOCAL_H64_MIN_C = 0.0625;

// 1/sqrt(q) for f64 q in [1e-20, 1e20] (squared lengths of inputs the caller has tested,
// and |l + v|^2, in [4e-8, 4] above the horizon, where |l + v| >= cos_i + cos_o):
// float32's inversesqrt of q's rounding (within 2 ulp, the Vulkan precision table, plus
// the argument's rounding: e <= 5u) and one Newton step in f64, which takes e to
// 1.5 e^2 < 2e-13. rsqrt64's second step (frame64.glsl) buys f64's last bits, which a
// value rounded once to f32 does not keep.
double rsqrt64_once(double q) {
    double y = double(inversesqrt(float(q)));
    return y * (1.5 - 0.5 * q * y * y);
}

// Whether material m's lanes with N = +z take this frame: Beckmann Cook-Torrance, and not
// the dielectric Fresnel term, which reads the exact c near total internal reflection.
bool local_h64_material(GpuMaterial m) {
    return material_model(m) == MODEL_COOK_TORRANCE && material_distribution(m) == DIST_BECKMANN
        && material_fresnel(m) != FRESNEL_DIELECTRIC;
}

// The frame of a lane of a local_h64_material with N = +z: h = L s_l + V s_v in f64 (the
// exact half vector's direction to ~1e-12, whatever c) and its scale, so that cos_h, c and
// |n x h|^2 are each within u/2 of the exact values, as on the f64 local frame; l = L s_l
// and v = V s_v in f32 (cos_i, cos_o within u, |n x l|^2 and |n x v|^2 within 3u). Lanes
// with a cosine below LOCAL_H64_MIN_COS or c below LOCAL_H64_MIN_C (where the models read the
// exact f64 values, or grazing mirror geometry), or lengths beyond [1e-10, 1e10], get
// STATUS_NOT_LOCAL_H64 and take the f64 local frame.
uint frame_scalars_local_h64(Row r, GpuMaterial m, inout Frame f) {
    dvec3 dl = dvec3(r.l), dv = dvec3(r.v); // exact: r.l, r.v are normal (input_vector)
    double ql = dot(dl, dl), qv = dot(dv, dv);
    // `>=` is false for NaN: no such lane passes.
    if (!(ql >= 1e-20 && ql <= 1e20 && qv >= 1e-20 && qv <= 1e20)) {
        return STATUS_NOT_LOCAL_H64;
    }
    double sl = rsqrt64_once(ql), sv = rsqrt64_once(qv);
    vec3 l = r.l * float(sl), v = r.v * float(sv);
    if (!(l.z >= LOCAL_H64_MIN_COS && v.z >= LOCAL_H64_MIN_COS)) {
        return STATUS_NOT_LOCAL_H64;
    }
    dvec3 h = dl * sl + dv * sv;
    double qh = dot(h, h);
    double sh = rsqrt64_once(qh);
    f.cos_h = float(h.z * sh);
    f.c = float(0.5 * (qh * sh));
    if (!(f.cos_h >= LOCAL_H64_MIN_COS && f.c >= LOCAL_H64_MIN_C)) {
        return STATUS_NOT_LOCAL_H64;
    }
    f.sin2_h = float(dot(h.xy, h.xy) * (sh * sh));
    f.h = vec3(h * sh);
    f.cos_i = l.z;
    f.cos_o = v.z;
    f.sin2_i = dot(l.xy, l.xy);
    f.sin2_o = dot(v.xy, v.xy);
    // The f64 fields the models read only below TINY_COS (never on this frame's lanes).
    f.cos_i_exact = double(l.z);
    f.cos_o_exact = double(v.z);
    f.cos_h_exact = double(f.cos_h);
    f.c_exact = double(f.c);
    return STATUS_VALID;
}
#endif

#endif
