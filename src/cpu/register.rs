//! The register path: the local form's GGX lanes on the f32 frame from rows to outputs,
//! every value in a register of the instruction set (`pulp`'s `f32s`) instead of a block's
//! arrays — two registers a step, in two stages ([`ggx_local_dgk`], [`ggx_local_finish`]).
//! The lane loops (`kernel::microfacet_block`) pass each quantity of a 16-tuple block
//! through memory between their loops and left LLVM to spill the rest.
//!
//! The arithmetic is the lane loops' own: the frame (`frame::frame_local32`), the terms'
//! lane forms and `kernel::dgk_of`/`channels_of` are generic over [`Real`], instantiated
//! here with [`Reg`], so a lane's result is the same bits on either path (a test compares
//! them). A lane the local frame cannot serve is left to the caller's general f32 or f64
//! frame, and a lane the lanes cannot vouch for to the reference, exactly as a block of
//! the lane loops flags them.

use super::frame::frame_local32;
use super::kernel::{self, Params, FAST_MIN_C};
use crate::terms::d::ggx;
use crate::terms::f::{conductor, schlick};
use crate::terms::g::{cook_torrance, smith, smith_correlated};
use crate::terms::math::Fused;
use crate::terms::real::Real;
use crate::terms::{FresnelKind, Geometry};
use pulp::Simd;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

/// A register of f32 lanes with the instruction set that computes on it.
#[derive(Clone, Copy)]
pub(super) struct Reg<S: Simd> {
    s: S,
    v: S::f32s,
}

/// A register of comparison results.
#[derive(Clone, Copy)]
pub(super) struct RegMask<S: Simd> {
    s: S,
    m: S::m32s,
}

impl<S: Simd> Reg<S> {
    /// The register `v` of `simd`.
    #[inline(always)]
    pub(super) fn new(simd: S, v: S::f32s) -> Reg<S> {
        Reg { s: simd, v }
    }

    /// The lanes.
    #[inline(always)]
    pub(super) fn get(self) -> S::f32s {
        self.v
    }
}

impl<S: Simd> RegMask<S> {
    /// The lanes' comparison results.
    #[inline(always)]
    pub(super) fn get(self) -> S::m32s {
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
}

/// Whether a material group runs on the register path: GGX, isotropic, with no geometry,
/// the V-cavity or a Smith form, Fresnel none, Schlick or a conductor legal for the metal
/// form, on the f32 frame, without the terms, its f64-frame lanes left to the caller —
/// what the engine's `vkbrdf eval` and bench run for the common GGX materials. The other
/// groups take the lane loops.
pub(super) fn serves(
    d: crate::terms::DistributionKind,
    aniso: bool,
    g: Geometry,
    f: FresnelKind,
    p: &Params,
) -> bool {
    let g_ok = matches!(
        g,
        Geometry::None | Geometry::CookTorrance | Geometry::Smith | Geometry::SmithCorrelated
    );
    let f_ok = match f {
        FresnelKind::None | FresnelKind::Schlick => true,
        FresnelKind::Conductor => p.conductor.metal,
        FresnelKind::Dielectric => false,
    };
    d == crate::terms::DistributionKind::Ggx
        && !aniso
        && g_ok
        && f_ok
        && p.fast_frame
        && p.defer_slow
        && !p.terms
}

/// The first of two stages of one register of the local form's lanes (`l`, `v` as read,
/// N = +z) of a group [`serves`] takes, geometry `G` and Fresnel `F` (the kernel's codes):
/// the frame, the flags and D·G·K, handed to [`ggx_local_finish`] as a few values
/// ([`Staged`]), so that a step runs this stage on one register, then on a second, while
/// the first one's square roots and divisions are still in flight, without holding both
/// registers' frames. Together the stages give the BRDF's channels and which lanes they
/// are not for ([`Flags`], [`Flags::rescue`]), as `kernel::microfacet_block` decides for the same lanes.
#[inline(always)]
pub(super) fn ggx_local_dgk<T: Real, const G: u8, const F: u8>(
    p: &Params,
    l: [T; 3],
    v: [T; 3],
) -> Staged<T> {
    let fr = frame_local32::<Fused, T>(l, v);
    let certified = ggx::local_frame_ok(fr.cos_h, fr.sin2_h, fr.c, p.m2_f, p.ggx_local_guard);
    let slow = fr.ok & fr.c.lt_scalar(FAST_MIN_C);
    let general = fr.ok & !slow & !certified;
    let (cos_i, cos_o, one) = (fr.cos_i, fr.cos_o, fr.c.splat_as(1.0));
    let d = ggx::d_ratio32::<Fused, _>(fr.cos_h, fr.sin2_h, p.m2_f, p.d_norm_f);
    let m2 = p.m2 as f32;
    let g = match const { Geometry::from_code(G) } {
        Geometry::Smith => smith::g_ratio_ggx::<Fused, _>(cos_i, fr.sin2_i, cos_o, fr.sin2_o, m2),
        Geometry::SmithCorrelated => {
            smith_correlated::g_ratio_ggx::<Fused, _>(cos_i, fr.sin2_i, cos_o, fr.sin2_o, m2)
        }
        Geometry::CookTorrance => (cook_torrance::g_lane(fr.cos_h, cos_i, cos_o, fr.c), one),
        _ => (one, one),
    };
    let (dgk, size) = kernel::dgk_of(p, d, g, cos_i, cos_o);
    // 1 − c = sin²/(1 + c), which does not cancel (as `kernel::Lane` forms it).
    let schlick = matches!(const { FresnelKind::from_code(F) }, FresnelKind::Schlick);
    let one_minus_c = if schlick { fr.s2 / (fr.c + 1.0) } else { one };
    Staged {
        c: fr.c,
        s2: fr.s2,
        one_minus_c,
        dgk,
        size,
        ok: fr.ok,
        slow,
        general,
    }
}

/// What [`ggx_local_dgk`] hands to [`ggx_local_finish`].
#[derive(Clone, Copy)]
pub(super) struct Staged<T: Real> {
    c: T,
    s2: T,
    one_minus_c: T,
    dgk: T,
    size: T,
    ok: T::Mask,
    slow: T::Mask,
    general: T::Mask,
}

/// F (`F`, the kernel's code) of a staged register's channels.
struct Fresnel<'a, T: Real, const F: u8, const Q: bool> {
    p: &'a Params,
    st: Staged<T>,
}

impl<T: Real, const F: u8, const Q: bool> kernel::FresnelOf<T> for Fresnel<'_, T, F, Q> {
    #[inline(always)]
    fn channel(&self, ch: usize) -> T {
        let (p, st) = (self.p, &self.st);
        match const { FresnelKind::from_code(F) } {
            FresnelKind::Schlick => schlick::f_lane(st.one_minus_c, p.f0[ch]),
            FresnelKind::Conductor if Q => {
                conductor::f_lane_metal_quotient::<Fused, _>(st.c, st.s2, &p.conductor, ch)
            }
            FresnelKind::Conductor => {
                conductor::f_lane_metal::<Fused, _>(st.c, st.s2, &p.conductor, ch)
            }
            _ => st.c.splat_as(1.0),
        }
    }
}

/// The second stage (after [`ggx_local_dgk`]): F, the channels, and the lanes whose output
/// may be non-finite or out of range (`kernel::channels_of`'s test). Which lanes the
/// reference or another frame takes follows from these and [`Staged::flags`], which the
/// caller reads as bits after the first stage (masks held across the second stage's
/// arithmetic were spilled).
#[inline(always)]
pub(super) fn ggx_local_finish<T: Real, const F: u8, const Q: bool>(
    p: &Params,
    st: Staged<T>,
) -> ([T; 3], T::Mask) {
    let f = Fresnel::<T, F, Q> { p, st };
    kernel::channels_of::<Fused, _>(p, st.dgk, st.size, f)
}

/// The lanes of a register as the first stage flags them, as bits (lane k is bit k).
#[derive(Clone, Copy)]
pub(super) struct Flags {
    /// Lanes whose frame failed (invalid, below the horizon, grazing) and that no other
    /// frame takes: the reference's.
    pub(super) failed: u32,
    /// Lanes another frame takes (`slow | general`): the output test does not decide them.
    pub(super) elsewhere: u32,
    /// Lanes for the f64 frame (`c` below `FAST_MIN_C`).
    pub(super) slow: u32,
    /// Lanes for the general f32 frame (D's certificate refused the local one).
    pub(super) general: u32,
}

impl Flags {
    /// The lanes for the reference once the outputs' test (`bad`, as bits) is known: the
    /// frame's failures and the outputs', except on the lanes another frame takes — as a
    /// block flags them.
    #[inline(always)]
    pub(super) fn rescue(&self, bad: u32) -> u32 {
        self.failed | (bad & !self.elsewhere)
    }
}

impl<S: RegisterIo> Staged<Reg<S>> {
    /// The first stage's flags as bits ([`Flags`]).
    #[inline(always)]
    pub(super) fn flags(&self) -> Flags {
        let s = self.c.s;
        let elsewhere = self.slow | self.general;
        Flags {
            failed: s.bits((!self.ok & !elsewhere).get()),
            elsewhere: s.bits(elsewhere.get()),
            slow: s.bits(self.slow.get()),
            general: s.bits(self.general.get()),
        }
    }
}

/// Work on the register path, for the instruction sets that have one
/// ([`Registers::serve`]).
pub(super) trait RegisterOp {
    /// What the work returns.
    type Output;
    /// The work in `simd`'s registers.
    fn run<S: RegisterIo>(self, simd: S) -> Self::Output;
}

/// The instruction sets the engine's lanes run with FMA, and whether they have a register
/// path.
pub(super) trait Registers: Simd {
    /// `op` on this instruction set's register path, or `None` where it has none.
    fn serve<O: RegisterOp>(self, op: O) -> Option<O::Output>;
}

/// An instruction set's register path: the width of a register and its own ways to read
/// the local form's rows into registers and write RGB back.
pub(super) trait RegisterIo: Simd {
    /// Tuples a register.
    const WIDTH: usize = Self::F32_LANES;

    /// The 6 columns of [`Self::WIDTH`] rows of the local form.
    fn local_columns(self, rows: &[f32]) -> [Self::f32s; 6];

    /// 3 columns (RGB) into [`Self::WIDTH`] rows of 3.
    fn rgb_rows(self, rgb: [Self::f32s; 3], rows: &mut [f32]);

    /// The mask's lanes as bits (lane k is bit k).
    fn bits(self, m: Self::m32s) -> u32;
}

/// AVX2: the register path, 8 tuples a register.
#[cfg(target_arch = "x86_64")]
impl Registers for pulp::x86::V3 {
    #[inline(always)]
    fn serve<O: RegisterOp>(self, op: O) -> Option<O::Output> {
        Some(op.run(self))
    }
}

/// AVX2's reads and writes: the transposes of `transpose::avx2`, `vmovmskps`.
#[cfg(target_arch = "x86_64")]
impl RegisterIo for pulp::x86::V3 {
    #[inline(always)]
    fn local_columns(self, rows: &[f32]) -> [Self::f32s; 6] {
        let rows: &[f32; 48] = rows[..48].try_into().expect("8 rows of 6");
        let [a, b, c, d, e, f] = super::transpose::avx2::local_columns(self, rows);
        let r = bytemuck::cast;
        [r(a), r(b), r(c), r(d), r(e), r(f)]
    }

    #[inline(always)]
    fn rgb_rows(self, rgb: [Self::f32s; 3], rows: &mut [f32]) {
        let rows: &mut [f32; 24] = (&mut rows[..24]).try_into().expect("8 rows of 3");
        let [x, y, z] = rgb;
        let r = bytemuck::cast;
        super::transpose::avx2::rgb_rows(self, [r(x), r(y), r(z)], rows)
    }

    #[inline(always)]
    fn bits(self, m: Self::m32s) -> u32 {
        self.avx._mm256_movemask_ps(bytemuck::cast(m)) as u32
    }
}

/// AVX-512: no register path yet — it would be measured and tested only on a machine
/// with AVX-512, and this one has none — so its groups take the lane loops.
#[cfg(target_arch = "x86_64")]
impl Registers for pulp::x86::V4 {
    #[inline(always)]
    fn serve<O: RegisterOp>(self, _op: O) -> Option<O::Output> {
        None
    }
}
