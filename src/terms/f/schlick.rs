//! Schlick 1994, "An inexpensive BRDF model for physically-based rendering":
//! `F = F0 + (1 − F0)(1 − c)⁵`.

use crate::terms::real::Real;

/// The spelling in a materials file.
pub const NAME: &str = "schlick";
/// The work the formula comes from.
pub const CITATION: &str = "Schlick 1994";

/// F in f64.
pub fn f(c: f64, f0: f64) -> f64 {
    f0 + (1.0 - f0) * (1.0 - c).powi(5)
}

/// [`f_lane`]'s largest relative error in units of u = 2⁻²⁴ (FMA or not), from the frame's
/// `c` and `sin²θ` (its `sin²` rounded once, as a frame forms it at best; the frame's own
/// errors are its), F0 rounded once to f32: `1 − c = sin²/(1 + c)` 3u (sin²'s rounding,
/// the sum's and the quotient's); its square 7u, fourth power 15u, fifth 19u; times
/// `1 − F0` (one rounding; F0's own rounding moves F by `u F0 (1 − x⁵)` ≤ uF, as the
/// term and F0 move together) and the product 21u of the term; the sum of non-negative
/// parts one more u: in all ≤ `21u + u + u` of F, written with a margin as 24u. GGX's
/// certificate gives D what F leaves of the metal form's 48u
/// (`ggx::local_frame_guard_for_f`).
pub const LANE_BOUND_U: f64 = 24.0;

/// F in a lane (f32), given `1 − c` formed without cancelling (`sin²/(1 + c)`).
#[inline(always)]
pub fn f_lane<T: Real>(one_minus_c: T, f0: f32) -> T {
    let x2 = one_minus_c * one_minus_c;
    x2 * x2 * one_minus_c * (1.0 - f0) + f0
}

/// `F0 = ((n-1)² + k²)/((n+1)² + k²)` per channel: the reflectance at normal incidence of
/// an index `n + ik` (FORMULAS.md §4), Schlick's F0 when given `ior` and `extinction`.
pub fn f0_from_ior(ior: [f64; 3], extinction: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|c| {
        let (n, k) = (ior[c], extinction[c]);
        ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lane form stays inside [`LANE_BOUND_U`] from grazing to normal incidence for F0
    /// from a dielectric's to a metal's, `sin²` rounded once from f64 as a frame gives it,
    /// against the f64 form at the f32 `c` and the f64 F0.
    #[test]
    fn the_lane_form_stays_inside_its_bound() {
        let u = f64::from(f32::EPSILON) / 2.0;
        let mut worst = 0f64;
        for f0 in [0.0, 0.02, 0.04, 0.1, 0.5, 0.9, 0.99, 0.999_999] {
            for i in 0..=100_000 {
                let c = (1e-4 + (1.0 - 1e-4) * f64::from(i) / 100_000.0) as f32;
                let cc = f64::from(c);
                let s2 = ((1.0 - cc) * (1.0 + cc)) as f32;
                let want = f(cc, f0);
                let got = f64::from(f_lane(s2 / (1.0 + c), f0 as f32));
                worst = worst.max((got - want).abs() / want / u);
            }
        }
        assert!(worst <= LANE_BOUND_U, "{worst}u above {LANE_BOUND_U}u");
        assert!(worst > 1.0, "the sweep should find a few u ({worst})");
    }
}
