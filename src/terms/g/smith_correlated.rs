//! Heitz 2014, "Understanding the masking-shadowing function in microfacet-based BRDFs":
//! the height-correlated Smith term `1/(1 + Λ(v) + Λ(l))`, Λ the distribution's. Needs a
//! distribution with Λ (Beckmann, GGX).

use crate::terms::d::DistributionKind;

/// The spelling in a materials file.
pub const NAME: &str = "smith-correlated";
/// The work the formula comes from.
pub const CITATION: &str = "Heitz 2014";

/// Its rule: the distribution must have a Λ.
pub fn legality(d: DistributionKind, _anisotropic: bool) -> Result<(), String> {
    super::rules::needs_lambda(d)
}

/// G in f64 from Λ of each direction.
pub fn g(lambda_o: f64, lambda_i: f64) -> f64 {
    1.0 / (1.0 + lambda_o + lambda_i)
}

/// G in a lane (f32) from Λ of each direction.
#[inline(always)]
pub fn g_lane(lambda_o: f32, lambda_i: f32) -> f32 {
    1.0 / (1.0 + lambda_o + lambda_i)
}
