//! The native CPU engine ([`CpuEngine`]): the whole contract on every core, every material
//! group in SIMD lanes (see [`kernel`]; measured materials in `measured`), and the tuples
//! the lanes cannot vouch for through the f64 reference (docs/CPU_ENGINE.md).
//!
//! The batch is cut into chunks of rows, taken from a shared queue by the calling thread
//! and the workers of a persistent pool (`rayon-core`, built once per engine). A chunk of
//! a batch with several materials groups its own rows by material (a stable counting
//! sort) and puts the outputs back in row order, all within the cache. Each tuple's
//! result depends only on the tuple and its material, so the
//! output is the same for any chunk size and thread count. The local-frame form
//! ([`LocalBatch`]: `Lx Ly Lz Vx Vy Vz`, N = +z, one material) is read as it is, never
//! expanded to rows.
//!
//! Instruction sets are chosen at run time by `pulp` (AVX-512, AVX2+FMA, or the baseline;
//! [`isa`], `VKBRDF_CPU_ISA` forces one): one portable binary, and no `unsafe` here — pulp
//! proves the CPU feature before it enters a function compiled for it.

// Lane loops index the lanes' arrays by lane number (see kernel.rs).
#![allow(clippy::needless_range_loop)]

pub mod aniso;
mod generated;
pub mod htsg;
pub mod importance;
pub mod isa;
pub mod kernel;
pub mod lobes;

mod dispatch;
mod measured;
pub mod plan;
mod slice_tuples;
pub mod transpose;
pub(crate) use dispatch::block;

use crate::backend::{Backend, Counts, Output, Request, TERM_COLUMNS};
use crate::batch::{Batch, LocalBatch, Tuple, COLUMNS_LOCAL, COLUMNS_PLAIN, COLUMNS_TANGENT};
use crate::cancel::Cancel;
use crate::error::Result;
use crate::material::{Material, Model};
use crate::reference::{evaluate_tuple, to_output_f32, Status};
pub use isa::Isa;
use kernel::{Inputs, Outputs, LANES};
use plan::Plan;
use std::sync::{Arc, Mutex};

/// Rows per chunk: the unit the workers take and between which they check the cancel token.
const CHUNK: usize = 16_384;

/// Fewest rows per chunk: a small batch is cut into at least [`CHUNKS_PER_THREAD`] chunks a
/// thread, down to this size.
const MIN_CHUNK: usize = 1024;

/// Chunks a thread gets at least (for batches of more than `MIN_CHUNK` rows a chunk): with
/// one or two chunks a thread, the calling thread had often taken them all before a pooled
/// worker woke (1 → 2 threads 0.98× at 65,536 tuples, four chunks).
const CHUNKS_PER_THREAD: usize = 8;

/// Rows per chunk for a batch of `n` rows on `threads` threads: [`CHUNK`], or less for a
/// small batch (a multiple of the lanes' block, at least [`MIN_CHUNK`]). A tuple's result
/// does not depend on the chunking.
fn chunk_rows(n: usize, threads: usize) -> usize {
    let share = n
        .div_ceil(threads * CHUNKS_PER_THREAD)
        .next_multiple_of(LANES);
    share.clamp(MIN_CHUNK, CHUNK)
}

/// The native CPU engine.
#[derive(Debug, Clone)]
pub struct CpuEngine {
    threads: usize,
    isa: Isa,
    cancel: Cancel,
    last: Tally,
    /// The `threads − 1` workers beside the calling thread, started at the first batch of
    /// more than one chunk and kept for the engine's life (spawning threads per call cost
    /// a large share of a small batch's time).
    pool: Option<Arc<rayon_core::ThreadPool>>,
}

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
}

impl Tally {
    fn add(&mut self, o: &Tally) {
        self.lanes += o.lanes;
        self.rescued += o.rescued;
        self.reference += o.reference;
    }
}

impl Default for CpuEngine {
    fn default() -> Self {
        Self::new()
    }
}

/// The instruction set a default engine's lanes run on this machine (`avx512`, `avx2+fma`
/// or `scalar`): the one `VKBRDF_CPU_ISA` names, else the best the CPU has.
pub fn instruction_set() -> &'static str {
    Isa::from_env().unwrap_or_else(|_| Isa::best()).name()
}

impl CpuEngine {
    /// An engine using every available core.
    pub fn new() -> CpuEngine {
        CpuEngine::with_threads(std::thread::available_parallelism().map_or(1, |n| n.get()))
    }

    /// An engine with `threads` workers (at least 1), on the instruction set
    /// `VKBRDF_CPU_ISA` names (the best the CPU has when it is unset; a front end calls
    /// [`Isa::from_env`] first to report a bad name).
    pub fn with_threads(threads: usize) -> CpuEngine {
        CpuEngine::with_isa(threads, Isa::from_env().unwrap_or_else(|_| Isa::best()))
    }

    /// An engine with `threads` workers on instruction set `isa`; the best available one
    /// if the CPU lacks `isa` (check [`Isa::available`] first).
    pub fn with_isa(threads: usize, isa: Isa) -> CpuEngine {
        CpuEngine {
            threads: threads.max(1),
            isa: if isa.available() { isa } else { Isa::best() },
            cancel: Cancel::new(),
            last: Tally::default(),
            pool: None,
        }
    }

    /// The instruction set this engine's lanes run.
    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// pulp's handle for [`CpuEngine::isa`] (available: `with_isa` made sure).
    fn arch(&self) -> pulp::Arch {
        self.isa.arch().unwrap_or(pulp::Arch::Scalar)
    }

    /// Where the tuples of the last [`Backend::evaluate`] went: lanes, rescued, reference.
    pub fn last_tally(&self) -> Tally {
        self.last
    }

    /// Worker threads.
    pub fn threads(&self) -> usize {
        self.threads
    }
}

/// What the engine reads: ordinary rows, or the local-frame form.
#[derive(Clone, Copy)]
enum Source<'a> {
    Rows(&'a Batch<'a>),
    Local(&'a LocalBatch),
    /// A half/difference slice whose tuples the workers make block by block.
    Slice(&'a slice_tuples::SliceTuples),
}

impl Source<'_> {
    fn len(&self) -> usize {
        match self {
            Source::Rows(b) => b.len(),
            Source::Local(b) => b.len(),
            Source::Slice(s) => s.len(),
        }
    }

    fn material(&self, i: usize) -> usize {
        match self {
            Source::Rows(b) => b.material(i),
            Source::Local(b) => b.material(),
            Source::Slice(_) => 0,
        }
    }

    fn tuple(&self, i: usize) -> Tuple {
        match self {
            Source::Rows(b) => b.tuple(i),
            Source::Local(b) => b.tuple(i),
            Source::Slice(s) => s.tuple(i),
        }
    }

    fn data(&self) -> &[f32] {
        match self {
            Source::Rows(b) => b.as_slice(),
            Source::Local(b) => b.as_slice(),
            // Made block by block (see `run_chunk`), never read as rows.
            Source::Slice(_) => &[],
        }
    }

    fn columns(&self) -> usize {
        match self {
            Source::Rows(b) => b.columns(),
            Source::Local(_) => COLUMNS_LOCAL,
            // The columns its tuples would have as rows.
            Source::Slice(s) => s.columns(),
        }
    }
}

/// One unit of work: its outputs, from position `start` of the order its rows are read
/// in (the batch's, or a chunk's grouped order).
struct Work<'a> {
    /// The one material of its rows, or `None`: the chunk groups its rows itself.
    material: Option<usize>,
    start: usize,
    brdf: &'a mut [f32],
    terms: Option<&'a mut [f32]>,
}

/// What every chunk of one evaluation shares.
struct Context<'a> {
    arch: pulp::Arch,
    plans: &'a [Plan],
    materials: &'a [Material],
    src: Source<'a>,
}

/// A worker's buffers for grouping a mixed chunk, kept from chunk to chunk.
#[derive(Default)]
struct Grouping {
    /// Each row's material, read once from the batch.
    material: Vec<usize>,
    /// Rows per material in the chunk, then where each material's rows start.
    start: Vec<usize>,
    /// The chunk's rows (batch indices) grouped by material, in row order within a group.
    order: Vec<usize>,
    /// Outputs in that order.
    brdf: Vec<f32>,
    terms: Vec<f32>,
}

impl Context<'_> {
    /// Material `mi`'s lanes over `w`, whose rows are `order[w.start..]` (or the batch's
    /// rows from `w.start` on), in the instruction set pulp chose.
    fn lanes(&self, mi: usize, order: Option<&[usize]>, w: &mut Work) -> (Counts, Tally) {
        let op = ChunkOp {
            plan: &self.plans[mi],
            batch: self.src,
            order,
            material: &self.materials[mi],
            work: w,
        };
        #[cfg(target_arch = "x86_64")]
        if let pulp::Arch::V4(simd) = self.arch {
            return simd.vectorize(ChunkOp4 { simd, op });
        }
        self.arch.dispatch(op)
    }

    /// A chunk of a batch with several materials: its rows grouped by material (a stable
    /// counting sort), each group through its lanes into `g`'s buffers, and the outputs
    /// put back in row order. Everything it touches is the chunk's, so it stays in the
    /// cache (grouping the whole batch first made every block a gather from far apart:
    /// slower than lavapipe at 2^20 rows).
    fn mixed_chunk(&self, w: &mut Work, g: &mut Grouping) -> (Counts, Tally) {
        let len = w.brdf.len() / 3;
        let m = self.materials.len();
        g.material.clear();
        g.material
            .extend((w.start..w.start + len).map(|r| self.src.material(r)));
        g.start.clear();
        g.start.resize(m + 1, 0);
        for &mi in &g.material {
            g.start[mi + 1] += 1;
        }
        if let Some(mi) = (0..m).find(|&mi| g.start[mi + 1] == len) {
            // One material in this chunk: read in place.
            return self.lanes(mi, None, w);
        }
        for mi in 0..m {
            g.start[mi + 1] += g.start[mi];
        }
        g.order.clear();
        g.order.resize(len, 0);
        let mut next = g.start.clone();
        for (j, &mi) in g.material.iter().enumerate() {
            g.order[next[mi]] = w.start + j;
            next[mi] += 1;
        }
        let terms = w.terms.is_some();
        set_len(&mut g.brdf, len * 3);
        if terms {
            set_len(&mut g.terms, len * TERM_COLUMNS);
        }
        let mut counts = Counts::default();
        let mut tally = Tally::default();
        for mi in 0..m {
            let (a, b) = (g.start[mi], g.start[mi + 1]);
            if a == b {
                continue;
            }
            let mut part = Work {
                material: Some(mi),
                start: a,
                brdf: &mut g.brdf[a * 3..b * 3],
                terms: terms.then(|| &mut g.terms[a * TERM_COLUMNS..b * TERM_COLUMNS]),
            };
            let (c, t) = self.lanes(mi, Some(&g.order), &mut part);
            counts.absorb(&c);
            tally.add(&t);
        }
        for (p, &r) in g.order.iter().enumerate() {
            let j = r - w.start;
            w.brdf[j * 3..j * 3 + 3].copy_from_slice(&g.brdf[p * 3..p * 3 + 3]);
            if let Some(t) = w.terms.as_deref_mut() {
                t[j * TERM_COLUMNS..(j + 1) * TERM_COLUMNS]
                    .copy_from_slice(&g.terms[p * TERM_COLUMNS..(p + 1) * TERM_COLUMNS]);
            }
        }
        (counts, tally)
    }
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
        run_chunk(
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

/// [`ChunkOp`] on AVX-512, where whole blocks are transposed by permutes.
#[cfg(target_arch = "x86_64")]
struct ChunkOp4<'a, 'b> {
    simd: pulp::x86::V4,
    op: ChunkOp<'a, 'b>,
}

#[cfg(target_arch = "x86_64")]
impl pulp::NullaryFnOnce for ChunkOp4<'_, '_> {
    type Output = (Counts, Tally);

    #[inline(always)]
    fn call(self) -> (Counts, Tally) {
        let o = self.op;
        run_chunk(
            self.simd, self.simd, o.plan, o.batch, o.order, o.work, o.material,
        )
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

/// `C` lane arrays into `LANES` rows of `C` columns.
#[inline(always)]
fn untranspose<const C: usize>(cols: &[[f32; LANES]; C], rows: &mut [f32]) {
    let rows = &mut rows[..LANES * C];
    for k in 0..LANES {
        for c in 0..C {
            rows[k * C + c] = cols[c][k];
        }
    }
}

/// Blocks a chunk's loop fills before it runs their lanes: one call into a group's lanes
/// ([`dispatch::apart`]) serves them all, so the call and the group's constants are paid
/// once a run rather than once a block (about 9 KiB of inputs and outputs, in L1).
const RUN: usize = 8;

#[inline(always)]
fn run_chunk<S: pulp::Simd, T: transpose::Transpose>(
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
        run_blocks::<S, T, 1>(simd, tr, plan, batch, order, w, m)
    } else {
        run_blocks::<S, T, RUN>(simd, tr, plan, batch, order, w, m)
    }
}

/// The chunk loop over runs of `R` blocks.
#[inline(always)]
fn run_blocks<S: pulp::Simd, T: transpose::Transpose, const R: usize>(
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
            _ => block(
                simd,
                plan,
                &inp[..blocks],
                &mut out[..blocks],
                cols == COLUMNS_LOCAL,
            ),
        }
        for b in 0..blocks {
            let j = j0 + b * LANES;
            let n = LANES.min(len - j);
            write_block(&out[b], j, n, w);
            if out[b].any_rescue() {
                let whole = order.is_none() && n == LANES;
                for k in 0..n {
                    if out[b].rescue[k] {
                        let row = if whole { w.start + j + k } else { idx[b][k] };
                        rescue(batch, m, row, j + k, w, &mut counts);
                        tally.rescued += 1;
                    }
                }
            }
        }
        j0 += (blocks * LANES).min(len - j0);
    }
    (counts, tally)
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

/// A block's `n` lanes into the chunk's outputs from position `j` on.
#[inline(always)]
fn write_block(out: &Outputs, j: usize, n: usize, w: &mut Work) {
    if n == LANES {
        // Fixed-size interleaving stores the compiler turns into shuffles.
        untranspose::<3>(&out.brdf, &mut w.brdf[j * 3..(j + LANES) * 3]);
        if let Some(t) = w.terms.as_deref_mut() {
            untranspose::<TERM_COLUMNS>(
                &out.terms,
                &mut t[j * TERM_COLUMNS..(j + LANES) * TERM_COLUMNS],
            );
        }
    } else {
        for k in 0..n {
            for ch in 0..3 {
                w.brdf[(j + k) * 3 + ch] = out.brdf[ch][k];
            }
            if let Some(t) = w.terms.as_deref_mut() {
                for c in 0..TERM_COLUMNS {
                    t[(j + k) * TERM_COLUMNS + c] = out.terms[c][k];
                }
            }
        }
    }
}

impl CpuEngine {
    /// The whole evaluation of `src` into `out` (see [`Backend::evaluate_into`]).
    fn run(
        &mut self,
        src: Source,
        materials: &[Material],
        request: &Request,
        out: &mut Output,
    ) -> Result<()> {
        let n = src.len();
        let plans: Vec<Plan> = materials.iter().map(Plan::for_material).collect();
        // The material of every row when the batch says so without a pass over it; else
        // each chunk groups its own rows (`mixed_chunk`).
        let single = match src {
            // Every row is material 0 (the batch validated its indices).
            Source::Rows(_) if materials.len() == 1 => Some(0),
            Source::Rows(_) => None,
            Source::Local(b) => Some(b.material()),
            Source::Slice(_) => Some(0),
        };
        // The caller's buffers, reused: no fresh pages to fault in and zero.
        out.terms = request.terms.then(|| out.terms.take().unwrap_or_default());
        set_len(&mut out.brdf, n * 3);
        if let Some(t) = out.terms.as_mut() {
            set_len(t, n * TERM_COLUMNS);
        }
        let chunk = chunk_rows(n, self.threads);
        let mut queue = Vec::with_capacity(n.div_ceil(chunk));
        {
            let mut rest_b: &mut [f32] = &mut out.brdf;
            let mut rest_t: Option<&mut [f32]> = out.terms.as_deref_mut();
            let mut start = 0;
            while start < n {
                let len = chunk.min(n - start);
                let (b, rb) = std::mem::take(&mut rest_b).split_at_mut(len * 3);
                rest_b = rb;
                let t = match rest_t.take() {
                    Some(t) => {
                        let (a, rt) = t.split_at_mut(len * TERM_COLUMNS);
                        rest_t = Some(rt);
                        Some(a)
                    }
                    None => None,
                };
                queue.push(Work {
                    material: single,
                    start,
                    brdf: b,
                    terms: t,
                });
                start += len;
            }
        }
        queue.reverse(); // workers pop from the back: rows go out roughly in order
        let chunks = queue.len();
        let queue = Mutex::new(queue);
        let helpers = self.threads.min(chunks).saturating_sub(1);
        let pool = if helpers > 0 { self.pool() } else { None };
        let cancel = &self.cancel;
        let arch = self.arch();
        let ctx = Context {
            arch,
            plans: &plans,
            materials,
            src,
        };
        let work = || -> (Counts, Tally) {
            let mut total = Counts::default();
            let mut tally = Tally::default();
            let mut local = Grouping::default();
            loop {
                if cancel.is_cancelled() {
                    break;
                }
                let Some(mut w) = queue.lock().expect("queue lock").pop() else {
                    break;
                };
                let (c, t) = match w.material {
                    Some(mi) => ctx.lanes(mi, None, &mut w),
                    None => ctx.mixed_chunk(&mut w, &mut local),
                };
                total.absorb(&c);
                tally.add(&t);
            }
            (total, tally)
        };
        let parts: Vec<(Counts, Tally)> = match pool {
            None => vec![work()],
            Some(pool) => {
                let parts = Mutex::new(Vec::with_capacity(helpers + 1));
                pool.in_place_scope(|s| {
                    for _ in 0..helpers {
                        s.spawn(|_| {
                            let p = work();
                            parts.lock().expect("parts lock").push(p);
                        });
                    }
                    let p = work();
                    parts.lock().expect("parts lock").push(p);
                });
                parts.into_inner().expect("parts lock")
            }
        };
        self.cancel.check()?;
        let mut counts = Counts {
            tuples: n as u64,
            ..Counts::default()
        };
        self.last = Tally::default();
        for (c, t) in &parts {
            counts.absorb(c);
            self.last.add(t);
        }
        out.counts = counts;
        Ok(())
    }

    /// The worker pool, started on first use; `None` (the calling thread works alone) if
    /// the system refuses the threads.
    fn pool(&mut self) -> Option<Arc<rayon_core::ThreadPool>> {
        if self.pool.is_none() {
            self.pool = rayon_core::ThreadPoolBuilder::new()
                .num_threads(self.threads - 1)
                .thread_name(|i| format!("vkbrdf-cpu-{i}"))
                .build()
                .ok()
                .map(Arc::new);
        }
        self.pool.clone()
    }
}

/// Makes `v` exactly `len` long. Every element is overwritten by the evaluation, so a
/// reused buffer keeps its stale values instead of being zeroed again; only growth is
/// filled. A buffer that must grow is replaced by a zeroed allocation (`calloc`: fresh
/// pages arrive zero from the system), so its pages are faulted in by the workers that
/// write them, in parallel, instead of by a serial fill here first.
fn set_len(v: &mut Vec<f32>, len: usize) {
    if len > v.capacity() {
        *v = vec![0.0; len];
    } else {
        v.truncate(len);
        v.resize(len, 0.0);
    }
}

impl Backend for CpuEngine {
    fn name(&self) -> String {
        format!(
            "cpu ({}, {} thread{})",
            self.isa.name(),
            self.threads,
            if self.threads == 1 { "" } else { "s" }
        )
    }

    fn set_cancel(&mut self, cancel: Cancel) {
        self.cancel = cancel;
    }

    fn evaluate(
        &mut self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
    ) -> Result<Output> {
        let mut out = Output::default();
        self.run(Source::Rows(batch), materials, request, &mut out)?;
        Ok(out)
    }

    fn evaluate_into(
        &mut self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
        out: &mut Output,
    ) -> Result<()> {
        self.run(Source::Rows(batch), materials, request, out)
    }

    fn evaluate_local_into(
        &mut self,
        batch: &LocalBatch,
        materials: &[Material],
        request: &Request,
        out: &mut Output,
    ) -> Result<()> {
        self.run(Source::Local(batch), materials, request, out)
    }

    fn generated_directions(&mut self) -> Option<&mut dyn crate::backend::GeneratedDirections> {
        Some(self)
    }
}
