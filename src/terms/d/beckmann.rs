//! Beckmann 1963, in the Cook & Torrance 1982 form: `exp(−tan²δ/m²) / (k m² cos⁴δ)`, `k`
//! from the convention (seed 4, cook-torrance-1982 1, modern π); anisotropic (Walter et
//! al. 2007 / Heitz 2014, modern convention only) `exp(−((hx/mx)² + (hy/my)²)/hz²) /
//! (π mx my hz⁴)`; and its Smith Λ (Walter et al. 2007, eq. 25 via Heitz 2014).

use crate::terms::math::{erfc, exp_neg, exp_neg_above, MulAdd};
use crate::terms::real::Real;
use crate::terms::k::Convention;
use std::f64::consts::PI;

/// The spelling in a materials file.
pub const NAME: &str = "beckmann";
/// The work the formula comes from.
pub const CITATION: &str = "Beckmann 1963; Cook & Torrance 1982";
/// It has Smith's Λ ([`lambda`]).
pub const HAS_LAMBDA: bool = true;

/// Its rule for anisotropic roughness: defined in the `modern` convention only.
pub fn anisotropic(convention: Convention) -> Result<(), String> {
    super::rules::anisotropic_in_modern(NAME, convention)
}

/// D in f64, isotropic, `k` the convention's normalisation ([`Convention::beckmann_k`]).
pub fn d(cos_h: f64, sin2_h: f64, m: f64, k: f64) -> f64 {
    let tan2 = sin2_h / (cos_h * cos_h);
    let e = (-tan2 / (m * m)).exp();
    let c4 = cos_h.powi(4);
    guarded_exp_ratio(e, c4, -tan2 / (m * m), k * m * m, cos_h)
}

/// D in f64, anisotropic, from h in the tangent frame.
pub fn d_aniso(h_local: [f64; 3], mx: f64, my: f64) -> f64 {
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

/// Smith's Λ in f64: `(erf(a) − 1)/2 + exp(−a²)/(2a√π)` with `a = 1/(m tan θ)`, given as
/// `a2_inv = m² tan²θ = 1/a²`.
///
/// Written as `(exp(−a²)/(a√π) − erfc(a))/2`: `erf(a) − 1` computed directly loses every
/// digit for a ≳ 6 (it is −erfc(a), below f64 resolution next to 1).
pub fn lambda(a2_inv: f64) -> f64 {
    if a2_inv == 0.0 {
        return 0.0; // tan θ = 0: the direction is the normal, nothing is hidden.
    }
    let a = (1.0 / a2_inv).sqrt();
    ((-a * a).exp() / (a * PI.sqrt()) - libm::erfc(a)) / 2.0
}

/// D in a lane of the f32 frame, given tan²θ_h (the frame's `tan2_h`), `1/m²` and
/// `1/(k m²)` rounded once: `1/cos⁴θ_h = (1 + tan²θ_h)²`, so D reads no cosine and no
/// division. The f32 frame's materials have m ≥ `FAST_MIN_ROUGHNESS` and its lanes
/// cos_h ≥ `GRAZING`, which keeps every quantity inside f32's normal range
/// (`1 + tan²` ≤ 1e8, the norm ≤ 5.7e17). `exp(−x)·norm` as `(e·norm)·e` with
/// `e = exp(−x/2)`, as [`d_lane64`]; 0 where `−x/2 < floor` ([`lane_exp_floor`]).
#[inline(always)]
pub fn d_lane32<A: MulAdd, T: Real>(tan2_h: T, inv_m2: f32, norm: f32, floor: f32) -> T {
    let sec2 = tan2_h + 1.0;
    let half_x = tan2_h * inv_m2 * 0.5;
    let e = exp_neg_above::<A, T>(half_x * -1.0, floor);
    e * (sec2 * norm * sec2) * e
}

/// Cosines (`cos_i`, `cos_o`, `cos_h`) of the lanes [`d_lane32`] serves are at least this
/// (`cpu::frame::GRAZING`; the f32 frames send smaller ones elsewhere).
const LANE_MIN_COS: f64 = 1e-4;

/// The argument of `exp` below which [`d_lane32`] gives 0: where D and the specular part
/// of f it enters are below 1e-12, a tenth of what the rule (FORMULAS.md §1) allows any
/// value at its floor (`1e-5 · 1e-6`), so 0 conforms. Without it, D's last product
/// `(e·norm)·e` and the products after it go subnormal on the lanes far in the tail (12 %
/// of the bench's uniform lanes at m = 0.3), and x86 takes a microcode assist for each
/// such register.
///
/// With `e = exp(−x/2)` and `−x/2 < floor`: D = e²·norm/cos⁴_h < e^{2 floor}·norm/LANE_MIN_COS⁴,
/// and the specular part `s c_spec · D·G·F·K` ≤ that times `weight` = `s c_spec` · G's
/// largest (smith-fast's fit reaches 1.000123) · F's largest (`f_max`: 1 but for a Schlick
/// F0 above it) · K's largest at these cosines over every convention (`1/(π cos_i cos_o)`).
/// So `floor = −½ ln(norm · max(1, weight) / (LANE_MIN_COS⁴ · 1e-12))`, at least −87
/// (`exp_neg`'s own range): −41.5 for the bench's m = 0.3.
pub fn lane_exp_floor(norm: f64, spec_max: f64, f_max: f64) -> f32 {
    let k_max = 1.0 / (PI * LANE_MIN_COS * LANE_MIN_COS);
    let weight = (spec_max * 1.000_123 * f_max.max(1.0) * k_max).max(1.0);
    let half = 0.5 * (norm * weight / (LANE_MIN_COS.powi(4) * 1e-12)).ln();
    // A NaN or a non-positive norm (no Beckmann material has one) keeps exp_neg's range.
    if half.is_finite() && half > 0.0 {
        (-half).max(-87.0) as f32
    } else {
        -87.0
    }
}

/// D in a lane of the f64 frame: `exp(−tan²/m²)/(k m² cos⁴)` as `(e·norm)·e` with
/// `e = exp(−tan²/(2m²))`: each factor stays in f32's range until tan²/m² ≈ 174, where the
/// direct `exp(−x)·norm` would already have underflowed to 0 next to a large norm.
#[inline(always)]
pub fn d_lane64(cos_h2: f64, sin2_h: f64, inv_m2: f64, norm: f64) -> f32 {
    let ic = 1.0 / cos_h2;
    let half_x = (sin2_h * ic * inv_m2 * 0.5) as f32;
    let e = exp_neg(-half_x);
    let norm = (norm * ic * ic) as f32;
    e * norm * e
}

/// Anisotropic D in a lane (f64 frame), given `(hx/mx)² + (hy/my)²`, `hz²` and
/// `1/(π mx my)`: `exp(−slope²/hz²)/(π mx my hz⁴)` as `(e·norm)·e`, as [`d_lane64`].
#[inline(always)]
pub fn d_aniso_lane(slope2: f64, cos_h2: f64, norm: f64) -> f32 {
    let e = exp_neg(-(slope2 / cos_h2 * 0.5) as f32);
    let norm = (norm / (cos_h2 * cos_h2)) as f32;
    e * norm * e
}

/// Smith's Λ in a lane, given `q2 = m² tan²θ`: `(exp(−a²)/(a√π) − erfc(a))/2`,
/// `a = 1/√q2`, as [`lambda`]; q2 = 0 (w = n) is Λ = 0, where a = ∞ would make inf·0.
#[inline(always)]
pub fn lambda_lane(q2: f32) -> f32 {
    let a = 1.0 / q2.sqrt();
    let v = 0.5 * (exp_neg(-a * a) * (std::f32::consts::FRAC_2_SQRT_PI * 0.5) / a - erfc(a));
    if q2 == 0.0 {
        0.0
    } else {
        v
    }
}
