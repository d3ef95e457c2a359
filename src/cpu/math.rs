//! Branch-free f32 helpers for the lanes (the GLSL kernel's `exp_acc` and `erfc_nr`,
//! `glsl/math.glsl`, measured there against f64): written so that a loop over lanes
//! vectorises — no calls into libm, no data-dependent branches.

/// ln 2 split into a high part with trailing zero bits (k · LN2_HI is exact for |k| < 2^9)
/// and the rest (Cody–Waite).
const LN2_HI: f32 = 0.693_145_75;
const LN2_LO: f32 = 1.428_606_8e-6;

/// 1.5 · 2^23: adding and subtracting it rounds an f32 of magnitude < 2^22 to an integer
/// without `floor` (a libm call below SSE4.1, which stops vectorisation).
const ROUND_MAGIC: f32 = 12_582_912.0;

/// e^x in f32 to about 2 ulp for x ≤ 0 (the lanes only need x ≤ 0): Cody–Waite reduction
/// x = k ln2 + r, |r| ≤ ln2/2, a degree-7 Taylor polynomial (truncation < 6e-9 relative)
/// and an exact scaling by 2^k built from the exponent bits. Below ln(FLT_MIN) = −87.3 the
/// result is 0: 2^k would leave the normal range there, and the bit pattern would not be
/// a power of two.
#[inline(always)]
pub fn exp_neg(x: f32) -> f32 {
    let xc = if x < -87.0 { -87.0 } else { x };
    let k = (xc * std::f32::consts::LOG2_E + ROUND_MAGIC) - ROUND_MAGIC;
    let r = (xc - k * LN2_HI) - k * LN2_LO;
    let p = 1.0
        + r * (1.0
            + r * (1.0 / 2.0
                + r * (1.0 / 6.0
                    + r * (1.0 / 24.0
                        + r * (1.0 / 120.0 + r * (1.0 / 720.0 + r * (1.0 / 5040.0)))))));
    let scale = f32::from_bits(((k as i32 + 127) as u32) << 23);
    if x < -87.0 {
        0.0
    } else {
        p * scale
    }
}

/// erfc(z) for z ≥ 0 (Numerical Recipes' `erfcc`, a Chebyshev fit with fractional error
/// < 1.2e-7): relative error ≤ 5e-7 for z < 1 and ~2 z² u beyond, from the rounding of −z²
/// in the exponent — absolute error far below what `G = 1/(1 + Λ)` can see.
#[inline(always)]
#[allow(clippy::excessive_precision)] // the published coefficients, digit for digit
pub fn erfc(z: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.5 * z);
    let p = -z * z - 1.265_512_2
        + t * (1.000_023_7
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_9
                                + t * (1.488_515_9 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    t * exp_neg(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_neg_is_within_a_few_ulp_of_f64_exp() {
        let mut worst = 0f64;
        for i in 0..200_000 {
            let x = -87.0 * f64::from(i) / 200_000.0;
            let got = f64::from(exp_neg(x as f32));
            let want = f64::from(x as f32).exp();
            worst = worst.max(((got - want) / want).abs());
        }
        assert!(worst < 5e-7, "worst relative error {worst}");
        assert_eq!(exp_neg(-88.0), 0.0);
        assert_eq!(exp_neg(f32::NEG_INFINITY), 0.0);
    }

    #[test]
    fn erfc_matches_libm_in_absolute_terms() {
        for i in 0..10_000 {
            let z = 9.0 * f64::from(i) / 10_000.0;
            let got = f64::from(erfc(z as f32));
            let want = libm::erfc(f64::from(z as f32));
            let err = (got - want).abs();
            assert!(
                err <= 5e-7 && err <= 1e-5 * want + 1e-30,
                "z = {z}: {got} vs {want}"
            );
        }
    }
}
