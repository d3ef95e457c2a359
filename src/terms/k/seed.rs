//! The seed lecture's convention, after Foley et al. 1990 ("Computer Graphics: Principles
//! and Practice", 2nd ed., §16.7): the glare term `K = 1/cos_o` and the Beckmann
//! normalisation `k = 4`.

use super::lane::LaneK;

/// The spelling in a materials file.
pub const NAME: &str = "seed";
/// The work the formula comes from.
pub const CITATION: &str = "the seed lecture; Foley et al. 1990";
/// Beckmann's `k`.
pub const BECKMANN_K: f64 = 4.0;
/// K in a lane.
pub const LANE_K: LaneK = LaneK {
    numerator: 1.0,
    divides_cos_i: false,
};

/// K in f64.
pub fn k(_cos_i: f64, cos_o: f64) -> f64 {
    1.0 / cos_o
}

/// ln K in f64.
pub fn ln_k(_cos_i: f64, cos_o: f64) -> f64 {
    -cos_o.ln()
}
