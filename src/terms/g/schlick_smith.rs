//! Schlick 1994, "An Inexpensive BRDF Model for Physically-based Rendering", with the k of
//! Karis 2013, "Real Shading in Unreal Engine 4": separable `G1(w) = cos_w/(cos_w + k (1 −
//! cos_w))`, `k = m/2` with GGX and `m √(2/π)` with Beckmann. Isotropic Beckmann or GGX only.

use crate::terms::d::DistributionKind;
use std::f64::consts::PI;

/// The spelling in a materials file.
pub const NAME: &str = "schlick-smith";
/// The work the formula comes from.
pub const CITATION: &str = "Schlick 1994; Karis 2013";

/// Its rule: k comes from a Beckmann or GGX roughness, an isotropic one.
pub fn legality(d: DistributionKind, anisotropic: bool) -> Result<(), String> {
    if !d.has_lambda() {
        let d = d.toml_name();
        return Err(format!("`schlick-smith` takes its k from a Beckmann or GGX roughness, and `{d}` has none; use `cook-torrance`, `neubelt` or `none`, or distribution `beckmann`/`ggx`"));
    }
    if anisotropic {
        return Err(format!("`{NAME}` is defined for isotropic roughness only; give one roughness, or use `smith` or `smith-correlated`"));
    }
    Ok(())
}

/// k (Karis 2013): `m √(2/π)` with Beckmann, `m/2` with GGX.
pub fn k(ggx: bool, m: f64) -> f64 {
    if ggx {
        m / 2.0
    } else {
        m * (2.0 / PI).sqrt()
    }
}

/// G1 in f64, given `one_minus_cos_w = 1 − cos_w` formed where `cos_w` is known best (k up
/// to 8e3 multiplies its error). Not `cos_w (1 − k) + k`, which cancels once k > 1.
pub fn g1(cos_w: f64, one_minus_cos_w: f64, k: f64) -> f64 {
    cos_w / (cos_w + k * one_minus_cos_w)
}

/// G in a lane (f32), given each direction's cosine and `sin² = |n × w|²`: `1 − cos =
/// sin²/(1 + cos)`, as [`g1`] wants it (the subtraction would carry cos's absolute error,
/// which k multiplies).
#[inline(always)]
pub fn g_lane(cos_o: f32, sin2_o: f32, cos_i: f32, sin2_i: f32, k: f32) -> f32 {
    let (omc_o, omc_i) = (sin2_o / (1.0 + cos_o), sin2_i / (1.0 + cos_i));
    cos_o / (cos_o + k * omc_o) * (cos_i / (cos_i + k * omc_i))
}
