// bindings.glsl — the kernel's interface: its buffers and push constants. Binding numbers
// come from src/gpu/layout.rs (BINDING_*, injected as macros); the structs there mirror
// Counts (GpuCounts) and Params (PushConstants) field for field. The measured tables'
// binding (BINDING_MERL) is declared in measured.glsl, with the code that reads it.

#ifndef VKBRDF_BINDINGS_GLSL
#define VKBRDF_BINDINGS_GLSL

#include "layout.glsl"

// Rows `Lx Ly Lz Vx Vy Vz Nx Ny Nz material [Tx Ty Tz]` (src/batch.rs), row-major f32,
// read with tangents (13 columns) as RGBA32F texels of a uniform texel buffer over the
// same bytes, whose 4-word fetches cost on lavapipe about what one scalar storage-buffer
// load does (bounds check and address per lane): 4 fetches instead of 13 loads per row
// (measured: src/gpu/mod.rs, "Input"); without (10 columns) as five word pairs of the
// storage buffer BINDING_TUPLES (input.glsl).
// textureBuffer, not samplerBuffer: a sampled image of Dim Buffer draws a SPIR-V warning
// from the validation layer, and texelFetch needs no sampler.
// Read as RGBA32UI, the bits themselves: see input_vector.
layout(set = 0, binding = BINDING_TUPLE_TEXELS) uniform utextureBuffer tuple_texels;
layout(std430, set = 0, binding = BINDING_MATERIALS) readonly buffer Materials {
    GpuMaterial materials[];
};
// The batch's one material as specialization constants 1-29 (src/gpu/kernel.rs,
// `SpecializedMaterial`): set by the host only for a large single-material batch, so that
// the compiler folds the material's constants into the code (the conductor's complex
// arithmetic, the terms' dispatch, the material's loads) as a kernel written for that
// material would. Without them (MATERIAL_IS_CONSTANT false) the table is read.
layout(constant_id = 1) const bool MATERIAL_IS_CONSTANT = false;
layout(constant_id = 2) const float MATERIAL_DIFFUSE_X = 0.0;
layout(constant_id = 3) const float MATERIAL_DIFFUSE_Y = 0.0;
layout(constant_id = 4) const float MATERIAL_DIFFUSE_Z = 0.0;
layout(constant_id = 5) const float MATERIAL_DIFFUSE_W = 0.0;
layout(constant_id = 6) const float MATERIAL_SPECULAR_X = 0.0;
layout(constant_id = 7) const float MATERIAL_SPECULAR_Y = 0.0;
layout(constant_id = 8) const float MATERIAL_SPECULAR_Z = 0.0;
layout(constant_id = 9) const float MATERIAL_SPECULAR_W = 0.0;
layout(constant_id = 10) const float MATERIAL_FRESNEL0_X = 0.0;
layout(constant_id = 11) const float MATERIAL_FRESNEL0_Y = 0.0;
layout(constant_id = 12) const float MATERIAL_FRESNEL0_Z = 0.0;
layout(constant_id = 13) const float MATERIAL_FRESNEL0_W = 0.0;
layout(constant_id = 14) const float MATERIAL_FRESNEL1_X = 0.0;
layout(constant_id = 15) const float MATERIAL_FRESNEL1_Y = 0.0;
layout(constant_id = 16) const float MATERIAL_FRESNEL1_Z = 0.0;
layout(constant_id = 17) const float MATERIAL_FRESNEL1_W = 0.0;
layout(constant_id = 18) const float MATERIAL_LOBE_X = 0.0;
layout(constant_id = 19) const float MATERIAL_LOBE_Y = 0.0;
layout(constant_id = 20) const float MATERIAL_LOBE_Z = 0.0;
layout(constant_id = 21) const float MATERIAL_LOBE_W = 0.0;
layout(constant_id = 22) const float MATERIAL_SCALE_X = 0.0;
layout(constant_id = 23) const float MATERIAL_SCALE_Y = 0.0;
layout(constant_id = 24) const float MATERIAL_SCALE_Z = 0.0;
layout(constant_id = 25) const float MATERIAL_SCALE_W = 0.0;
layout(constant_id = 26) const uint MATERIAL_KIND_X = 0u;
layout(constant_id = 27) const uint MATERIAL_KIND_Y = 0u;
layout(constant_id = 28) const uint MATERIAL_KIND_Z = 0u;
layout(constant_id = 29) const uint MATERIAL_KIND_W = 0u;

// Rows an invocation of a folded kernel built with MULTI_ROW evaluates, 1-4
// (VulkanOptions::folded_tuples_per_invocation, src/gpu/evaluator/options.rs): rows
// `row`, `row + stride`, … with stride = ceil(tuple_count / TUPLES_PER_INVOCATION), so
// neighbouring invocations still read neighbouring rows.
layout(constant_id = 30) const uint TUPLES_PER_INVOCATION = 1u;

// Material mi of the batch's table, or the constant one (see above).
GpuMaterial material_at(uint mi) {
    if (MATERIAL_IS_CONSTANT) {
        return GpuMaterial(
        vec4(MATERIAL_DIFFUSE_X, MATERIAL_DIFFUSE_Y, MATERIAL_DIFFUSE_Z, MATERIAL_DIFFUSE_W),
        vec4(MATERIAL_SPECULAR_X, MATERIAL_SPECULAR_Y, MATERIAL_SPECULAR_Z, MATERIAL_SPECULAR_W),
        vec4(MATERIAL_FRESNEL0_X, MATERIAL_FRESNEL0_Y, MATERIAL_FRESNEL0_Z, MATERIAL_FRESNEL0_W),
        vec4(MATERIAL_FRESNEL1_X, MATERIAL_FRESNEL1_Y, MATERIAL_FRESNEL1_Z, MATERIAL_FRESNEL1_W),
        vec4(MATERIAL_LOBE_X, MATERIAL_LOBE_Y, MATERIAL_LOBE_Z, MATERIAL_LOBE_W),
        vec4(MATERIAL_SCALE_X, MATERIAL_SCALE_Y, MATERIAL_SCALE_Z, MATERIAL_SCALE_W),
        uvec4(MATERIAL_KIND_X, MATERIAL_KIND_Y, MATERIAL_KIND_Z, MATERIAL_KIND_W));
    }
    return materials[mi];
}

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

#endif
