//! Cook & Torrance 1982, "A Reflectance Model for Computer Graphics": `K = 1/(π cos_i
//! cos_o)` and the Beckmann normalisation `k = 1`.

use super::lane::LaneK;
use std::f64::consts::PI;

/// The spelling in a materials file.
pub const NAME: &str = "cook-torrance-1982";
/// The work the formula comes from.
pub const CITATION: &str = "Cook & Torrance 1982";
/// Beckmann's `k`.
pub const BECKMANN_K: f64 = 1.0;
/// K in a lane.
pub const LANE_K: LaneK = LaneK {
    numerator: (1.0 / PI) as f32,
    divides_cos_i: true,
};

/// K in f64.
pub fn k(cos_i: f64, cos_o: f64) -> f64 {
    1.0 / (PI * cos_i * cos_o)
}

/// ln K in f64.
pub fn ln_k(cos_i: f64, cos_o: f64) -> f64 {
    -(PI.ln() + cos_i.ln() + cos_o.ln())
}
