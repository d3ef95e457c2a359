//! FORMULAS.md §4: Fresnel reflectance F at `c = v·h`, one channel at a time.

use num_complex::Complex64;

/// Exact unpolarised dielectric Fresnel (Cook & Torrance 1982, eq. 8, with the seed's typo
/// in the last denominator corrected to `c(g − c) + 1`):
/// `g² = μ² + c² − 1`; `g² < 0` is total internal reflection (F = 1); else
/// `F = ½ ((g−c)/(g+c))² (1 + ((c(g+c) − 1)/(c(g−c) + 1))²)`.
pub fn dielectric_f(c: f64, ior: f64) -> f64 {
    let g2 = ior * ior + c * c - 1.0;
    if g2 < 0.0 {
        return 1.0;
    }
    let g = g2.sqrt();
    // g − c = (μ² − 1)/(g + c): the subtraction cancels for μ ≈ 1 (F ≈ 0 there, and its
    // relative error would be unbounded); the product form is exact to a few ulps.
    let g_minus_c = (ior * ior - 1.0) / (g + c);
    let r = g_minus_c / (g + c);
    let q = (c * (g + c) - 1.0) / (c * g_minus_c + 1.0);
    0.5 * r * r * (1.0 + q * q)
}

/// Exact conductor Fresnel for complex `η = n + ik` (Born & Wolf, "Principles of Optics",
/// §14.2; the form of pbrt-v4's `FrComplex`): `sin²θt = (1 − c²)/η²`,
/// `cos θt = √(1 − sin²θt)` (principal root), `r∥ = (ηc − cos θt)/(ηc + cos θt)`,
/// `r⊥ = (c − η cos θt)/(c + η cos θt)`, `F = (|r∥|² + |r⊥|²)/2`.
pub fn conductor_f(c: f64, ior: f64, extinction: f64) -> f64 {
    let eta = Complex64::new(ior, extinction);
    // cos²θt = 1 − (1 − c²)/η² = (η² − 1 + c²)/η², with Re η² − 1 = n² − k² − 1 formed
    // before c² is added: 1 − (1 − c²)/η² loses c² entirely below c ~ 1e-8 when η = 1
    // (index-matched, F = 0 exactly), and F came out 1 (the kernel has the same form).
    let eta2 = eta * eta;
    let cos2_t =
        Complex64::new((ior * ior - 1.0 - extinction * extinction) + c * c, eta2.im) / eta2;
    let cos_t = cos2_t.sqrt();
    let r_par = (eta * c - cos_t) / (eta * c + cos_t);
    let r_perp = (c - eta * cos_t) / (c + eta * cos_t);
    (r_par.norm_sqr() + r_perp.norm_sqr()) / 2.0
}

/// Schlick 1994, "An inexpensive BRDF model for physically-based rendering":
/// `F0 + (1 − F0)(1 − c)⁵`.
pub fn schlick_f(c: f64, f0: f64) -> f64 {
    f0 + (1.0 - f0) * (1.0 - c).powi(5)
}
