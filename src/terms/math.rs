//! The math the terms' forms share: branch-free f32 (and one f64) helpers for the lanes
//! (the GLSL kernel's `exp_acc` and `erfc_nr`, `glsl/math.glsl`, measured there against
//! f64), written so that a loop over lanes vectorises — no calls into libm, no
//! data-dependent branches; and the f64 power of a cosine the `cos^e` lobes share.

use super::real::{Real, Wide};

/// How the lanes form `a·b + c`: [`Fused`] with one rounding where their instruction set
/// has a fused multiply–add, [`Rounded`] with two where it has none (`f32::mul_add` is a
/// call into libm there: the scalar variant ran 3.3× the instructions). The engine picks
/// it with the instruction set, so a variant's bits never depend on where a lane runs.
pub trait MulAdd {
    /// `a·b + c`, in one lane or a register of them ([`Real`]).
    fn mul_add<T: Real>(a: T, b: T, c: T) -> T;
    /// `a·b + c` in f64.
    fn mul_add64(a: f64, b: f64, c: f64) -> f64;
    /// `a·b + c` in f64 lanes ([`Wide`]).
    fn mul_add_wide<W: Wide>(a: W, b: W, c: W) -> W;
}

/// `a·b + c` rounded once (FMA): the AVX2+FMA and AVX-512 lanes'.
pub struct Fused;

/// `a·b + c` rounded twice: the lanes of an instruction set without FMA.
pub struct Rounded;

impl MulAdd for Fused {
    #[inline(always)]
    fn mul_add<T: Real>(a: T, b: T, c: T) -> T {
        a.fused_mul_add(b, c)
    }

    #[inline(always)]
    fn mul_add64(a: f64, b: f64, c: f64) -> f64 {
        a.mul_add(b, c)
    }

    #[inline(always)]
    fn mul_add_wide<W: Wide>(a: W, b: W, c: W) -> W {
        a.fused_mul_add(b, c)
    }
}

impl MulAdd for Rounded {
    #[inline(always)]
    fn mul_add<T: Real>(a: T, b: T, c: T) -> T {
        a * b + c
    }

    #[inline(always)]
    fn mul_add64(a: f64, b: f64, c: f64) -> f64 {
        a * b + c
    }

    #[inline(always)]
    fn mul_add_wide<W: Wide>(a: W, b: W, c: W) -> W {
        a * b + c
    }
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
pub fn exp_neg<T: Real>(x: T) -> T {
    exp_neg_above::<Rounded, T>(x, -87.0)
}

/// [`exp_neg`] with 0 below `floor` (≥ −87) instead of below −87: for a caller whose
/// result is below what the rule can tell from 0 once `x < floor`, and whose products of
/// such tiny values would otherwise leave f32's normal range (subnormal operands and
/// results cost a microcode assist a register on x86). Its multiply-adds as `A` forms
/// them: with [`Rounded`] the same bits as [`exp_neg`] for `x ≥ floor`; with [`Fused`]
/// half the operations (a lane form's, where the instruction set has FMA).
#[inline(always)]
pub fn exp_neg_above<A: MulAdd, T: Real>(x: T, floor: f32) -> T {
    let below = x.lt_scalar(floor);
    let xc = T::select(below, x.splat_as(floor), x);
    // k = round(x log₂e) in the low bits of `t` (ROUND_MAGIC's ulp is 1), taken from them
    // as an integer: `k as i32` on the float is a saturating cast, which LLVM does not
    // vectorise (it made every lane of a block a scalar conversion and compare, a third of
    // Beckmann's block). 2^k's bits are `(k + 127) << 23`, i.e. `t`'s bits shifted, plus
    // `(127 − ROUND_MAGIC's bits) << 23`, wrapping.
    let t = A::mul_add(
        xc,
        xc.splat_as(std::f32::consts::LOG2_E),
        xc.splat_as(ROUND_MAGIC),
    );
    let k = t - ROUND_MAGIC;
    // k·LN2_HI is exact (LN2_HI's low bits are zero), so `xc − k·LN2_HI` is one rounding
    // either way.
    let r = A::mul_add(
        k,
        k.splat_as(-LN2_LO),
        A::mul_add(k, k.splat_as(-LN2_HI), xc),
    );
    // Estrin's scheme: the same polynomial at depth 4 instead of Horner's 7, so that a
    // register path, which has few lanes in flight, does not wait on one long chain.
    let r2 = r * r;
    let r4 = r2 * r2;
    let poly = |a: f32, b: f32| A::mul_add(r, r.splat_as(a), r.splat_as(b));
    let (p01, p23) = (r + 1.0, poly(1.0 / 6.0, 1.0 / 2.0));
    let (p45, p67) = (
        poly(1.0 / 120.0, 1.0 / 24.0),
        poly(1.0 / 5040.0, 1.0 / 720.0),
    );
    let p = A::mul_add(A::mul_add(p67, r2, p45), r4, A::mul_add(p23, r2, p01));
    const BIAS: u32 = 127u32.wrapping_sub(ROUND_MAGIC.to_bits()) << 23;
    let scale = t.exponent_bits(BIAS);
    T::select(below, x.splat_as(0.0), p * scale)
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

/// ln(1 + y) for |y| ≤ 0.42 as 2 atanh(s), s = y/(2 + y), |s| ≤ 0.27, the series to s¹³
/// (truncation below 1e-9 relative): relative precision even for tiny y, where
/// `ln(1 + y)` would lose everything to the rounding of 1 + y. The kernel's
/// `log1p_small` (`glsl/math.glsl`).
#[inline(always)]
pub fn log1p_small(y: f32) -> f32 {
    let s = y / (2.0 + y);
    let s2 = s * s;
    2.0 * s
        * (1.0
            + s2 * (1.0 / 3.0
                + s2 * (1.0 / 5.0
                    + s2 * (1.0 / 7.0 + s2 * (1.0 / 9.0 + s2 * (1.0 / 11.0 + s2 * (1.0 / 13.0)))))))
}

/// ln x for a normal f32 x > 0 to about 2 ulp: x = 2^e f with f in [√½, √2), f − 1 exact
/// (Sterbenz) and ln f from [`log1p_small`]; the exponent and mantissa are taken from the
/// bits (no `frexp`, a libm call that stops vectorisation). The kernel's `log_acc`. Other
/// inputs (0, subnormal, negative, non-finite) give finite nonsense, never a trap: the
/// lanes use it only where the frame guarantees a normal positive argument.
#[inline(always)]
pub fn log_acc(x: f32) -> f32 {
    let bits = x.to_bits();
    // f in [1, 2) from the mantissa; e the unbiased exponent.
    let f = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    let e = ((bits >> 23) & 0xff) as i32 - 127;
    // f ≥ √2: take f/2 and e + 1, so that f − 1 stays within [√½ − 1, √2 − 1].
    let (f, e) = if f >= std::f32::consts::SQRT_2 {
        (0.5 * f, e + 1)
    } else {
        (f, e)
    };
    let fe = e as f32;
    fe * LN2_HI + (log1p_small(f - 1.0) + fe * LN2_LO)
}

/// ln(1 + y) for y > −1: [`log1p_small`] where it converges, `ln(1 + y)` elsewhere.
#[inline(always)]
pub fn log1p_acc(y: f32) -> f32 {
    if y.abs() <= 0.42 {
        log1p_small(y)
    } else {
        log_acc(1.0 + y)
    }
}

/// ln cos of an angle given both `cos > 0` and `sin² = |n × w|²`: near the pole `cos` is
/// `1 − sin²/2` and `ln(1 − sin²)/2` keeps the relative precision `ln cos` itself would
/// lose; near the horizon `cos` is the accurate number. The kernel's `log_cos`.
#[inline(always)]
pub fn log_cos(cos_w: f32, sin2_w: f32) -> f32 {
    if sin2_w < 0.5 {
        0.5 * log1p_acc(-sin2_w)
    } else {
        log_acc(cos_w)
    }
}

/// atan(y/x) for x ≥ 0, y ≥ 0 (an angle in [0, π/2]) to a few ulp: reduced to t ≤ 1, the
/// angle halved twice (`atan t = 2 atan(t/(1 + √(1 + t²)))`) to |t| ≤ tan(π/16), then the
/// series to t¹⁵ (truncation below 1e-13). The kernel's `atan2_positive`.
#[inline(always)]
pub fn atan2_positive(y: f32, x: f32) -> f32 {
    let swap = y > x;
    let t = if swap { x / y } else { y / x };
    let t = t / (1.0 + (1.0 + t * t).sqrt());
    let t = t / (1.0 + (1.0 + t * t).sqrt());
    let t2 = t * t;
    let a = 4.0
        * t
        * (1.0
            - t2 * (1.0 / 3.0
                - t2 * (1.0 / 5.0
                    - t2 * (1.0 / 7.0
                        - t2 * (1.0 / 9.0
                            - t2 * (1.0 / 11.0 - t2 * (1.0 / 13.0 - t2 * (1.0 / 15.0))))))));
    if swap {
        std::f32::consts::FRAC_PI_2 - a
    } else {
        a
    }
}

/// atan2(y, x) in f64 for y ≥ 0 (an angle in [0, π]; 0 for (0, 0)) to a few ulp, branch
/// free, for f64 lanes (the MERL lookup's half/difference angles): reduced to
/// t = min/max ≤ 1, then to |t| ≤ tan(π/8) by `atan t = π/4 + atan((t − 1)/(t + 1))`,
/// halved once (`atan t = 2 atan(t/(1 + √(1 + t²)))`) to |t| ≤ tan(π/16) ≈ 0.2, and the
/// Taylor series to t²¹ (the first term left out, t²³/23, is below 2e-17 of t); within
/// 1e-15 relative of libm (test).
#[inline(always)]
pub fn atan2_upper64(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let ax = x.abs();
    let swap = y > ax;
    let (num, den) = if swap { (ax, y) } else { (y, ax) };
    // (0, 0): 0, as libm's atan2(+0, +0).
    let t = if den > 0.0 { num / den } else { 0.0 };
    let big = t > std::f64::consts::SQRT_2 - 1.0;
    let t = if big { (t - 1.0) / (t + 1.0) } else { t };
    let t = t / (1.0 + (1.0 + t * t).sqrt());
    let t2 = t * t;
    let mut p = 1.0 / 21.0;
    for k in (0..10).rev() {
        // 1/19, 1/17, …, 1: alternating signs.
        let c = 1.0 / f64::from(2 * k + 1);
        p = c - t2 * p;
    }
    let a = 2.0 * t * p + if big { FRAC_PI_4 } else { 0.0 };
    let a = if swap { FRAC_PI_2 - a } else { a };
    if x < 0.0 {
        PI - a
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atan2_upper64_is_within_a_few_ulp_of_libm() {
        let mut worst = 0f64;
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for i in 0..400_000 {
            // Magnitudes from 1e-12 to 1, x of either sign; the axes and diagonals too.
            let y = next() * 10f64.powf(-12.0 * next());
            let x = (next() - 0.5) * 10f64.powf(-12.0 * next());
            let (y, x) = match i % 100 {
                0 => (0.0, x),
                1 => (y, 0.0),
                2 => (y, y),
                3 => (y, -y),
                _ => (y, x),
            };
            let (got, want) = (atan2_upper64(y, x), y.atan2(x));
            let err = (got - want).abs() / want.abs().max(f64::MIN_POSITIVE);
            assert!(err <= 1e-15, "atan2({y:e}, {x:e}) = {got:e}, libm {want:e}");
            worst = worst.max(err);
        }
        assert_eq!(atan2_upper64(0.0, 0.0), 0.0);
        assert!(worst > 0.0, "compared something");
    }

    #[test]
    fn exp_neg_is_within_a_few_ulp_of_f64_exp() {
        // Both multiply-add kinds: `exp_neg` (two roundings) and the fused lane form.
        let (mut worst, mut worst_fused) = (0f64, 0f64);
        for i in 0..200_000 {
            let x = -87.0 * f64::from(i) / 200_000.0;
            let want = f64::from(x as f32).exp();
            let got = f64::from(exp_neg(x as f32));
            worst = worst.max(((got - want) / want).abs());
            let fused = f64::from(exp_neg_above::<Fused, f32>(x as f32, -87.0));
            worst_fused = worst_fused.max(((fused - want) / want).abs());
        }
        // About 2 ulp, as documented (measured 1.72e-7 on both kinds; 1 ulp ≤ 1.19e-7).
        assert!(worst < 2.5e-7, "worst relative error {worst}");
        assert!(
            worst_fused < 2.5e-7,
            "fused: worst relative error {worst_fused}"
        );
        // The floor: 0 below it, exp_neg's value at and above it.
        assert_eq!(exp_neg_above::<Rounded, f32>(-41.6, -41.5), 0.0);
        assert_eq!(exp_neg_above::<Rounded, f32>(-41.5, -41.5), exp_neg(-41.5));
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
    #[test]
    fn log_acc_and_log_cos_are_within_a_few_ulp_of_f64() {
        let mut worst = 0f64;
        for i in 1..200_000 {
            let x = (f64::from(i) / 200_000.0).powi(3) * 4.0;
            let xf = x as f32;
            let got = f64::from(log_acc(xf));
            let want = f64::from(xf).ln();
            worst = worst.max((got - want).abs() / want.abs().max(1e-30));
        }
        assert!(worst < 5e-7, "log_acc: worst relative error {worst}");
        // ln cos from sin² near the pole: ln(1 − s)/2 to relative precision at s = 1e-12,
        // where cos itself rounds to 1.
        for s in [1e-12f64, 1e-8, 1e-4, 0.3, 0.6, 0.99] {
            let (cos, s2) = ((1.0 - s).sqrt() as f32, s as f32);
            let got = f64::from(log_cos(cos, s2));
            let want = 0.5 * (-f64::from(s2)).ln_1p();
            assert!(
                (got - want).abs() <= 1e-6 * want.abs(),
                "log_cos at sin² = {s}: {got} vs {want}"
            );
        }
    }

    #[test]
    fn atan2_positive_is_within_a_few_ulp_of_f64() {
        let mut worst = 0f64;
        for i in 0..=20_000 {
            let a = std::f64::consts::FRAC_PI_2 * f64::from(i) / 20_000.0;
            let (y, x) = (a.sin() as f32, a.cos() as f32);
            let got = f64::from(atan2_positive(y, x));
            let want = f64::from(y).atan2(f64::from(x));
            worst = worst.max((got - want).abs() / want.max(1e-30));
        }
        assert!(worst < 5e-7, "worst relative error {worst}");
        assert_eq!(atan2_positive(0.0, 1.0), 0.0);
    }
}
