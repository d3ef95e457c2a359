//! FORMULAS.md §3: geometric attenuation G (shadowing and masking), dimensionless in [0, 1]
//! (except `smith-fast`, whose published fit peaks at 1.0000613 per direction).

use super::frame::{dot, Frame};
use crate::material::{CookTorrance, Distribution, Geometry, Roughness};
use std::f64::consts::PI;

/// Blinn 1977 / Cook & Torrance 1982 V-cavity:
/// `min(1, 2 cos_h cos_o / c, 2 cos_h cos_i / c)`.
pub fn cook_torrance_g(cos_h: f64, cos_i: f64, cos_o: f64, c: f64) -> f64 {
    let masking = 2.0 * cos_h * cos_o / c;
    let shadowing = 2.0 * cos_h * cos_i / c;
    1.0f64.min(masking).min(shadowing)
}

/// Smith's Λ for Beckmann (Walter et al. 2007, eq. 25 via Heitz 2014):
/// `Λ = (erf(a) − 1)/2 + exp(−a²)/(2a√π)` with `a = 1/(m tan θ)`, given as
/// `a2_inv = m² tan²θ = 1/a²`.
///
/// Written as `(exp(−a²)/(a√π) − erfc(a))/2`: `erf(a) − 1` computed directly loses every
/// digit for a ≳ 6 (it is −erfc(a), below f64 resolution next to 1).
pub fn beckmann_lambda(a2_inv: f64) -> f64 {
    if a2_inv == 0.0 {
        return 0.0; // tan θ = 0: the direction is the normal, nothing is hidden.
    }
    let a = (1.0 / a2_inv).sqrt();
    ((-a * a).exp() / (a * PI.sqrt()) - libm::erfc(a)) / 2.0
}

/// Smith's Λ for GGX (Walter et al. 2007; Heitz 2014): `(−1 + √(1 + m² tan²θ))/2`, given
/// `x = m² tan²θ`.
///
/// Evaluated as `x / (2 (1 + √(1 + x)))` for `x ≤ 1`: the textbook form cancels for small
/// `x` (near normal incidence or tiny m) and returns 0 for x < 1e-16. For `x > 1` the
/// textbook form has no cancellation and stays ∞ (G = 0) where `x` overflows, where the
/// quotient would be ∞/∞ = NaN.
pub fn ggx_lambda(x: f64) -> f64 {
    let r = (1.0 + x).sqrt();
    if x <= 1.0 {
        x / (2.0 * (1.0 + r))
    } else {
        0.5 * (r - 1.0)
    }
}

/// Separable Smith: `G1(v) · G1(l)`, `G1 = 1/(1 + Λ)`.
pub fn smith_g(lambda_o: f64, lambda_i: f64) -> f64 {
    1.0 / (1.0 + lambda_o) * (1.0 / (1.0 + lambda_i))
}

/// Height-correlated Smith (Heitz 2014, "Understanding the masking-shadowing function"):
/// `1/(1 + Λ(v) + Λ(l))`.
pub fn smith_correlated_g(lambda_o: f64, lambda_i: f64) -> f64 {
    1.0 / (1.0 + lambda_o + lambda_i)
}

/// Walter et al. 2007's rational fit of Smith–Beckmann G1 (≤0.35 % error), kept as
/// published: `a < 1.6 ? (3.535a + 2.181a²)/(1 + 2.276a + 2.577a²) : 1` with
/// `a = 1/(m tan θ)`, given as `a2_inv = m² tan²θ`.
pub fn smith_fast_g1(a2_inv: f64) -> f64 {
    let a = (1.0 / a2_inv).sqrt(); // a2_inv = 0 gives a = ∞ and G1 = 1
    if a < 1.6 {
        (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    } else {
        1.0
    }
}

/// Schlick 1994, "An Inexpensive BRDF Model for Physically-based Rendering", with the k of
/// Karis 2013, "Real Shading in Unreal Engine 4": `G1(w) = cos_w/(cos_w + k (1 − cos_w))`,
/// given `one_minus_cos_w = 1 − cos_w` formed where `cos_w` is known best (k up to 8e3
/// multiplies its error). Not `cos_w (1 − k) + k`, which cancels once k > 1.
pub fn schlick_smith_g1(cos_w: f64, one_minus_cos_w: f64, k: f64) -> f64 {
    cos_w / (cos_w + k * one_minus_cos_w)
}

/// The k of [`schlick_smith_g1`] (Karis 2013): `m √(2/π)` with Beckmann, `m/2` with GGX
/// (the only distributions it is legal with, FORMULAS.md §3).
pub fn schlick_smith_k(ggx: bool, m: f64) -> f64 {
    if ggx {
        m / 2.0
    } else {
        m * (2.0 / PI).sqrt()
    }
}

/// Neubelt & Pettineo 2013, "Crafting a Next-Gen Material Pipeline for The Order: 1886"
/// (cloth): `cos_i cos_o/(cos_i + cos_o − cos_i cos_o)`, the denominator written
/// `cos_i + cos_o (1 − cos_i)` (a sum of non-negative terms: no cancellation near 1).
pub fn neubelt_g(cos_i: f64, cos_o: f64) -> f64 {
    cos_i * cos_o / (cos_i + cos_o * (1.0 - cos_i))
}

/// `m² tan²θ(w)` for direction `w` (§3), or for anisotropic roughness
/// `(mx² (w·t)² + my² (w·b)²)/(n·w)²`. Uses `|n × w|²` for `sin²θ`.
pub fn projected_roughness2(fr: &Frame, w: [f64; 3], cos_w: f64, roughness: Roughness) -> f64 {
    match (roughness, fr.tb) {
        (Roughness::Anisotropic(mx, my), Some((t, b))) => {
            ((mx * dot(w, t)).powi(2) + (my * dot(w, b)).powi(2)) / (cos_w * cos_w)
        }
        _ => {
            let (m, _) = roughness.xy();
            m * m * super::frame::length_squared(super::frame::cross(fr.n, w)) / (cos_w * cos_w)
        }
    }
}

/// G of §3 for the material's geometry term.
pub fn microfacet_g(fr: &Frame, ct: &CookTorrance) -> f64 {
    let roughness = match ct.distribution {
        Distribution::Beckmann(r) | Distribution::Ggx(r) => Some(r),
        _ => None,
    };
    let x = |w, cos_w| {
        projected_roughness2(
            fr,
            w,
            cos_w,
            roughness.expect("Smith needs beckmann/ggx (validated)"),
        )
    };
    let lambda = |w, cos_w| match ct.distribution {
        Distribution::Beckmann(_) => beckmann_lambda(x(w, cos_w)),
        _ => ggx_lambda(x(w, cos_w)),
    };
    match ct.geometry {
        Geometry::None => 1.0,
        Geometry::CookTorrance => cook_torrance_g(fr.cos_h, fr.cos_i, fr.cos_o, fr.c),
        Geometry::Smith => smith_g(lambda(fr.v, fr.cos_o), lambda(fr.l, fr.cos_i)),
        Geometry::SmithCorrelated => {
            smith_correlated_g(lambda(fr.v, fr.cos_o), lambda(fr.l, fr.cos_i))
        }
        Geometry::SmithFast => smith_fast_g1(x(fr.v, fr.cos_o)) * smith_fast_g1(x(fr.l, fr.cos_i)),
        Geometry::SchlickSmith => {
            let m = roughness
                .expect("schlick-smith needs beckmann/ggx (validated)")
                .xy()
                .0;
            // 1 − cos_w = |n × w|²/(1 + cos_w): the subtraction carries cos_w's absolute
            // error (~1e-16), which k (up to 8e3) multiplies into G near normal incidence.
            let one_minus = |w, cos_w: f64| {
                super::frame::length_squared(super::frame::cross(fr.n, w)) / (1.0 + cos_w)
            };
            let k = schlick_smith_k(matches!(ct.distribution, Distribution::Ggx(_)), m);
            schlick_smith_g1(fr.cos_o, one_minus(fr.v, fr.cos_o), k)
                * schlick_smith_g1(fr.cos_i, one_minus(fr.l, fr.cos_i), k)
        }
        Geometry::Neubelt => neubelt_g(fr.cos_i, fr.cos_o),
    }
}
