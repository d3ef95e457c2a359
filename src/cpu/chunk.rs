//! One chunk's rows through a material group's lanes: what the engine reads
//! ([`Source`]), a unit of work's outputs ([`Work`]), the loop that fills a run of blocks,
//! calls the group's lanes ([`super::dispatch`]) and writes the run out, and the rescue of
//! the lanes the lanes cannot vouch for by the f64 reference.

// Lane loops index the lanes' arrays by lane number (see kernel.rs).
#![allow(clippy::needless_range_loop)]

use super::dispatch::block;
use super::kernel::{self, Inputs, Outputs, LANES};
use super::plan::Plan;
use super::register::{self, RegisterIo};
use super::{measured, transpose};

mod deferred;
mod registers;
mod work;
use crate::backend::{Counts, TERM_COLUMNS};
use crate::batch::columns::Column;
use crate::batch::{COLUMNS_LOCAL, COLUMNS_PLAIN, COLUMNS_TANGENT};
use crate::material::{Material, Model};
use crate::terms::math::{Fused, MulAdd, Rounded};
use deferred::{lanes_of, rescue, write_lane, Chunk, Elsewhere, F64_FRAME, GENERAL_FRAME};
use registers::LocalRegisters;
pub use work::Tally;
pub(super) use work::{Source, Work};

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
    fn with_fma<S: transpose::Transpose + RegisterIo>(self, simd: S) -> (Counts, Tally) {
        if let (None, Plan::Microfacet { d, aniso, g, f, p }) = (self.order, self.plan) {
            // The local form, or columns of L and V (each one a row or one for every row)
            // with N = +z given once.
            let local = match self.batch {
                Source::Local(_) => true,
                Source::Columns(_) => self.batch.normal_is_z(),
                _ => false,
            };
            if local && register::serves(*d, *aniso, *g, *f, p) {
                let op = LocalRegisters {
                    plan: self.plan,
                    batch: self.batch,
                    work: &mut *self.work,
                    material: self.material,
                };
                return op.run(simd);
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
    let cx = Chunk { simd, z, batch, m };
    let mut elsewhere = Elsewhere::new(plan, cx);
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
            // The lanes another frame takes, as each block's flags say. (Two tests, not a
            // loop over the two kinds: the loop cost 1.5–3 instructions an evaluation.)
            let (o, c, t) = (&out[b], &mut counts, &mut tally);
            if o.any_slow() {
                for k in lanes_of(kernel::bits(&o.slow) & valid) {
                    let (x, at) = (kernel::lane_inputs(&inp[b], k), (j + k, row(k)));
                    elsewhere.push::<A>(F64_FRAME, x, at, w, c, t);
                }
            }
            if o.any_general() {
                for k in lanes_of(kernel::bits(&o.general) & valid) {
                    let (x, at) = (kernel::lane_inputs(&inp[b], k), (j + k, row(k)));
                    elsewhere.push::<A>(GENERAL_FRAME, x, at, w, c, t);
                }
            }
        }
        j0 += (blocks * LANES).min(len - j0);
    }
    elsewhere.finish::<A>(w, &mut counts, &mut tally);
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
    } else if let Some(b) = batch.local_columns() {
        // Six columns: a whole block's lanes are each column's 16 values as they are.
        if whole {
            for (c, lanes) in inp.v[..COLUMNS_LOCAL].iter_mut().enumerate() {
                let col = b.column(c).expect("a batch of columns");
                lanes.copy_from_slice(&col[first..first + LANES]);
            }
        } else {
            for (k, slot) in idx.iter_mut().enumerate() {
                *slot = rows(first + k.min(n - 1));
                for (c, x) in b.row(*slot).into_iter().enumerate() {
                    inp.v[c][k] = x;
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

/// One column of a [`ColumnBatch`](crate::batch::columns::ColumnBatch) into lanes `base..base + 3`: a vector for every row
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
