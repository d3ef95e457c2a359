//! Smith 1967, separable: `G = G1(v) · G1(l)`, `G1 = 1/(1 + Λ)`, Λ the distribution's
//! (Walter et al. 2007; Heitz 2014). Needs a distribution with Λ (Beckmann, GGX).

use crate::terms::d::{ggx, DistributionKind};
use crate::terms::math::MulAdd;
use crate::terms::real::Real;

/// The spelling in a materials file.
pub const NAME: &str = "smith";
/// The work the formula comes from.
pub const CITATION: &str = "Smith 1967; Walter et al. 2007";

/// Its rule: the distribution must have a Λ.
pub fn legality(d: DistributionKind, _anisotropic: bool) -> Result<(), String> {
    super::rules::needs_lambda(d)
}

/// G in f64 from Λ of each direction.
pub fn g(lambda_o: f64, lambda_i: f64) -> f64 {
    1.0 / (1.0 + lambda_o) * (1.0 / (1.0 + lambda_i))
}

/// G in a lane (f32) from Λ of each direction.
#[inline(always)]
pub fn g_lane(lambda_o: f32, lambda_i: f32) -> f32 {
    1.0 / (1.0 + lambda_o) * (1.0 / (1.0 + lambda_i))
}

/// GGX's G in a lane as a quotient `(num, den)`, with no division: GGX's
/// `1 + Λ = (1 + √(1 + m² tan²θ))/2 = (cos + R)/(2 cos)`, `R = √(cos² + m² sin²)`, so
/// `G = 4 cos_i cos_o/((cos_i + R_i)(cos_o + R_o))` — sums of positive terms, nothing
/// cancels (Λ's own `(√(1 + q²) − 1)/2` would, for small q²) — and the lane divides once
/// for D·G·K. The denominator is within [4e-8, (1 + m)⁴] for cosines ≥ 1e-4.
#[inline(always)]
pub fn g_ratio_ggx<A: MulAdd, T: Real>(cos_i: T, sin2_i: T, cos_o: T, sin2_o: T, m2: f32) -> (T, T) {
    let r_i = ggx::lambda_root_lane::<A, T>(cos_i, sin2_i, m2);
    let r_o = ggx::lambda_root_lane::<A, T>(cos_o, sin2_o, m2);
    (cos_i * 4.0 * cos_o, (cos_i + r_i) * (cos_o + r_o))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sweep both GGX quotients are tested on: grazing to normal cosines (sin² from
    /// the f64 cosine, as the frame gives it, and exactly 0 at the normal) and roughness
    /// from the f64 frame's smallest to the largest legal, each lane's `(cos, sin², m²)`.
    fn sweep() -> Vec<(f32, f32, f32)> {
        let mut v = Vec::new();
        for c in [1e-4f64, 1e-3, 0.01, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99, 0.9999, 1.0] {
            for m in [1e-7f64, 1e-3, 0.075, 0.3, 1.0, 10.0, 1e4] {
                v.push((c as f32, ((1.0 - c) * (1.0 + c)) as f32, (m * m) as f32));
            }
        }
        v
    }

    /// q2 = m² tan²θ in f64 of a lane's f32 values.
    fn q2(w: (f32, f32, f32)) -> f64 {
        let (c, s2, m2) = (f64::from(w.0), f64::from(w.1), f64::from(w.2));
        m2 * s2 / (c * c)
    }

    /// Both division-free quotients (separable and, from `smith_correlated`, height-
    /// correlated) against their `g` of GGX's f64 Λ on the same f32 values.
    #[test]
    fn the_ggx_quotients_are_g_of_lambda() {
        use crate::terms::g::smith_correlated;
        type Ratio = fn(f32, f32, f32, f32, f32) -> (f32, f32);
        type Exact = fn(f64, f64) -> f64;
        use crate::terms::math::{Fused, Rounded};
        let forms: [(Ratio, Exact); 4] = [
            (g_ratio_ggx::<Rounded, f32>, g),
            (smith_correlated::g_ratio_ggx::<Rounded, f32>, smith_correlated::g),
            (g_ratio_ggx::<Fused, f32>, g),
            (smith_correlated::g_ratio_ggx::<Fused, f32>, smith_correlated::g),
        ];
        let s = sweep();
        for (ratio, exact) in forms {
            let mut worst = 0f64;
            for &i in &s {
                for &o in s.iter().filter(|o| o.2 == i.2) {
                    let (n, d) = ratio(i.0, i.1, o.0, o.1, i.2);
                    let want = exact(ggx::lambda(q2(o)), ggx::lambda(q2(i)));
                    worst = worst.max((f64::from(n / d) - want).abs() / want);
                }
            }
            // Measured 2.0e-7 (separable) and 1.5e-7 (correlated): a few f32 roundings.
            assert!(worst < 3e-7, "{worst:e}");
        }
    }
}
