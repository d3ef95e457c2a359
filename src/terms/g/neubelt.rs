//! Neubelt & Pettineo 2013, "Crafting a Next-Gen Material Pipeline for The Order: 1886"
//! (cloth): `G = cos_i cos_o/(cos_i + cos_o − cos_i cos_o)`. Defined with every distribution.

use crate::terms::d::DistributionKind;

/// The spelling in a materials file.
pub const NAME: &str = "neubelt";
/// The work the formula comes from.
pub const CITATION: &str = "Neubelt & Pettineo 2013";

/// Its rule: defined with every distribution.
pub fn legality(_: DistributionKind, _anisotropic: bool) -> Result<(), String> {
    Ok(())
}

/// G in f64, the denominator written `cos_i + cos_o (1 − cos_i)` (a sum of non-negative
/// terms: no cancellation near 1).
pub fn g(cos_i: f64, cos_o: f64) -> f64 {
    cos_i * cos_o / (cos_i + cos_o * (1.0 - cos_i))
}

/// G in a lane (f32), written as [`g`].
#[inline(always)]
pub fn g_lane(cos_i: f32, cos_o: f32) -> f32 {
    cos_i * cos_o / (cos_i + cos_o * (1.0 - cos_i))
}
