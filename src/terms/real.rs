//! The value a term's lane form computes with: one `f32` (the lane loops, which LLVM
//! vectorises across a block) or a whole register of them (the CPU engine's register path,
//! `cpu::register`), so that each lane form is written once for both — as Mitsuba 3 writes
//! its terms once over Dr.Jit's `Float`.
//!
//! Scalars enter on the right (`x * 2.0`, `x + 1.0`; multiplication and addition are
//! commutative bit for bit) or through [`Real::splat_as`] (`a − x` as
//! `x.splat_as(a) - x`), because a register type needs its instruction set's token to
//! make a constant.

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

/// One lane or a register of lanes of f32, with the operations the lane forms use: the
/// four correctly rounded operations, `√`, `|x|`, a fused multiply–add, comparisons and a
/// select — each the IEEE operation lane by lane, so that every instantiation of a lane
/// form gives the same bits.
pub trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Add<f32, Output = Self>
    + Sub<f32, Output = Self>
    + Mul<f32, Output = Self>
    + Div<f32, Output = Self>
{
    /// A comparison's result, lane by lane.
    type Mask: Copy
        + BitAnd<Output = Self::Mask>
        + BitOr<Output = Self::Mask>
        + Not<Output = Self::Mask>;

    /// `x` in every lane, as a value of `self`'s kind.
    fn splat_as(self, x: f32) -> Self;
    /// The correctly rounded square root.
    fn sqrt(self) -> Self;
    /// `|x|`.
    fn abs(self) -> Self;
    /// `self · b + c` rounded once.
    fn fused_mul_add(self, b: Self, c: Self) -> Self;
    /// `self < o` (false for NaN).
    fn lt(self, o: Self) -> Self::Mask;
    /// `self ≤ o` (false for NaN).
    fn le(self, o: Self) -> Self::Mask;
    /// `a` where `m`, else `b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
    /// The lanes' bits shifted left by 23 (into an f32's exponent field) plus `bias`,
    /// wrapping, as f32s: `exp`'s scaling by 2^k from the bits of `k + 1.5·2^23`
    /// (`math::exp_neg`).
    fn exponent_bits(self, bias: u32) -> Self;

    /// `self ≥ x` for a scalar `x` (false for NaN).
    #[inline(always)]
    fn ge_scalar(self, x: f32) -> Self::Mask {
        self.splat_as(x).le(self)
    }

    /// `self ≤ x` for a scalar `x` (false for NaN).
    #[inline(always)]
    fn le_scalar(self, x: f32) -> Self::Mask {
        self.le(self.splat_as(x))
    }

    /// `self < x` for a scalar `x` (false for NaN).
    #[inline(always)]
    fn lt_scalar(self, x: f32) -> Self::Mask {
        self.lt(self.splat_as(x))
    }
}

impl Real for f32 {
    type Mask = bool;

    #[inline(always)]
    fn splat_as(self, x: f32) -> f32 {
        x
    }

    #[inline(always)]
    fn sqrt(self) -> f32 {
        f32::sqrt(self)
    }

    #[inline(always)]
    fn abs(self) -> f32 {
        f32::abs(self)
    }

    #[inline(always)]
    fn fused_mul_add(self, b: f32, c: f32) -> f32 {
        f32::mul_add(self, b, c)
    }

    #[inline(always)]
    fn lt(self, o: f32) -> bool {
        self < o
    }

    #[inline(always)]
    fn le(self, o: f32) -> bool {
        self <= o
    }

    /// By bits, not `if`: written as a branch, LLVM sank the work of one side into it
    /// (a division, in the conductor's metal form), and the branch kept the lane loop from
    /// vectorising (200 instructions an evaluation instead of 70).
    #[inline(always)]
    fn select(m: bool, a: f32, b: f32) -> f32 {
        let keep = u32::from(m).wrapping_neg();
        f32::from_bits((a.to_bits() & keep) | (b.to_bits() & !keep))
    }

    #[inline(always)]
    fn exponent_bits(self, bias: u32) -> f32 {
        f32::from_bits((self.to_bits() << 23).wrapping_add(bias))
    }
}

/// f64 lanes beside f32 lanes ([`Wide::Narrow`]), with the operations the f32 frame's
/// f64 part uses (`cpu::frame`), each the IEEE operation lane by lane: one f64 beside one
/// f32 (the lane loops), a register of four f64 beside half of AVX2's register of eight
/// f32 (the register path, `cpu::register`).
pub trait Wide: Copy + Add<Output = Self> + Mul<Output = Self> + Mul<f64, Output = Self> {
    /// The f32 lanes these stand beside.
    type Narrow: Real;
    /// `self · b + c` rounded once.
    fn fused_mul_add(self, b: Self, c: Self) -> Self;
    /// `x` in every lane, as a value of `self`'s kind.
    fn splat_as(self, x: f64) -> Self;
    /// Each lane rounded to the nearest f32 (as `x as f32`).
    fn narrow(self) -> Self::Narrow;
    /// The lanes of `x` that `self`'s stand beside, exactly in f64.
    fn widen_like(self, x: Self::Narrow) -> Self;
}

impl Wide for f64 {
    type Narrow = f32;

    #[inline(always)]
    fn fused_mul_add(self, b: f64, c: f64) -> f64 {
        f64::mul_add(self, b, c)
    }

    #[inline(always)]
    fn splat_as(self, x: f64) -> f64 {
        x
    }

    #[inline(always)]
    fn narrow(self) -> f32 {
        self as f32
    }

    #[inline(always)]
    fn widen_like(self, x: f32) -> f64 {
        f64::from(x)
    }
}
