//! Streaming evaluation: a `.npy` batch read, evaluated and written chunk by chunk, so that
//! host memory stays within a budget whatever the batch's size, and a batch larger than the
//! machine's memory evaluates instead of being killed.
//!
//! Each output is a [`StagedWriter`]: its `.npy` header (the
//! shape is known from the input's) and then each chunk's rows go to a temporary file beside
//! the target, renamed at the end with the others ([`crate::atomic::commit`]): a failure, a
//! cancellation or `strict` with an invalid tuple leaves the previous files and no temporary
//! one. Results do not depend on the chunk size: every engine evaluates tuple by tuple.

pub mod shard;

use crate::atomic::{self, StagedWriter};
use crate::backend::{Backend, Counts, Output, Request, TERM_COLUMNS};
use crate::batch::rows::NpyRows;
use crate::batch::{check_tangent_rows, local_material, Batch, LocalBatch, COLUMNS_LOCAL};
use crate::cancel::Cancel;
use crate::error::{Error, Result};
use crate::material::Material;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The default host-memory budget of a streamed evaluation: 512 MiB.
pub const DEFAULT_MAX_MEMORY: u64 = 512 << 20;

/// What to evaluate and where the results go.
pub struct StreamJob<'a> {
    /// The tuples (`.npy`, `(n, 10)` or `(n, 13)`, or the local-frame `(n, 6)`; float32
    /// or float64).
    pub input: &'a Path,
    /// The material of a local-frame `(n, 6)` input, by name or index (see
    /// [`local_material`]); must be `None` for rows, which carry their own.
    pub material: Option<&'a str>,
    /// The materials the rows index.
    pub materials: &'a [Material],
    /// Where the BRDF goes (`.npy`, float32 `(n, 3)`).
    pub output: &'a Path,
    /// Where the terms go (`.npy`, float32 `(n, 6)`), if wanted.
    pub terms: Option<&'a Path>,
    /// Where the mirror spike's weight `ρ_s` of HTSG materials goes (`.npy`, float32
    /// `(n, 3)`, FORMULAS.md §8), if wanted: every material of the table must be HTSG's.
    /// Computed on the host from the f64 form for each chunk the engine evaluates, and
    /// written with the other outputs (all or none).
    pub spike: Option<&'a Path>,
    /// Host memory for the chunk buffers, in bytes (see [`chunk_rows`]).
    pub max_memory: u64,
    /// Write nothing when any tuple is invalid (the counts are still returned).
    pub strict: bool,
    /// Evaluate only this part of the batch, and write its sidecar beside the output.
    pub shard: Option<shard::Shard>,
    /// The materials file (fingerprinted into a shard's sidecar).
    pub materials_file: &'a Path,
    /// Evaluate at wavelengths instead of in RGB (FORMULAS.md §9): the output then has
    /// the job's columns (`W` values, or 3 for a colour reduction). No terms or spike.
    pub spectral: Option<&'a crate::spectral_eval::SpectralJob>,
}

/// What a streamed evaluation did.
#[derive(Debug, Clone, Default)]
pub struct StreamSummary {
    /// The whole batch's counts (the first invalid row counted from the batch's start).
    pub counts: Counts,
    /// Rows per chunk.
    pub chunk_rows: usize,
    /// Chunks evaluated.
    pub chunks: usize,
    /// Seconds spent reading, evaluating and writing.
    pub read_s: f64,
    /// See `read_s`.
    pub eval_s: f64,
    /// See `read_s`.
    pub write_s: f64,
    /// Whether the outputs were written (false under `strict` with an invalid tuple).
    pub written: bool,
}

/// Rows per chunk for a budget of `max_memory` bytes: each row holds its input as read
/// (`row_bytes`) and as f32, and the outputs (3 floats, 6 more with the terms) both in the
/// engine's result and in the writer's buffer; with the three stages overlapping about five
/// chunks are alive at once, and a sixth of the budget is left to the engine's own working
/// memory and the buffered writers. At least one row, at most [`MAX_CHUNK_ROWS`].
pub fn chunk_rows(max_memory: u64, row_bytes: usize, columns: usize, terms: bool) -> usize {
    chunk_rows_for(
        max_memory,
        row_bytes,
        columns,
        3 + if terms { TERM_COLUMNS } else { 0 },
    )
}

/// [`chunk_rows`] for `out_columns` float32 outputs a row (a spectral evaluation's `W`).
pub fn chunk_rows_for(
    max_memory: u64,
    row_bytes: usize,
    columns: usize,
    out_columns: usize,
) -> usize {
    let outputs = 4 * out_columns;
    let per_row = (row_bytes + 4 * columns + 2 * outputs) as u64;
    ((max_memory / 6) / per_row).clamp(1, MAX_CHUNK_ROWS as u64) as usize
}

/// The largest chunk, whatever the budget: the stages overlap only from the second chunk
/// on, and the first and last run alone, so a batch of a few budget-sized chunks barely
/// overlapped; and the chunks alive at once (about five) should stay in the last-level
/// cache, where the reader's copy leaves a chunk for the engine and the engine its results
/// for the writer. 2^17 rows (5 MiB of float32 rows) keep every engine efficient (the
/// Vulkan kernel streams 256 K-tuple chunks itself, the CPU engine cuts 16 K-row blocks);
/// docs/STREAMING.md has the measurement.
pub const MAX_CHUNK_ROWS: usize = 1 << 17;

/// Evaluates `job` on `backend`, chunk by chunk; `progress` is told the rows done so far.
pub fn evaluate(
    job: &StreamJob,
    backend: &mut dyn Backend,
    cancel: &Cancel,
    mut progress: impl FnMut(u64, u64),
) -> Result<StreamSummary> {
    let mut rows = NpyRows::open(job.input, job.materials.len())?;
    // The local form's one material, resolved before any work.
    let local = if rows.columns() == COLUMNS_LOCAL {
        Some(local_material(job.material, job.materials, job.input)?)
    } else if let Some(m) = job.material {
        return Err(Error::Batch {
            path: job.input.to_owned(),
            message: format!(
                "--material {m:?} applies only to a 6-column local-frame batch (Lx Ly Lz Vx Vy Vz); this batch has {} columns and each row names its material in column 9",
                rows.columns()
            ),
        });
    } else {
        None
    };
    if job.spike.is_some() {
        spike_allowed(job)?;
    }
    if job.spectral.is_some() && (job.spike.is_some() || job.terms.is_some()) {
        return Err(Error::Unsupported(
            "a spectral evaluation writes f(λ) only: the terms and the spike are RGB outputs (evaluate them without --wavelengths)".into(),
        ));
    }
    let out_columns = job.spectral.map_or(3, |s| s.columns());
    let total = rows.rows();
    let part = job.shard.map_or(0..total, |s| s.rows(total));
    rows.restrict(part.clone())?;
    let n = part.end - part.start;
    let request = Request {
        terms: job.terms.is_some(),
    };
    let chunk = match job.spectral {
        // The W outputs, and the triplet's RGB the engine writes before they are spread.
        Some(s) => chunk_rows_for(
            job.max_memory,
            rows.row_bytes(),
            rows.columns(),
            s.columns() + 3,
        ),
        None => chunk_rows(
            job.max_memory,
            rows.row_bytes(),
            rows.columns(),
            request.terms,
        ),
    };
    let mut brdf = NpyOut::start(job.output, n, out_columns, cancel)?;
    let mut terms = match job.terms {
        Some(path) => Some(NpyOut::start(path, n, TERM_COLUMNS, cancel)?),
        None => None,
    };
    let mut spike = match job.spike {
        Some(path) => Some(NpyOut::start(path, n, 3, cancel)?),
        None => None,
    };
    let mut summary = StreamSummary {
        chunk_rows: chunk,
        ..StreamSummary::default()
    };
    summary.counts.tuples = n;
    // Three stages overlap: a reader thread reads chunk k+1 while the engine evaluates chunk
    // k on this thread and a writer thread writes chunk k-1. One chunk waits in each
    // channel, so at most about five are alive at once (`chunk_rows` divides the budget).
    // The writer hands each written output back, and the engine evaluates into it again:
    // a few buffers serve the whole batch, faulted in and zeroed once.
    let (read_tx, read_rx) = std::sync::mpsc::sync_channel::<Result<(u64, Chunk, f64)>>(1);
    let (write_tx, write_rx) = std::sync::mpsc::sync_channel::<(Output, Vec<f32>)>(1);
    let (recycle_tx, recycle_rx) = std::sync::mpsc::channel::<Output>();
    // Spent input buffers go back to the reader, which reads the next chunk into one.
    let (spent_tx, spent_rx) = std::sync::mpsc::sync_channel::<Vec<f32>>(2);
    let (written, evaluated) = std::thread::scope(|scope| {
        let reader = scope.spawn(move || loop {
            let t = std::time::Instant::now();
            let next = match local {
                Some(m) => rows
                    .next_local(chunk, m, job.materials)
                    .map(|c| c.map(|(first, b)| (first, Chunk::Local(b)))),
                None => rows
                    .next_chunk_reusing(chunk, spent_rx.try_recv().unwrap_or_default())
                    .and_then(|c| {
                        if let Some((first, batch)) = &c {
                            check_tangent_rows(
                                batch.as_slice(),
                                batch.columns(),
                                *first,
                                job.materials,
                                job.input,
                            )?;
                        }
                        Ok(c.map(|(first, b)| (first, Chunk::Rows(b))))
                    }),
            };
            let message = match next {
                Ok(None) => break,
                Ok(Some((first, batch))) => Ok((first, batch, t.elapsed().as_secs_f64())),
                Err(e) => Err(e),
            };
            let failed = message.is_err();
            if read_tx.send(message).is_err() || failed {
                break; // the evaluator stopped, or this was the error it will report
            }
        });
        let writer = scope.spawn(
            move || -> Result<(NpyOut, Option<NpyOut>, Option<NpyOut>, f64)> {
                let mut write_s = 0.0;
                for (out, spikes) in write_rx {
                    let t = std::time::Instant::now();
                    brdf.rows(&out.brdf)?;
                    if let (Some(w), Some(v)) = (terms.as_mut(), out.terms.as_ref()) {
                        w.rows(v)?;
                    }
                    if let Some(w) = spike.as_mut() {
                        w.rows(&spikes)?;
                    }
                    write_s += t.elapsed().as_secs_f64();
                    // The evaluator may have stopped; then the buffer is simply dropped.
                    let _ = recycle_tx.send(out);
                }
                Ok((brdf, terms, spike, write_s))
            },
        );
        let evaluated = (|| -> Result<()> {
            for message in read_rx {
                cancel.check()?;
                let (first, batch, read_s) = message?;
                summary.read_s += read_s;
                let t = std::time::Instant::now();
                let mut out = recycle_rx.try_recv().unwrap_or_default();
                let len = match (&batch, job.spectral) {
                    (Chunk::Rows(b), None) => {
                        backend.evaluate_into(b, job.materials, &request, &mut out)?;
                        b.len()
                    }
                    (Chunk::Local(b), None) => {
                        backend.evaluate_local_into(b, job.materials, &request, &mut out)?;
                        b.len()
                    }
                    (Chunk::Rows(b), Some(s)) => {
                        let triplets = backend.is_reference();
                        s.evaluate_with(
                            b.len(),
                            triplets,
                            &crate::spectral_eval::batch_rows(b),
                            |m, o| backend.evaluate_into(b, m, &request, o),
                            &mut out,
                        )?;
                        b.len()
                    }
                    (Chunk::Local(b), Some(s)) => {
                        let triplets = backend.is_reference();
                        s.evaluate_with(
                            b.len(),
                            triplets,
                            &crate::spectral_eval::local_rows(b),
                            |m, o| backend.evaluate_local_into(b, m, &request, o),
                            &mut out,
                        )?;
                        b.len()
                    }
                };
                // The spike's weights, when asked for: the host's f64 form (cheap next to
                // the BRDF's series), in the same chunk, so all outputs advance together.
                let spikes = match (&batch, job.spike.is_some()) {
                    (_, false) => Vec::new(),
                    (Chunk::Rows(b), true) => spike_rows(b, job.materials),
                    (Chunk::Local(b), true) => spike_rows(&b.rows(0..b.len()), job.materials),
                };
                summary.eval_s += t.elapsed().as_secs_f64();
                let mut counted = out.counts;
                counted.first_invalid = counted.first_invalid.map(|r| r + first);
                summary.counts.absorb(&counted);
                summary.chunks += 1;
                progress(first + len as u64 - part.start, n);
                if let Chunk::Rows(b) = batch {
                    let _ = spent_tx.try_send(b.into_data()); // full: the reader has spares
                }
                if write_tx.send((out, spikes)).is_err() {
                    break; // the writer failed: its error is reported below
                }
            }
            Ok(())
        })();
        drop(write_tx);
        let written = writer.join().expect("the writer thread does not panic");
        reader.join().expect("the reader thread does not panic");
        (written, evaluated)
    });
    evaluated?;
    let (brdf, terms, spike, write_s) = written?;
    summary.write_s = write_s;
    if job.strict && summary.counts.invalid > 0 {
        return Ok(summary); // the writers drop: their temporary files go
    }
    let mut staged = vec![brdf.finish()?];
    if let Some(w) = terms {
        staged.push(w.finish()?);
    }
    if let Some(w) = spike {
        staged.push(w.finish()?);
    }
    if let Some(s) = job.shard {
        let c = summary.counts;
        // The parts' fingerprints as staged (the bytes the rename will publish); an output
        // held in memory (a device) cannot be merged anyway.
        let print = |st: Option<&atomic::Staged>| -> Result<Option<shard::InputPrint>> {
            st.and_then(atomic::Staged::temp_path)
                .map(shard::fingerprint)
                .transpose()
        };
        let part_print = print(staged.first())?.unwrap_or(shard::InputPrint {
            size: 0,
            hash: String::new(),
        });
        let terms_part = print(staged.get(1))?;
        let car = shard::Sidecar {
            schema: shard::SIDECAR_SCHEMA,
            shard: s,
            rows: [part.start, part.end],
            total_rows: total,
            input: shard::fingerprint(job.input)?,
            materials: shard::fingerprint(job.materials_file)?,
            engine: backend.name(),
            version: env!("CARGO_PKG_VERSION").to_string(),
            // Relative to the part's own directory when it lies there, as merge reads it.
            terms: job.terms.map(|t| relative_to_dir_of(t, job.output)),
            part: part_print,
            terms_part,
            invalid: c.invalid,
            below_horizon: c.below_horizon,
            saturated: c.saturated,
            first_invalid: c.first_invalid,
        };
        let json = car.to_json();
        staged.push(atomic::stage(
            &shard::sidecar_path(job.output),
            cancel,
            |w| w.write_all(json.as_bytes()),
        )?);
    }
    atomic::commit(staged)?;
    summary.written = true;
    Ok(summary)
}

/// Writes `chunks` (each a block of whole rows of `columns` floats, `rows` in all) as one
/// float32 `.npy` at `path`, block by block as [`evaluate`] writes them, staged and renamed
/// at the end: the write stage of the bench ([`crate::bench::stages`]).
pub fn write_chunks(
    path: &Path,
    rows: u64,
    columns: usize,
    chunks: &[&[f32]],
    cancel: &Cancel,
) -> Result<()> {
    let mut out = NpyOut::start(path, rows, columns, cancel)?;
    for c in chunks {
        out.rows(c)?;
    }
    atomic::commit(vec![out.finish()?])
}

/// One chunk as read: rows, or the local-frame form.
enum Chunk {
    Rows(Batch<'static>),
    Local(LocalBatch),
}

/// A float32 `.npy` of known shape written row block by row block.
struct NpyOut {
    writer: StagedWriter,
    path: PathBuf,
    expected: u64,
    written: u64,
    bytes: Vec<u8>,
}

impl NpyOut {
    fn start(path: &Path, rows: u64, columns: usize, cancel: &Cancel) -> Result<NpyOut> {
        let mut writer = atomic::stage_writer(path, cancel)?;
        writer
            .write_all(&crate::batch::npy_header_f32(rows, columns))
            .map_err(|e| writer.error(e))?;
        Ok(NpyOut {
            writer,
            path: path.to_owned(),
            expected: rows * columns as u64,
            written: 0,
            bytes: Vec::new(),
        })
    }

    fn rows(&mut self, values: &[f32]) -> Result<()> {
        let written = if cfg!(target_endian = "little") {
            // The floats' own bytes: no copy before the file's buffer.
            self.writer.write_all(bytemuck::cast_slice(values))
        } else {
            // One byte buffer for every chunk (a fresh one per chunk is fresh pages to fault).
            let bytes = &mut self.bytes;
            bytes.clear();
            for v in values {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
            self.writer.write_all(bytes)
        };
        written.map_err(|e| self.writer.error(e))?;
        self.written += values.len() as u64;
        Ok(())
    }

    fn finish(self) -> Result<atomic::Staged> {
        if self.written != self.expected {
            return Err(Error::Batch {
                path: self.path.clone(),
                message: format!(
                    "wrote {} values where the header promises {} (the input changed while it was read?)",
                    self.written, self.expected
                ),
            });
        }
        self.writer.finish()
    }
}

/// `path` relative to `base`'s directory when it lies in it (its file name), else as given.
fn relative_to_dir_of(path: &Path, base: &Path) -> PathBuf {
    match (path.parent(), base.parent(), path.file_name()) {
        (Some(a), Some(b), Some(name)) if a == b => PathBuf::from(name),
        _ => path.to_owned(),
    }
}

/// `--spike` asks for a quantity only HTSG defines (FORMULAS.md §8): every material of the
/// table must be HTSG's, and a shard's part would have no place for it in `merge`.
fn spike_allowed(job: &StreamJob) -> Result<()> {
    if job.shard.is_some() {
        return Err(Error::Unsupported(
            "--spike with --shard: merge joins BRDF and terms parts only; evaluate the spike's weights unsharded"
                .into(),
        ));
    }
    if let Some((i, m)) = job
        .materials
        .iter()
        .enumerate()
        .find(|(_, m)| !matches!(m.model, crate::material::Model::Htsg(_)))
    {
        return Err(Error::Unsupported(format!(
            "--spike: material `{}` (index {i}) is {}; the mirror spike's weight ρ_s is defined for htsg materials only (FORMULAS.md §8)",
            m.name,
            m.model.toml_name()
        )));
    }
    Ok(())
}

/// `ρ_s` of each row of `batch` ([`crate::reference::htsg_spike_rows`]); every material is
/// HTSG's ([`spike_allowed`] checked it before any work), so no row can fail.
fn spike_rows(batch: &crate::batch::Batch, materials: &[Material]) -> Vec<f32> {
    crate::reference::htsg_spike_rows(batch, materials).unwrap_or_default()
}
