//! Walter et al. 2007, "Microfacet models for refraction through rough surfaces" (as in
//! Mitsuba 3 and pbrt-v4): `K = 1/(4 cos_i cos_o)` and the Beckmann normalisation `k = π`
//! that makes `∫ D cos_h dω = 1`.

use super::lane::LaneK;
use std::f64::consts::PI;

/// The spelling in a materials file.
pub const NAME: &str = "modern";
/// The work the formula comes from.
pub const CITATION: &str = "Walter et al. 2007";
/// Beckmann's `k`.
pub const BECKMANN_K: f64 = PI;
/// K in a lane.
pub const LANE_K: LaneK = LaneK {
    numerator: 0.25,
    divides_cos_i: true,
};

/// K in f64.
pub fn k(cos_i: f64, cos_o: f64) -> f64 {
    1.0 / (4.0 * cos_i * cos_o)
}

/// ln K in f64.
pub fn ln_k(cos_i: f64, cos_o: f64) -> f64 {
    -(4f64.ln() + cos_i.ln() + cos_o.ln())
}
