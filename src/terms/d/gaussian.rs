//! Torrance & Sparrow 1967, "Theory for off-specular reflection from roughened surfaces":
//! the Gaussian distribution `exp(−(δ/m)²)` (the seed prints `e^{−(αm)²}`, a typo).
//! Unnormalised: D = 1 at the peak. Isotropic only; no Smith Λ.

use crate::terms::math::{atan2_positive, exp_neg};
use crate::terms::k::Convention;

/// The spelling in a materials file.
pub const NAME: &str = "gaussian";
/// The work the formula comes from.
pub const CITATION: &str = "Torrance & Sparrow 1967";
/// No Smith Λ: the Smith geometry terms are not defined with it.
pub const HAS_LAMBDA: bool = false;

/// Its rule for anisotropic roughness: none exists.
pub fn anisotropic(_: Convention) -> Result<(), String> {
    super::rules::isotropic_only(NAME)
}

/// D in f64: `exp(−(δ/m)²)`, `δ = atan2(sin δ, cos δ)`.
pub fn d(cos_h: f64, sin2_h: f64, m: f64) -> f64 {
    // atan2 of (sin, cos) keeps δ exact near 0, where acos(cos_h) loses half the digits.
    let delta = sin2_h.sqrt().atan2(cos_h);
    (-(delta / m).powi(2)).exp()
}

/// D in a lane (f32), given `1/m²`; δ by the branch-free atan2 for the same reason as [`d`].
#[inline(always)]
pub fn d_lane(cos_h: f32, sin2_h: f32, inv_m2: f32) -> f32 {
    let delta = atan2_positive(sin2_h.sqrt(), cos_h);
    exp_neg(-(delta * delta) * inv_m2)
}
