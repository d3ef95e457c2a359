//! FORMULAS.md §5: the glare / normalisation factor K of `R_s = D·G·F·K`, and the Beckmann
//! normalisation constant `k` each convention pairs with it.

use crate::material::Convention;
use std::f64::consts::PI;

/// K for a convention: seed `1/cos_o` (the lecture's glare term; Foley's D);
/// cook-torrance-1982 `1/(π cos_i cos_o)` (Cook & Torrance 1982);
/// modern `1/(4 cos_i cos_o)` (Walter et al. 2007, as in Mitsuba 3 and pbrt-v4).
pub fn glare_k(convention: Convention, cos_i: f64, cos_o: f64) -> f64 {
    match convention {
        Convention::Seed => 1.0 / cos_o,
        Convention::CookTorrance1982 => 1.0 / (PI * cos_i * cos_o),
        Convention::Modern => 1.0 / (4.0 * cos_i * cos_o),
    }
}

/// The Beckmann normalisation `k` in `exp(−tan²δ/m²)/(k m² cos⁴δ)`: seed 4,
/// cook-torrance-1982 1, modern π (the one that makes `∫ D cos_h dω = 1`).
pub fn beckmann_k(convention: Convention) -> f64 {
    match convention {
        Convention::Seed => 4.0,
        Convention::CookTorrance1982 => 1.0,
        Convention::Modern => PI,
    }
}

/// `ln K`, from the cosines' logarithms: finite even where `K` itself overflows (cosines
/// near 1e-170, reachable from f64 callers), so the product `D·G·F·K` can be formed in the
/// log domain there.
pub fn glare_ln_k(convention: Convention, cos_i: f64, cos_o: f64) -> f64 {
    match convention {
        Convention::Seed => -cos_o.ln(),
        Convention::CookTorrance1982 => -(PI.ln() + cos_i.ln() + cos_o.ln()),
        Convention::Modern => -(4f64.ln() + cos_i.ln() + cos_o.ln()),
    }
}
