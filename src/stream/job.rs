//! What a streamed evaluation is asked and reports ([`StreamJob`], [`StreamSummary`]),
//! how its chunks are sized within the memory budget, and the in-order `.npy` writer the
//! pipeline and the bench's write stage use: the parts `stream`'s two paths share.

use crate::atomic::{self, StagedWriter};
use crate::backend::{Counts, Request, TERM_COLUMNS};
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
    /// [`local_material`](crate::batch::local_material)); must be `None` for rows, which carry their own.
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
    pub shard: Option<super::shard::Shard>,
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
    /// Chunks evaluated (slices, where an engine's workers took them).
    pub chunks: usize,
    /// Seconds spent reading, evaluating and writing: each stage's thread's, or summed
    /// over the workers where an engine's workers run the stages side by side (so they
    /// may add up to more than the wall time).
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

/// What both paths (`pipeline`, `fused`) are given: the local form's material, the rows to
/// evaluate, rows per chunk, the output's columns and the request.
pub(super) struct Setup {
    pub(super) local: Option<usize>,
    pub(super) part: std::ops::Range<u64>,
    pub(super) chunk: usize,
    pub(super) out_columns: usize,
    pub(super) request: Request,
}

/// A float32 `.npy` of known shape written row block by row block.
pub(super) struct NpyOut {
    writer: StagedWriter,
    path: PathBuf,
    expected: u64,
    written: u64,
    bytes: Vec<u8>,
}

impl NpyOut {
    pub(super) fn start(path: &Path, rows: u64, columns: usize, cancel: &Cancel) -> Result<NpyOut> {
        let mut writer = atomic::stage_writer(path, cancel)?;
        let header = crate::batch::npy_header_f32(rows, columns);
        writer.preallocate(header.len() as u64 + rows * columns as u64 * 4)?;
        writer.write_all(&header).map_err(|e| writer.error(e))?;
        Ok(NpyOut {
            writer,
            path: path.to_owned(),
            expected: rows * columns as u64,
            written: 0,
            bytes: Vec::new(),
        })
    }

    pub(super) fn rows(&mut self, values: &[f32]) -> Result<()> {
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

    pub(super) fn finish(self) -> Result<atomic::Staged> {
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
