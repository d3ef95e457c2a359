//! The native CPU engine ([`CpuEngine`]): the whole contract on every core, with the most
//! common material groups in f32 SIMD lanes (see [`kernel`]) and every other group through
//! the f64 reference, tuple by tuple, in parallel (docs/CPU_ENGINE.md).
//!
//! Rows are grouped by material (a stable counting sort when the batch has several), cut
//! into chunks that never straddle two groups, and the chunks are taken by scoped worker
//! threads from a shared queue. Each tuple's result depends only on the tuple and its
//! material, so the output is the same for any chunk size and thread count.
//!
//! Instruction sets are chosen at run time by `pulp` (AVX-512, AVX2+FMA, or the baseline):
//! one portable binary, and no `unsafe` here — pulp proves the CPU feature before it enters
//! a function compiled for it.

// Lane loops index the lanes' arrays by lane number (see kernel.rs).
#![allow(clippy::needless_range_loop)]

pub mod kernel;
pub mod math;

use crate::backend::{Backend, Counts, Output, Request, TERM_COLUMNS};
use crate::batch::{Batch, COLUMNS_PLAIN, COLUMNS_TANGENT};
use crate::cancel::Cancel;
use crate::error::Result;
use crate::material::Material;
use crate::reference::{evaluate_tuple, to_output_f32, Status};
use kernel::{Inputs, Outputs, Plan, LANES};
use std::sync::Mutex;

/// Rows per chunk: the unit the workers take and between which they check the cancel token.
const CHUNK: usize = 16_384;

/// The native CPU engine.
#[derive(Debug, Clone)]
pub struct CpuEngine {
    threads: usize,
    cancel: Cancel,
    last: Tally,
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

/// The instruction set the lanes run on this machine (`avx512`, `avx2+fma` or `scalar`).
pub fn instruction_set() -> &'static str {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    {
        match pulp::Arch::new() {
            pulp::Arch::V4(_) => "avx512",
            pulp::Arch::V3(_) => "avx2+fma",
            _ => "scalar",
        }
    }
    #[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
    {
        "native"
    }
}

impl CpuEngine {
    /// An engine using every available core.
    pub fn new() -> CpuEngine {
        CpuEngine::with_threads(std::thread::available_parallelism().map_or(1, |n| n.get()))
    }

    /// An engine with `threads` workers (at least 1).
    pub fn with_threads(threads: usize) -> CpuEngine {
        CpuEngine {
            threads: threads.max(1),
            cancel: Cancel::new(),
            last: Tally::default(),
        }
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

/// One unit of work: rows `start..end` of the (grouped) order, all of material `material`.
struct Work<'a> {
    material: usize,
    start: usize,
    brdf: &'a mut [f32],
    terms: Option<&'a mut [f32]>,
}

/// The lanes over one chunk, inside the instruction set pulp chose.
struct ChunkOp<'a, 'b> {
    plan: &'a Plan,
    batch: &'a Batch<'a>,
    order: Option<&'a [usize]>,
    work: &'a mut Work<'b>,
    material: &'a Material,
}

impl pulp::WithSimd for ChunkOp<'_, '_> {
    type Output = (Counts, Tally);

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> (Counts, Tally) {
        run_chunk(self.plan, self.batch, self.order, self.work, self.material)
    }
}

#[inline(always)]
pub(crate) fn block(plan: &Plan, inp: &Inputs, out: &mut Outputs) {
    use kernel::*;
    let Plan::Microfacet { d, g, f, p } = plan else {
        if let Plan::Lambert(p) = plan {
            lambert_block(p, inp, out);
        }
        return;
    };
    macro_rules! by_f {
        ($d:expr, $g:expr) => {
            match *f {
                F_NONE => microfacet_block::<$d, $g, F_NONE>(p, inp, out),
                F_SCHLICK => microfacet_block::<$d, $g, F_SCHLICK>(p, inp, out),
                F_DIELECTRIC => microfacet_block::<$d, $g, F_DIELECTRIC>(p, inp, out),
                _ => microfacet_block::<$d, $g, F_CONDUCTOR>(p, inp, out),
            }
        };
    }
    macro_rules! by_g {
        ($d:expr) => {
            match *g {
                G_NONE => by_f!($d, G_NONE),
                G_CT => by_f!($d, G_CT),
                G_SMITH => by_f!($d, G_SMITH),
                G_SMITH_CORRELATED => by_f!($d, G_SMITH_CORRELATED),
                _ => by_f!($d, G_SMITH_FAST),
            }
        };
    }
    if *d == D_GGX {
        by_g!(D_GGX)
    } else {
        by_g!(D_BECKMANN)
    }
}

/// Writes the f64 reference's result for batch row `row` at position `j` of the chunk and
/// counts its status.
fn rescue(batch: &Batch, m: &Material, row: usize, j: usize, w: &mut Work, counts: &mut Counts) {
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

/// Columns 0–8 (L, V, N) of `LANES` consecutive rows of `C` columns into lanes.
#[inline(always)]
fn transpose<const C: usize>(rows: &[f32], inp: &mut Inputs) {
    for (c, col) in inp.v.iter_mut().enumerate() {
        for (k, x) in col.iter_mut().enumerate() {
            *x = rows[k * C + c];
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

#[inline(always)]
fn run_chunk(
    plan: &Plan,
    batch: &Batch,
    order: Option<&[usize]>,
    w: &mut Work,
    m: &Material,
) -> (Counts, Tally) {
    let rows = |p: usize| order.map_or(p, |o| o[p]);
    let mut counts = Counts::default();
    let len = w.brdf.len() / 3;
    let mut tally = Tally::default();
    if !plan.is_simd() {
        for j in 0..len {
            rescue(batch, m, rows(w.start + j), j, w, &mut counts);
        }
        tally.reference = len as u64;
        return (counts, tally);
    }
    tally.lanes = len as u64;
    let data = batch.as_slice();
    let cols = batch.columns();
    let mut inp = Inputs {
        v: [[0.0; LANES]; 9],
    };
    let mut out = Outputs::default();
    let mut idx = [0usize; LANES];
    let mut j0 = 0;
    while j0 < len {
        let n = LANES.min(len - j0);
        for (k, slot) in idx.iter_mut().enumerate() {
            // The tail block repeats its last row: its extra lanes are computed and dropped.
            *slot = rows(w.start + j0 + k.min(n - 1));
        }
        if order.is_none() && n == LANES {
            // Consecutive rows: a fixed-stride transpose the compiler unrolls.
            let base = idx[0] * cols;
            if cols == COLUMNS_PLAIN {
                transpose::<COLUMNS_PLAIN>(&data[base..base + LANES * COLUMNS_PLAIN], &mut inp);
            } else {
                transpose::<COLUMNS_TANGENT>(&data[base..base + LANES * COLUMNS_TANGENT], &mut inp);
            }
        } else {
            for (k, &r) in idx.iter().enumerate() {
                let row = &data[r * cols..r * cols + 9];
                for (c, &x) in row.iter().enumerate() {
                    inp.v[c][k] = x;
                }
            }
        }
        block(plan, &inp, &mut out);
        if n == LANES {
            // Fixed-size interleaving stores the compiler turns into shuffles.
            untranspose::<3>(&out.brdf, &mut w.brdf[j0 * 3..(j0 + LANES) * 3]);
            if let Some(t) = w.terms.as_deref_mut() {
                untranspose::<TERM_COLUMNS>(
                    &out.terms,
                    &mut t[j0 * TERM_COLUMNS..(j0 + LANES) * TERM_COLUMNS],
                );
            }
        } else {
            for k in 0..n {
                let j = j0 + k;
                for ch in 0..3 {
                    w.brdf[j * 3 + ch] = out.brdf[ch][k];
                }
                if let Some(t) = w.terms.as_deref_mut() {
                    for c in 0..TERM_COLUMNS {
                        t[j * TERM_COLUMNS + c] = out.terms[c][k];
                    }
                }
            }
        }
        for k in 0..n {
            if out.rescue[k] {
                rescue(batch, m, idx[k], j0 + k, w, &mut counts);
                tally.rescued += 1;
            }
        }
        j0 += n;
    }
    (counts, tally)
}

impl Backend for CpuEngine {
    fn name(&self) -> String {
        format!(
            "cpu ({}, {} thread{})",
            instruction_set(),
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
        let n = batch.len();
        let plans: Vec<Plan> = materials.iter().map(Plan::for_material).collect();
        // Group the rows by material: a stable counting sort, skipped when one material
        // covers the batch (then the grouped order is the row order).
        let mut counts_per = vec![0usize; materials.len()];
        if materials.len() == 1 {
            // Every row is material 0 (the batch validated its indices): no pass over it.
            counts_per[0] = n;
        } else {
            for i in 0..n {
                counts_per[batch.material(i)] += 1;
            }
        }
        let single = counts_per.iter().filter(|&&c| c > 0).count() <= 1;
        let mut group_start = vec![0usize; materials.len() + 1];
        for (mi, c) in counts_per.iter().enumerate() {
            group_start[mi + 1] = group_start[mi] + c;
        }
        let order: Option<Vec<usize>> = (!single).then(|| {
            let mut next = group_start.clone();
            let mut order = vec![0usize; n];
            for i in 0..n {
                let mi = batch.material(i);
                order[next[mi]] = i;
                next[mi] += 1;
            }
            order
        });

        // Outputs in the grouped order (the row order itself when there is one group).
        let mut brdf = vec![0f32; n * 3];
        let mut terms = request.terms.then(|| vec![0f32; n * TERM_COLUMNS]);
        let mut queue = Vec::new();
        {
            let mut rest_b: &mut [f32] = &mut brdf;
            let mut rest_t: Option<&mut [f32]> = terms.as_deref_mut();
            for (mi, &count) in counts_per.iter().enumerate() {
                let mut start = group_start[mi];
                let end = start + count;
                while start < end {
                    let len = CHUNK.min(end - start);
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
                        material: if single { batch.material(0) } else { mi },
                        start,
                        brdf: b,
                        terms: t,
                    });
                    start += len;
                }
            }
        }
        queue.reverse(); // workers pop from the back: rows go out roughly in order
        let queue = Mutex::new(queue);
        let cancel = &self.cancel;
        let workers = self.threads.min(n.div_ceil(CHUNK)).max(1);
        let arch = pulp::Arch::new();
        let work = |_: usize| -> (Counts, Tally) {
            let mut total = Counts::default();
            let mut tally = Tally::default();
            loop {
                if cancel.is_cancelled() {
                    break;
                }
                let Some(mut w) = queue.lock().expect("queue lock").pop() else {
                    break;
                };
                let (c, t) = arch.dispatch(ChunkOp {
                    plan: &plans[w.material],
                    batch,
                    order: order.as_deref(),
                    material: &materials[w.material],
                    work: &mut w,
                });
                total.absorb(&c);
                tally.add(&t);
            }
            (total, tally)
        };
        let parts: Vec<(Counts, Tally)> = if workers == 1 {
            vec![work(0)]
        } else {
            std::thread::scope(|s| {
                let handles: Vec<_> = (0..workers).map(|t| s.spawn(move || work(t))).collect();
                handles
                    .into_iter()
                    .map(|h| h.join().expect("cpu engine worker panicked"))
                    .collect()
            })
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
        // Back to row order.
        if let Some(order) = order {
            let mut b = vec![0f32; n * 3];
            for (p, &r) in order.iter().enumerate() {
                b[r * 3..r * 3 + 3].copy_from_slice(&brdf[p * 3..p * 3 + 3]);
            }
            brdf = b;
            if let Some(t) = terms.as_mut() {
                let mut u = vec![0f32; n * TERM_COLUMNS];
                for (p, &r) in order.iter().enumerate() {
                    u[r * TERM_COLUMNS..(r + 1) * TERM_COLUMNS]
                        .copy_from_slice(&t[p * TERM_COLUMNS..(p + 1) * TERM_COLUMNS]);
                }
                *t = u;
            }
        }
        Ok(Output {
            brdf,
            terms,
            counts,
        })
    }
}
