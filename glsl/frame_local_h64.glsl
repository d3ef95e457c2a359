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
#include "frame_local32.glsl"

#if defined(HAS_FLOAT64) && defined(HAS_COOK_TORRANCE) && defined(HAS_D_BECKMANN) \
    && !defined(NO_LOCAL_FRAME) && !defined(NO_LOCAL_H64_FRAME)
#define HAS_LOCAL_H64_FRAME

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
// with a cosine below LOCAL32_MIN_COS or c below LOCAL32_MIN_C (where the models read the
// exact f64 values, or grazing mirror geometry), or lengths beyond [1e-10, 1e10], get
// STATUS_UNCERTIFIED and take the f64 local frame.
uint frame_scalars_local_h64(Row r, GpuMaterial m, inout Frame f) {
    dvec3 dl = dvec3(r.l), dv = dvec3(r.v); // exact: r.l, r.v are normal (input_vector)
    double ql = dot(dl, dl), qv = dot(dv, dv);
    // `>=` is false for NaN: no such lane passes.
    if (!(ql >= 1e-20 && ql <= 1e20 && qv >= 1e-20 && qv <= 1e20)) {
        return STATUS_UNCERTIFIED;
    }
    double sl = rsqrt64_input(ql), sv = rsqrt64_input(qv);
    vec3 l = r.l * float(sl), v = r.v * float(sv);
    if (!(l.z >= LOCAL32_MIN_COS && v.z >= LOCAL32_MIN_COS)) {
        return STATUS_UNCERTIFIED;
    }
    dvec3 h = dl * sl + dv * sv;
    double qh = dot(h, h);
    double sh = rsqrt64_once(qh);
    f.cos_h = float(h.z * sh);
    f.c = float(0.5 * (qh * sh));
    if (!(f.cos_h >= LOCAL32_MIN_COS && f.c >= LOCAL32_MIN_C)) {
        return STATUS_UNCERTIFIED;
    }
    f.sin2_h = float(dot(h.xy, h.xy) * (sh * sh));
    f.h = vec3(h * sh);
    // make_frame calls this before its normalisations (see frame_scalars_local32).
    f.l = l;
    f.v = v;
    f.n = vec3(0.0, 0.0, 1.0);
    local_frame_cosines(l, v, f);
    return STATUS_VALID;
}
#endif

#endif
