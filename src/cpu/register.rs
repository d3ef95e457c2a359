//! The register path: the local form's GGX and Beckmann lanes on the f32 frames from rows
//! to outputs, every value in a register of the instruction set (`pulp`'s `f32s`,
//! [`Reg`]) instead of a block's arrays — two registers a step, in two stages
//! ([`local_dgk`], [`local_finish`]). The lane loops (`kernel::microfacet_block`) pass each
//! quantity of a 16-tuple block through memory between their loops and left LLVM to spill
//! the rest.
//!
//! The arithmetic is the lane loops' own: the frames (`frame::frame_local32`, GGX's, and
//! `frame::frame_local_h64`, Beckmann's, its half vector from f64), the terms' lane
//! forms and `kernel::dgk_of`/`channels_of` are generic over [`Real`], instantiated here
//! with [`Reg`] (`lanes.rs`, with the f64 lanes beside it), so a lane's result is the same
//! bits on either path (a test compares them). A lane the local frame cannot serve is left
//! to the caller's general f32 or f64 frame, and a lane the lanes cannot vouch for to the
//! reference, exactly as a block of the lane loops flags them. Which instruction sets have
//! the path, and their reads and writes: `io.rs`.

use super::frame::{frame_local32, frame_local_h64, near_unit_lanes, Frame, FrameLanes};
use super::kernel::{self, Params, FAST_MIN_C};
use super::segments::SegmentLanes;
use crate::terms::d::{beckmann, ggx};
use crate::terms::f::conductor::poly::Polynomial;
use crate::terms::f::conductor::segments::Segments;
use crate::terms::f::{conductor, schlick};
use crate::terms::g::{cook_torrance, smith, smith_correlated, smith_fast};
use crate::terms::math::Fused;
use crate::terms::real::Real;
use crate::terms::{FresnelKind, Geometry};

mod io;
mod lanes;

pub(super) use io::RegisterIo;
pub(super) use lanes::Reg;

/// Whether a material group runs on the register path: GGX or Beckmann, isotropic, with
/// no geometry, the V-cavity or a Smith form (GGX: separable or height-correlated;
/// Beckmann: smith-fast), Fresnel none, Schlick or a conductor legal for the metal form,
/// on the f32 frame, without the terms, its f64-frame lanes left to the caller — what the
/// engine's `vkbrdf eval` and bench run for the common GGX and Beckmann materials. The
/// other groups take the lane loops.
pub(super) fn serves(
    d: crate::terms::DistributionKind,
    aniso: bool,
    g: Geometry,
    f: FresnelKind,
    p: &Params,
) -> bool {
    use crate::terms::DistributionKind as D;
    let g_ok = match d {
        D::Ggx => matches!(
            g,
            Geometry::None | Geometry::CookTorrance | Geometry::Smith | Geometry::SmithCorrelated
        ),
        D::Beckmann => matches!(
            g,
            Geometry::None | Geometry::CookTorrance | Geometry::SmithFast
        ),
        _ => false,
    };
    let f_ok = match f {
        FresnelKind::None | FresnelKind::Schlick => true,
        FresnelKind::Conductor => p.conductor.metal,
        FresnelKind::Dielectric => false,
    };
    !aniso && g_ok && f_ok && p.fast_frame && p.defer_slow && !p.terms
}

/// The first of two stages of one register of the local form's lanes (`l`, `v` as read,
/// N = +z) of a group [`serves`] takes, geometry `G` and Fresnel `F` (the kernel's codes):
/// the frame, the flags and D·G·K, handed to [`local_finish`] as a few values
/// ([`Staged`]), so that a step runs this stage on one register, then on a second, while
/// the first one's square roots and divisions are still in flight, without holding both
/// registers' frames. Together the stages give the BRDF's channels and which lanes they
/// are not for ([`Flags`], [`Flags::rescue`]), as `kernel::microfacet_block` decides for the same lanes.
#[inline(always)]
pub(super) fn ggx_local_dgk<T: Real, const G: u8, const F: u8, const NEAR: bool>(
    p: &Params,
    l: [T; 3],
    v: [T; 3],
) -> Staged<T> {
    let fr = frame_local32::<Fused, T, NEAR>(l, v);
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
    staged::<T, F>(p, &fr, d, g, slow, general)
}

/// [`ggx_local_dgk`] for Beckmann: its local frame (`frame::frame_local_h64`: the scales
/// and h formed in f64 registers, each rounded once, the rest in f32), whose bound holds on
/// every lane of a material allowed the f32 frame — Beckmann's D has no certificate to pass
/// (its slope grows without bound away from the peak, docs/CPU_ENGINE.md) and needs none on
/// this frame — so no lane is left to the general frame; `c` below `FAST_MIN_C` still takes
/// the f64 frame. D, G (none, the V-cavity, smith-fast) and K are the lane loops' forms.
#[inline(always)]
pub(super) fn beckmann_local_dgk<T: FrameLanes, const G: u8, const F: u8, const NEAR: bool>(
    p: &Params,
    l: [T; 3],
    v: [T; 3],
) -> Staged<T> {
    let fr = frame_local_h64::<Fused, T, NEAR>(l, v);
    let slow = fr.ok & fr.c.lt_scalar(FAST_MIN_C);
    // No lane for the general frame: this is it (an all-false mask of the lanes' kind).
    let general = slow & !slow;
    let (cos_i, cos_o, one) = (fr.cos_i, fr.cos_o, fr.c.splat_as(1.0));
    let d = (
        beckmann::d_lane32::<Fused, _>(fr.tan2_h, p.inv_m2_f, p.d_norm_f, p.d_exp_floor),
        one,
    );
    let g = match const { Geometry::from_code(G) } {
        Geometry::SmithFast => {
            smith_fast::g_ratio::<Fused, _>(cos_i, fr.sin2_i, cos_o, fr.sin2_o, p.m_f)
        }
        Geometry::CookTorrance => (cook_torrance::g_lane(fr.cos_h, cos_i, cos_o, fr.c), one),
        _ => (one, one),
    };
    staged::<T, F>(p, &fr, d, g, slow, general)
}

/// The first stage's common end, from the frame, D and G (each a quotient) and the lanes
/// another frame takes: D·G·K and its output test's sum, and `1 − c` for Schlick.
#[inline(always)]
fn staged<T: Real, const F: u8>(
    p: &Params,
    fr: &Frame<T>,
    d: (T, T),
    g: (T, T),
    slow: T::Mask,
    general: T::Mask,
) -> Staged<T> {
    let (dgk, size) = kernel::dgk_of(p, d, g, fr.cos_i, fr.cos_o);
    // 1 − c = sin²/(1 + c), which does not cancel (as `kernel::Lane` forms it).
    let schlick = matches!(const { FresnelKind::from_code(F) }, FresnelKind::Schlick);
    let one_minus_c = if schlick {
        fr.s2 / (fr.c + 1.0)
    } else {
        fr.c.splat_as(1.0)
    };
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

/// The first stage for distribution `D` (the kernel's code): [`beckmann_local_dgk`] or
/// [`ggx_local_dgk`].
#[inline(always)]
pub(super) fn local_dgk<T: FrameLanes, const D: u8, const G: u8, const F: u8, const NEAR: bool>(
    p: &Params,
    l: [T; 3],
    v: [T; 3],
) -> Staged<T> {
    if D == kernel::D_BECKMANN {
        beckmann_local_dgk::<T, G, F, NEAR>(p, l, v)
    } else {
        ggx_local_dgk::<T, G, F, NEAR>(p, l, v)
    }
}

/// Whether every lane of a step's two registers (L, V each) has L and V of unit length
/// (`frame::near_unit_lanes`): the step then runs its frames with `NEAR`.
#[inline(always)]
pub(super) fn near_unit_step<S: RegisterIo>(
    la: [Reg<S>; 3],
    va: [Reg<S>; 3],
    lb: [Reg<S>; 3],
    vb: [Reg<S>; 3],
) -> bool {
    (near_unit_lanes::<Fused, _>(la, va) & near_unit_lanes::<Fused, _>(lb, vb)).all()
}

/// What [`ggx_local_dgk`] and [`beckmann_local_dgk`] hand to [`local_finish`].
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
/// `Q`: the conductor's lane form (`conductor::FORM_*`: the metal form or its quotient;
/// [`local_finish`] forms the polynomial's three channels at once).
struct Fresnel<'a, T: Real, const F: u8, const Q: u8> {
    p: &'a Params,
    st: Staged<T>,
}

impl<T: Real, const F: u8, const Q: u8> kernel::FresnelOf<T> for Fresnel<'_, T, F, Q> {
    #[inline(always)]
    fn channel(&self, ch: usize) -> T {
        let (p, st) = (self.p, &self.st);
        match const { FresnelKind::from_code(F) } {
            FresnelKind::Schlick => schlick::f_lane(st.one_minus_c, p.f0[ch]),
            FresnelKind::Conductor if Q == conductor::FORM_QUOTIENT => {
                conductor::f_lane_metal_quotient::<Fused, _>(st.c, st.s2, &p.conductor, ch)
            }
            FresnelKind::Conductor => {
                conductor::f_lane_metal::<Fused, _>(st.c, st.s2, &p.conductor, ch)
            }
            _ => st.c.splat_as(1.0),
        }
    }
}

/// The second stage (after [`ggx_local_dgk`]): F (`poly`: the material's polynomial, as
/// the caller reads it, [`Params::conductor_poly`]; `tables`: its segment tables where the
/// plan took them, [`Params::conductor_segments`], in the polynomial's place, on an
/// instruction set with [`SegmentLanes::TABLES`]), the channels, and the lanes whose output
/// may be non-finite or out of range (`kernel::channels_of`'s test). Which lanes the
/// reference or another frame takes follows from these and [`Staged::flags`], which the
/// caller reads as bits after the first stage (masks held across the second stage's
/// arithmetic were spilled).
#[inline(always)]
pub(super) fn local_finish<T: SegmentLanes, const F: u8, const Q: u8>(
    p: &Params,
    poly: &Polynomial,
    tables: Option<&Segments>,
    st: Staged<T>,
) -> ([T; 3], T::Mask) {
    if F == kernel::F_CONDUCTOR && Q == conductor::FORM_POLY {
        if let (true, Some(tables)) = (T::TABLES, tables) {
            let f = T::f_segments(st.c, tables);
            return kernel::channels_of::<Fused, _>(p, st.dgk, st.size, f);
        }
        // The three channels' polynomials at once (their Horner chains interleaved).
        let f = conductor::poly::f_lanes_poly::<Fused, _>(st.c, poly);
        return kernel::channels_of::<Fused, _>(p, st.dgk, st.size, f);
    }
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
        let s = self.c.simd();
        let elsewhere = self.slow | self.general;
        Flags {
            failed: s.bits((!self.ok & !elsewhere).get()),
            elsewhere: s.bits(elsewhere.get()),
            slow: s.bits(self.slow.get()),
            general: s.bits(self.general.get()),
        }
    }
}
