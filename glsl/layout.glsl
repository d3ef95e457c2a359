// layout.glsl — the GPU-side data structures, mirrored field for field by src/gpu/layout.rs.
//
// Every member is a vec4 or uvec4, so std430 and Rust's #[repr(C)] agree without padding
// rules (a vec3 would be 16-byte aligned in std430 but 12 bytes in Rust). The Rust side has
// compile-time size/offset asserts; tests/conformance.rs (`gpu_material_layout_round_trips`)
// has a kernel copy every field back to the host, so the two cannot drift apart silently.
//
// The integer codes (MODEL_*, DIST_*, GEOM_*, FRESNEL_*, CONV_*, FLAG_*) and the binding
// numbers (BINDING_*) are not typed here: src/gpu/kernel.rs injects them as macros from the
// Rust constants in src/gpu/layout.rs, so they exist once.

#ifndef VKBRDF_LAYOUT_GLSL
#define VKBRDF_LAYOUT_GLSL

// One material, converted from a validated `Material` on the host (gpu_materials()), with
// every per-material constant precomputed in f64 and rounded once.
struct GpuMaterial {
    // rgb: the whole diffuse term, d * c_diff / pi (d = 1 outside cook-torrance). a: 0.
    vec4 diffuse;
    // rgb: s * c_spec (s = 1 outside cook-torrance; htsg: T = 2 pi tau / lambda per
    // channel, glsl/htsg.glsl). a: 0.
    vec4 specular;
    // rgb: dielectric mu^2 - 1 (formed in f64: it cancels for mu near 1) | conductor n |
    // schlick F0. a: 0.
    vec4 fresnel0;
    // rgb: conductor extinction k. a: 0.
    vec4 fresnel1;
    // Lobe shape. Roughness-based lobes (beckmann, ggx, ward, gaussian):
    // x = 1/mx^2, y = 1/my^2 (gaussian: x = y = 1/m^2), z = mx^2, w = my^2 (Smith's Lambda).
    // Exponent-based lobes (phong, blinn-phong, rtr, blinn D): x = exponent e.
    vec4 lobe;
    // x: the lobe's normalisation constant (beckmann 1/(k mx my), ggx 1/(pi mx my),
    // ward 1/(4 pi mx my), blinn and phong (e+2)/(2 pi), rtr (e+8)/(8 pi), blinn-phong 1/pi,
    // gaussian 1). yzw: conductor Fresnel n^2 - k^2 - 1 per channel, formed in f64 (it
    // cancels in f32 for eta near 1); dielectric: the f32 rounding error of fresnel0.rgb
    // (mu^2 - 1 = fresnel0 + this, to ~48 bits); 0 otherwise.
    vec4 scale;
    // x: MODEL_*, y: DIST_*, z: GEOM_*, w: FRESNEL_* | CONV_* << 8 | FLAG_ANISOTROPIC |
    // FLAG_METAL_FORM.
    uvec4 kind;
};

#endif
