//! The register path's loop over a chunk of the local form (`cpu::register`): 16 rows a
//! step read into two registers, evaluated in two stages and written back, and the lanes
//! it flags handled after a run of steps — sent to the reference or gathered, as
//! [`super::run_blocks`] gathers a block's, for the f64 frame or the general f32 frame.

use super::deferred::{lanes_of, rescue, Chunk, Elsewhere, F64_FRAME, GENERAL_FRAME};
use super::work::{Source, Tally, Work};
use crate::backend::Counts;
use crate::batch::columns::Column;
use crate::batch::COLUMNS_LOCAL;
use crate::cpu::kernel::{self, LANES};
use crate::cpu::plan::Plan;
use crate::cpu::register::{self, Reg, RegisterIo};
use crate::material::Material;
use crate::terms::f::conductor;
use crate::terms::math::Fused;

/// A chunk of the local form on the register path ([`register::serves`]).
pub(super) struct LocalRegisters<'a, 'b> {
    pub(super) plan: &'a Plan,
    pub(super) batch: Source<'a>,
    pub(super) work: &'a mut Work<'b>,
    pub(super) material: &'a Material,
}

impl LocalRegisters<'_, '_> {
    /// The chunk in `simd`'s registers, by the group's distribution, geometry and Fresnel
    /// term.
    #[inline(always)]
    pub(super) fn run<S: RegisterIo>(self, simd: S) -> (Counts, Tally) {
        use crate::terms::{DistributionKind as D, FresnelKind as F, Geometry as G};
        use kernel::{D_BECKMANN, D_GGX, F_CONDUCTOR, F_NONE, F_SCHLICK};
        use kernel::{G_CT, G_NONE, G_SMITH, G_SMITH_CORRELATED, G_SMITH_FAST};
        let Plan::Microfacet { d, g, f, p, .. } = self.plan else {
            unreachable!("the register path serves microfacet groups (`register::serves`)")
        };
        // The conductor's lane form: its segment tables or polynomial where the plan took
        // one (one variant: `register::local_finish` takes the tables where they are
        // present), else the metal form (without its selects where every channel has
        // Re η² < 0).
        use conductor::FORM_TABLES as TABLES;
        use conductor::{FORM_METAL as METAL, FORM_POLY as POLY, FORM_QUOTIENT as QUOTIENT};
        let form = p.conductor_form();
        // The input's form (`INPUT_*`): a function each, so that no loop holds another
        // form's pointers (the local form's rows took 4.5 more instructions an evaluation
        // on AVX2 beside the six columns' test, 63.1 → 67.6 for Beckmann).
        let input = match self.batch {
            Source::Columns(_) => INPUT_XYZ,
            _ if self.batch.local_columns().is_some() => INPUT_PLANAR,
            _ => INPUT_ROWS,
        };
        macro_rules! apart {
            ($d:expr, $g:expr, $f:expr, $q:expr) => {
                match input {
                    INPUT_ROWS => registers_apart::<S, $d, $g, $f, $q, INPUT_ROWS>(simd, self),
                    INPUT_PLANAR => registers_apart::<S, $d, $g, $f, $q, INPUT_PLANAR>(simd, self),
                    _ => registers_apart::<S, $d, $g, $f, $q, INPUT_XYZ>(simd, self),
                }
            };
        }
        macro_rules! by_f {
            ($d:expr, $g:expr) => {
                match f {
                    F::None => apart!($d, $g, F_NONE, METAL),
                    F::Schlick => apart!($d, $g, F_SCHLICK, METAL),
                    _ if form == POLY || form == TABLES => apart!($d, $g, F_CONDUCTOR, POLY),
                    _ if form == QUOTIENT => apart!($d, $g, F_CONDUCTOR, QUOTIENT),
                    _ => apart!($d, $g, F_CONDUCTOR, METAL),
                }
            };
        }
        match (d, g) {
            (D::Beckmann, G::None) => by_f!(D_BECKMANN, G_NONE),
            (D::Beckmann, G::CookTorrance) => by_f!(D_BECKMANN, G_CT),
            (D::Beckmann, _) => by_f!(D_BECKMANN, G_SMITH_FAST),
            (_, G::None) => by_f!(D_GGX, G_NONE),
            (_, G::CookTorrance) => by_f!(D_GGX, G_CT),
            (_, G::Smith) => by_f!(D_GGX, G_SMITH),
            _ => by_f!(D_GGX, G_SMITH_CORRELATED),
        }
    }
}

/// The register path's input: the local form's rows (`(n, 6)`, C order).
const INPUT_ROWS: u8 = 0;
/// The local form as six columns (`LocalLayout::Columns`).
const INPUT_PLANAR: u8 = 1;
/// `(n, 3)` columns of L and V with N = +z given once (a `ColumnBatch`).
const INPUT_XYZ: u8 = 2;

/// [`run_registers`] as a function of its own compiled for `simd` (as each group's lanes
/// are, `dispatch::apart`); `X`: the input's form (`INPUT_*`).
#[inline(never)]
fn registers_apart<
    S: RegisterIo,
    const D: u8,
    const G: u8,
    const F: u8,
    const Q: u8,
    const X: u8,
>(
    simd: S,
    op: LocalRegisters,
) -> (Counts, Tally) {
    simd.vectorize(RegistersFn::<S, D, G, F, Q, X> { simd, op })
}

/// [`run_registers`] as pulp calls it inside the instruction set's features (a struct,
/// not a closure: LLVM left the closure out of line, and with it every intrinsic became a
/// call).
struct RegistersFn<'a, 'b, S, const D: u8, const G: u8, const F: u8, const Q: u8, const X: u8> {
    simd: S,
    op: LocalRegisters<'a, 'b>,
}

impl<S: RegisterIo, const D: u8, const G: u8, const F: u8, const Q: u8, const X: u8>
    pulp::NullaryFnOnce for RegistersFn<'_, '_, S, D, G, F, Q, X>
{
    type Output = (Counts, Tally);

    #[inline(always)]
    fn call(self) -> (Counts, Tally) {
        run_registers::<S, D, G, F, Q, X>(self.simd, self.op)
    }
}

/// The register path's loop over a chunk of the local form: a register of rows at a time
/// read, evaluated (`register::ggx_local_dgk` or `beckmann_local_dgk` by `D`, then
/// `local_finish`) and written, the lanes it flags sent to the reference or gathered for
/// the f64 frame as [`super::run_blocks`] does with a block's.
#[inline(always)]
fn run_registers<S: RegisterIo, const D: u8, const G: u8, const F: u8, const Q: u8, const X: u8>(
    simd: S,
    op: LocalRegisters,
) -> (Counts, Tally) {
    let LocalRegisters {
        plan,
        batch,
        work: w,
        material: m,
    } = op;
    let Plan::Microfacet { p, .. } = plan else {
        unreachable!("the register path serves microfacet groups (`register::serves`)")
    };
    // Two registers a step, staged (`register::ggx_local_dgk`).
    let width = 2 * S::WIDTH;
    let len = w.brdf.len() / 3;
    let data = batch.data();
    let mut counts = Counts::default();
    let mut tally = Tally {
        lanes: len as u64,
        registers: len as u64,
        ..Tally::default()
    };
    let mut later = Flagged {
        steps: [FlaggedStep::default(); FLAGGED_STEPS],
        n: 0,
        elsewhere: Elsewhere::new(
            plan,
            Chunk {
                simd,
                z: true,
                batch,
                m,
            },
        ),
    };
    // The tail's rows, the last repeated (its extra lanes are computed and dropped), and
    // its outputs.
    let mut tail_rows = [0f32; COLUMNS_LOCAL * 2 * LANES];
    let mut tail_out = [0f32; 3 * 2 * LANES];
    // The six columns of a batch held so (`LocalLayout::Columns`).
    let columns: Option<[&[f32]; 6]> =
        batch
            .local_columns()
            .filter(|_| X == INPUT_PLANAR)
            .map(|b| {
                let c = |i| b.column(i).expect("a batch of columns");
                [c(0), c(1), c(2), c(3), c(4), c(5)]
            });
    // L's and V's columns of a `ColumnBatch` (N = +z given once): one vector a row, or
    // one for every row.
    let xyz = match batch {
        Source::Columns(b) if X == INPUT_XYZ => {
            let [l, v, _] = b.directions();
            Some((l, v))
        }
        _ => None,
    };
    let mut j = 0;
    while j < len {
        let n = width.min(len - j);
        let row0 = w.start + j;
        let half = S::WIDTH;
        let ([ax, ay, az, au, av, aw], [bx, by, bz, bu, bv, bw]) = match (columns, xyz) {
            // `(n, 3)` columns: each register's x, y, z from its rows of 3 (one transpose
            // of 3 columns each, where rows of 6 take one of 6).
            (_, Some((l, v))) if n == width => {
                let (a, b) = (row0, row0 + half);
                let ([lx, ly, lz], [vx, vy, vz]) = (xyz_at(simd, l, a), xyz_at(simd, v, a));
                let ([mx, my, mz], [wx, wy, wz]) = (xyz_at(simd, l, b), xyz_at(simd, v, b));
                ([lx, ly, lz, vx, vy, vz], [mx, my, mz, wx, wy, wz])
            }
            // Six columns: each register is 16 (or 8) consecutive values of one.
            (Some(c), _) if n == width => (load6(simd, c, row0), load6(simd, c, row0 + half)),
            _ => {
                let rows = match (columns, xyz) {
                    (None, None) if n == width => {
                        &data[row0 * COLUMNS_LOCAL..(row0 + width) * COLUMNS_LOCAL]
                    }
                    // A tail (of any form) as rows, its last row repeated.
                    _ => {
                        for k in 0..width {
                            let r = row0 + k.min(n - 1);
                            let t = batch.tuple(r);
                            tail_rows[k * COLUMNS_LOCAL..(k + 1) * COLUMNS_LOCAL]
                                .copy_from_slice(&[t.l[0], t.l[1], t.l[2], t.v[0], t.v[1], t.v[2]]);
                        }
                        &tail_rows[..width * COLUMNS_LOCAL]
                    }
                };
                (
                    simd.local_columns(&rows[..half * COLUMNS_LOCAL]),
                    simd.local_columns(&rows[half * COLUMNS_LOCAL..]),
                )
            }
        };
        let r = |x| Reg::new(simd, x);
        let (la, va) = ([r(ax), r(ay), r(az)], [r(au), r(av), r(aw)]);
        let (lb, vb) = ([r(bx), r(by), r(bz)], [r(bu), r(bv), r(bw)]);
        // A step whose lanes all have unit-length L and V (every normalised input) takes
        // the frames' near-unit scales alone, without a branch inside the step.
        let (lo, hi, bad_a, bad_b, fa, fb) = if register::near_unit_step(la, va, lb, vb) {
            two_registers::<S, D, G, F, Q, true>(simd, p, (la, va), (lb, vb))
        } else {
            two_registers::<S, D, G, F, Q, false>(simd, p, (la, va), (lb, vb))
        };
        let out: &mut [f32] = if n == width {
            &mut w.brdf[j * 3..(j + width) * 3]
        } else {
            &mut tail_out[..width * 3]
        };
        simd.rgb_rows(lo, &mut out[..half * 3]);
        simd.rgb_rows(hi, &mut out[half * 3..]);
        if n < width {
            w.brdf[j * 3..(j + n) * 3].copy_from_slice(&tail_out[..n * 3]);
        }
        let valid = u32::MAX >> (32 - n);
        let both = |a: u32, b: u32| (a | (b << half)) & valid;
        let step = FlaggedStep {
            j,
            row0,
            rescue: both(fa.rescue(bad_a), fb.rescue(bad_b)),
            slow: both(fa.slow, fb.slow),
            general: both(fa.general, fb.general),
        };
        // No branch on the flags: which lanes they name is data (a step in three has one
        // at m = 0.3), and a branch a step on them, mispredicted, cost more than the
        // flagged lanes' own work. The slot is kept when a flag is set.
        later.steps[later.n % FLAGGED_STEPS] = step;
        later.n += usize::from(step.rescue | step.slow | step.general != 0);
        if later.n == FLAGGED_STEPS {
            later.handle(w, &mut counts, &mut tally);
        }
        j += n;
    }
    later.handle(w, &mut counts, &mut tally);
    (later.elsewhere).finish::<Fused>(w, &mut counts, &mut tally);
    (counts, tally)
}

/// A step's two registers (`a`, `b`: L and V) through both stages (`NEAR`: every lane's L
/// and V of unit length, `register::near_unit_step`): their RGB, the bits of their output
/// tests, and their first stage's flags.
#[inline(always)]
#[allow(clippy::type_complexity)]
fn two_registers<
    S: RegisterIo,
    const D: u8,
    const G: u8,
    const F: u8,
    const Q: u8,
    const NEAR: bool,
>(
    simd: S,
    p: &kernel::Params,
    a: ([Reg<S>; 3], [Reg<S>; 3]),
    b: ([Reg<S>; 3], [Reg<S>; 3]),
) -> (
    [S::f32s; 3],
    [S::f32s; 3],
    u32,
    u32,
    register::Flags,
    register::Flags,
) {
    // Each register's flags leave its registers as bits after the first stage.
    let sa = register::local_dgk::<_, D, G, F, NEAR>(p, a.0, a.1);
    let fa = sa.flags();
    let sb = register::local_dgk::<_, D, G, F, NEAR>(p, b.0, b.1);
    let fb = sb.flags();
    // The conductor's polynomial, on AVX-512 through an opaque reference: LLVM
    // otherwise hoists its 45 broadcast coefficients out of the loop and spills them,
    // which cost more than the metal form's roots save; read each step, they fold
    // into the FMAs as broadcast operands (`RegisterIo::BROADCAST_OPERANDS`).
    // Each register's own: one reference for both let LLVM read the coefficients
    // for the second while it held the first's.
    let poly = || {
        if S::BROADCAST_OPERANDS {
            std::hint::black_box(p.conductor_poly())
        } else {
            p.conductor_poly()
        }
    };
    // The segment tables likewise: hoisted, their 19 registers would spill.
    let tables = || {
        if S::BROADCAST_OPERANDS {
            std::hint::black_box(p.conductor_segments.as_ref())
        } else {
            p.conductor_segments.as_ref()
        }
    };
    let ([ra, ga, ba], bad_a) = register::local_finish::<_, F, Q>(p, poly(), tables(), sa);
    let ([rb, gb, bb], bad_b) = register::local_finish::<_, F, Q>(p, poly(), tables(), sb);
    (
        [ra.get(), ga.get(), ba.get()],
        [rb.get(), gb.get(), bb.get()],
        simd.bits(bad_a.get()),
        simd.bits(bad_b.get()),
        fa,
        fb,
    )
}

/// A register each of x, y, z of rows `at..` of a direction's column (a vector given once,
/// splatted). A function, not a closure: LLVM left a closure out of line, its intrinsics
/// calls (the `(n, 3)` columns took 94.9 instructions an evaluation instead of 47.9).
#[inline(always)]
fn xyz_at<S: RegisterIo>(simd: S, c: Column, at: usize) -> [S::f32s; 3] {
    match c {
        Column::Each(rows) => simd.xyz_columns(&rows[3 * at..]),
        Column::Every([x, y, z]) => [simd.splat_f32s(x), simd.splat_f32s(y), simd.splat_f32s(z)],
    }
}

/// A register each of the six columns' values from row `at` on.
#[inline(always)]
fn load6<S: RegisterIo>(simd: S, c: [&[f32]; 6], at: usize) -> [S::f32s; 6] {
    [
        load(simd, &c[0][at..]),
        load(simd, &c[1][at..]),
        load(simd, &c[2][at..]),
        load(simd, &c[3][at..]),
        load(simd, &c[4][at..]),
        load(simd, &c[5][at..]),
    ]
}

/// A register of the first [`RegisterIo::WIDTH`] values of `column` (loaded unaligned).
#[inline(always)]
fn load<S: RegisterIo>(_simd: S, column: &[f32]) -> S::f32s {
    bytemuck::pod_read_unaligned(bytemuck::cast_slice(&column[..S::WIDTH]))
}

/// A register step's flagged lanes (bits over its rows, lane k is row `row0 + k`, output
/// `j + k`), for [`Flagged::handle`].
#[derive(Clone, Copy, Default)]
struct FlaggedStep {
    j: usize,
    row0: usize,
    rescue: u32,
    slow: u32,
    general: u32,
}

/// Steps the register path keeps before it handles their flagged lanes.
const FLAGGED_STEPS: usize = 64;

/// The register path's flagged steps and the queues of the lanes other frames take.
struct Flagged<'a, S> {
    steps: [FlaggedStep; FLAGGED_STEPS],
    n: usize,
    elsewhere: Elsewhere<'a, S>,
}

impl<S: pulp::Simd> Flagged<'_, S> {
    /// The kept steps' lanes: to the reference (written now), or gathered for the f64
    /// frame or the general f32 frame (run a block at a time). Their outputs overwrite
    /// what the register path wrote for them.
    fn handle(&mut self, w: &mut Work, counts: &mut Counts, tally: &mut Tally) {
        let Chunk { batch, m, .. } = self.elsewhere.chunk();
        for step in &self.steps[..self.n] {
            let (j, row0) = (step.j, step.row0);
            for k in lanes_of(step.rescue) {
                rescue(batch, m, row0 + k, j + k, w, counts);
                tally.rescued += 1;
            }
            for (lanes, to) in [(step.slow, F64_FRAME), (step.general, GENERAL_FRAME)] {
                for k in lanes_of(lanes) {
                    let (l, v) = {
                        let t = batch.tuple(row0 + k);
                        (t.l, t.v)
                    };
                    let x = [l[0], l[1], l[2], v[0], v[1], v[2], 0.0, 0.0, 1.0];
                    let at = (j + k, row0 + k);
                    self.elsewhere.push::<Fused>(to, x, at, w, counts, tally);
                }
            }
        }
        self.n = 0;
    }
}
