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
mod chunk;
mod generated;
pub mod htsg;
pub mod importance;
pub mod isa;
pub mod kernel;
pub mod lobes;

mod dispatch;
mod frame;
mod measured;
pub mod plan;
mod register;
mod segments;
mod slice_tuples;
pub mod transpose;
pub use chunk::Tally;
use chunk::{Source, Work};
#[cfg(test)]
pub(crate) use dispatch::block;

use crate::backend::{Backend, Counts, Output, Request, TERM_COLUMNS};
use crate::batch::columns::{ColumnBatch, MaterialColumn};
use crate::batch::{Batch, LocalBatch};
use crate::cancel::Cancel;
use crate::error::Result;
use crate::material::Material;
pub use isa::Isa;
use kernel::LANES;
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

/// The length of the next chunk when `rest` rows are left, `chunk` a chunk and `threads`
/// threads take them: `chunk` until the last `threads` chunks' worth, then a quarter of
/// it (at least `MIN_CHUNK`, a multiple of the lanes' block), so that the thread that
/// finishes first waits on a short chunk, not a whole one, for the other (guided
/// scheduling's tail).
fn chunk_len(rest: usize, chunk: usize, threads: usize) -> usize {
    let len = if rest > chunk * threads {
        chunk
    } else {
        (chunk / 4)
            .next_multiple_of(LANES)
            .max(MIN_CHUNK)
            .min(chunk)
    };
    len.min(rest)
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
        chunk::lanes(
            self.arch,
            &self.plans[mi],
            &self.materials[mi],
            self.src,
            order,
            w,
        )
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
        let plans: Vec<Plan> = materials
            .iter()
            .map(|m| {
                Plan::for_material(m)
                    .with_conductor_poly(m, self.isa)
                    .with_terms(request.terms)
                    .with_deferred_slow()
            })
            .collect();
        // The material of every row when the batch says so without a pass over it; else
        // each chunk groups its own rows (`mixed_chunk`).
        let single = match src {
            // Every row is material 0 (the batch validated its indices).
            Source::Rows(_) if materials.len() == 1 => Some(0),
            Source::Rows(_) => None,
            Source::Local(b) => Some(b.material()),
            Source::Slice(_) => Some(0),
            Source::Columns(b) => match b.materials() {
                MaterialColumn::Every(m) => Some(m),
                MaterialColumn::Each(_) if materials.len() == 1 => Some(0),
                MaterialColumn::Each(_) => None,
            },
        };
        // The caller's buffers, reused: no fresh pages to fault in and zero.
        out.terms = request.terms.then(|| out.terms.take().unwrap_or_default());
        set_len(&mut out.brdf, n * 3);
        if let Some(t) = out.terms.as_mut() {
            set_len(t, n * TERM_COLUMNS);
        }
        let chunk = chunk_rows(n, self.threads);
        let mut queue = Vec::with_capacity(n.div_ceil(chunk) + 4 * self.threads);
        {
            let mut rest_b: &mut [f32] = &mut out.brdf;
            let mut rest_t: Option<&mut [f32]> = out.terms.as_deref_mut();
            let mut start = 0;
            while start < n {
                let len = chunk_len(n - start, chunk, self.threads);
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

    fn evaluate_columns_into(
        &mut self,
        batch: &ColumnBatch,
        materials: &[Material],
        request: &Request,
        out: &mut Output,
    ) -> Result<()> {
        self.run(Source::Columns(batch), materials, request, out)
    }

    fn generated_directions(&mut self) -> Option<&mut dyn crate::backend::GeneratedDirections> {
        Some(self)
    }

    fn stream_workers(&self) -> Option<Vec<Box<dyn Backend + Send>>> {
        Some(
            (0..self.threads)
                .map(|_| {
                    let mut w = CpuEngine::with_isa(1, self.isa);
                    w.cancel = self.cancel.clone();
                    Box::new(w) as Box<dyn Backend + Send>
                })
                .collect(),
        )
    }
}

#[cfg(test)]
mod chunk_tests {
    use super::*;

    /// The chunks cover the batch once, whole blocks but the last, and end in the short
    /// tail: at 262,144 rows on two threads fourteen chunks of 16,384 and eight of 4,096.
    #[test]
    fn chunks_cover_the_batch_and_end_short() {
        for (n, threads) in [
            (262_144, 2),
            (4_194_304, 2),
            (1_000_003, 16),
            (100, 2),
            (0, 2),
        ] {
            let chunk = chunk_rows(n, threads);
            let mut lens = Vec::new();
            let mut start = 0;
            while start < n {
                let len = chunk_len(n - start, chunk, threads);
                assert!(len > 0 && len <= chunk, "n = {n}: {len}");
                lens.push(len);
                start += len;
            }
            assert_eq!(start, n);
            let whole = &lens[..lens.len().saturating_sub(1)];
            assert!(whole.iter().all(|l| l % LANES == 0), "n = {n}: {lens:?}");
            if n == 262_144 {
                assert_eq!(lens, [[16_384; 14].as_slice(), &[4_096; 8]].concat());
            }
        }
    }
}
