// conductor_poly.glsl — the conductor's F as the CPU engine's fitted polynomial in c
// (src/terms/f/conductor/poly.rs, Trefethen 2013: the Chebyshev interpolant of F on
// [0.091875, 1.001875], degree 14, its coefficients rounded once to f32) for a folded
// material: the host sets MATERIAL_F_POLY and the coefficients as specialization
// constants 31-76 (src/gpu/kernel.rs) only for a Cook-Torrance conductor whose fit's
// written bound (Horner's running error with or without fused multiply-adds, which is
// Vulkan's allowance for fma, the coefficients' and t's roundings, the truncation) is
// within the metal form's 48u; + - * are correctly rounded on Vulkan, and no value here
// is subnormal. 14 multiply-adds a channel where the metal form takes two square roots
// and a division (lavapipe, 4M tuples folded: docs/VULKAN.md). Without the constants the
// compiler drops this code.

#ifndef VKBRDF_CONDUCTOR_POLY_GLSL
#define VKBRDF_CONDUCTOR_POLY_GLSL

layout(constant_id = 31) const bool MATERIAL_F_POLY = false;
layout(constant_id = 32) const float F_POLY_R0 = 0.0;
layout(constant_id = 33) const float F_POLY_R1 = 0.0;
layout(constant_id = 34) const float F_POLY_R2 = 0.0;
layout(constant_id = 35) const float F_POLY_R3 = 0.0;
layout(constant_id = 36) const float F_POLY_R4 = 0.0;
layout(constant_id = 37) const float F_POLY_R5 = 0.0;
layout(constant_id = 38) const float F_POLY_R6 = 0.0;
layout(constant_id = 39) const float F_POLY_R7 = 0.0;
layout(constant_id = 40) const float F_POLY_R8 = 0.0;
layout(constant_id = 41) const float F_POLY_R9 = 0.0;
layout(constant_id = 42) const float F_POLY_R10 = 0.0;
layout(constant_id = 43) const float F_POLY_R11 = 0.0;
layout(constant_id = 44) const float F_POLY_R12 = 0.0;
layout(constant_id = 45) const float F_POLY_R13 = 0.0;
layout(constant_id = 46) const float F_POLY_R14 = 0.0;
layout(constant_id = 47) const float F_POLY_G0 = 0.0;
layout(constant_id = 48) const float F_POLY_G1 = 0.0;
layout(constant_id = 49) const float F_POLY_G2 = 0.0;
layout(constant_id = 50) const float F_POLY_G3 = 0.0;
layout(constant_id = 51) const float F_POLY_G4 = 0.0;
layout(constant_id = 52) const float F_POLY_G5 = 0.0;
layout(constant_id = 53) const float F_POLY_G6 = 0.0;
layout(constant_id = 54) const float F_POLY_G7 = 0.0;
layout(constant_id = 55) const float F_POLY_G8 = 0.0;
layout(constant_id = 56) const float F_POLY_G9 = 0.0;
layout(constant_id = 57) const float F_POLY_G10 = 0.0;
layout(constant_id = 58) const float F_POLY_G11 = 0.0;
layout(constant_id = 59) const float F_POLY_G12 = 0.0;
layout(constant_id = 60) const float F_POLY_G13 = 0.0;
layout(constant_id = 61) const float F_POLY_G14 = 0.0;
layout(constant_id = 62) const float F_POLY_B0 = 0.0;
layout(constant_id = 63) const float F_POLY_B1 = 0.0;
layout(constant_id = 64) const float F_POLY_B2 = 0.0;
layout(constant_id = 65) const float F_POLY_B3 = 0.0;
layout(constant_id = 66) const float F_POLY_B4 = 0.0;
layout(constant_id = 67) const float F_POLY_B5 = 0.0;
layout(constant_id = 68) const float F_POLY_B6 = 0.0;
layout(constant_id = 69) const float F_POLY_B7 = 0.0;
layout(constant_id = 70) const float F_POLY_B8 = 0.0;
layout(constant_id = 71) const float F_POLY_B9 = 0.0;
layout(constant_id = 72) const float F_POLY_B10 = 0.0;
layout(constant_id = 73) const float F_POLY_B11 = 0.0;
layout(constant_id = 74) const float F_POLY_B12 = 0.0;
layout(constant_id = 75) const float F_POLY_B13 = 0.0;
layout(constant_id = 76) const float F_POLY_B14 = 0.0;

// The fitted interval's centre (35/64, exactly an f32): t = c - CONDUCTOR_POLY_CENTRE is
// exact for c in [CENTRE/2, 2 CENTRE] (Sterbenz) and otherwise rounded once.
const float CONDUCTOR_POLY_CENTRE = 0.546875;
// The least c the polynomial takes (the CPU engine's FAST_MIN_C): the fitted interval
// starts at 0.091875; a lane below takes the metal form.
const float CONDUCTOR_POLY_MIN_C = 0.1;

// F of the three channels at c in [CONDUCTOR_POLY_MIN_C, 1 + a few u], by Horner's rule
// in t, the channels' steps side by side.
vec3 conductor_f_poly(float c) {
    float t = c - CONDUCTOR_POLY_CENTRE;
    vec3 r = vec3(F_POLY_R14, F_POLY_G14, F_POLY_B14);
    r = r * t + vec3(F_POLY_R13, F_POLY_G13, F_POLY_B13);
    r = r * t + vec3(F_POLY_R12, F_POLY_G12, F_POLY_B12);
    r = r * t + vec3(F_POLY_R11, F_POLY_G11, F_POLY_B11);
    r = r * t + vec3(F_POLY_R10, F_POLY_G10, F_POLY_B10);
    r = r * t + vec3(F_POLY_R9, F_POLY_G9, F_POLY_B9);
    r = r * t + vec3(F_POLY_R8, F_POLY_G8, F_POLY_B8);
    r = r * t + vec3(F_POLY_R7, F_POLY_G7, F_POLY_B7);
    r = r * t + vec3(F_POLY_R6, F_POLY_G6, F_POLY_B6);
    r = r * t + vec3(F_POLY_R5, F_POLY_G5, F_POLY_B5);
    r = r * t + vec3(F_POLY_R4, F_POLY_G4, F_POLY_B4);
    r = r * t + vec3(F_POLY_R3, F_POLY_G3, F_POLY_B3);
    r = r * t + vec3(F_POLY_R2, F_POLY_G2, F_POLY_B2);
    r = r * t + vec3(F_POLY_R1, F_POLY_G1, F_POLY_B1);
    r = r * t + vec3(F_POLY_R0, F_POLY_G0, F_POLY_B0);
    return r;
}

#endif
