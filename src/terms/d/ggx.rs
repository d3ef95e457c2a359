//! Trowbridge & Reitz 1975; Walter et al. 2007, "Microfacet models for refraction through
//! rough surfaces" (GGX): `m² / (π cos⁴δ (m² + tan²δ)²)`; anisotropic (Burley 2012; Heitz
//! 2014, modern convention only) `1 / (π mx my ((hx/mx)² + (hy/my)² + hz²)²)`; and its
//! Smith Λ `(−1 + √(1 + m² tan²θ))/2` (Walter et al. 2007; Heitz 2014).

use crate::terms::f::conductor::METAL_FORM_BUDGET;
use crate::terms::k::Convention;
use crate::terms::math::MulAdd;
use crate::terms::real::Real;
use std::f64::consts::PI;

/// The spelling in a materials file.
pub const NAME: &str = "ggx";
/// The work the formula comes from.
pub const CITATION: &str = "Trowbridge & Reitz 1975; Walter et al. 2007";
/// It has Smith's Λ ([`lambda`]).
pub const HAS_LAMBDA: bool = true;

/// Its rule for anisotropic roughness: defined in the `modern` convention only.
pub fn anisotropic(convention: Convention) -> Result<(), String> {
    super::rules::anisotropic_in_modern(NAME, convention)
}

/// D in f64, evaluated as `m² / (π (m² cos²δ + sin²δ)²)`, the same value with `cos⁴`
/// multiplied through: it has no `tan²`, so nothing overflows as `cos δ → 0`.
pub fn d(cos_h: f64, sin2_h: f64, m: f64) -> f64 {
    let m2 = m * m;
    let denom = m2 * cos_h * cos_h + sin2_h;
    m2 / (PI * denom * denom)
}

/// D in f64, anisotropic, from h in the tangent frame.
pub fn d_aniso(h_local: [f64; 3], mx: f64, my: f64) -> f64 {
    let [hx, hy, hz] = h_local;
    let s = (hx / mx).powi(2) + (hy / my).powi(2) + hz * hz;
    1.0 / (PI * mx * my * s * s)
}

/// Smith's Λ in f64, given `x = m² tan²θ`.
///
/// Evaluated as `x / (2 (1 + √(1 + x)))` for `x ≤ 1`: the textbook form cancels for small
/// `x` (near normal incidence or tiny m) and returns 0 for x < 1e-16. For `x > 1` the
/// textbook form has no cancellation and stays ∞ (G = 0) where `x` overflows, where the
/// quotient would be ∞/∞ = NaN.
pub fn lambda(x: f64) -> f64 {
    let r = (1.0 + x).sqrt();
    if x <= 1.0 {
        x / (2.0 * (1.0 + r))
    } else {
        0.5 * (r - 1.0)
    }
}

/// D in a lane of the f32 frame as a quotient `(norm, s²)`, given `m²` and `m²/π` rounded
/// once, for a lane that takes D·G·K over one division (`s² ∈ [min(m², 1)², (1 + m²)²]`
/// on the f32 frame's materials, m ≥ 0.075: the square stays normal).
#[inline(always)]
pub fn d_ratio32<A: MulAdd, T: Real>(cos_h: T, sin2_h: T, m2: f32, norm: f32) -> (T, T) {
    let s = A::mul_add(cos_h.splat_as(m2), cos_h * cos_h, sin2_h);
    (cos_h.splat_as(norm), s * s)
}

/// The relative error of D that the local form's f32 frame (`cpu::frame::frame_local32`)
/// may add through its rounding of h, beside the rest of the frame (~14u, u = 2⁻²⁴), F
/// (≤ 48u with the conductor's metal form, `conductor::METAL_FORM_BUDGET`) and D's, G's
/// and K's own f32 arithmetic (~25u): 4e-6 + 87u = 9.2e-6 stays inside FORMULAS.md §1's
/// 1e-5 (docs/CPU_ENGINE.md, "The f32 frame's error bound").
pub const LOCAL_FRAME_D_BUDGET: f64 = 4e-6;

/// The constant of [`local_frame_ok`] for roughness² `m2`: `16 (1 − m²)² u²/B²`, with
/// B = [`LOCAL_FRAME_D_BUDGET`].
pub fn local_frame_guard(m2: f64) -> f32 {
    local_frame_guard_within(m2, LOCAL_FRAME_D_BUDGET)
}

/// [`local_frame_guard`] for a material whose F is bounded by `f_u` (in u) rather than
/// by the metal form's budget (48u): the total stays 9.2e-6, so D may take what F leaves,
/// `B = 4e-6 + (48 − f_u) u` (the conductor's fitted polynomial: 5–21u, `B` 5.6–6.5e-6).
/// `f_u` above the metal form's budget gives [`local_frame_guard`].
pub fn local_frame_guard_for_f(m2: f64, f_u: f64) -> f32 {
    let u = f64::from(f32::EPSILON) / 2.0;
    let spare = (METAL_FORM_BUDGET - f_u).max(0.0);
    local_frame_guard_within(m2, LOCAL_FRAME_D_BUDGET + spare * u)
}

/// `16 (1 − m²)² u²/B²` for D's budget `B`.
fn local_frame_guard_within(m2: f64, b: f64) -> f32 {
    let u = f64::from(f32::EPSILON) / 2.0;
    (16.0 * (1.0 - m2) * (1.0 - m2) * u * u / (b * b)) as f32
}

/// Whether D at this lane moves by at most [`LOCAL_FRAME_D_BUDGET`] (relative) when h is
/// turned by the local f32 frame's bound `δ = u (4.5/c + 1)` radians: D's slope
/// `|∂ ln D/∂θ_h| = 4 |1 − m²| sin θ_h cos θ_h/s`, `s = m² cos² θ_h + sin² θ_h` (at most
/// `2|1 − m²|/m`, at tan θ_h = m), times δ, squared so that neither a root nor a division
/// is taken: `guard · sin² cos² (4.5 + c)² ≤ (s c)²` with `guard` from
/// [`local_frame_guard`]. Every operand is the f32 frame's own (their few-u errors move the
/// test, not the bound, by a few u).
#[inline(always)]
pub fn local_frame_ok<T: Real>(cos_h: T, sin2_h: T, c: T, m2: f32, guard: f32) -> T::Mask {
    let cos2 = cos_h * cos_h;
    let s = cos2 * m2 + sin2_h;
    let a = c + 4.5;
    (cos_h.splat_as(guard) * (sin2_h * cos2) * (a * a)).le((s * c) * (s * c))
}

/// D in a lane of the f64 frame: as [`d`], in f64 because the square of the sum leaves
/// f32's normal range for m near its lower bound.
#[inline(always)]
pub fn d_lane64(cos_h2: f64, sin2_h: f64, m2: f64, norm: f64) -> f32 {
    let s = m2 * cos_h2 + sin2_h;
    (norm / (s * s)) as f32
}

/// Anisotropic D in a lane (f64 frame), given `(hx/mx)² + (hy/my)²`, `hz²` and
/// `1/(π mx my)`: no 1/hz⁴ to overflow.
#[inline(always)]
pub fn d_aniso_lane(slope2: f64, cos_h2: f64, norm: f64) -> f32 {
    let s = slope2 + cos_h2;
    (norm / (s * s)) as f32
}

/// `R = √(cos² + m² sin²)` in a lane: GGX's Λ in root form, `1 + 2Λ = R/cos`, which the
/// Smith terms' quotients (`smith::g_ratio_ggx`, `smith_correlated::g_ratio_ggx`) take
/// without a division and without Λ's cancellation for small `m² tan²θ`.
#[inline(always)]
pub fn lambda_root_lane<A: MulAdd, T: Real>(cos: T, sin2: T, m2: f32) -> T {
    A::mul_add(cos.splat_as(m2), sin2, cos * cos).sqrt()
}

/// Smith's Λ in a lane, given `q2 = m² tan²θ`, rewritten for `q2 ≤ 1` as [`lambda`].
#[inline(always)]
pub fn lambda_lane(q2: f32) -> f32 {
    let r = (1.0 + q2).sqrt();
    if q2 <= 1.0 {
        q2 / (2.0 * (1.0 + r))
    } else {
        0.5 * (r - 1.0)
    }
}

#[cfg(test)]
mod guard_tests {
    use super::*;

    /// D's certificate takes what F leaves of the metal form's 48u and no more: the same
    /// guard at 48u (and above), a smaller one (more lanes certified) below, and D's
    /// budget plus F's bound the same total, 4e-6 + 48u, whatever F's bound.
    #[test]
    fn the_guard_for_a_tighter_f_keeps_the_total() {
        let u = f64::from(f32::EPSILON) / 2.0;
        for m2 in [0.075f64 * 0.075, 0.09, 0.49, 2.25] {
            assert_eq!(local_frame_guard_for_f(m2, 48.0), local_frame_guard(m2));
            assert_eq!(local_frame_guard_for_f(m2, 60.0), local_frame_guard(m2));
            let (g, tight) = (local_frame_guard(m2), local_frame_guard_for_f(m2, 8.8));
            assert!(tight < g, "m² = {m2}: {tight} !< {g}");
            // guard = 16 (1 − m²)² u²/B², so B = 4u|1 − m²|/√guard.
            let b = 4.0 * u * (1.0 - m2).abs() / f64::from(tight).sqrt();
            let total = b + 8.8 * u;
            let want = LOCAL_FRAME_D_BUDGET + 48.0 * u;
            assert!((total - want).abs() < 1e-6 * want, "m² = {m2}: {total:e} vs {want:e}");
        }
    }
}
