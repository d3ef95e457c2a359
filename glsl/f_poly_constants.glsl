// f_poly_constants.glsl — the specialization constants of the conductor's F as the CPU
// engine's fitted polynomial in c (src/terms/f/conductor/poly.rs, Trefethen 2013: the Chebyshev interpolant of F on
// [0.091875, 1.001875], degree 14, its coefficients rounded once to f32) for a folded
// material: the host sets MATERIAL_F_POLY and the coefficients as specialization
// constants 31-76 (src/gpu/fold.rs) only for a Cook-Torrance conductor whose fit's
// written bound (Horner's running error with or without fused multiply-adds, which is
// Vulkan's allowance for fma, the coefficients' and t's roundings, the truncation) is
// within the metal form's 48u; + - * are correctly rounded on Vulkan, and no value here
// is subnormal. terms.glsl's conductor block evaluates it (conductor_f_poly).

#ifndef VKBRDF_F_POLY_CONSTANTS_GLSL
#define VKBRDF_F_POLY_CONSTANTS_GLSL

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

#endif
