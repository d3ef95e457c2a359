//! FORMULAS.md §2: microfacet distributions D. Each returns D in 1/sr (the normalised
//! forms satisfy `∫ D cos_h dω_h = 1`); none includes G, F or the 1/(4 cos cos) factor.

use super::frame::Frame;
use crate::material::{CookTorrance, Distribution, Roughness};
use std::f64::consts::PI;

/// Torrance & Sparrow 1967, "Theory for off-specular reflection from roughened surfaces":
/// `exp(−(δ/m)²)` with `δ = atan2(sin δ, cos δ)` (the seed prints `e^{−(αm)²}`, a typo).
/// Unnormalised: D = 1 at the peak.
pub fn gaussian_d(cos_h: f64, sin2_h: f64, m: f64) -> f64 {
    // atan2 of (sin, cos) keeps δ exact near 0, where acos(cos_h) loses half the digits.
    let delta = sin2_h.sqrt().atan2(cos_h);
    (-(delta / m).powi(2)).exp()
}

/// Beckmann 1963 (the Cook & Torrance 1982 form): `exp(−tan²δ/m²) / (k m² cos⁴δ)`, `k`
/// from the convention (seed 4, cook-torrance-1982 1, modern π).
pub fn beckmann_d(cos_h: f64, sin2_h: f64, m: f64, k: f64) -> f64 {
    let tan2 = sin2_h / (cos_h * cos_h);
    let e = (-tan2 / (m * m)).exp();
    let c4 = cos_h.powi(4);
    guarded_exp_ratio(e, c4, -tan2 / (m * m), k * m * m, cos_h)
}

/// Anisotropic Beckmann (Walter et al. 2007 / Heitz 2014, modern convention):
/// `exp(−((hx/mx)² + (hy/my)²)/hz²) / (π mx my hz⁴)`.
pub fn beckmann_aniso_d(h_local: [f64; 3], mx: f64, my: f64) -> f64 {
    let [hx, hy, hz] = h_local;
    let arg = -((hx / mx).powi(2) + (hy / my).powi(2)) / (hz * hz);
    guarded_exp_ratio(arg.exp(), hz.powi(4), arg, PI * mx * my, hz)
}

/// `exp(arg) / (norm · cos⁴)`, where `e = exp(arg)` and `c4 = cos⁴` were computed directly.
///
/// Near grazing, `exp(arg)` underflows to 0 while `1/cos⁴` overflows: the direct product
/// is then 0·∞ = NaN (or a spurious 0 where the true value is representable). In that case
/// evaluate in the log domain, `exp(arg − 4 ln cos − ln norm)`; otherwise keep the direct
/// form, which is exact to a few ulps.
fn guarded_exp_ratio(e: f64, c4: f64, arg: f64, norm: f64, cos: f64) -> f64 {
    if e.is_normal() && c4.is_normal() {
        e / (norm * c4)
    } else {
        (arg - 4.0 * cos.ln() - norm.ln()).exp()
    }
}

/// Trowbridge & Reitz 1975; Walter et al. 2007, "Microfacet models for refraction through
/// rough surfaces" (GGX): `m² / (π cos⁴δ (m² + tan²δ)²)`.
///
/// Evaluated as `m² / (π (m² cos²δ + sin²δ)²)`, the same value with `cos⁴` multiplied
/// through: it has no `tan²`, so nothing overflows as `cos δ → 0`.
pub fn ggx_d(cos_h: f64, sin2_h: f64, m: f64) -> f64 {
    let m2 = m * m;
    let denom = m2 * cos_h * cos_h + sin2_h;
    m2 / (PI * denom * denom)
}

/// Anisotropic GGX (Burley 2012; Heitz 2014): `1 / (π mx my ((hx/mx)² + (hy/my)² + hz²)²)`.
pub fn ggx_aniso_d(h_local: [f64; 3], mx: f64, my: f64) -> f64 {
    let [hx, hy, hz] = h_local;
    let s = (hx / mx).powi(2) + (hy / my).powi(2) + hz * hz;
    1.0 / (PI * mx * my * s * s)
}

/// Blinn 1977, "Models of light reflection for computer synthesized pictures", normalised
/// so that `∫ D cos_h dω = 1`: `(e + 2)/(2π) cos_h^e`.
pub fn blinn_d(cos_h: f64, sin2_h: f64, exponent: f64) -> f64 {
    (exponent + 2.0) / (2.0 * PI) * cos_pow(cos_h, sin2_h, exponent)
}

/// Estevez & Kulla 2017, "Production Friendly Microfacet Sheen BRDF" (the "Charlie"
/// sheen): `(2 + 1/m)/(2π) sin_h^(1/m)`, `0 < m ≤ 1` (the paper's α = r²). Normalised:
/// `∫ D cos_h dω = 1`. 0 at `sin_h = 0`.
///
/// `sin_h^(1/m)` is [`cos_pow`] of the complementary angle (`sin_h` with `1 − sin_h² =
/// cos_h²`): where `h` is near grazing, `ln sin_h` comes from `cos_h²` (`ln_1p`), not from
/// `sin_h` rounded next to 1, whose error the exponent 1/m (up to 1e7) would multiply.
pub fn charlie_d(cos_h: f64, sin2_h: f64, m: f64) -> f64 {
    let e = 1.0 / m;
    (2.0 + e) / (2.0 * PI) * cos_pow(sin2_h.sqrt(), cos_h * cos_h, e)
}

/// `cos^e` of an angle given both `cos > 0` and `sin² = 1 − cos²` (each accurate), as
/// `exp(e ln cos)`.
///
/// Near the pole `ln cos = ln(1 − sin²)/2` is taken from `sin²` (`ln_1p`): `cos` itself is
/// 1 − sin²/2 rounded to 53 bits, so `cos.powf(e)` carries a relative error of ~e·u
/// (2e-12 for e = 10⁴ at normal incidence) where the exact value moves by only ~e·u·sin².
/// `e = 0` is 1 (also where `cos` underflows to 0, which `0·ln 0` would turn into NaN).
pub fn cos_pow(cos: f64, sin2: f64, e: f64) -> f64 {
    if e == 0.0 {
        return 1.0;
    }
    let ln_cos = if sin2 < 0.5 {
        0.5 * (-sin2).ln_1p()
    } else {
        cos.ln()
    };
    (e * ln_cos).exp()
}

/// D of §2 for the material's distribution.
pub fn microfacet_d(fr: &Frame, ct: &CookTorrance) -> f64 {
    match ct.distribution {
        Distribution::Gaussian { m } => gaussian_d(fr.cos_h, fr.sin2_h, m),
        Distribution::Beckmann(Roughness::Isotropic(m)) => beckmann_d(
            fr.cos_h,
            fr.sin2_h,
            m,
            super::convention::beckmann_k(ct.convention),
        ),
        Distribution::Beckmann(Roughness::Anisotropic(mx, my)) => beckmann_aniso_d(
            fr.h_local().expect("anisotropic frame has a tangent"),
            mx,
            my,
        ),
        Distribution::Ggx(Roughness::Isotropic(m)) => ggx_d(fr.cos_h, fr.sin2_h, m),
        Distribution::Ggx(Roughness::Anisotropic(mx, my)) => ggx_aniso_d(
            fr.h_local().expect("anisotropic frame has a tangent"),
            mx,
            my,
        ),
        Distribution::Blinn { exponent } => blinn_d(fr.cos_h, fr.sin2_h, exponent),
        Distribution::Charlie { m } => charlie_d(fr.cos_h, fr.sin2_h, m),
    }
}
