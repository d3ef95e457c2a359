//! The streamed path of an engine that runs one copy a core ([`Backend::stream_workers`]:
//! the CPU engine): each worker takes the next slice of rows, reads it from the file
//! (mapped where the page cache holds it, else a positioned read into its own buffer),
//! checks it, evaluates it and writes its outputs where they go in the staged files
//! (positioned writes), then takes the next. A slice stays in its core's cache from the
//! file to the output, and no stage waits on another's thread: the pipeline of a reader,
//! an engine and a writer thread kept four threads busy on two cores and moved every chunk
//! between caches (docs/STREAMING.md has the figures). Where the run has the cores to
//! itself, each worker is held to one ([`super::pin`]).
//!
//! Errors keep their batch order: a worker that meets one (a bad material index, a missing
//! tangent, a short file) records it with its slice's index, and no worker takes a slice
//! after it; the slices before it still run, so the error reported is the first in the
//! batch, as the pipeline reports it.

use super::job::{chunk_rows_for, Setup, StreamJob, StreamSummary};
use super::pin::{cores_for, Held};
use crate::atomic::{stage_writer, Staged, StagedWriter};
use crate::backend::{Backend, Counts, Output, TERM_COLUMNS};
use crate::batch::rows::NpyRows;
use crate::batch::{check_tangent_rows, npy_header_f32, Batch};
use crate::cancel::Cancel;
use crate::error::{Error, Result};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// Rows a worker takes at a time, at most: 1.3–1.7 MB of rows and 0.4–1.2 MB of outputs,
/// past a core's L2 but within the last-level cache, and few enough calls that the
/// kernel's work a read or write (the page-cache lookups, the file's lock) costs little
/// a row; 8,192 rows (in L2) and 65,536 or more (fewer slices than a small batch's two
/// workers balance well) both ran slower. docs/STREAMING.md has the measurement.
const SLICE_ROWS: usize = 32768;

/// Whether this path can run `job`: every output is a regular file ([`Outputs::start`]
/// decides that), the rows are evaluated in RGB, and no HTSG spike is asked for (those
/// take the pipeline, which computes them on the host beside each chunk).
pub(super) fn applies(job: &StreamJob) -> bool {
    job.spectral.is_none() && job.spike.is_none() && cfg!(target_endian = "little")
}

/// Rows a worker takes at a time for `workers` workers within a budget of `max_memory`
/// bytes, rows of `columns` values (`row_bytes` in the file) and `out_columns` outputs.
pub(super) fn slice_rows(
    max_memory: u64,
    row_bytes: usize,
    columns: usize,
    out_columns: usize,
    workers: usize,
) -> usize {
    // chunk_rows_for divides the budget among about six chunks alive at once; here one
    // slice a worker is alive.
    let budget = max_memory.saturating_mul(6) / workers.max(1) as u64;
    chunk_rows_for(budget, row_bytes, columns, out_columns).min(SLICE_ROWS)
}

/// The bytes of a page: slice boundaries fall on them ([`Slices`]).
const PAGE: u64 = 4096;

/// How the rows of a part are cut into slices: a first, shorter one (`lead` rows) that
/// ends where an output's row starts on a page boundary, then slices of `slice` rows, a
/// whole number of pages of that output each. Every later write then covers whole pages
/// (but the last): a write that shares its first and last page with a neighbouring slice
/// (the 128-byte `.npy` header shifts every row) fills them twice, from two workers, and
/// costs more a byte (docs/STREAMING.md has the figures).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Slices {
    n: u64,
    lead: u64,
    slice: u64,
}

impl Slices {
    /// `n` rows in slices of `slice` rows, aligned for an output whose rows (`row_bytes`
    /// each) start at byte `data_start`; no shorter first slice when `slice` is not a whole
    /// number of pages of it.
    fn new(n: u64, slice: u64, data_start: u64, row_bytes: u64) -> Slices {
        let slice = slice.max(1);
        // Rows whose bytes make a whole number of pages: PAGE / gcd(row_bytes, PAGE).
        let period = (1..=PAGE)
            .find(|r| (r * row_bytes).is_multiple_of(PAGE))
            .unwrap_or(PAGE);
        let lead = (0..period)
            .find(|r| (data_start + r * row_bytes).is_multiple_of(PAGE))
            .filter(|_| slice.is_multiple_of(period))
            .unwrap_or(0)
            .min(n);
        Slices { n, lead, slice }
    }

    /// How many slices.
    fn count(&self) -> u64 {
        u64::from(self.lead > 0) + (self.n - self.lead).div_ceil(self.slice)
    }

    /// Slice `k`'s rows, from the part's first.
    fn rows(&self, k: u64) -> std::ops::Range<u64> {
        if self.lead > 0 && k == 0 {
            return 0..self.lead;
        }
        let k = k - u64::from(self.lead > 0);
        let start = self.lead + k * self.slice;
        start..(start + self.slice).min(self.n)
    }
}

/// One float32 `.npy` output written by rows at their places.
struct RowsOut {
    writer: StagedWriter,
    /// Where row 0 of the part starts in the file (the header's length).
    data_start: u64,
    columns: usize,
    /// Values written so far (checked against the shape at the end).
    written: AtomicU64,
    expected: u64,
}

impl RowsOut {
    fn start(
        path: &std::path::Path,
        rows: u64,
        columns: usize,
        cancel: &Cancel,
    ) -> Result<Option<RowsOut>> {
        let writer = stage_writer(path, cancel)?;
        if !writer.is_positioned() {
            return Ok(None);
        }
        let header = npy_header_f32(rows, columns);
        writer.preallocate(header.len() as u64 + rows * columns as u64 * 4)?;
        writer.write_at(0, &header)?;
        Ok(Some(RowsOut {
            writer,
            data_start: header.len() as u64,
            columns,
            written: AtomicU64::new(0),
            expected: rows * columns as u64,
        }))
    }

    /// `values` (whole rows) as the part's rows from `row` on.
    fn rows_at(&self, row: u64, values: &[f32]) -> Result<()> {
        let offset = self.data_start + row * 4 * self.columns as u64;
        self.writer.write_at(offset, bytemuck::cast_slice(values))?;
        self.written
            .fetch_add(values.len() as u64, Ordering::Relaxed);
        Ok(())
    }

    fn finish(self, path: &std::path::Path) -> Result<Staged> {
        let written = self.written.into_inner();
        if written != self.expected {
            return Err(Error::Batch {
                path: path.to_owned(),
                message: format!(
                    "wrote {written} values where the header promises {} (the input changed while it was read?)",
                    self.expected
                ),
            });
        }
        self.writer.finish()
    }
}

/// The outputs of a fused run: the BRDF and, when asked for, the terms.
pub(super) struct Outputs {
    brdf: RowsOut,
    terms: Option<RowsOut>,
}

impl Outputs {
    /// Stages `job`'s outputs for positioned writes; `None` when one of them is not a
    /// regular file (a FIFO, a device, standard output), which the pipeline writes in order.
    pub(super) fn start(job: &StreamJob, rows: u64, cancel: &Cancel) -> Result<Option<Outputs>> {
        let Some(brdf) = RowsOut::start(job.output, rows, 3, cancel)? else {
            return Ok(None);
        };
        let terms = match job.terms {
            Some(path) => match RowsOut::start(path, rows, TERM_COLUMNS, cancel)? {
                Some(t) => Some(t),
                None => return Ok(None),
            },
            None => None,
        };
        Ok(Some(Outputs { brdf, terms }))
    }
}

/// What one worker did: its counts and the seconds it spent in each stage.
#[derive(Default)]
struct Part {
    counts: Counts,
    read_s: f64,
    eval_s: f64,
    write_s: f64,
    slices: usize,
}

/// The state the workers share.
struct Shared<'a> {
    job: &'a StreamJob<'a>,
    setup: &'a Setup,
    rows: &'a NpyRows,
    outputs: &'a Outputs,
    cancel: &'a Cancel,
    slices: Slices,
    /// The next slice to take.
    next: AtomicU64,
    /// The first slice that failed (`u64::MAX`: none): no worker takes a later one.
    stop: AtomicU64,
    /// Rows evaluated so far, for the progress report.
    done: AtomicU64,
    failures: Mutex<Vec<(u64, Error)>>,
}

impl Shared<'_> {
    /// A worker's loop: slices until none is left, the run is cancelled or one failed
    /// before the next; `tick` is told after each slice. Held to `core` while it runs,
    /// when given ([`super::pin`]).
    fn work(&self, engine: &mut dyn Backend, mut tick: impl FnMut(), core: Option<usize>) -> Part {
        let _held = core.map(Held::to);
        let mut part = Part::default();
        let (mut buffer, mut bytes, mut out) = (Vec::new(), Vec::new(), Output::default());
        loop {
            if self.cancel.is_cancelled() {
                break;
            }
            let k = self.next.fetch_add(1, Ordering::Relaxed);
            if k >= self.slices.count() || k > self.stop.load(Ordering::Relaxed) {
                break;
            }
            let rows = self.slices.rows(k);
            let at = self.setup.part.start + rows.start;
            let len = (rows.end - rows.start) as usize;
            match self.slice_at(
                engine,
                at,
                len,
                &mut buffer,
                &mut bytes,
                &mut out,
                &mut part,
            ) {
                Ok(()) => {
                    part.slices += 1;
                    self.done.fetch_add(len as u64, Ordering::Relaxed);
                    tick();
                }
                Err(e) => {
                    self.stop.fetch_min(k, Ordering::Relaxed);
                    self.failures
                        .lock()
                        .unwrap_or_else(|p| p.into_inner())
                        .push((k, e));
                }
            }
        }
        part
    }

    /// Rows `at..at + len`: read, checked, evaluated and written.
    #[allow(clippy::too_many_arguments)]
    fn slice_at(
        &self,
        engine: &mut dyn Backend,
        at: u64,
        len: usize,
        buffer: &mut Vec<f32>,
        bytes: &mut Vec<u8>,
        out: &mut Output,
        part: &mut Part,
    ) -> Result<()> {
        let (job, request) = (self.job, &self.setup.request);
        let t = Instant::now();
        let data = std::mem::take(buffer);
        let t1 = match self.setup.local {
            Some(m) => {
                let b = self.rows.local_at(at, len, m, job.materials, data, bytes)?;
                let t1 = Instant::now();
                engine.evaluate_local_into(&b, job.materials, request, out)?;
                *buffer = b.into_data();
                t1
            }
            None => {
                let evaluate = |b: &Batch<'_>, engine: &mut dyn Backend, out: &mut Output| {
                    check_tangent_rows(b.as_slice(), b.columns(), at, job.materials, job.input)?;
                    let t1 = Instant::now();
                    engine.evaluate_into(b, job.materials, request, out)?;
                    Ok(t1)
                };
                // Where the page cache holds the rows, read in place; else copied out.
                match self.rows.with_mapped(at, len, |b| evaluate(b, engine, out)) {
                    Some(t1) => {
                        *buffer = data;
                        t1?
                    }
                    None => {
                        let b = self.rows.batch_at(at, len, data, bytes)?;
                        let t1 = evaluate(&b, engine, out)?;
                        *buffer = b.into_data();
                        t1
                    }
                }
            }
        };
        let t2 = Instant::now();
        let row = at - self.setup.part.start;
        self.outputs.brdf.rows_at(row, &out.brdf)?;
        if let (Some(w), Some(v)) = (&self.outputs.terms, &out.terms) {
            w.rows_at(row, v)?;
        }
        let mut counted = out.counts;
        counted.first_invalid = counted.first_invalid.map(|r| r + at);
        part.counts.absorb(&counted);
        part.read_s += (t1 - t).as_secs_f64();
        part.eval_s += (t2 - t1).as_secs_f64();
        part.write_s += t2.elapsed().as_secs_f64();
        Ok(())
    }
}

/// Evaluates the rows `setup.part` of `rows` on `workers` (one thread each, the calling
/// thread among them) into `outputs`; returns the staged outputs (`None` when `strict`
/// found an invalid tuple). `summary`'s seconds are summed over the workers.
pub(super) fn evaluate(
    job: &StreamJob,
    setup: &Setup,
    rows: &NpyRows,
    mut workers: Vec<Box<dyn Backend + Send>>,
    outputs: Outputs,
    cancel: &Cancel,
    mut progress: impl FnMut(u64, u64),
) -> Result<(StreamSummary, Option<Vec<Staged>>)> {
    let n = setup.part.end - setup.part.start;
    let outputs_a_row = setup.out_columns + if setup.request.terms { TERM_COLUMNS } else { 0 };
    let slice = slice_rows(
        job.max_memory,
        rows.row_bytes(),
        rows.columns(),
        outputs_a_row,
        workers.len(),
    ) as u64;
    // The boundaries on the pages of the larger output (the terms', when asked for).
    let widest = outputs.terms.as_ref().unwrap_or(&outputs.brdf);
    let slices = Slices::new(n, slice, widest.data_start, 4 * widest.columns as u64);
    let shared = Shared {
        job,
        setup,
        rows,
        outputs: &outputs,
        cancel,
        slices,
        next: AtomicU64::new(0),
        stop: AtomicU64::new(u64::MAX),
        done: AtomicU64::new(0),
        failures: Mutex::new(Vec::new()),
    };
    let cores = cores_for(workers.len());
    let core = |i: usize| cores.as_ref().map(|c| c[i]);
    let mut workers = workers.iter_mut();
    let mine = workers.next();
    let parts: Vec<Part> = std::thread::scope(|scope| {
        let shared = &shared;
        let helpers: Vec<_> = workers
            .enumerate()
            .map(|(i, w)| scope.spawn(move || shared.work(w.as_mut(), || {}, core(i + 1))))
            .collect();
        let mut parts = Vec::with_capacity(helpers.len() + 1);
        if let Some(w) = mine {
            let tick = || progress(shared.done.load(Ordering::Relaxed), n);
            parts.push(shared.work(w.as_mut(), tick, core(0)));
        }
        for h in helpers {
            parts.push(h.join().expect("a stream worker does not panic"));
        }
        parts
    });
    let first_failure = shared
        .failures
        .into_inner()
        .unwrap_or_else(|p| p.into_inner())
        .into_iter()
        .min_by_key(|(k, _)| *k);
    if let Some((_, e)) = first_failure {
        return Err(e);
    }
    cancel.check()?;
    progress(n, n);
    let mut summary = StreamSummary {
        chunk_rows: slice as usize,
        ..StreamSummary::default()
    };
    summary.counts.tuples = n;
    for p in &parts {
        summary.counts.absorb(&p.counts);
        summary.read_s += p.read_s;
        summary.eval_s += p.eval_s;
        summary.write_s += p.write_s;
        summary.chunks += p.slices;
    }
    if job.strict && summary.counts.invalid > 0 {
        return Ok((summary, None)); // the writers drop: their temporary files go
    }
    let Outputs { brdf, terms } = outputs;
    let mut staged = vec![brdf.finish(job.output)?];
    if let (Some(w), Some(path)) = (terms, job.terms) {
        staged.push(w.finish(path)?);
    }
    Ok((summary, Some(staged)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The slices cover the rows once, in order, each at most `slice` rows; with a
    /// `slice` that is a whole number of pages of the output, every boundary after the
    /// first slice starts a row on a page (the BRDF's 12-byte rows and the terms'
    /// 24-byte rows behind a 128-byte header: 672 and 336 rows first), and without one
    /// the slices are even.
    #[test]
    fn slices_cover_the_rows_once_and_start_on_pages() {
        for (row_bytes, lead) in [(12, 672), (24, 336)] {
            assert_eq!(Slices::new(1 << 20, 8192, 128, row_bytes).lead, lead);
            for n in [0, 1, 335, 336, 671, 672, 673, 8192, 8864, 100_000, 1 << 20] {
                for slice in [8192, 4096, 1000, 1] {
                    let s = Slices::new(n, slice, 128, row_bytes);
                    let mut next = 0;
                    for k in 0..s.count() {
                        let r = s.rows(k);
                        assert_eq!(r.start, next, "n {n}, slice {slice}, k {k}");
                        assert!(r.end > r.start && r.end - r.start <= slice);
                        if k > 0 && slice.is_multiple_of(1024) {
                            assert!(
                                (128 + r.start * row_bytes).is_multiple_of(PAGE),
                                "n {n}, k {k}"
                            );
                        }
                        next = r.end;
                    }
                    assert_eq!(next, n, "n {n}, slice {slice}");
                    if !slice.is_multiple_of(1024) {
                        assert_eq!(s.lead, 0, "slice {slice}");
                    }
                }
            }
        }
    }
}
