// frame.glsl — the frame of FORMULAS.md §1 for one tuple, and its classification: the
// validity tests (lengths, the tangent), then the scalars the models read, from
// frame64.glsl on a device with f64 or frame32.glsl without.

#ifndef VKBRDF_FRAME_GLSL
#define VKBRDF_FRAME_GLSL

#include "math.glsl"
#include "frame_fields.glsl"
#include "material.glsl"
#include "input.glsl"
#include "frame64.glsl"
#include "frame32.glsl"
#include "frame_local32.glsl"
#include "frame_local_h64.glsl"

// Builds the frame of FORMULAS.md §1 and classifies the tuple. The invalid test comes first,
// but for the lanes a local frame takes (valid by that frame's own tests, below).
uint make_frame(Row r, GpuMaterial m, out Frame f) {
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
    // Rows with N exactly +z (the local shading frame, and the rows the slices and tables
    // generate) take a local frame (docs/VULKAN.md, "The local frames"): GGX's lanes the
    // f32 one where D's slope certifies it (frame_local32.glsl), Beckmann's, with f64, the
    // one with h in f64 and l, v in f32 (frame_local_h64.glsl). Both come before the
    // general normalisations: a lane either takes has L and V finite and nonzero (their
    // squared lengths within [1e-20, 1e20], the cosines at least 1e-4), so it is valid,
    // and it reads none of the normalised l, v, n; every other lane (invalid ones among
    // them) goes on below as before. Anisotropic materials keep the general frame, whose
    // tangent frame needs n.
    bool local = r.n_bits == LOCAL_N_BITS;
#if defined(HAS_ANISOTROPIC)
    local = local && !is_anisotropic(m);
#endif
#if defined(HAS_LOCAL32_FRAME)
    if (local && local32_material(m)) {
        uint status = frame_scalars_local32(r, m, f);
        if (status != STATUS_UNCERTIFIED) {
            return status;
        }
    }
#endif
#if defined(HAS_LOCAL_H64_FRAME)
    if (local && local_h64_material(m)) {
        uint status = frame_scalars_local_h64(r, m, f);
        if (status != STATUS_UNCERTIFIED) {
            return status;
        }
    }
#endif
    bool ok_l, ok_v, ok_n;
    f.l = safe_normalize(r.l, ok_l);
    f.v = safe_normalize(r.v, ok_v);
    f.n = safe_normalize(r.n, ok_n);
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
        // Without f64: in frame_scalars_f32 (frame32.glsl), from N x T exact to a pair.
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
    // The other lanes with N = +z, with f64: the f64 frame without N's normalisation and
    // the products with n (frame_scalars_f64_local), the same values, faster.
    // NO_LOCAL_FRAME, NO_LOCAL32_FRAME and NO_LOCAL_H64_FRAME (kernel_time variants) turn
    // the local frames off.
#if defined(HAS_FLOAT64)
#if !defined(NO_LOCAL_FRAME)
    if (local) {
        return frame_scalars_f64_local(r, m, f);
    }
#endif
    return frame_scalars_f64(r, m, f);
#else
    return frame_scalars_f32(r, m, f);
#endif
}

#endif
