//! Blinn 1977 / Cook & Torrance 1982, the V-cavity geometry term:
//! `min(1, 2 cos_h cos_o / c, 2 cos_h cos_i / c)`. Defined with every distribution.

use crate::terms::d::DistributionKind;
use crate::terms::real::Real;

/// The spelling in a materials file.
pub const NAME: &str = "cook-torrance";
/// The work the formula comes from.
pub const CITATION: &str = "Blinn 1977; Cook & Torrance 1982";

/// Its rule: defined with every distribution.
pub fn legality(_: DistributionKind, _anisotropic: bool) -> Result<(), String> {
    Ok(())
}

/// G in f64.
pub fn g(cos_h: f64, cos_i: f64, cos_o: f64, c: f64) -> f64 {
    let masking = 2.0 * cos_h * cos_o / c;
    let shadowing = 2.0 * cos_h * cos_i / c;
    1.0f64.min(masking).min(shadowing)
}

/// G in a lane (f32).
#[inline(always)]
pub fn g_lane<T: Real>(cos_h: T, cos_i: T, cos_o: T, c: T) -> T {
    let t = cos_h * 2.0 / c;
    min(c.splat_as(1.0), min(t * cos_o, t * cos_i))
}

/// The smaller of two numbers (the second where either is NaN), as one compare and
/// select the lanes vectorise.
#[inline(always)]
fn min<T: Real>(a: T, b: T) -> T {
    T::select(a.lt(b), a, b)
}
