//! Walter et al. 2007's rational fit of Smith–Beckmann G1 (≤ 0.35 % error), kept as
//! published: `G = G1(v) G1(l)`, `G1 = a < 1.6 ? (3.535a + 2.181a²)/(1 + 2.276a + 2.577a²)
//! : 1` with `a = 1/(m tan θ)`. Beckmann only.

use crate::terms::d::DistributionKind;
use crate::terms::math::MulAdd;
use crate::terms::real::Real;

/// The spelling in a materials file.
pub const NAME: &str = "smith-fast";
/// The work the formula comes from.
pub const CITATION: &str = "Walter et al. 2007";

/// Its rule: a fit of Smith–Beckmann, so Beckmann only (and a Λ, as every Smith term).
pub fn legality(d: DistributionKind, _anisotropic: bool) -> Result<(), String> {
    super::rules::needs_lambda(d)?;
    if d != DistributionKind::Beckmann {
        return Err("`smith-fast` is a fit of Smith–Beckmann (Beckmann only); use `smith` or `smith-correlated` with ggx".into());
    }
    Ok(())
}

/// G1 in f64, given `a2_inv = m² tan²θ`.
pub fn g1(a2_inv: f64) -> f64 {
    let a = (1.0 / a2_inv).sqrt(); // a2_inv = 0 gives a = ∞ and G1 = 1
    if a < 1.6 {
        (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    } else {
        1.0
    }
}

/// G of both directions in a lane as a quotient `(num, den)`, given each direction's cosine
/// and `sin²` and m: each fit's quotient with numerator and denominator multiplied by
/// `t² = (m sin θ)²` (`fit_scaled`), which takes `a = cos/t` out of it, and the two
/// quotients multiplied, so that the lane's one division for D·G·K is G's too (6
/// divisions become 0 here).
#[inline(always)]
pub fn g_ratio<A: MulAdd, T: Real>(cos_i: T, sin2_i: T, cos_o: T, sin2_o: T, m: f32) -> (T, T) {
    let (n_i, d_i) = fit_scaled::<A, T>(cos_i, sin2_i, m);
    let (n_o, d_o) = fit_scaled::<A, T>(cos_o, sin2_o, m);
    (n_i * n_o, d_i * d_o)
}

/// The fit of G1 at `a = cos/t`, `t = m sin θ`, as `(num, den)` times t²:
/// `cos (3.535 t + 2.181 cos)` over `t² + 2.276 cos t + 2.577 cos²` — sums of positive
/// terms, each within a few u, as the quotient in `a` was — and `(1, 1)` where
/// `a ≥ 1.6`, tested as `cos² ≥ 2.56 t²` (true for NaN; a sine of 0 makes t = 0 and
/// takes it too, where `a = ∞`). A function, not a closure: a closure in a lane form was
/// left out of line on the register path, where its intrinsics then became calls.
///
/// Range, on the lanes that take it (cos ≥ `GRAZING` = 1e-4): where the fit is taken,
/// t > cos/1.6, so every product stays normal down to D·G·K values of 1e-11 and below,
/// which is all the rule can see (FORMULAS.md §1: its floor's absolute 1e-11).
#[inline(always)]
fn fit_scaled<A: MulAdd, T: Real>(cos: T, sin2: T, m: f32) -> (T, T) {
    let t = sin2.sqrt() * m;
    let t2 = t * t;
    let c2 = cos * cos;
    let n = A::mul_add(t, t.splat_as(3.535), cos * 2.181) * cos;
    let d = A::mul_add(c2, c2.splat_as(2.577), A::mul_add(cos * 2.276, t, t2));
    let (past, one) = (!c2.lt(t2 * 2.56), cos.splat_as(1.0));
    (T::select(past, one, n), T::select(past, one, d))
}

/// G1 in a lane (f32), given `q2 = m² tan²θ`.
#[inline(always)]
pub fn g1_lane(q2: f32) -> f32 {
    let a = 1.0 / q2.sqrt(); // q2 = 0: a = ∞ and G1 = 1
    let r = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
    if a < 1.6 {
        r
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quotient of both directions against `g1 · g1` in f64 on the same f32 values:
    /// cosines from grazing to the normal (sin = 0, the floor's case), m from the f64
    /// frame's smallest to the largest legal, and `a` a hair either side of the fit's 1.6.
    #[test]
    fn the_quotient_is_the_product_of_the_fits() {
        let mut lanes: Vec<(f32, f32, f64)> = Vec::new();
        for m in [1e-7f64, 1e-3, 0.075, 0.3, 1.0, 10.0, 1e4] {
            for c in [1e-4f64, 0.01, 0.3, 0.7, 0.99, 1.0] {
                lanes.push((c as f32, ((1.0 - c) * (1.0 + c)) as f32, m));
            }
            for a in [1.6 * (1.0 - 1e-4), 1.6 * (1.0 + 1e-4), 0.5, 1.2] {
                // cos/(m sin) = a: tan θ = 1/(a m).
                let t: f64 = 1.0 / (a * m);
                let c = 1.0 / (1.0 + t * t).sqrt();
                lanes.push((c as f32, (t * t * c * c) as f32, m));
            }
        }
        let mut worst = 0f64;
        for (&i, fused) in lanes.iter().flat_map(|i| [(i, false), (i, true)]) {
            for &o in lanes.iter().filter(|o| o.2 == i.2) {
                let m = i.2;
                let (n, d) = if fused {
                    g_ratio::<crate::terms::math::Fused, f32>(i.0, i.1, o.0, o.1, m as f32)
                } else {
                    g_ratio::<crate::terms::math::Rounded, f32>(i.0, i.1, o.0, o.1, m as f32)
                };
                let q2 = |w: (f32, f32, f64)| {
                    let c = f64::from(w.0);
                    f64::from(m as f32).powi(2) * f64::from(w.1) / (c * c)
                };
                let want = g1(q2(o)) * g1(q2(i));
                worst = worst.max((f64::from(n / d) - want).abs() / want);
            }
        }
        // Measured 3.6e-7 (a few f32 roundings of G), with and without FMA.
        assert!(worst < 5e-7, "{worst:e}");
    }
}
