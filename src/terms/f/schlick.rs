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
