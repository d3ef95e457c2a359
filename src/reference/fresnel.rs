//! FORMULAS.md §4: Fresnel reflectance F at `c = v·h`, one channel at a time.

use num_complex::Complex64;

/// Exact unpolarised dielectric Fresnel (Cook & Torrance 1982, eq. 8, with the seed's typo
/// in the last denominator corrected to `c(g − c) + 1`):
/// `g² = μ² + c² − 1`; `g² < 0` is total internal reflection (F = 1); else
/// `F = ½ ((g−c)/(g+c))² (1 + ((c(g+c) − 1)/(c(g−c) + 1))²)`.
pub fn dielectric_f(c: f64, ior: f64) -> f64 {
    // 1 − c² as (1 − c)(1 + c): 1 − c is exact for c in [0.5, 1].
    dielectric_f_with_sin2(c, (1.0 - c) * (1.0 + c), ior)
}

/// [`dielectric_f`] given also `s2 = 1 − c²`, accurate near c = 1 where `1 − c` of a
/// rounded `c` is not (the frame forms it from the inputs: [`super::frame::Frame::sin2_d`]).
pub fn dielectric_f_with_sin2(c: f64, s2: f64, ior: f64) -> f64 {
    // μ² − 1 as (μ − 1)(μ + 1): `μ·μ − 1` rounds μ² first and, for μ = 1 + 1e-9, keeps
    // only ~7 of its digits (μ − 1 is exact by Sterbenz's lemma for μ in [0.5, 2]).
    let mu2m1 = (ior - 1.0) * (ior + 1.0);
    // g² = μ² + c² − 1 in whichever grouping rounds least (each form's error is ~u times the
    // sum of its terms' magnitudes): (μ² − 1) + c² near μ = 1, where μ² + c² − 1 rounds
    // c² ≤ 1e-16 away next to 1 (g² = 0 instead of c², F = 1 instead of 0 at grazing c);
    // μ² − (1 − c²) near c = 1 with μ ≪ 1, where (μ² − 1) + c² cancels −1 against 1 to
    // leave μ² (μ = 1e-6 at normal incidence: F off by 2e-10 relative).
    let g2 = if mu2m1.abs() + c * c <= ior * ior + s2 {
        mu2m1 + c * c
    } else {
        ior * ior - s2
    };
    if g2 < 0.0 {
        return 1.0;
    }
    let g = g2.sqrt();
    // g − c = (μ² − 1)/(g + c): the subtraction cancels for μ ≈ 1 (F ≈ 0 there, and its
    // relative error would be unbounded); the product form is exact to a few ulps.
    let g_minus_c = mu2m1 / (g + c);
    let r = g_minus_c / (g + c);
    // c(g + c) − 1 = c·g − (1 − c²) and c(g − c) + 1 = c·g + (1 − c²): near c = 1 with
    // g ≪ 1 (μ ≪ 1 at normal incidence) both printed forms cancel 1 against ~1 (the
    // denominator is ~μ there: F off by 3e-11 relative at μ = 1e-6).
    let q = (c * g - s2) / (c * g + s2);
    0.5 * r * r * (1.0 + q * q)
}

/// Principal square root of `z` (Re ≥ 0, the sign of Im kept), computed from the larger of
/// `(|z| + x)/2` and `(|z| − x)/2` with the other part by division: the polar form
/// (`num_complex`'s) takes `cos(θ/2)` of a rounded angle, which has no relative precision
/// when `z` is nearly a negative real (a conductor with n < 1 and small k at grazing c), and
/// the direct formulas `√((|z| ± x)/2)` cancel there too.
fn csqrt(z: Complex64) -> Complex64 {
    let (x, y) = (z.re, z.im);
    let r = x.hypot(y);
    if r == 0.0 {
        return Complex64::new(0.0, 0.0);
    }
    if x >= 0.0 {
        let re = (0.5 * (r + x)).sqrt();
        Complex64::new(re, 0.5 * y / re)
    } else {
        let im = (0.5 * (r - x)).sqrt();
        Complex64::new(0.5 * y.abs() / im, if y < 0.0 { -im } else { im })
    }
}

/// Exact conductor Fresnel for complex `η = n + ik` (Born & Wolf, "Principles of Optics",
/// §14.2; the form of pbrt-v4's `FrComplex`): `sin²θt = (1 − c²)/η²`,
/// `cos θt = √(1 − sin²θt)` (principal root), `r∥ = (ηc − cos θt)/(ηc + cos θt)`,
/// `r⊥ = (c − η cos θt)/(c + η cos θt)`, `F = (|r∥|² + |r⊥|²)/2`.
///
/// Evaluated in the same values rearranged so that nothing cancels:
/// - `cos²θt = 1 − (1 − c²)/η² = (η² − 1 + c²)/η²`, with `Re(η² − 1 + c²) = (n − 1)(n + 1) +
///   (c − k)(c + k)` formed directly. The printed form rounds `c²` away next to 1: for
///   η = 1 (F = 0 exactly) at c = 1e-8 it gave cos θt = 0 and F = 1, and f at a grazing
///   mirror configuration was 201,302 instead of 0.0318.
/// - `c − η cos θt = (c² − η² cos²θt)/(c + η cos θt) = (1 − η²)/(c + η cos θt)`, so
///   `r⊥ = (1 − η²)/(c + η cos θt)²`: the difference of two nearly equal numbers (η ≈ 1,
///   where F ≈ 0 and its relative error would be unbounded) becomes the exact factor
///   `1 − η² = −((n − 1)(n + 1) − k²) − 2ink`.
/// - likewise `ηc − cos θt = (η²c² − cos²θt)/(ηc + cos θt)` with
///   `η²c² − cos²θt = (η² − 1)((η² + 1)c² − 1)/η²`, so
///   `r∥ = (η² − 1)((η² + 1)c² − 1)/(η² (ηc + cos θt)²)`. Its second factor still vanishes
///   at the (pseudo-)Brewster angle, as r∥ itself does; there |r∥|² ≪ |r⊥|² and F keeps its
///   relative precision.
///
/// The denominators have positive real parts (`c > 0`, `n > 0`, `Re cos θt ≥ 0`), so they
/// do not cancel.
pub fn conductor_f(c: f64, ior: f64, extinction: f64) -> f64 {
    let (n, k) = (ior, extinction);
    let eta = Complex64::new(n, k);
    let eta2 = eta * eta;
    let n2m1 = (n - 1.0) * (n + 1.0); // n² − 1 without rounding n² first
    let eta2m1 = Complex64::new(n2m1 - k * k, 2.0 * n * k); // η² − 1
    let g2 = Complex64::new(n2m1 + (c - k) * (c + k), 2.0 * n * k); // η² − 1 + c²
    let cos_t = csqrt(g2 / eta2);
    let eta_cos_t = eta * cos_t;
    let u = c + eta_cos_t;
    let r_perp = -eta2m1 / (u * u);
    let w = eta * c + cos_t;
    // (η² + 1)c² − 1 = Re(η²)c² − (1 − c)(1 + c) + i Im(η²)c²
    let brewster = Complex64::new(eta2.re * c * c - (1.0 - c) * (1.0 + c), eta2.im * c * c);
    let r_par = (eta2m1 / eta2) * (brewster / (w * w));
    (r_par.norm_sqr() + r_perp.norm_sqr()) / 2.0
}

/// Schlick 1994, "An inexpensive BRDF model for physically-based rendering":
/// `F0 + (1 − F0)(1 − c)⁵`.
pub fn schlick_f(c: f64, f0: f64) -> f64 {
    f0 + (1.0 - f0) * (1.0 - c).powi(5)
}
