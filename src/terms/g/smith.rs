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

/// GGX's G in a lane as a quotient `(num, den)`, with no division: GGX's
/// `1 + Λ = (1 + √(1 + m² tan²θ))/2 = (cos + R)/(2 cos)`, `R = √(cos² + m² sin²)`, so
/// `G = 4 cos_i cos_o/((cos_i + R_i)(cos_o + R_o))` — sums of positive terms, nothing
/// cancels (Λ's own `(√(1 + q²) − 1)/2` would, for small q²) — and the lane divides once
/// for D·G·K. The denominator is within [4e-8, (1 + m)⁴] for cosines ≥ 1e-4.
#[inline(always)]
pub fn g_ratio_ggx(cos_i: f32, sin2_i: f32, cos_o: f32, sin2_o: f32, m2: f32) -> (f32, f32) {
    let r_i = (cos_i * cos_i + m2 * sin2_i).sqrt();
    let r_o = (cos_o * cos_o + m2 * sin2_o).sqrt();
    (4.0 * cos_i * cos_o, (cos_i + r_i) * (cos_o + r_o))
}
