//! A register of lanes as the terms' lane forms compute with it: [`Reg`] (pulp's `f32s`
//! with its instruction set's token) as `terms::real::Real`, and the f64 lanes beside it
//! ([`WideReg`], `terms::real::Wide`) through which the register path forms the f64 part
//! of Beckmann's local frame (`frame::frame_local_h64`).

use super::io::RegisterIo;
use crate::cpu::frame::{self, FrameLanes, HalfParts};
use crate::cpu::segments::SegmentLanes;
use crate::terms::f::conductor::segments::Segments;
use crate::terms::math::MulAdd;
use crate::terms::real::{Real, Wide};
use pulp::Simd;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

/// A register of f32 lanes with the instruction set that computes on it.
#[derive(Clone, Copy)]
pub(crate) struct Reg<S: Simd> {
    s: S,
    v: S::f32s,
}

/// A register of comparison results.
#[derive(Clone, Copy)]
pub(crate) struct RegMask<S: Simd> {
    s: S,
    m: S::m32s,
}

impl<S: Simd> Reg<S> {
    /// The register `v` of `simd`.
    #[inline(always)]
    pub(crate) fn new(simd: S, v: S::f32s) -> Reg<S> {
        Reg { s: simd, v }
    }

    /// The lanes.
    #[inline(always)]
    pub(crate) fn get(self) -> S::f32s {
        self.v
    }

    /// The instruction set.
    #[inline(always)]
    pub(crate) fn simd(self) -> S {
        self.s
    }
}

impl<S: Simd> RegMask<S> {
    /// The lanes' comparison results.
    #[inline(always)]
    pub(crate) fn get(self) -> S::m32s {
        self.m
    }
}

/// `Op<Reg>` and `Op<f32>` (the scalar splatted) for one of pulp's binary operations.
macro_rules! binary {
    ($tr:ident, $f:ident, $simd:ident) => {
        impl<S: Simd> $tr for Reg<S> {
            type Output = Reg<S>;
            #[inline(always)]
            fn $f(self, o: Reg<S>) -> Reg<S> {
                Reg {
                    s: self.s,
                    v: self.s.$simd(self.v, o.v),
                }
            }
        }

        impl<S: Simd> $tr<f32> for Reg<S> {
            type Output = Reg<S>;
            #[inline(always)]
            fn $f(self, o: f32) -> Reg<S> {
                self.$f(self.splat_as(o))
            }
        }
    };
}

binary!(Add, add, add_f32s);
binary!(Sub, sub, sub_f32s);
binary!(Mul, mul, mul_f32s);
binary!(Div, div, div_f32s);

impl<S: Simd> BitAnd for RegMask<S> {
    type Output = RegMask<S>;
    #[inline(always)]
    fn bitand(self, o: RegMask<S>) -> RegMask<S> {
        RegMask {
            s: self.s,
            m: self.s.and_m32s(self.m, o.m),
        }
    }
}

impl<S: Simd> BitOr for RegMask<S> {
    type Output = RegMask<S>;
    #[inline(always)]
    fn bitor(self, o: RegMask<S>) -> RegMask<S> {
        RegMask {
            s: self.s,
            m: self.s.or_m32s(self.m, o.m),
        }
    }
}

impl<S: Simd> Not for RegMask<S> {
    type Output = RegMask<S>;
    #[inline(always)]
    fn not(self) -> RegMask<S> {
        RegMask {
            s: self.s,
            m: self.s.not_m32s(self.m),
        }
    }
}

impl<S: Simd> Real for Reg<S> {
    type Mask = RegMask<S>;

    #[inline(always)]
    fn splat_as(self, x: f32) -> Reg<S> {
        Reg {
            s: self.s,
            v: self.s.splat_f32s(x),
        }
    }

    #[inline(always)]
    fn sqrt(self) -> Reg<S> {
        Reg {
            s: self.s,
            v: self.s.sqrt_f32s(self.v),
        }
    }

    #[inline(always)]
    fn abs(self) -> Reg<S> {
        Reg {
            s: self.s,
            v: self.s.abs_f32s(self.v),
        }
    }

    /// One rounding on every instruction set (pulp emulates it where there is no FMA
    /// instruction; the engine takes this path only where there is one).
    #[inline(always)]
    fn fused_mul_add(self, b: Reg<S>, c: Reg<S>) -> Reg<S> {
        Reg {
            s: self.s,
            v: self.s.mul_add_f32s(self.v, b.v, c.v),
        }
    }

    #[inline(always)]
    fn lt(self, o: Reg<S>) -> RegMask<S> {
        RegMask {
            s: self.s,
            m: self.s.less_than_f32s(self.v, o.v),
        }
    }

    #[inline(always)]
    fn le(self, o: Reg<S>) -> RegMask<S> {
        RegMask {
            s: self.s,
            m: self.s.less_than_or_equal_f32s(self.v, o.v),
        }
    }

    #[inline(always)]
    fn select(m: RegMask<S>, a: Reg<S>, b: Reg<S>) -> Reg<S> {
        Reg {
            s: a.s,
            v: a.s.select_f32s(m.m, a.v, b.v),
        }
    }

    #[inline(always)]
    fn exponent_bits(self, bias: u32) -> Reg<S> {
        let s = self.s;
        let bits = s.transmute_u32s_f32s(self.v);
        let shifted = s.wrapping_dyn_shl_u32s(bits, s.splat_u32s(23));
        Reg {
            s,
            v: s.transmute_f32s_u32s(s.add_u32s(shifted, s.splat_u32s(bias))),
        }
    }
}

/// The f64 lanes beside a [`Reg`]'s: two registers of f64, the low and the high half of
/// its lanes.
#[derive(Clone, Copy)]
pub(crate) struct WideReg<S: Simd> {
    s: S,
    lo: S::f64s,
    hi: S::f64s,
}

/// `Op<WideReg>` for one of pulp's binary f64 operations, half by half.
macro_rules! wide_binary {
    ($tr:ident, $f:ident, $simd:ident) => {
        impl<S: RegisterIo> $tr for WideReg<S> {
            type Output = WideReg<S>;
            #[inline(always)]
            fn $f(self, o: WideReg<S>) -> WideReg<S> {
                WideReg {
                    s: self.s,
                    lo: self.s.$simd(self.lo, o.lo),
                    hi: self.s.$simd(self.hi, o.hi),
                }
            }
        }
    };
}

wide_binary!(Add, add, add_f64s);
wide_binary!(Mul, mul, mul_f64s);

impl<S: RegisterIo> Mul<f64> for WideReg<S> {
    type Output = WideReg<S>;
    #[inline(always)]
    fn mul(self, o: f64) -> WideReg<S> {
        self * self.splat_as(o)
    }
}

impl<S: RegisterIo> Wide for WideReg<S> {
    type Narrow = Reg<S>;

    #[inline(always)]
    fn fused_mul_add(self, b: WideReg<S>, c: WideReg<S>) -> WideReg<S> {
        WideReg {
            s: self.s,
            lo: self.s.mul_add_f64s(self.lo, b.lo, c.lo),
            hi: self.s.mul_add_f64s(self.hi, b.hi, c.hi),
        }
    }

    #[inline(always)]
    fn splat_as(self, x: f64) -> WideReg<S> {
        let x = self.s.splat_f64s(x);
        WideReg {
            s: self.s,
            lo: x,
            hi: x,
        }
    }

    #[inline(always)]
    fn narrow(self) -> Reg<S> {
        Reg {
            s: self.s,
            v: self.s.narrow([self.lo, self.hi]),
        }
    }

    #[inline(always)]
    fn widen_like(self, x: Reg<S>) -> WideReg<S> {
        widen(x)
    }
}

/// A register's lanes in f64.
#[inline(always)]
fn widen<S: RegisterIo>(x: Reg<S>) -> WideReg<S> {
    let [lo, hi] = x.s.widen(x.v);
    WideReg { s: x.s, lo, hi }
}

impl<S: RegisterIo> FrameLanes for Reg<S> {
    #[inline(always)]
    fn half_parts<A: MulAdd, const NEAR: bool>(
        l: [Reg<S>; 3],
        v: [Reg<S>; 3],
        near: RegMask<S>,
    ) -> HalfParts<Reg<S>> {
        frame::half_parts::<A, WideReg<S>, NEAR>(
            [widen(l[0]), widen(l[1]), widen(l[2])],
            [widen(v[0]), widen(v[1]), widen(v[2])],
            near,
        )
    }
}

impl<S: RegisterIo> SegmentLanes for Reg<S> {
    const TABLES: bool = S::TABLES;

    #[inline(always)]
    fn f_segments(c: Reg<S>, tables: &Segments) -> [Reg<S>; 3] {
        c.s.f_segments(c.v, tables).map(|v| Reg { s: c.s, v })
    }
}

impl<S: RegisterIo> RegMask<S> {
    /// Whether every lane is set.
    #[inline(always)]
    pub(crate) fn all(self) -> bool {
        self.s.bits(self.m) == u32::MAX >> (32 - S::WIDTH)
    }
}
