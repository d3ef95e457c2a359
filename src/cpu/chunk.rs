//! One chunk's rows through a material group's lanes: what the engine reads
//! ([`Source`]), a unit of work's outputs ([`Work`]), the loop that fills a run of blocks,
//! calls the group's lanes ([`super::dispatch`]) and writes the run out, and the rescue of
//! the lanes the lanes cannot vouch for by the f64 reference.

// Lane loops index the lanes' arrays by lane number (see kernel.rs).
#![allow(clippy::needless_range_loop)]

use super::dispatch::block;
use super::kernel::{self, Inputs, Outputs, LANES};
use super::plan::Plan;
use super::register::{self, Reg, RegisterIo, RegisterOp, Registers};
use super::{measured, slice_tuples, transpose};
use crate::backend::{Counts, TERM_COLUMNS};
use crate::batch::columns::{Column, ColumnBatch};
use crate::batch::{Batch, LocalBatch, Tuple, COLUMNS_LOCAL, COLUMNS_PLAIN, COLUMNS_TANGENT};
use crate::material::{Material, Model};
use crate::reference::{evaluate_tuple, to_output_f32, Status};
use crate::terms::math::{Fused, MulAdd, Rounded};

/// Where the tuples of the last evaluation went.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Tally {
    /// Tuples of material groups that run in the lanes.
    pub lanes: u64,
    /// Of those, tuples re-evaluated by the reference (invalid, below the horizon, grazing,
    /// or an output the lanes cannot vouch for).
    pub rescued: u64,
    /// Tuples of material groups that run on the reference.
    pub reference: u64,
    /// Of `lanes`, tuples their block's f32 frame could not serve, gathered into blocks of
    /// the f64 frame ([`kernel::Params::defer_slow`]).
    pub deferred: u64,
    /// Of `lanes`, tuples read and evaluated on the register path
    /// (`cpu::register`; their deferred and rescued lanes are counted above too).
    pub registers: u64,
}

impl Tally {
    pub(super) fn add(&mut self, o: &Tally) {
        self.lanes += o.lanes;
        self.rescued += o.rescued;
        self.reference += o.reference;
        self.deferred += o.deferred;
        self.registers += o.registers;
    }
}

/// What the engine reads: ordinary rows, or the local-frame form.
#[derive(Clone, Copy)]
pub(super) enum Source<'a> {
    Rows(&'a Batch<'a>),
    Local(&'a LocalBatch),
    /// A half/difference slice whose tuples the workers make block by block.
    Slice(&'a slice_tuples::SliceTuples),
    /// A batch given as columns, read in place.
    Columns(&'a ColumnBatch<'a>),
}

impl Source<'_> {
    pub(super) fn len(&self) -> usize {
        match self {
            Source::Rows(b) => b.len(),
            Source::Local(b) => b.len(),
            Source::Slice(s) => s.len(),
            Source::Columns(b) => b.len(),
        }
    }

    pub(super) fn material(&self, i: usize) -> usize {
        match self {
            Source::Rows(b) => b.material(i),
            Source::Local(b) => b.material(),
            Source::Slice(_) => 0,
            Source::Columns(b) => b.material(i),
        }
    }

    pub(super) fn tuple(&self, i: usize) -> Tuple {
        match self {
            Source::Rows(b) => b.tuple(i),
            Source::Local(b) => b.tuple(i),
            Source::Slice(s) => s.tuple(i),
            Source::Columns(b) => b.tuple(i),
        }
    }

    pub(super) fn data(&self) -> &[f32] {
        match self {
            Source::Rows(b) => b.as_slice(),
            Source::Local(b) => b.as_slice(),
            // Made block by block (see `run_chunk`), never read as rows.
            Source::Slice(_) | Source::Columns(_) => &[],
        }
    }

    pub(super) fn columns(&self) -> usize {
        match self {
            Source::Rows(b) => b.columns(),
            Source::Local(_) => COLUMNS_LOCAL,
            // The columns its tuples would have as rows.
            Source::Slice(s) => s.columns(),
            Source::Columns(b) => b.columns(),
        }
    }

    /// Whether every row's N is (0, 0, 1) bit for bit, so that the groups with an f32 frame
    /// may run their N = +z variants (the same bits as the general frame there).
    fn normal_is_z(&self) -> bool {
        match self {
            Source::Local(_) => true,
            Source::Columns(b) => {
                matches!(b.directions()[2], Column::Every(n) if n.map(f32::to_bits) == [0.0f32, 0.0, 1.0].map(f32::to_bits))
            }
            Source::Rows(_) | Source::Slice(_) => false,
        }
    }
}

/// One unit of work: its outputs, from position `start` of the order its rows are read
/// in (the batch's, or a chunk's grouped order).
pub(super) struct Work<'a> {
    /// The one material of its rows, or `None`: the chunk groups its rows itself.
    pub(super) material: Option<usize>,
    /// Its first position in the order its rows are read in.
    pub(super) start: usize,
    /// RGB outputs, 3 a row.
    pub(super) brdf: &'a mut [f32],
    /// Term outputs, [`TERM_COLUMNS`] a row, when asked for.
    pub(super) terms: Option<&'a mut [f32]>,
}

/// `plan`'s lanes over `w`, whose rows are `order[w.start..]` (or the batch's rows from
/// `w.start` on), in the instruction set `arch`.
pub(super) fn lanes(
    arch: pulp::Arch,
    plan: &Plan,
    material: &Material,
    batch: Source,
    order: Option<&[usize]>,
    work: &mut Work,
) -> (Counts, Tally) {
    let op = ChunkOp {
        plan,
        batch,
        order,
        material,
        work,
    };
    super::isa::run_lanes(arch, op)
}

/// The lanes over one chunk, inside the instruction set pulp chose.
struct ChunkOp<'a, 'b> {
    plan: &'a Plan,
    batch: Source<'a>,
    order: Option<&'a [usize]>,
    work: &'a mut Work<'b>,
    material: &'a Material,
}

impl pulp::WithSimd for ChunkOp<'_, '_> {
    type Output = (Counts, Tally);

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) -> (Counts, Tally) {
        // `S` may lack FMA (the scalar variant): `a·b + c` rounded twice.
        run_chunk::<S, _, Rounded>(
            simd,
            transpose::Portable,
            self.plan,
            self.batch,
            self.order,
            self.work,
            self.material,
        )
    }
}

/// [`ChunkOp`] on AVX-512 and AVX2: whole blocks transposed by the instruction set's
/// shuffles (`transpose`), `a·b + c` fused.
impl super::isa::WithFma for ChunkOp<'_, '_> {
    #[inline(always)]
    fn with_fma<S: transpose::Transpose + Registers>(self, simd: S) -> (Counts, Tally) {
        if let (Source::Local(_), None, Plan::Microfacet { d, aniso, g, f, p }) =
            (self.batch, self.order, self.plan)
        {
            if register::serves(*d, *aniso, *g, *f, p) {
                let op = LocalRegisters {
                    plan: self.plan,
                    batch: self.batch,
                    work: &mut *self.work,
                    material: self.material,
                };
                if let Some(r) = simd.serve(op) {
                    return r;
                }
            }
        }
        run_chunk::<S, S, Fused>(
            simd,
            simd,
            self.plan,
            self.batch,
            self.order,
            self.work,
            self.material,
        )
    }
}

/// A chunk of the local form on the register path ([`register::serves`]).
struct LocalRegisters<'a, 'b> {
    plan: &'a Plan,
    batch: Source<'a>,
    work: &'a mut Work<'b>,
    material: &'a Material,
}

impl RegisterOp for LocalRegisters<'_, '_> {
    type Output = (Counts, Tally);

    #[inline(always)]
    fn run<S: RegisterIo>(self, simd: S) -> (Counts, Tally) {
        use crate::terms::{FresnelKind as F, Geometry as G};
        use kernel::{F_CONDUCTOR, F_NONE, F_SCHLICK, G_CT, G_NONE, G_SMITH, G_SMITH_CORRELATED};
        let Plan::Microfacet { g, f, p, .. } = self.plan else {
            unreachable!("the register path serves microfacet groups (`register::serves`)")
        };
        // A conductor whose every channel has Re η² < 0 skips the metal form's selects.
        let quotient = p.conductor.metal_quotient;
        macro_rules! by_f {
            ($g:expr) => {
                match f {
                    F::None => registers_apart::<S, $g, F_NONE, false>(simd, self),
                    F::Schlick => registers_apart::<S, $g, F_SCHLICK, false>(simd, self),
                    _ if quotient => registers_apart::<S, $g, F_CONDUCTOR, true>(simd, self),
                    _ => registers_apart::<S, $g, F_CONDUCTOR, false>(simd, self),
                }
            };
        }
        match g {
            G::None => by_f!(G_NONE),
            G::CookTorrance => by_f!(G_CT),
            G::Smith => by_f!(G_SMITH),
            _ => by_f!(G_SMITH_CORRELATED),
        }
    }
}

/// [`run_registers`] as a function of its own compiled for `simd` (as each group's lanes
/// are, `dispatch::apart`).
#[inline(never)]
fn registers_apart<S: RegisterIo, const G: u8, const F: u8, const Q: bool>(
    simd: S,
    op: LocalRegisters,
) -> (Counts, Tally) {
    simd.vectorize(RegistersFn::<S, G, F, Q> { simd, op })
}

/// [`run_registers`] as pulp calls it inside the instruction set's features (a struct,
/// not a closure: LLVM left the closure out of line, and with it every intrinsic became a
/// call).
struct RegistersFn<'a, 'b, S, const G: u8, const F: u8, const Q: bool> {
    simd: S,
    op: LocalRegisters<'a, 'b>,
}

impl<S: RegisterIo, const G: u8, const F: u8, const Q: bool> pulp::NullaryFnOnce
    for RegistersFn<'_, '_, S, G, F, Q>
{
    type Output = (Counts, Tally);

    #[inline(always)]
    fn call(self) -> (Counts, Tally) {
        run_registers::<S, G, F, Q>(self.simd, self.op)
    }
}

/// The register path's loop over a chunk of the local form: a register of rows at a time
/// read, evaluated (`register::ggx_local_dgk` and `ggx_local_finish`) and written, the lanes it flags sent to the
/// reference or gathered for the f64 frame as [`run_blocks`] does with a block's.
#[inline(always)]
fn run_registers<S: RegisterIo, const G: u8, const F: u8, const Q: bool>(
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
        plan64: plan.f64_frame(),
        plan_general: plan.general_frame_only(),
        deferred: Deferred::new(),
        deferred_general: Deferred::new(),
    };
    // The tail's rows, the last repeated (its extra lanes are computed and dropped), and
    // its outputs.
    let mut tail_rows = [0f32; COLUMNS_LOCAL * 2 * LANES];
    let mut tail_out = [0f32; 3 * 2 * LANES];
    let mut j = 0;
    while j < len {
        let n = width.min(len - j);
        let row0 = w.start + j;
        let rows = if n == width {
            &data[row0 * COLUMNS_LOCAL..(row0 + width) * COLUMNS_LOCAL]
        } else {
            for k in 0..width {
                let r = row0 + k.min(n - 1);
                tail_rows[k * COLUMNS_LOCAL..(k + 1) * COLUMNS_LOCAL]
                    .copy_from_slice(&data[r * COLUMNS_LOCAL..(r + 1) * COLUMNS_LOCAL]);
            }
            &tail_rows[..width * COLUMNS_LOCAL]
        };
        let half = S::WIDTH;
        let [ax, ay, az, au, av, aw] = simd.local_columns(&rows[..half * COLUMNS_LOCAL]);
        let [bx, by, bz, bu, bv, bw] = simd.local_columns(&rows[half * COLUMNS_LOCAL..]);
        let r = |x| Reg::new(simd, x);
        let (la, va) = ([r(ax), r(ay), r(az)], [r(au), r(av), r(aw)]);
        let (lb, vb) = ([r(bx), r(by), r(bz)], [r(bu), r(bv), r(bw)]);
        // Each register's flags leave its registers as bits after the first stage.
        let sa = register::ggx_local_dgk::<_, G, F>(p, la, va);
        let fa = sa.flags();
        let sb = register::ggx_local_dgk::<_, G, F>(p, lb, vb);
        let fb = sb.flags();
        let ([ra, ga, ba], bad_a) = register::ggx_local_finish::<_, F, Q>(p, sa);
        let ([rb, gb, bb], bad_b) = register::ggx_local_finish::<_, F, Q>(p, sb);
        let (lo, hi) = (
            [ra.get(), ga.get(), ba.get()],
            [rb.get(), gb.get(), bb.get()],
        );
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
        let (bad_a, bad_b) = (simd.bits(bad_a.get()), simd.bits(bad_b.get()));
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
            later.handle::<S>(simd, batch, m, w, &mut counts, &mut tally);
        }
        j += n;
    }
    later.handle::<S>(simd, batch, m, w, &mut counts, &mut tally);
    for (queue, plan) in [
        (&mut later.deferred, &later.plan64),
        (&mut later.deferred_general, &later.plan_general),
    ] {
        queue.run::<S, Fused>(simd, plan, true, batch, m, w, &mut counts, &mut tally);
    }
    (counts, tally)
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
struct Flagged {
    steps: [FlaggedStep; FLAGGED_STEPS],
    n: usize,
    plan64: Plan,
    plan_general: Plan,
    deferred: Deferred,
    deferred_general: Deferred,
}

impl Flagged {
    /// The kept steps' lanes: to the reference (written now), or gathered for the f64
    /// frame or the general f32 frame (run a block at a time). Their outputs overwrite
    /// what the register path wrote for them.
    fn handle<S: pulp::Simd>(
        &mut self,
        simd: S,
        batch: Source,
        m: &Material,
        w: &mut Work,
        counts: &mut Counts,
        tally: &mut Tally,
    ) {
        let data = batch.data();
        for step in &self.steps[..self.n] {
            let (j, row0) = (step.j, step.row0);
            for k in lanes_of(step.rescue) {
                rescue(batch, m, row0 + k, j + k, w, counts);
                tally.rescued += 1;
            }
            for (lanes, queue, plan) in [
                (step.slow, &mut self.deferred, &self.plan64),
                (step.general, &mut self.deferred_general, &self.plan_general),
            ] {
                for k in lanes_of(lanes) {
                    let r = &data[(row0 + k) * COLUMNS_LOCAL..(row0 + k + 1) * COLUMNS_LOCAL];
                    let x = [r[0], r[1], r[2], r[3], r[4], r[5], 0.0, 0.0, 1.0];
                    if queue.push_lane(x, j + k, row0 + k) {
                        queue.run::<S, Fused>(simd, plan, true, batch, m, w, counts, tally);
                    }
                }
            }
        }
        self.n = 0;
    }
}

/// Writes the f64 reference's result for batch row `row` at position `j` of the chunk and
/// counts its status.
fn rescue(batch: Source, m: &Material, row: usize, j: usize, w: &mut Work, counts: &mut Counts) {
    let e = evaluate_tuple(&batch.tuple(row), m);
    match e.status {
        Status::Invalid => {
            counts.invalid += 1;
            counts.first_invalid = Some(
                counts
                    .first_invalid
                    .map_or(row as u64, |f| f.min(row as u64)),
            );
        }
        Status::BelowHorizon => counts.below_horizon += 1,
        Status::Valid => counts.saturated += u64::from(e.saturated()),
    }
    for (ch, x) in e.brdf.into_iter().enumerate() {
        w.brdf[j * 3 + ch] = to_output_f32(x);
    }
    if let Some(t) = w.terms.as_deref_mut() {
        for (c, x) in e.terms().into_iter().enumerate() {
            t[j * TERM_COLUMNS + c] = to_output_f32(x);
        }
    }
}

/// Columns `0..K` (L, V, and N when K = 9) of `LANES` consecutive rows of `C` columns into
/// lanes.
#[inline(always)]
fn transpose<const C: usize, const K: usize>(rows: &[f32], inp: &mut Inputs) {
    for (c, col) in inp.v[..K].iter_mut().enumerate() {
        for (k, x) in col.iter_mut().enumerate() {
            *x = rows[k * C + c];
        }
    }
}

/// The tangent columns (10–12) of `LANES` consecutive 13-column rows into components
/// 9–11 of the lanes.
#[inline(always)]
fn tangent_columns(rows: &[f32], inp: &mut Inputs) {
    for c in 0..3 {
        for k in 0..LANES {
            inp.v[9 + c][k] = rows[k * COLUMNS_TANGENT + 10 + c];
        }
    }
}

/// Blocks a chunk's loop fills before it runs their lanes: one call into a group's lanes
/// ([`super::dispatch::apart`]) serves them all, so the call and the group's constants are paid
/// once a run rather than once a block (about 9 KiB of inputs and outputs, in L1).
const RUN: usize = 8;

#[inline(always)]
fn run_chunk<S: pulp::Simd, T: transpose::Transpose, A: MulAdd>(
    simd: S,
    tr: T,
    plan: &Plan,
    batch: Source,
    order: Option<&[usize]>,
    w: &mut Work,
    m: &Material,
) -> (Counts, Tally) {
    if let Plan::Lambert(_) = plan {
        // Block by block: Lambert's lanes are inline (no call to amortise), and with one
        // block's arrays LLVM keeps its few values in registers (runs of `RUN` blocks
        // took it from 31 to 76 instructions an evaluation).
        run_blocks::<S, T, A, 1>(simd, tr, plan, batch, order, w, m)
    } else {
        run_blocks::<S, T, A, RUN>(simd, tr, plan, batch, order, w, m)
    }
}

/// The chunk loop over runs of `R` blocks.
#[inline(always)]
fn run_blocks<S: pulp::Simd, T: transpose::Transpose, A: MulAdd, const R: usize>(
    simd: S,
    tr: T,
    plan: &Plan,
    batch: Source,
    order: Option<&[usize]>,
    w: &mut Work,
    m: &Material,
) -> (Counts, Tally) {
    let mut counts = Counts::default();
    let len = w.brdf.len() / 3;
    let mut tally = Tally::default();
    let cols = batch.columns();
    // A group that reads the tangent, on rows without one: the reference counts those
    // tuples invalid (FORMULAS.md §1).
    let tangent = plan.needs_tangent();
    if !plan.is_simd() || (tangent && cols != COLUMNS_TANGENT) {
        let rows = |p: usize| order.map_or(p, |o| o[p]);
        for j in 0..len {
            rescue(batch, m, rows(w.start + j), j, w, &mut counts);
        }
        tally.reference = len as u64;
        return (counts, tally);
    }
    tally.lanes = len as u64;
    let mut inp = [Inputs::default(); R];
    let mut out = [Outputs::default(); R];
    for (i, o) in inp.iter_mut().zip(out.iter_mut()) {
        // The local form's N = (0, 0, 1) in every lane; its transposes fill only L and V.
        i.v[8] = [1.0; LANES];
        if let Plan::Lambert(_) | Plan::Lobe { .. } | Plan::Measured = plan {
            // G = F = K = 1 (and D = 0 for Lambert and measured data; a lobe's blocks
            // write their D).
            kernel::lambert_terms(o);
        }
    }
    let mut idx = [[0usize; LANES]; R];
    let z = batch.normal_is_z();
    let (plan64, mut deferred) = (plan.f64_frame(), Deferred::new());
    let (plan_general, mut deferred_general) = (plan.general_frame_only(), Deferred::new());
    let mut j0 = 0;
    while j0 < len {
        // Fill up to `R` blocks, run their lanes, then write them out.
        let blocks = R.min((len - j0).div_ceil(LANES));
        for b in 0..blocks {
            let j = j0 + b * LANES;
            let n = LANES.min(len - j);
            fill_block(
                tr,
                batch,
                order,
                tangent,
                w.start + j,
                n,
                &mut inp[b],
                &mut idx[b],
            );
        }
        match (plan, &m.model) {
            (Plan::Measured, Model::Measured(data)) => {
                for b in 0..blocks {
                    measured::measured_block(&data.data, data.lookup, &inp[b], &mut out[b]);
                }
            }
            _ => block::<S, A>(simd, plan, &inp[..blocks], &mut out[..blocks], z),
        }
        for b in 0..blocks {
            let j = j0 + b * LANES;
            let n = LANES.min(len - j);
            write_block(tr, &out[b], j, n, w);
            let whole = order.is_none() && n == LANES;
            let start = w.start;
            let row = |k: usize| if whole { start + j + k } else { idx[b][k] };
            // The flagged lanes by their bits: a few lanes a block, where a loop over the
            // block's 16 tested each.
            let valid = u32::MAX >> (32 - n);
            if out[b].any_rescue() {
                for k in lanes_of(kernel::bits(&out[b].rescue) & valid) {
                    rescue(batch, m, row(k), j + k, w, &mut counts);
                    tally.rescued += 1;
                }
            }
            if out[b].any_slow() {
                for k in lanes_of(kernel::bits(&out[b].slow) & valid) {
                    if deferred.push(&inp[b], k, j + k, row(k)) {
                        deferred.run::<S, A>(
                            simd,
                            &plan64,
                            z,
                            batch,
                            m,
                            w,
                            &mut counts,
                            &mut tally,
                        );
                    }
                }
            }
            if out[b].any_general() {
                for k in lanes_of(kernel::bits(&out[b].general) & valid) {
                    let (q, plan) = (&mut deferred_general, &plan_general);
                    if q.push(&inp[b], k, j + k, row(k)) {
                        q.run::<S, A>(simd, plan, z, batch, m, w, &mut counts, &mut tally);
                    }
                }
            }
        }
        j0 += (blocks * LANES).min(len - j0);
    }
    for (queue, plan) in [
        (&mut deferred, &plan64),
        (&mut deferred_general, &plan_general),
    ] {
        queue.run::<S, A>(simd, plan, z, batch, m, w, &mut counts, &mut tally);
    }
    (counts, tally)
}

/// The lanes whose bits are set in `bits`, lowest first.
#[inline(always)]
fn lanes_of(mut bits: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (bits != 0).then(|| {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            k
        })
    })
}

/// The lanes a chunk's blocks left to the f64 frame ([`kernel::Params::defer_slow`]),
/// gathered into one block: a few lanes in a hundred cost a few blocks in a hundred, where
/// running the f64 frame over each block that had one cost a third of the blocks. Each
/// lane's result depends on its own tuple alone, so where it is evaluated does not change
/// it.
struct Deferred {
    inp: Inputs,
    /// Each lane's output position in the chunk and its batch row.
    at: [(usize, usize); LANES],
    n: usize,
}

impl Deferred {
    fn new() -> Deferred {
        Deferred {
            inp: Inputs::default(),
            at: [(0, 0); LANES],
            n: 0,
        }
    }

    /// Lane `k` of `inp` (output position `j`, batch row `row`); whether the block is full.
    #[inline(always)]
    fn push(&mut self, inp: &Inputs, k: usize, j: usize, row: usize) -> bool {
        self.push_lane(kernel::lane_inputs(inp, k % LANES), j, row)
    }

    /// A lane's L, V, N `x` (output position `j`, batch row `row`); whether the block is
    /// full.
    #[inline(always)]
    fn push_lane(&mut self, x: [f32; 9], j: usize, row: usize) -> bool {
        // `n < LANES` always (a full block is run before the next push); the mask says so
        // to the compiler, which then drops the bounds checks.
        let n = self.n % LANES;
        for c in 0..9 {
            self.inp.v[c][n] = x[c];
        }
        self.at[n] = (j, row);
        self.n = n + 1;
        self.n == LANES
    }

    /// The gathered lanes on `plan64` (the group's f64 frame), into their places in `w`,
    /// rescued where the lanes say so.
    #[allow(clippy::too_many_arguments)]
    fn run<S: pulp::Simd, A: MulAdd>(
        &mut self,
        simd: S,
        plan64: &Plan,
        z: bool,
        batch: Source,
        m: &Material,
        w: &mut Work,
        counts: &mut Counts,
        tally: &mut Tally,
    ) {
        let n = self.n;
        if n == 0 {
            return;
        }
        // The unused lanes repeat the first (computed and dropped).
        for k in n..LANES {
            for c in 0..9 {
                self.inp.v[c][k] = self.inp.v[c][0];
            }
        }
        let mut out = [Outputs::default()];
        block::<S, A>(simd, plan64, std::slice::from_ref(&self.inp), &mut out, z);
        tally.deferred += n as u64;
        for (k, &(j, row)) in self.at[..n].iter().enumerate() {
            if out[0].rescue[k] {
                rescue(batch, m, row, j, w, counts);
                tally.rescued += 1;
            } else {
                write_lane(&out[0], k, j, w);
            }
        }
        self.n = 0;
    }
}

/// The block of rows `first..first + n` of the chunk's order (or of the batch) into
/// `inp`'s lanes; `idx` gets each lane's batch row when the block is not a whole run of
/// consecutive rows (the tail block repeats its last row: its extra lanes are computed
/// and dropped).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn fill_block<T: transpose::Transpose>(
    tr: T,
    batch: Source,
    order: Option<&[usize]>,
    tangent: bool,
    first: usize,
    n: usize,
    inp: &mut Inputs,
    idx: &mut [usize; LANES],
) {
    let rows = |p: usize| order.map_or(p, |o| o[p]);
    let cols = batch.columns();
    let data = batch.data();
    let take = cols.min(9);
    // A whole block of consecutive rows (the common case): fixed-stride transposes the
    // compiler unrolls, and no row indices to form.
    let whole = order.is_none() && n == LANES;
    if let Source::Slice(s) = batch {
        // The block's tuples made here, lane by lane.
        for (k, slot) in idx.iter_mut().enumerate() {
            *slot = first + k.min(n - 1);
            let t = s.tuple(*slot);
            for c in 0..3 {
                inp.v[c][k] = t.l[c];
                inp.v[3 + c][k] = t.v[c];
                inp.v[6 + c][k] = t.n[c];
                if let Some(tt) = t.t {
                    inp.v[9 + c][k] = tt[c];
                }
            }
        }
    } else if let Source::Columns(b) = batch {
        if !whole {
            for (k, slot) in idx.iter_mut().enumerate() {
                *slot = rows(first + k.min(n - 1));
            }
        }
        let at = whole.then_some(first);
        for (c, column) in b.directions().into_iter().enumerate() {
            column_lanes(tr, column, 3 * c, at, idx, inp);
        }
        if let Some(t) = b.tangent().filter(|_| tangent) {
            column_lanes(tr, t, 9, at, idx, inp);
        }
    } else if whole {
        let base = first * cols;
        match cols {
            COLUMNS_LOCAL => tr.local(
                data[base..base + transpose::BLOCK]
                    .try_into()
                    .expect("a whole block"),
                inp,
            ),
            COLUMNS_PLAIN => tr.plain(
                data[base..base + transpose::BLOCK_PLAIN]
                    .try_into()
                    .expect("a whole block"),
                inp,
            ),
            _ => {
                let rows = &data[base..base + LANES * COLUMNS_TANGENT];
                transpose::<COLUMNS_TANGENT, 9>(rows, inp);
                if tangent {
                    tangent_columns(rows, inp);
                }
            }
        }
    } else {
        for (k, slot) in idx.iter_mut().enumerate() {
            *slot = rows(first + k.min(n - 1));
        }
        if cols == COLUMNS_PLAIN {
            // Rows gathered whole into a block, then the block's transpose (on AVX-512
            // permutes): a mixed batch's blocks are all gathered, and value by value the
            // gather was a fifth of its time.
            let mut block = [0f32; transpose::BLOCK_PLAIN];
            for (k, &r) in idx.iter().enumerate() {
                block[k * COLUMNS_PLAIN..(k + 1) * COLUMNS_PLAIN]
                    .copy_from_slice(&data[r * cols..(r + 1) * cols]);
            }
            tr.plain(&block, inp);
        }
        for (k, &r) in idx.iter().enumerate() {
            if cols != COLUMNS_PLAIN {
                let row = &data[r * cols..r * cols + take];
                for (c, &x) in row.iter().enumerate() {
                    inp.v[c][k] = x;
                }
            }
            if tangent {
                for c in 0..3 {
                    inp.v[9 + c][k] = data[r * cols + 10 + c];
                }
            }
        }
    }
}

/// One column of a [`ColumnBatch`] into lanes `base..base + 3`: a vector for every row
/// splatted, else the rows `first..first + LANES` (a whole block) or `idx`'s.
#[inline(always)]
fn column_lanes<T: transpose::Transpose>(
    tr: T,
    column: Column,
    base: usize,
    first: Option<usize>,
    idx: &[usize; LANES],
    inp: &mut Inputs,
) {
    match (column, first) {
        (Column::Every(x), _) => {
            for j in 0..3 {
                inp.v[base + j] = [x[j]; LANES];
            }
        }
        (Column::Each(c), Some(first)) => {
            let block = c[3 * first..3 * (first + LANES)]
                .try_into()
                .expect("a whole block");
            let lanes: &mut [[f32; LANES]; 3] = (&mut inp.v[base..base + 3])
                .try_into()
                .expect("three lanes");
            tr.xyz(block, lanes);
        }
        (Column::Each(c), None) => {
            for (k, &r) in idx.iter().enumerate() {
                for j in 0..3 {
                    inp.v[base + j][k] = c[3 * r + j];
                }
            }
        }
    }
}

/// A block's `n` lanes into the chunk's outputs from position `j` on.
#[inline(always)]
fn write_block<T: transpose::Transpose>(tr: T, out: &Outputs, j: usize, n: usize, w: &mut Work) {
    if n == LANES {
        tr.rgb(
            &out.brdf,
            (&mut w.brdf[j * 3..(j + LANES) * 3])
                .try_into()
                .expect("a whole block"),
        );
        if let Some(t) = w.terms.as_deref_mut() {
            transpose::untranspose::<TERM_COLUMNS>(
                &out.terms,
                &mut t[j * TERM_COLUMNS..(j + LANES) * TERM_COLUMNS],
            );
        }
    } else {
        for k in 0..n {
            write_lane(out, k, j + k, w);
        }
    }
}

/// Lane `k` of `out` into output position `j`.
#[inline(always)]
fn write_lane(out: &Outputs, k: usize, j: usize, w: &mut Work) {
    for ch in 0..3 {
        w.brdf[j * 3 + ch] = out.brdf[ch][k];
    }
    if let Some(t) = w.terms.as_deref_mut() {
        for c in 0..TERM_COLUMNS {
            t[j * TERM_COLUMNS + c] = out.terms[c][k];
        }
    }
}
