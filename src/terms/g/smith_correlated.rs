//! Heitz 2014, "Understanding the masking-shadowing function in microfacet-based BRDFs":
//! the height-correlated Smith term `1/(1 + Λ(v) + Λ(l))`, Λ the distribution's. Needs a
//! distribution with Λ (Beckmann, GGX).

use crate::terms::d::{ggx, DistributionKind};
use crate::terms::math::MulAdd;
use crate::terms::real::Real;

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

/// GGX's G in a lane as a quotient `(num, den)`, with no division: with GGX's
/// `1 + 2Λ = R/cos`, `R = √(cos² + m² sin²)`, `1 + Λ_o + Λ_i = (R_o cos_i + R_i cos_o)/(2
/// cos_i cos_o)` (the form of Filament's `V_SmithGGXCorrelated`), so
/// `G = 2 cos_i cos_o/(R_o cos_i + R_i cos_o)`: positive terms, nothing cancels, and the
/// lane divides once for D·G·K.
#[inline(always)]
pub fn g_ratio_ggx<A: MulAdd, T: Real>(cos_i: T, sin2_i: T, cos_o: T, sin2_o: T, m2: f32) -> (T, T) {
    let r_i = ggx::lambda_root_lane::<A, T>(cos_i, sin2_i, m2);
    let r_o = ggx::lambda_root_lane::<A, T>(cos_o, sin2_o, m2);
    (cos_i * 2.0 * cos_o, r_o * cos_i + r_i * cos_o)
}

