//! K in a lane, as each convention's file gives it (below the conventions and their list).

use crate::terms::real::Real;

/// K in a lane: `K = numerator / cos_o / (cos_i when divides_cos_i)`, one cosine at a
/// time, the numerator rounded once.
#[derive(Debug, Clone, Copy, Default)]
pub struct LaneK {
    /// 1/4 modern, 1/π Cook–Torrance 1982, 1 seed.
    pub numerator: f32,
    /// Whether K divides by `cos_i` too (all but the seed convention).
    pub divides_cos_i: bool,
}

impl LaneK {
    /// K of one lane.
    #[inline(always)]
    pub fn k(self, cos_i: f32, cos_o: f32) -> f32 {
        self.numerator / cos_o / if self.divides_cos_i { cos_i } else { 1.0 }
    }

    /// K of one lane as a quotient `(numerator, cos_o · cos_i)` (or `cos_o`), for a lane
    /// that takes D·G·K over one division; the denominator is ≥ 1e-8 for cosines ≥ 1e-4.
    #[inline(always)]
    pub fn ratio<T: Real>(self, cos_i: T, cos_o: T) -> (T, T) {
        let d = if self.divides_cos_i {
            cos_o * cos_i
        } else {
            cos_o
        };
        (cos_o.splat_as(self.numerator), d)
    }
}
