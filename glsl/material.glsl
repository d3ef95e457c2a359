// material.glsl — named reads of GpuMaterial's packed slots (layout.glsl), one accessor
// per meaning, as src/gpu/layout.rs (gpu_material) packs them. Code outside this file
// reads a material through these, so a slot's meaning is said here once.

#ifndef VKBRDF_MATERIAL_GLSL
#define VKBRDF_MATERIAL_GLSL

#include "layout.glsl"

// kind.x: the model (MODEL_*).
uint material_model(GpuMaterial m) {
    return m.kind.x;
}

// kind.y of a microfacet model: the distribution (DIST_*).
uint material_distribution(GpuMaterial m) {
    return m.kind.y;
}

// kind.z of a microfacet model: the geometry term (GEOM_*).
uint material_geometry(GpuMaterial m) {
    return m.kind.z;
}

// kind.w & 0xff: the Fresnel term (FRESNEL_*).
uint material_fresnel(GpuMaterial m) {
    return m.kind.w & 0xffu;
}

// (kind.w >> 8) & 0xff: the convention (CONV_*).
uint material_convention(GpuMaterial m) {
    return (m.kind.w >> 8) & 0xffu;
}

// kind.w & FLAG_METAL_FORM: the conductor takes F's metal form (conductor_f_metal).
bool material_metal_form(GpuMaterial m) {
    return (m.kind.w & FLAG_METAL_FORM) != 0u;
}

// kind.w & FLAG_ANISOTROPIC: the material reads the tangent frame.
bool is_anisotropic(GpuMaterial m) {
    return (m.kind.w & FLAG_ANISOTROPIC) != 0u;
}

// kind.y of a measured material: its table in the batch's MERL buffer.
uint material_merl_table(GpuMaterial m) {
    return m.kind.y;
}

// kind.z of a measured material: the lookup (LOOKUP_*).
uint material_merl_lookup(GpuMaterial m) {
    return m.kind.z;
}

// lobe.x of an exponent lobe (phong, blinn-phong, rtr, blinn D): e; charlie D: 1/m.
float material_exponent(GpuMaterial m) {
    return m.lobe.x;
}

// lobe.xy of a roughness lobe: 1/mx^2, 1/my^2 (gaussian: 1/m^2 in x).
vec2 material_inv_roughness2(GpuMaterial m) {
    return m.lobe.xy;
}

// lobe.zw of a roughness lobe: mx^2, my^2 (Smith's Lambda).
vec2 material_roughness2(GpuMaterial m) {
    return m.lobe.zw;
}

// lobe.w with GEOM_SCHLICK_SMITH (isotropic only, so my^2 is not needed): Schlick's k.
float material_schlick_k(GpuMaterial m) {
    return m.lobe.w;
}

// scale.x: the lobe's normalisation constant.
float material_norm(GpuMaterial m) {
    return m.scale.x;
}

// scale.yzw: conductor n^2 - k^2 - 1 per channel; dielectric the f32 rounding error of
// fresnel0.rgb (mu^2 - 1 = fresnel0 + this); 0 otherwise. Both formed in f64.
vec3 material_fresnel_lo(GpuMaterial m) {
    return m.scale.yzw;
}

#endif
