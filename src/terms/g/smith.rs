//! Smith 1967, separable: `G = G1(v) · G1(l)`, `G1 = 1/(1 + Λ)`, Λ the distribution's
//! (Walter et al. 2007; Heitz 2014). Needs a distribution with Λ (Beckmann, GGX).

use crate::terms::d::DistributionKind;

/// The spelling in a materials file.
pub const NAME: &str = "smith";
/// The work the formula comes from.
pub const CITATION: &str = "Smith 1967; Walter et al. 2007";

/// Its rule: the distribution must have a Λ.
pub fn legality(d: DistributionKind, _anisotropic: bool) -> Result<(), String> {
    super::rules::needs_lambda(d)
}

/// G in f64 from Λ of each direction.
pub fn g(lambda_o: f64, lambda_i: f64) -> f64 {
    1.0 / (1.0 + lambda_o) * (1.0 / (1.0 + lambda_i))
}

/// G in a lane (f32) from Λ of each direction.
#[inline(always)]
pub fn g_lane(lambda_o: f32, lambda_i: f32) -> f32 {
    1.0 / (1.0 + lambda_o) * (1.0 / (1.0 + lambda_i))
}
