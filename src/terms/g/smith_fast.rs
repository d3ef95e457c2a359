//! Walter et al. 2007's rational fit of Smith–Beckmann G1 (≤ 0.35 % error), kept as
//! published: `G = G1(v) G1(l)`, `G1 = a < 1.6 ? (3.535a + 2.181a²)/(1 + 2.276a + 2.577a²)
//! : 1` with `a = 1/(m tan θ)`. Beckmann only.

use crate::terms::d::DistributionKind;

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
/// and `sin²` and m: `a = cos/(m sin)` of both over one division, `1/(m² sin_i sin_o)`,
/// and the two fits' quotients multiplied, so that the lane divides once more for D·G·K
/// (6 divisions become 1). A sine below 1e-12 is taken as 1e-12, where `a` ≥ 1e4 is far
/// past the fit's 1.6 and G1 = 1 either way; that floor keeps `m sin_i sin_o` ≥ 1e-31 for
/// m ≥ 1e-7. An `a` past 1.6 (or non-finite) takes the fit's 1 as `1/1`.
#[inline(always)]
pub fn g_ratio(cos_i: f32, sin2_i: f32, cos_o: f32, sin2_o: f32, m: f32) -> (f32, f32) {
    let (s_i, s_o) = (sin2_i.sqrt().max(1e-12), sin2_o.sqrt().max(1e-12));
    let inv = 1.0 / (m * s_i * s_o);
    let fit = |a: f32| {
        let (n, d) = (3.535 * a + 2.181 * a * a, 1.0 + 2.276 * a + 2.577 * a * a);
        if a < 1.6 {
            (n, d)
        } else {
            (1.0, 1.0)
        }
    };
    let (n_i, d_i) = fit(cos_i * s_o * inv);
    let (n_o, d_o) = fit(cos_o * s_i * inv);
    (n_i * n_o, d_i * d_o)
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
