//! Estevez & Kulla 2017, "Production Friendly Microfacet Sheen BRDF" (the "Charlie" sheen):
//! `(2 + 1/m)/(2π) sin_h^(1/m)`, `0 < m ≤ 1` (the paper's α = r²). Normalised:
//! `∫ D cos_h dω = 1`. 0 at `sin_h = 0`. Isotropic only; no Smith Λ.

use crate::terms::math::{cos_pow, exp_neg, log_cos};
use crate::terms::k::Convention;
use std::f64::consts::PI;

/// The spelling in a materials file.
pub const NAME: &str = "charlie";
/// The work the formula comes from.
pub const CITATION: &str = "Estevez & Kulla 2017";
/// No Smith Λ: the Smith geometry terms are not defined with it.
pub const HAS_LAMBDA: bool = false;
/// The largest m the formula is defined for: the paper's α = r² ≤ 1.
pub const MAX_M: f64 = 1.0;

/// Its rule for anisotropic roughness: none exists.
pub fn anisotropic(_: Convention) -> Result<(), String> {
    super::rules::isotropic_only(NAME)
}

/// The normalisation `(2 + 1/m)/(2π)`.
pub fn norm(m: f64) -> f64 {
    (2.0 + 1.0 / m) / (2.0 * PI)
}

/// D in f64.
///
/// `sin_h^(1/m)` is [`cos_pow`] of the complementary angle (`sin_h` with `1 − sin_h² =
/// cos_h²`): where `h` is near grazing, `ln sin_h` comes from `cos_h²` (`ln_1p`), not from
/// `sin_h` rounded next to 1, whose error the exponent 1/m (up to 1e7) would multiply.
pub fn d(cos_h: f64, sin2_h: f64, m: f64) -> f64 {
    norm(m) * cos_pow(sin2_h.sqrt(), cos_h * cos_h, 1.0 / m)
}

/// D in a lane (f32), given `1/m` and the normalisation rounded once, `ln sin_h` as the log
/// of the complementary angle's cosine (from `cos²_h` near grazing h), as [`d`].
#[inline(always)]
pub fn d_lane(cos_h2: f32, sin2_h: f32, exponent: f32, norm: f32) -> f32 {
    let x = exponent * log_cos(sin2_h.sqrt(), cos_h2);
    let v = norm * exp_neg(x);
    if sin2_h == 0.0 {
        0.0
    } else {
        v
    }
}
