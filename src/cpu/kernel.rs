//! The specialised lanes: one block of [`LANES`] tuples of one material group, the frame
//! (`cpu/frame.rs`) in f32 or f64 lanes, the terms in f32 lanes (FORMULAS.md §1–§6), compiled once per material group
//! (distribution × geometry × Fresnel, as const generics) and per instruction set (the
//! caller dispatches with `pulp`). Every loop runs over the lanes with no data-dependent
//! branch and no call, so it vectorises to the widest registers the dispatch enabled.
//!
//! A lane whose tuple the f32 arithmetic cannot be trusted with is flagged for *rescue* —
//! the caller re-evaluates it with the f64 reference, which also decides its status:
//! invalid and below-horizon tuples, cosines below `frame::GRAZING`, and any output that came
//! out non-finite or above [`OUTPUT_LIMIT`] (the saturation and overflow cases).

// The lane loops index several arrays with the same lane (or column) number; iterator
// forms would hide that the loops are the vectorised dimension.
#![allow(clippy::needless_range_loop)]

use super::frame::{
    frame, frame64, frame_local32, frame_local_h64, length2_ok, near_unit_lanes, rsqrt, Frame,
    Frame64, GRAZING,
};
use crate::backend::TERM_COLUMNS;
use crate::terms::d::{beckmann, blinn, charlie, gaussian, ggx};
use crate::terms::f::{conductor, dielectric, schlick};
use crate::terms::g::{cook_torrance, neubelt, schlick_smith, smith, smith_correlated, smith_fast};
use crate::terms::math::MulAdd;
use crate::terms::{DistributionKind, FresnelKind, Geometry};

mod channels;
mod params;
pub mod two_pass;
pub use channels::OUTPUT_LIMIT;
pub(super) use channels::{brdf_of, channels_of, dgk_of, FresnelOf};
pub use params::Params;

/// Tuples per block: 16 f32 lanes fill one AVX-512 register (two AVX2 registers).
pub const LANES: usize = 16;

// The lanes' const parameters: each family's codes, from its list (`crate::terms`).
/// Distribution: GGX.
pub const D_GGX: u8 = DistributionKind::Ggx.code();
/// Distribution: Beckmann.
pub const D_BECKMANN: u8 = DistributionKind::Beckmann.code();
/// Distribution: Torrance–Sparrow Gaussian.
pub const D_GAUSSIAN: u8 = DistributionKind::Gaussian.code();
/// Distribution: normalised Blinn–Phong NDF.
pub const D_BLINN: u8 = DistributionKind::Blinn.code();
/// Distribution: Estevez–Kulla "Charlie" sheen.
pub const D_CHARLIE: u8 = DistributionKind::Charlie.code();
/// Geometry: none.
pub const G_NONE: u8 = Geometry::None.code();
/// Geometry: Cook–Torrance V-cavity.
pub const G_CT: u8 = Geometry::CookTorrance.code();
/// Geometry: separable Smith.
pub const G_SMITH: u8 = Geometry::Smith.code();
/// Geometry: height-correlated Smith.
pub const G_SMITH_CORRELATED: u8 = Geometry::SmithCorrelated.code();
/// Geometry: Walter's rational Smith–Beckmann fit.
pub const G_SMITH_FAST: u8 = Geometry::SmithFast.code();
/// Geometry: Schlick–Smith with Karis's k.
pub const G_SCHLICK_SMITH: u8 = Geometry::SchlickSmith.code();
/// Geometry: Neubelt–Pettineo cloth.
pub const G_NEUBELT: u8 = Geometry::Neubelt.code();
/// Fresnel: none.
pub const F_NONE: u8 = FresnelKind::None.code();
/// Fresnel: Schlick.
pub const F_SCHLICK: u8 = FresnelKind::Schlick.code();
/// Fresnel: exact dielectric.
pub const F_DIELECTRIC: u8 = FresnelKind::Dielectric.code();
/// Fresnel: exact conductor.
pub const F_CONDUCTOR: u8 = FresnelKind::Conductor.code();

/// One block's inputs as structure of arrays (f32, as read from the rows).
#[derive(Clone, Copy)]
pub struct Inputs {
    /// L, V, N and T components: `v[j][k]` is component `j` of lane `k` (0–8: L, V, N;
    /// 9–11: T, filled only for the groups that read it).
    pub v: [[f32; LANES]; 12],
}

impl Default for Inputs {
    fn default() -> Self {
        Inputs {
            v: [[0.0; LANES]; 12],
        }
    }
}

/// One block's outputs.
#[derive(Clone, Copy)]
pub struct Outputs {
    /// RGB per lane.
    pub brdf: [[f32; LANES]; 3],
    /// D, G, F_r, F_g, F_b, K per lane.
    pub terms: [[f32; LANES]; TERM_COLUMNS],
    /// Lanes to re-evaluate with the reference.
    pub rescue: [bool; LANES],
    /// Lanes left to the f64 frame by a block of a plan that defers them
    /// ([`Params::defer_slow`]): their other outputs are not the lane's.
    pub slow: [bool; LANES],
    /// Lanes left to the general f32 frame by such a block (the local frame's certificate
    /// refused them): their other outputs are not the lane's.
    pub general: [bool; LANES],
}

impl Outputs {
    /// Whether any lane is flagged for rescue ([`any`]).
    #[inline(always)]
    pub fn any_rescue(&self) -> bool {
        any(&self.rescue)
    }

    /// Whether any lane was left to the f64 frame ([`Outputs::slow`], [`any`]).
    #[inline(always)]
    pub fn any_slow(&self) -> bool {
        any(&self.slow)
    }

    /// Whether any lane was left to the general f32 frame ([`Outputs::general`], [`any`]).
    #[inline(always)]
    pub fn any_general(&self) -> bool {
        any(&self.general)
    }
}

/// Whether any of a block's flags is set: one 16-byte test instead of a branch a lane (the
/// per-lane loop cost about 5 % of a microfacet block).
#[inline(always)]
pub fn any(flags: &[bool; LANES]) -> bool {
    u128::from_ne_bytes(flags.map(u8::from)) != 0
}

/// A block's flags as bits (lane k is bit k).
#[inline(always)]
pub fn bits(flags: &[bool; LANES]) -> u32 {
    flags
        .iter()
        .enumerate()
        .fold(0, |m, (k, &f)| m | (u32::from(f) << k))
}

impl Default for Outputs {
    fn default() -> Self {
        Outputs {
            brdf: [[0.0; LANES]; 3],
            terms: [[0.0; LANES]; TERM_COLUMNS],
            rescue: [false; LANES],
            slow: [false; LANES],
            general: [false; LANES],
        }
    }
}

#[inline(always)]
pub(super) fn lane_inputs(inp: &Inputs, k: usize) -> [f32; 9] {
    std::array::from_fn(|j| inp.v[j][k])
}

/// Smith's Λ (FORMULAS.md §3) given `q2 = m² tan²θ`: the distribution `D`'s own.
#[inline(always)]
fn lambda<const D: u8>(q2: f32) -> f32 {
    match const { DistributionKind::from_code(D) } {
        DistributionKind::Ggx => ggx::lambda_lane(q2),
        DistributionKind::Beckmann => beckmann::lambda_lane(q2),
        // The Smith terms are not defined without a Λ (`Geometry::legality`), and the
        // dispatch (`cpu::block`) compiles none of these groups with one.
        DistributionKind::Gaussian | DistributionKind::Blinn | DistributionKind::Charlie => {
            unreachable!("no Smith Λ for this distribution")
        }
    }
}

/// Lambert on one block (`Z`: N = (0, 0, 1), the local form): only the validity and the
/// horizon matter, so only the two cosines are formed, as `frame` forms them (a cosine
/// below `frame::GRAZING` still goes to the reference, which decides the horizon case).
#[inline(always)]
pub fn lambert_block<const Z: bool>(p: &Params, inp: &Inputs, out: &mut Outputs) {
    for k in 0..LANES {
        let x = lane_inputs(inp, k);
        let (lx, ly, lz) = (x[0], x[1], x[2]);
        let (vx, vy, vz) = (x[3], x[4], x[5]);
        let (ll, vv) = (lx * lx + ly * ly + lz * lz, vx * vx + vy * vy + vz * vz);
        let (il, iv) = (rsqrt(ll), rsqrt(vv));
        let (cos_i, cos_o, n_ok) = if Z {
            // N = (0, 0, 1): the general form's bits (see `frame`).
            (lz * il, vz * iv, true)
        } else {
            let (nx, ny, nz) = (x[6], x[7], x[8]);
            let nn = nx * nx + ny * ny + nz * nz;
            let inn = rsqrt(nn);
            let (nx, ny, nz) = (nx * inn, ny * inn, nz * inn);
            (
                nx * (lx * il) + ny * (ly * il) + nz * (lz * il),
                nx * (vx * iv) + ny * (vy * iv) + nz * (vz * iv),
                length2_ok(nn),
            )
        };
        let g = GRAZING as f32;
        out.rescue[k] = !(length2_ok(ll) && length2_ok(vv) && n_ok && cos_i >= g && cos_o >= g);
        for ch in 0..3 {
            out.brdf[ch][k] = p.diffuse[ch];
        }
    }
}

/// Lambert's terms, the same in every lane: D = 0, G = F = K = 1 (FORMULAS.md §6). Set once
/// a chunk, not by [`lambert_block`] (whose per-lane stores of these constants took 15 %
/// of its time).
pub fn lambert_terms(out: &mut Outputs) {
    out.terms[0] = [0.0; LANES];
    for t in 1..TERM_COLUMNS {
        out.terms[t] = [1.0; LANES];
    }
}

/// A lane's frame as the terms read it: f32 values, and f64 ones where D and the
/// dielectric Fresnel take f64 — from [`frame`], or [`frame64`] rounded.
#[derive(Clone, Copy)]
pub(crate) struct Lane {
    cos_i: f32,
    cos_o: f32,
    cos_h: f32,
    c: f32,
    sin2_i: f32,
    sin2_o: f32,
    /// `1 − c` and `sin²` of `c`, for Schlick and the conductor.
    one_minus_c: f32,
    s2: f32,
    sin2_h32: f32,
    /// tan²θ_h (Beckmann's f32 D).
    tan2_h32: f32,
    cos_h2: f64,
    sin2_h: f64,
    c64: f64,
    s2_64: f64,
    pub(super) ok: bool,
}

impl Lane {
    #[inline(always)]
    fn from32(f: &Frame) -> Lane {
        // 1 − c = sin²/(1 + c), which does not cancel.
        let one_minus_c = f.s2 / (1.0 + f.c);
        let c64 = f64::from(f.c);
        Lane {
            cos_i: f.cos_i,
            cos_o: f.cos_o,
            cos_h: f.cos_h,
            c: f.c,
            sin2_i: f.sin2_i,
            sin2_o: f.sin2_o,
            one_minus_c,
            s2: f.s2,
            sin2_h32: f.sin2_h,
            tan2_h32: f.tan2_h,
            cos_h2: f64::from(f.cos_h) * f64::from(f.cos_h),
            sin2_h: f64::from(f.sin2_h),
            c64,
            s2_64: f64::from(f.s2),
            ok: f.ok,
        }
    }

    #[inline(always)]
    pub(super) fn from64(f: &Frame64) -> Lane {
        // 1 − c in f64: of a c rounded to f32 it would cancel.
        let s2_64 = (1.0 - f.c) * (1.0 + f.c);
        Lane {
            cos_i: f.cos_i as f32,
            cos_o: f.cos_o as f32,
            cos_h: f.cos_h as f32,
            c: f.c as f32,
            sin2_i: f.sin2_i as f32,
            sin2_o: f.sin2_o as f32,
            one_minus_c: (1.0 - f.c) as f32,
            s2: s2_64 as f32,
            sin2_h32: f.sin2_h as f32,
            // Not read: the f64 frame's lanes take D's f64 forms.
            tan2_h32: (f.sin2_h / (f.cos_h * f.cos_h)) as f32,
            cos_h2: f.cos_h * f.cos_h,
            sin2_h: f.sin2_h,
            c64: f.c,
            s2_64,
            ok: f.ok,
        }
    }
}

/// Smallest `c = v · h` for which a lane may take the f32 frame: below it (l and v more
/// than 168° apart, grazing mirror geometry) the half vector's components cancel, which
/// the rule allows for but the f64 frame does not need to (docs/CPU_ENGINE.md has the
/// tolerance each threshold used). Uniform directions fall below it in 0.09 % of lanes.
pub const FAST_MIN_C: f32 = 0.1;

/// Smallest roughness m for which a material may take the f32 frame. With h formed in
/// f64 and its cross product with N too, the frame no longer turns h (its D error is
/// ~10u, u = 2⁻²⁴), and the f32 terms add ≤ 25u; the threshold was set from the earlier
/// bound `10u/m + 25u ≤ 1e-5` (m ≥ 0.0687) and keeps D's f32 quantities far inside f32's
/// normal range. Lowering it is a measured change still to make (docs/CPU_ENGINE.md, "The
/// f32 frame's error bound"). Below it the f64 frame takes the material.
pub const FAST_MIN_ROUGHNESS: f64 = 0.075;

/// Isotropic Cook–Torrance on one block, specialised to one distribution, geometry and
/// Fresnel term, and (`Z`) to N = (0, 0, 1) for the local form.
///
/// The frame is f32 (`frame`; for GGX's lanes with N = +z `frame_local32`, where D's
/// test `ggx::local_frame_ok` certifies it, for Beckmann's `frame_local_h64`) when the
/// material allows it
/// ([`Params::fast_frame`]) and the lane does (`c` ≥ [`FAST_MIN_C`]); the other lanes take
/// the f64 frame (`frame64`), which a block computes only when it has such a lane — or,
/// for a plan that defers them ([`Params::defer_slow`]), leaves to the caller, which
/// gathers them from many blocks. The choice depends only on the lane's own f32 frame,
/// whose bits the local form and the rows with N = (0, 0, 1) share, so a lane's result
/// depends on its tuple alone and both forms give the same bits.
#[inline(always)]
pub fn microfacet_block<A: MulAdd, const D: u8, const G: u8, const F: u8, const Z: bool>(
    p: &Params,
    inp: &Inputs,
    out: &mut Outputs,
) {
    // Lanes for the f64 frame: every lane unless the material may take the f32 frame
    // (`Params::fast_frame`). Only the fused groups (`fused`) are compiled here: the
    // dielectric and the other distributions take `dg_block64`.
    let mut slow = [true; LANES];
    // Lanes of the local frame its certificate refused, for the general f32 frame.
    let mut general = [false; LANES];
    if p.fast_frame {
        // The block's f32 frames as structure of arrays (an array of `Frame`s kept LLVM
        // from vectorising either loop: 4× slower).
        let mut fs = [[0.0f32; LANES]; 8];
        let mut ok = [false; LANES];
        // GGX's lanes with N = +z take the f32 local frame where D's test certifies it
        // (`frame_local32`), Beckmann's the one with h in f64 (`frame_local_h64`, no
        // certificate): the local form's lanes always, the rows' where N is exactly
        // (0, 0, 1) (so that both forms keep giving the same bits); a block computes only
        // the frames its lanes take.
        let local_d = const {
            matches!(
                DistributionKind::from_code(D),
                DistributionKind::Ggx | DistributionKind::Beckmann
            )
        };
        // Which lanes have N = +z (every lane of the local form).
        let z: [bool; LANES] = if Z || !local_d {
            [Z; LANES]
        } else {
            std::array::from_fn(|k| inp.v[6][k] == 0.0 && inp.v[7][k] == 0.0 && inp.v[8][k] == 1.0)
        };
        let mode = if !local_d || !any(&z) || p.general_frame_only {
            FRAME_GENERAL
        } else if !z.contains(&false) {
            // A loop, not `array::from_fn`'s closure: LLVM left that out of line, outside
            // the instruction set's features, and every FMA in it became a `fmaf` call.
            let mut near = [false; LANES];
            for (k, near) in near.iter_mut().enumerate() {
                let x = lane_inputs(inp, k);
                *near = near_unit_lanes::<A, f32>([x[0], x[1], x[2]], [x[3], x[4], x[5]]);
            }
            if near.contains(&false) {
                FRAME_LOCAL
            } else {
                FRAME_LOCAL_NEAR
            }
        } else {
            FRAME_EACH
        };
        // One call a mode (a const parameter each), the same arguments.
        macro_rules! frames_in {
            ($mode:expr) => {
                frames::<A, D, Z, { $mode }>(p, inp, &z, &mut fs, &mut ok, &mut slow, &mut general)
            };
        }
        match mode {
            FRAME_LOCAL_NEAR => frames_in!(FRAME_LOCAL_NEAR),
            FRAME_LOCAL => frames_in!(FRAME_LOCAL),
            FRAME_EACH => frames_in!(FRAME_EACH),
            _ => frames_in!(FRAME_GENERAL),
        }
        // In the block, unless the caller gathers them (as it does the f64 frame's lanes):
        // computed here, they made every block with one run both frames.
        if any(&general) && !p.defer_slow {
            general_frames::<A, D, Z>(inp, &general, &mut fs, &mut ok, &mut slow);
            general = [false; LANES];
        }
        // Two loops, so that the one without terms divides nothing out; a conductor whose
        // every channel is legal for it takes F's metal form (`conductor::f_lane_metal`,
        // half the arithmetic) or, where the plan fitted one, its polynomial in c or (on
        // AVX-512) its segment tables (valid for c ≥ FAST_MIN_C: these lanes), while the
        // f64 frame's lanes keep the scaled form, as the other Fresnel terms keep theirs.
        use conductor::FORM_TABLES as TABLES;
        use conductor::{FORM_METAL as METAL, FORM_POLY as POLY, FORM_SCALED as SCALED};
        // The quotient form is the metal form's bits: the lane loops keep one of the two.
        let form = match p.conductor_form() {
            _ if F != F_CONDUCTOR => SCALED,
            conductor::FORM_QUOTIENT => METAL,
            form => form,
        };
        match (p.terms, form) {
            (true, SCALED) => terms32::<A, D, G, F, true, SCALED>(p, &fs, &ok, out),
            (false, SCALED) => terms32::<A, D, G, F, false, SCALED>(p, &fs, &ok, out),
            (true, METAL) => terms32::<A, D, G, F, true, METAL>(p, &fs, &ok, out),
            (false, METAL) => terms32::<A, D, G, F, false, METAL>(p, &fs, &ok, out),
            (true, POLY) => terms32::<A, D, G, F, true, POLY>(p, &fs, &ok, out),
            (false, POLY) => terms32::<A, D, G, F, false, POLY>(p, &fs, &ok, out),
            (true, _) => terms32::<A, D, G, F, true, TABLES>(p, &fs, &ok, out),
            (false, _) => terms32::<A, D, G, F, false, TABLES>(p, &fs, &ok, out),
        }
    }
    if p.defer_slow && p.fast_frame {
        // The caller runs these lanes on the f64 frame and the general f32 frame (with the
        // other blocks' ones).
        out.slow = slow;
        out.general = general;
        for k in 0..LANES {
            out.rescue[k] &= !(slow[k] | general[k]);
        }
        return;
    }
    // Every lane of a material without the f32 frame is "slow": none is left to a caller.
    out.slow = [false; LANES];
    out.general = [false; LANES];
    if any(&slow) {
        // The lanes the f32 frame cannot serve take the f64 frame's results, lane by lane:
        // what a lane gets must not depend on its neighbours in the block, or the output
        // would change with the chunking (the stream's, the shards').
        let mut o64 = Outputs::default();
        microfacet_block64::<A, D, G, F>(p, inp, &mut o64);
        for k in 0..LANES {
            if slow[k] {
                for ch in 0..3 {
                    out.brdf[ch][k] = o64.brdf[ch][k];
                }
                for t in 0..TERM_COLUMNS {
                    out.terms[t][k] = o64.terms[t][k];
                }
                out.rescue[k] = o64.rescue[k];
            }
        }
    }
}

/// The terms and the BRDF of a block's lanes on their f32 frames (`fs`, `ok` from
/// [`frames`]); `T` and `M` as [`finish_lane`] takes them.
#[inline(always)]
fn terms32<A: MulAdd, const D: u8, const G: u8, const F: u8, const T: bool, const M: u8>(
    p: &Params,
    fs: &[[f32; LANES]; 8],
    ok: &[bool; LANES],
    out: &mut Outputs,
) {
    // The segment tables' form: the block's F at once, in AVX-512's registers (the
    // register path's instructions), before the lanes' loop, which reads it.
    let f_tables = match p.conductor_segments.as_ref() {
        Some(tables) if F == F_CONDUCTOR && M == conductor::FORM_TABLES => {
            super::segments::f_block(&fs[3], tables)
        }
        _ => [[1.0; LANES]; 3],
    };
    for k in 0..LANES {
        let lane = Lane::from32(&Frame {
            cos_i: fs[0][k],
            cos_o: fs[1][k],
            cos_h: fs[2][k],
            c: fs[3][k],
            // Slot 4 holds sin²θ_h, or tan²θ_h for Beckmann ([`frame_slots`]).
            sin2_h: fs[4][k],
            tan2_h: fs[4][k],
            sin2_i: fs[5][k],
            sin2_o: fs[6][k],
            s2: fs[7][k],
            ok: ok[k],
        });
        let f = [f_tables[0][k], f_tables[1][k], f_tables[2][k]];
        microfacet_lane::<A, D, G, F, true, T, M>(p, &lane, f, out, k);
    }
}

/// A lane's frame as [`terms32`] reads it from a block's eight arrays: slot 4 is
/// tan²θ_h for Beckmann (its D reads that and no sine), sin²θ_h for the others.
#[inline(always)]
fn frame_slots<const D: u8>(fr: &Frame) -> [f32; 8] {
    let beckmann = const { matches!(DistributionKind::from_code(D), DistributionKind::Beckmann) };
    let h = if beckmann { fr.tan2_h } else { fr.sin2_h };
    [
        fr.cos_i, fr.cos_o, fr.cos_h, fr.c, h, fr.sin2_i, fr.sin2_o, fr.s2,
    ]
}

/// Which f32 frame a block's lanes take (see [`frames`]).
const FRAME_GENERAL: u8 = 0;
const FRAME_LOCAL: u8 = 1;
const FRAME_EACH: u8 = 2;
/// [`FRAME_LOCAL`] where every lane's L and V are also of unit length
/// (`frame::near_unit_lanes`): the local frames' near-unit scales alone, as the register
/// path's steps take them.
const FRAME_LOCAL_NEAR: u8 = 3;

/// The f32 frames of a block into `fs` (structure of arrays) and `ok`, the lanes that
/// must take the f64 frame into `slow`, and the lanes of the local frame that its
/// certificate refused into `general`: `MODE` [`FRAME_GENERAL`] takes [`frame`] in every
/// lane, [`FRAME_LOCAL`] the local frame of distribution `D` ([`local_frame`]: GGX's lanes
/// with N = +z each certified by D's test `ggx::local_frame_ok`, else left to
/// [`general_frames`]; Beckmann's without a test), [`FRAME_EACH`] whichever of the two the
/// lane's N asks for (`z`: N is exactly (0, 0, 1), `-0` components included).
#[inline(always)]
fn frames<A: MulAdd, const D: u8, const Z: bool, const MODE: u8>(
    p: &Params,
    inp: &Inputs,
    z: &[bool; LANES],
    fs: &mut [[f32; LANES]; 8],
    ok: &mut [bool; LANES],
    slow: &mut [bool; LANES],
    general: &mut [bool; LANES],
) {
    for k in 0..LANES {
        let x = lane_inputs(inp, k);
        let (xl, xv) = ([x[0], x[1], x[2]], [x[3], x[4], x[5]]);
        let (fr, local) = match MODE {
            FRAME_LOCAL_NEAR => (local_frame::<A, D, true>(xl, xv), true),
            FRAME_LOCAL => (local_frame::<A, D, false>(xl, xv), true),
            FRAME_EACH => {
                let (a, b) = (local_frame::<A, D, false>(xl, xv), frame::<A, Z>(&x));
                (if z[k] { a } else { b }, z[k])
            }
            _ => (frame::<A, Z>(&x), false),
        };
        // `&` and `|`, not `&&` and `||`: the short-circuits kept this loop from
        // vectorising (a scalar frame a lane: 160 instructions an evaluation, not 70).
        let below = fr.ok & (fr.c < FAST_MIN_C);
        slow[k] = below;
        if MODE != FRAME_GENERAL {
            let ggx = const { matches!(DistributionKind::from_code(D), DistributionKind::Ggx) };
            let certified = !local
                | !ggx
                | ggx::local_frame_ok(fr.cos_h, fr.sin2_h, fr.c, p.m2_f, p.ggx_local_guard);
            general[k] = fr.ok & !below & !certified;
        }
        let v = frame_slots::<D>(&fr);
        for j in 0..8 {
            fs[j][k] = v[j];
        }
        ok[k] = fr.ok;
    }
}

/// The local form's f32 frame of distribution `D` (N = +z): GGX's `frame_local32`, whose
/// lanes D's certificate then tests, or Beckmann's `frame_local_h64`, whose bound holds on
/// every lane (docs/CPU_ENGINE.md).
#[inline(always)]
fn local_frame<A: MulAdd, const D: u8, const NEAR: bool>(l: [f32; 3], v: [f32; 3]) -> Frame {
    match const { DistributionKind::from_code(D) } {
        DistributionKind::Beckmann => frame_local_h64::<A, f32, NEAR>(l, v),
        _ => frame_local32::<A, f32, NEAR>(l, v),
    }
}

/// The general f32 frame ([`frame`], l, v and h formed in f64) in the lanes of `general`
/// — those whose local f32 frame D's certificate refused: its bound holds on every lane of
/// a material that may take the f32 frame (docs/CPU_ENGINE.md, "The f32 frame's error
/// bound") — with their `ok` and, where its `c` is below [`FAST_MIN_C`], `slow`.
#[inline(always)]
fn general_frames<A: MulAdd, const D: u8, const Z: bool>(
    inp: &Inputs,
    general: &[bool; LANES],
    fs: &mut [[f32; LANES]; 8],
    ok: &mut [bool; LANES],
    slow: &mut [bool; LANES],
) {
    for k in 0..LANES {
        let fr = frame::<A, Z>(&lane_inputs(inp, k));
        let v = frame_slots::<D>(&fr);
        if general[k] {
            for j in 0..8 {
                fs[j][k] = v[j];
            }
            ok[k] = fr.ok;
            slow[k] = fr.ok && fr.c < FAST_MIN_C;
        }
    }
}

/// [`microfacet_block`] with the f64 frame in every lane. The local form's blocks carry
/// N = (0, 0, 1) in their lanes, so one variant serves both forms (an N = +z variant
/// doubled the slow path's code and put the binary past its 48 MiB budget).
#[inline(always)]
fn microfacet_block64<A: MulAdd, const D: u8, const G: u8, const F: u8>(
    p: &Params,
    inp: &Inputs,
    out: &mut Outputs,
) {
    for k in 0..LANES {
        let fr = frame64(&lane_inputs(inp, k));
        microfacet_lane::<A, D, G, F, false, true, { conductor::FORM_SCALED }>(
            p,
            &Lane::from64(&fr),
            [1.0; 3],
            out,
            k,
        );
    }
}

/// Whether a microfacet group runs fused, with the f32 frame where it suffices
/// ([`microfacet_block`]): GGX and Beckmann with the V-cavity, a Smith geometry or none,
/// and any Fresnel term but the dielectric (whose f64 evaluation wants the f64 frame) —
/// the common groups. The others take the two-pass f64 path ([`two_pass::dg_block64`]).
pub fn fused(d: DistributionKind, aniso: bool, g: Geometry, f: FresnelKind) -> bool {
    let d = !aniso && matches!(d, DistributionKind::Ggx | DistributionKind::Beckmann);
    let g = match g {
        Geometry::None
        | Geometry::CookTorrance
        | Geometry::Smith
        | Geometry::SmithCorrelated
        | Geometry::SmithFast => true,
        Geometry::SchlickSmith | Geometry::Neubelt => false,
    };
    d && g && f != FresnelKind::Dielectric
}

/// The terms and the BRDF of lane `k` from its frame (`FAST`: the f32 frame's, see D;
/// `T`: the terms are wanted; `M`: the conductor's lane form, see [`finish_lane`], and
/// `f` its F where the block formed it: the segment tables' form).
#[inline(always)]
fn microfacet_lane<
    A: MulAdd,
    const D: u8,
    const G: u8,
    const F: u8,
    const FAST: bool,
    const T: bool,
    const M: u8,
>(
    p: &Params,
    fr: &Lane,
    f: [f32; 3],
    out: &mut Outputs,
    k: usize,
) {
    let (d, g) = microfacet_dg::<A, D, G, FAST>(p, fr);
    finish_lane::<A, F, T, M>(p, fr, d, g, f, out, k);
}

/// D and G of one lane (FORMULAS.md §2–§3) from its frame (`FAST`: the f32 frame's), each
/// as a quotient `(num, den)` where a form has one without a division of its own (GGX's
/// D on the f32 frame, GGX's Smith terms, smith-fast), else `(value, 1)`.
#[inline(always)]
fn microfacet_dg<A: MulAdd, const D: u8, const G: u8, const FAST: bool>(
    p: &Params,
    fr: &Lane,
) -> ((f32, f32), (f32, f32)) {
    let (cos_i, cos_o, cos_h) = (fr.cos_i, fr.cos_o, fr.cos_h);
    // D (FORMULAS.md §2): the f32 frame's lanes (`FAST`) take GGX's and Beckmann's f32
    // forms, the f64 frame's their f64 ones.
    let d = match const { DistributionKind::from_code(D) } {
        DistributionKind::Gaussian => (gaussian::d_lane(cos_h, fr.sin2_h32, p.inv_m2_f), 1.0),
        DistributionKind::Blinn => (
            blinn::d_lane(cos_h, fr.sin2_h32, p.exponent, p.d_norm_f),
            1.0,
        ),
        DistributionKind::Charlie => (
            charlie::d_lane(fr.cos_h2 as f32, fr.sin2_h32, p.exponent, p.d_norm_f),
            1.0,
        ),
        DistributionKind::Ggx if FAST => {
            ggx::d_ratio32::<A, f32>(cos_h, fr.sin2_h32, p.m2_f, p.d_norm_f)
        }
        DistributionKind::Ggx => (ggx::d_lane64(fr.cos_h2, fr.sin2_h, p.m2, p.d_norm), 1.0),
        DistributionKind::Beckmann if FAST => (
            beckmann::d_lane32::<A, _>(fr.tan2_h32, p.inv_m2_f, p.d_norm_f, p.d_exp_floor),
            1.0,
        ),
        DistributionKind::Beckmann => (
            beckmann::d_lane64(fr.cos_h2, fr.sin2_h, p.inv_m2, p.d_norm),
            1.0,
        ),
    };
    let m2 = p.m2 as f32;
    let ggx = const { matches!(DistributionKind::from_code(D), DistributionKind::Ggx) };
    let g = match const { Geometry::from_code(G) } {
        Geometry::Smith if ggx => {
            smith::g_ratio_ggx::<A, f32>(cos_i, fr.sin2_i, cos_o, fr.sin2_o, m2)
        }
        Geometry::SmithCorrelated if ggx => {
            smith_correlated::g_ratio_ggx::<A, f32>(cos_i, fr.sin2_i, cos_o, fr.sin2_o, m2)
        }
        Geometry::SmithFast => {
            smith_fast::g_ratio::<A, f32>(cos_i, fr.sin2_i, cos_o, fr.sin2_o, p.m_f)
        }
        _ => {
            // q2 = m² tan²θ = m² |n × w|² / cos²θ: products and quotients of positive
            // numbers, which f32 carries to a few ulp (the cancelling parts, |n × w|² and
            // the cosines, come from the frame).
            let q2_i = m2 * fr.sin2_i / (cos_i * cos_i);
            let q2_o = m2 * fr.sin2_o / (cos_o * cos_o);
            (geometry::<D, G>(p, fr, q2_i, q2_o), 1.0)
        }
    };
    (d, g)
}

/// G (FORMULAS.md §3) of one lane given `q2 = m² tan²θ` of each direction (for
/// anisotropic roughness `(mx² (w·t)² + my² (w·b)²)/cos²θ`); `D` picks Smith's Λ.
#[inline(always)]
pub(super) fn geometry<const D: u8, const G: u8>(
    p: &Params,
    fr: &Lane,
    q2_i: f32,
    q2_o: f32,
) -> f32 {
    let (cos_i, cos_o, cos_h, c) = (fr.cos_i, fr.cos_o, fr.cos_h, fr.c);
    match const { Geometry::from_code(G) } {
        Geometry::None => 1.0,
        Geometry::CookTorrance => cook_torrance::g_lane(cos_h, cos_i, cos_o, c),
        Geometry::Smith => smith::g_lane(lambda::<D>(q2_o), lambda::<D>(q2_i)),
        Geometry::SmithCorrelated => smith_correlated::g_lane(lambda::<D>(q2_o), lambda::<D>(q2_i)),
        Geometry::SmithFast => smith_fast::g1_lane(q2_o) * smith_fast::g1_lane(q2_i),
        Geometry::SchlickSmith => {
            schlick_smith::g_lane(cos_o, fr.sin2_o, cos_i, fr.sin2_i, p.schlick_k)
        }
        Geometry::Neubelt => neubelt::g_lane(cos_i, cos_o),
    }
}

/// F, K and the outputs of lane `k` given its D and G as quotients (FORMULAS.md §4–§6):
/// D·G·K takes one division (the divider is what a block waits on); the terms themselves
/// are divided out only when wanted (`T`), after the BRDF, whose bits do not depend on
/// `T`. `M`: the conductor's lane form (`conductor::FORM_*`): the metal form
/// (`conductor::f_lane_metal`) or the polynomial (`conductor::poly::f_lanes_poly`, the f32 frame's
/// lanes only), or the segment tables' (`FORM_TABLES`, which the block forms and hands
/// the lane's as `f_tables`, which no other form reads), which the caller chooses only for
/// a material legal for it, else the scaled form.
#[inline(always)]
fn finish_lane<A: MulAdd, const F: u8, const T: bool, const M: u8>(
    p: &Params,
    fr: &Lane,
    d: (f32, f32),
    g: (f32, f32),
    f_tables: [f32; 3],
    out: &mut Outputs,
    k: usize,
) {
    let (cos_i, cos_o) = (fr.cos_i, fr.cos_o);
    // F (FORMULAS.md §4) per channel. A loop, not `array::from_fn`: LLVM declined to
    // inline from_fn's closure around the conductor, which made every lane a call and
    // nothing vectorised.
    let mut f = [1.0f32; 3];
    if F == F_CONDUCTOR && M == conductor::FORM_TABLES {
        f = f_tables;
    } else if F == F_CONDUCTOR && M == conductor::FORM_POLY {
        // The three channels' polynomials at once.
        f = conductor::poly::f_lanes_poly::<A, f32>(fr.c, p.conductor_poly());
    } else {
        for ch in 0..3 {
            f[ch] = lane_f::<A, F, M>(p, fr, ch);
        }
    }
    let (brdf, too_large) = brdf_of::<A, f32>(p, d, g, f, cos_i, cos_o);
    for ch in 0..3 {
        out.brdf[ch][k] = brdf[ch];
    }
    if T {
        let terms = [d.0 / d.1, g.0 / g.1, f[0], f[1], f[2], p.k.k(cos_i, cos_o)];
        for (t, x) in terms.into_iter().enumerate() {
            out.terms[t][k] = x;
        }
    }
    out.rescue[k] = !fr.ok || too_large;
}

/// F of channel `ch` of a lane in any lane form but the polynomial ([`finish_lane`] forms
/// its three channels at once).
#[inline(always)]
fn lane_f<A: MulAdd, const F: u8, const M: u8>(p: &Params, fr: &Lane, ch: usize) -> f32 {
    let (c, s2_f, one_minus_c) = (fr.c, fr.s2, fr.one_minus_c);
    match const { FresnelKind::from_code(F) } {
        FresnelKind::None => 1.0,
        FresnelKind::Schlick => schlick::f_lane(one_minus_c, p.f0[ch]),
        FresnelKind::Dielectric => dielectric::f_lane(fr.c64, fr.s2_64, p.ior[ch], p.mu2m1[ch]),
        FresnelKind::Conductor if M == conductor::FORM_METAL => {
            conductor::f_lane_metal::<A, f32>(c, s2_f, &p.conductor, ch)
        }
        FresnelKind::Conductor => conductor::f_lane(c, s2_f, &p.conductor, ch),
    }
}

#[cfg(test)]
mod tests;
