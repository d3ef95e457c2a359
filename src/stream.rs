//! Streaming evaluation: a `.npy` batch read, evaluated and written chunk by chunk, so that
//! host memory stays within a budget whatever the batch's size, and a batch larger than the
//! machine's memory evaluates instead of being killed.
//!
//! Each output is a [`StagedWriter`](crate::atomic::StagedWriter): its `.npy` header (the
//! shape is known from the input's) and then each chunk's rows go to a temporary file beside
//! the target, renamed at the end with the others ([`crate::atomic::commit`]): a failure, a
//! cancellation or `strict` with an invalid tuple leaves the previous files and no temporary
//! one. Results do not depend on the chunk size: every engine evaluates tuple by tuple.

mod fused;
mod job;
mod pin;
mod pipeline;
pub mod shard;

pub use job::{
    chunk_rows, chunk_rows_for, StreamJob, StreamSummary, DEFAULT_MAX_MEMORY, MAX_CHUNK_ROWS,
};
use job::{NpyOut, Setup};

use crate::atomic;
use crate::backend::{Backend, Request};
use crate::batch::rows::NpyRows;
use crate::batch::{local_material, COLUMNS_LOCAL};
use crate::cancel::Cancel;
use crate::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Rows a streamed evaluation on `backend` reads at a time within `max_memory` (each of
/// an engine's stream workers its own slice, [`Backend::stream_workers`]; else the
/// pipeline's chunk, [`chunk_rows`]): the bench times the read stage in pieces of this size.
pub fn read_rows(
    backend: &dyn Backend,
    max_memory: u64,
    row_bytes: usize,
    columns: usize,
) -> usize {
    match backend.stream_workers() {
        Some(w) => fused::slice_rows(max_memory, row_bytes, columns, 3, w.len()),
        None => chunk_rows(max_memory, row_bytes, columns, false),
    }
}

/// Evaluates `job` on `backend`, chunk by chunk; `progress` is told the rows done so far.
pub fn evaluate(
    job: &StreamJob,
    backend: &mut dyn Backend,
    cancel: &Cancel,
    progress: impl FnMut(u64, u64),
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
    let setup = Setup {
        local,
        part: part.clone(),
        chunk,
        out_columns,
        request,
    };
    let fused = match backend.stream_workers() {
        Some(workers) if fused::applies(job) => {
            fused::Outputs::start(job, n, cancel)?.map(|outputs| (workers, outputs))
        }
        _ => None,
    };
    let (summary, staged) = match fused {
        Some((workers, outputs)) => {
            fused::evaluate(job, &setup, &rows, workers, outputs, cancel, progress)?
        }
        None => pipeline::evaluate(job, &setup, rows, backend, cancel, progress)?,
    };
    let Some(mut staged) = staged else {
        return Ok(summary); // strict with an invalid tuple: nothing is written
    };
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
    Ok(StreamSummary {
        written: true,
        ..summary
    })
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
