#version 450
// eval.comp — the BRDF kernel's entry: one invocation per tuple of one chunk (or, for the
// tables' integrals, per block of samples). Each idea lives in its own file, and each file
// includes what it uses (tests/glsl_includes.rs); the ones this entry calls:
//   bindings.glsl     the buffers and push constants
//   input.glsl        a row read from its texels (the f32 bits), input_vector, exact64
//   generators.glsl   rows and half vectors made on the device (slice, importance sampling)
//   frame.glsl        the frame of FORMULAS.md §1 (its fields in frame_fields.glsl) and its
//                     classification (frame64.glsl or frame32.glsl for the scalars)
//   measured.glsl     MERL lookups
//   integrators.glsl  the albedo/DFG sums
//   counts.glsl       invalid, below-horizon and saturated counts
// and evaluate.glsl (the model dispatch over models.glsl / terms.glsl, §2-§6, and
// htsg.glsl) with material.glsl's accessors of GpuMaterial.
//
// Compiled once per FeatureSet (src/gpu/kernel.rs): the HAS_* / WRITE_TERMS macros decide
// which models, terms and outputs exist at all. Also injected from Rust (said once there):
// the MODEL_* / DIST_* / GEOM_* / FRESNEL_* / CONV_* / FLAG_* codes, the BINDING_* numbers,
// USE_SUBGROUP_ARITHMETIC when the device can reduce counts across a subgroup, and on CPU
// devices ROW_FROM_SUBGROUP (main) and F64_ROOTS (math.glsl's rsqrt64_once). The workgroup size is specialization constant 0.

#extension GL_EXT_samplerless_texture_functions : require

#if defined(USE_SUBGROUP_ARITHMETIC) || defined(ROW_FROM_SUBGROUP)
#extension GL_KHR_shader_subgroup_basic : require
#endif
#if defined(USE_SUBGROUP_ARITHMETIC)
#extension GL_KHR_shader_subgroup_arithmetic : require
#endif

#include "layout.glsl"
#include "evaluate.glsl"

layout(local_size_x_id = 0) in;

#include "bindings.glsl"
#include "input.glsl"
#include "generators.glsl"
#include "frame.glsl"

#if defined(HAS_MEASURED)
#include "measured.glsl"
#endif

#include "integrators.glsl"
#include "counts.glsl"

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
    GpuMaterial m = material_at(mi);
    Frame f;
    uint status = make_frame(r, m, f);
    Eval e = status == STATUS_VALID ? evaluate(f, m) : eval_zero();
#if defined(HAS_MEASURED)
    if (status == STATUS_VALID && material_model(m) == MODEL_MEASURED) {
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

    // Counts, only where there is something to count (see count_tuple).
    if (status != STATUS_VALID || saturated) {
        count_tuple(row, status);
    }
}

void main() {
#if defined(ROW_FROM_SUBGROUP)
    // On a CPU device (src/gpu/kernel.rs, row_from_subgroup): the same rows, numbered by
    // full subgroups, without llvmpipe's division a lane for gl_GlobalInvocationID
    // (lavapipe, 4M tuples folded: mitsuba-ggx 83.5 -> 89.4 M/s, docs/VULKAN.md).
    uint row = gl_WorkGroupID.x * gl_WorkGroupSize.x + gl_SubgroupID * gl_SubgroupSize
        + gl_SubgroupInvocationID;
#else
    uint row = gl_GlobalInvocationID.x;
#endif
    // Out-of-range invocations of the last workgroup simply stop: the counts' subgroup
    // operations reduce over the invocations still active.
#if defined(GENERATE_IMPORTANCE)
    if (row < params.tuple_count) {
        importance_block(params.first_row + row);
    }
#elif defined(MULTI_ROW)
    // TUPLES_PER_INVOCATION rows, `stride` apart (the host dispatches `stride`
    // invocations): on llvmpipe, where an invocation is a SIMD lane, an invocation's
    // fixed cost is paid once for several rows and the rows' independent chains of roots
    // and divisions interleave. Written out, not as a loop: a loop over the same rows
    // gained nothing. Only the folded kernels are built with MULTI_ROW (src/gpu/kernel.rs):
    // in every kernel the four calls cost each pipeline creation the inlining of four
    // copies, even with the constant at 1 (a warm 1,000-tuple `eval` 0.07 -> 0.12 s).
    uint n = params.tuple_count;
    uint stride = (n + TUPLES_PER_INVOCATION - 1u) / TUPLES_PER_INVOCATION;
    if (row < stride) {
        evaluate_row(row);
        if (TUPLES_PER_INVOCATION > 1u && row + stride < n) {
            evaluate_row(row + stride);
        }
        if (TUPLES_PER_INVOCATION > 2u && row + 2u * stride < n) {
            evaluate_row(row + 2u * stride);
        }
        if (TUPLES_PER_INVOCATION > 3u && row + 3u * stride < n) {
            evaluate_row(row + 3u * stride);
        }
    }
#else
    if (row < params.tuple_count) {
        evaluate_row(row);
    }
#endif
}
