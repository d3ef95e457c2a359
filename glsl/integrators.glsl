// integrators.glsl — the importance-sampled integrals of the albedo and split-sum DFG
// tables (GENERATE_IMPORTANCE): each invocation sums one block of samples whose directions
// generators.glsl makes, through the same frame and models as a tuple read from a batch.

#ifndef VKBRDF_INTEGRATORS_GLSL
#define VKBRDF_INTEGRATORS_GLSL

#include "math.glsl"
#include "bindings.glsl"
#include "input.glsl"
#include "generators.glsl"
#include "frame.glsl"
#include "evaluate.glsl"

#if defined(GENERATE_IMPORTANCE)
// The albedo and split-sum DFG tables (src/table/albedo.rs, which states the method and
// its accuracy): invocation g integrates SAMPLES_PER_BLOCK samples of one (mu, alpha)
// point, making each sample's l on the device, and writes the block's sums of
// x = f cos_i / pdf(l) and x (1 - c)^5; the host adds the blocks in f64. Push constants:
// grid_width = blocks per point, grid_height = samples per point N, spacing = lobe
// (0 GGX by its visible normals, 1 Beckmann by D cos_h). Per point, 4 texels of the input
// (the host's f64 sampling constants, rounded once): (v, G1(v)), (t1, s), (t2, alpha),
// (v_h, material).
const uint SAMPLES_PER_BLOCK = 256u;

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
        vec3 h = importance_half_vector(hammersley(k, n), ggx, t1.xyz, t2.xyz, t3.xyz, s, alpha);
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

#endif
