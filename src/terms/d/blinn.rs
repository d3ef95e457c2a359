//! Blinn 1977, "Models of light reflection for computer synthesized pictures": the
//! Blinn–Phong distribution, normalised so that `∫ D cos_h dω = 1`: `(e + 2)/(2π) cos_h^e`.
//! Takes an exponent, not a roughness; no Smith Λ.

use crate::terms::math::{cos_pow, exp_neg, log_cos};
use crate::terms::k::Convention;
use std::f64::consts::PI;

/// The spelling in a materials file.
pub const NAME: &str = "blinn";
/// The work the formula comes from.
pub const CITATION: &str = "Blinn 1977";
/// No Smith Λ: the Smith geometry terms are not defined with it.
pub const HAS_LAMBDA: bool = false;

/// Its rule for anisotropic roughness: it takes no roughness at all.
pub fn anisotropic(_: Convention) -> Result<(), String> {
    Err("distribution `blinn` takes an `exponent`, not a roughness".into())
}

/// The normalisation `(e + 2)/(2π)`.
pub fn norm(exponent: f64) -> f64 {
    (exponent + 2.0) / (2.0 * PI)
}

/// D in f64.
pub fn d(cos_h: f64, sin2_h: f64, exponent: f64) -> f64 {
    norm(exponent) * cos_pow(cos_h, sin2_h, exponent)
}

/// D in a lane (f32), given the normalisation rounded once: `exp(e ln cos_h)`, ln cos_h
/// from sin²_h near the peak (`log_cos`), where cos_h itself keeps only absolute precision
/// that the exponent would multiply. `e·ln cos_h ≤ 0`: `exp_neg` suffices.
#[inline(always)]
pub fn d_lane(cos_h: f32, sin2_h: f32, exponent: f32, norm: f32) -> f32 {
    norm * exp_neg(exponent * log_cos(cos_h, sin2_h))
}
