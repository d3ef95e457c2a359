//! Tables of f: half/difference slices, directional albedo, split-sum DFG, MERL binaries and
//! PNG previews (`vkbrdf table <kind>`).
//!
//! Every table evaluates f through a [`Backend`] — the Vulkan kernel or the CPU reference —
//! so a table is exactly what the chosen evaluator computes. The host builds the tuples in
//! chunks of at most [`DEFAULT_CHUNK_TUPLES`] (bounded memory whatever the table size),
//! the backend evaluates them, and the host reduces the results; a [`Runner`] owns that loop
//! and its progress bar.
//!
//! Conventions shared by every 2-D table (written into each EXR header too):
//! - texel centres: column `i` ↔ `x = (i + 0.5)/W`, row `j` ↔ `y = (j + 0.5)/H`
//!   ([`texel_centre`]); row 0 is the first (top) row of the image;
//! - frame: `n = +z`, tangent `t = +x` (anisotropic materials), directions in the `xz` plane
//!   where a table has no azimuth of its own.
//!
//! Every output file is written atomically ([`crate::atomic::write`]): a failed run leaves
//! no partial file and never clobbers an existing one.

pub mod albedo;
pub mod axes;
pub mod canvas;
pub mod dfg;
pub mod exr_out;
pub mod font;
pub mod grid;
pub mod merl;
pub mod merl_file;
pub mod preview;
pub mod shard;
pub mod slice;
pub mod spectral;

pub use grid::{texel_centre, Grid, TEXEL_CENTRES, VERSION};

use crate::backend::{Backend, Output, Request};
use crate::batch::{Batch, COLUMNS_PLAIN, COLUMNS_TANGENT};
use crate::cancel::Cancel;
use crate::error::{Error, Result};
use crate::material::{Convention, Material};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::Path;

/// Tuples per backend call, 2¹⁹: at most 27 MB of rows in and 19 MB out (13 columns,
/// terms included). Large enough to amortise a backend call; small enough that the host's
/// buffers stay below glibc's 32 MiB `mmap` threshold and are reused from chunk to chunk
/// (measured: 2²¹ doubled the host's share of an albedo table's time).
pub const DEFAULT_CHUNK_TUPLES: usize = 1 << 19;

/// Memory the machine can still give (`MemAvailable` of `/proc/meminfo`), when known.
pub fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// Refuses, before anything is allocated, a job whose buffers need more memory than the
/// machine has available. `bytes` is `None` when the size computation itself overflowed.
pub fn check_memory(bytes: Option<u128>, what: &str) -> Result<()> {
    let gib = |b: u128| b as f64 / (1u64 << 30) as f64;
    match (bytes, available_memory()) {
        (None, _) => Err(Error::Memory(format!(
            "{what} would need more memory than can be addressed; use a smaller size"
        ))),
        (Some(b), Some(avail)) if b > avail as u128 => Err(Error::Memory(format!(
            "{what} would need {:.1} GiB of memory, more than the {:.1} GiB available; use a smaller size",
            gib(b),
            gib(avail as u128)
        ))),
        _ => Ok(()),
    }
}

/// Bytes a job over `grid` needs: `per_texel` bytes for each texel (the generator's
/// per-texel state, its f32 results and the EXR encoder's copy; each kind states its
/// own), plus one chunk of tuples in and out with their weights.
pub fn table_bytes(grid: Grid, per_texel: u64) -> Option<u128> {
    let texels = (grid.width as u128).checked_mul(grid.height as u128)?;
    let chunk = DEFAULT_CHUNK_TUPLES as u128 * ((COLUMNS_TANGENT + 3 + 6) * 4 + 16) as u128;
    texels.checked_mul(per_texel as u128)?.checked_add(chunk)
}

/// Fails early, before any evaluation, when `path` cannot be written
/// ([`crate::atomic::check_outputs`]: a directory, a missing or read-only directory).
pub fn check_output(path: &Path) -> Result<()> {
    crate::atomic::check_outputs(&[path], &[])
}

/// [`check_output`] for a whole table, which is written as OpenEXR: a name whose extension
/// says another format (`x.png`, `x.npy`, …) is refused rather than given EXR bytes under
/// it. Names without an extension, and `.exr`, are fine.
pub fn check_exr_output(path: &Path) -> Result<()> {
    const OTHER: &[&str] = &[
        "png", "jpg", "jpeg", "npy", "npz", "hdr", "tif", "tiff", "bmp", "txt", "json", "csv",
        "binary", "toml",
    ];
    if let Some(ext) = path.extension().and_then(|e| e.to_str()) {
        if OTHER.contains(&ext.to_ascii_lowercase().as_str()) {
            return Err(Error::Output {
                path: path.to_owned(),
                message: format!(
                    "the table is written as OpenEXR, not as .{ext}: name it .exr (`table slice` and `table preview` write pictures with --png; a sharded run's parts are .npy with --shard)"
                ),
            });
        }
    }
    check_output(path)
}

/// The material called `name`: from `materials_file` when given, else from the presets.
pub fn load_material(materials_file: Option<&Path>, name: &str) -> Result<Material> {
    let (list, source) = match materials_file {
        Some(path) => (
            crate::material::load_materials(path)?,
            path.display().to_string(),
        ),
        None => (crate::material::presets::all(), "the presets".to_string()),
    };
    find_material(&list, name, &source)
}

/// The material called `name` in `list`, or an error listing the names `source` defines.
pub fn find_material(list: &[Material], name: &str, source: &str) -> Result<Material> {
    list.iter()
        .find(|m| m.name == name)
        .cloned()
        .ok_or_else(|| {
            let names: Vec<&str> = list.iter().map(|m| m.name.as_str()).collect();
            Error::Table(format!(
                "material `{name}` is not defined in {source}; it defines: {}",
                names.join(", ")
            ))
        })
}

/// The convention a material's provenance records (`-` for non-microfacet models).
pub fn convention_name(m: &Material) -> &'static str {
    match m.cook_torrance().map(|ct| ct.convention) {
        Some(Convention::Seed) => "seed",
        Some(Convention::CookTorrance1982) => "cook-torrance-1982",
        Some(Convention::Modern) => "modern",
        None => "- (not a microfacet model)",
    }
}

/// The normal of every table's frame, `+z`.
pub const NORMAL: [f64; 3] = [0.0, 0.0, 1.0];

/// The tangent every table passes for anisotropic materials.
pub const TANGENT: [f64; 3] = [1.0, 0.0, 0.0];

/// Appends one tuple row `l v n material [t]` (f64 rounded to the f32 the backend reads).
pub fn push_row(
    rows: &mut Vec<f32>,
    l: [f64; 3],
    v: [f64; 3],
    n: [f64; 3],
    material: usize,
    t: Option<[f64; 3]>,
) {
    let f = |a: [f64; 3]| a.map(|x| x as f32);
    let ([l0, l1, l2], [v0, v1, v2], [n0, n1, n2]) = (f(l), f(v), f(n));
    rows.extend_from_slice(&[l0, l1, l2, v0, v1, v2, n0, n1, n2, material as f32]);
    if let Some(t) = t {
        rows.extend_from_slice(&f(t));
    }
}

pub use crate::importance::as_f32;

/// Runs a table's tuples through a backend in chunks, advancing a progress bar.
pub struct Runner<'a> {
    backend: &'a mut dyn Backend,
    progress: ProgressBar,
    chunk_tuples: usize,
    cancel: Cancel,
    warnings: Vec<String>,
}

impl<'a> Runner<'a> {
    /// A runner on `backend` without a progress bar and with [`DEFAULT_CHUNK_TUPLES`].
    pub fn new(backend: &'a mut dyn Backend) -> Runner<'a> {
        Runner {
            backend,
            progress: ProgressBar::hidden(),
            chunk_tuples: DEFAULT_CHUNK_TUPLES,
            cancel: Cancel::new(),
            warnings: Vec::new(),
        }
    }

    /// Stops the job (evaluation and the writing of its files) once `cancel` is set; the
    /// backend gets the token too.
    pub fn with_cancel(mut self, cancel: Cancel) -> Runner<'a> {
        self.backend.set_cancel(cancel.clone());
        self.cancel = cancel;
        self
    }

    /// The job's cancellation token.
    pub fn cancel(&self) -> &Cancel {
        &self.cancel
    }

    /// Shows a progress bar on stderr (drawn only when stderr is a terminal).
    pub fn with_progress(mut self, show: bool) -> Runner<'a> {
        if show {
            self.progress = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
            self.progress.set_style(
                ProgressStyle::with_template(
                    "{msg:>12} [{bar:40}] {human_pos}/{human_len} tuples, {elapsed} (eta {eta})",
                )
                .expect("static template")
                .progress_chars("=> "),
            );
        }
        self
    }

    /// Tuples per backend call (at least 1).
    pub fn with_chunk_tuples(mut self, tuples: usize) -> Runner<'a> {
        self.chunk_tuples = tuples.max(1);
        self
    }

    /// Tuples per backend call.
    pub fn chunk_tuples(&self) -> usize {
        self.chunk_tuples
    }

    /// The backend's name, for provenance and messages.
    pub fn backend_name(&self) -> String {
        self.backend.name()
    }

    /// Starts a job of `tuples` tuples labelled `what` on the progress bar.
    pub fn start(&self, what: &str, tuples: u64) {
        self.progress.set_message(what.to_string());
        self.progress.set_length(tuples);
        self.progress.set_position(0);
    }

    /// Ends the current job's progress bar.
    pub fn finish(&self) {
        self.progress.finish_and_clear();
    }

    /// Records a warning about the table being made (something written that is not
    /// exactly what was asked for), for the caller to show: [`Runner::take_warnings`].
    pub fn warn(&mut self, message: String) {
        self.warnings.push(message);
    }

    /// Records a warning for each layer of `path` that [`exr_out::write`] clamped to
    /// float16's largest finite value.
    pub fn warn_clamped(&mut self, path: &Path, clamped: &[exr_out::Clamped]) {
        for c in clamped {
            self.warn(format!(
                "{}: {} texel(s) of layer `{}` exceed float16's largest finite value and were written as {} (use float32, without --half, for the exact values)",
                path.display(),
                c.texels,
                c.layer,
                exr_out::HALF_MAX
            ));
        }
    }

    /// The warnings recorded so far, leaving none.
    pub fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }

    /// Advances the progress bar by `tuples` (generated, whether evaluated or skipped).
    pub fn advance(&self, tuples: u64) {
        self.progress.inc(tuples);
    }

    /// The half/difference slice made by the backend itself ([`GeneratedDirections::half_diff_slice`](crate::backend::GeneratedDirections::half_diff_slice)),
    /// or `None` when the backend has no such path. Checked like [`Runner::evaluate`].
    pub fn half_diff_slice(
        &mut self,
        material: &Material,
        grid: crate::directions::SliceGrid,
        terms: bool,
    ) -> Option<Result<Output>> {
        let out = self.backend.generated_directions()?.half_diff_slice(
            material,
            grid,
            &Request { terms },
        )?;
        Some(out.and_then(|out| {
            if out.counts.invalid > 0 {
                return Err(Error::Table(format!(
                    "{}: {} of {} generated texels came back invalid; this is a bug",
                    self.backend.name(),
                    out.counts.invalid,
                    out.counts.tuples
                )));
            }
            Ok(out)
        }))
    }

    /// The backend's own importance-sampled sums ([`GeneratedDirections::importance_sums`](crate::backend::GeneratedDirections::importance_sums)), shown on
    /// the progress bar as `what`, or `None` when the backend has no such path.
    pub fn importance_sums(
        &mut self,
        what: &str,
        job: &crate::directions::ImportanceJob,
    ) -> Option<Result<Vec<[f64; 2]>>> {
        let total = job.points.len() as u64 * u64::from(job.samples);
        self.start(what, total);
        let bar = &self.progress;
        let sums = self
            .backend
            .generated_directions()?
            .importance_sums(job, &mut |n| bar.inc(n))?;
        let sums = sums.and_then(|s| self.cancel.check().map(|()| s));
        bar.set_position(total); // the last block of each point may be partial
        self.finish();
        Some(sums)
    }

    /// Evaluates rows built by [`push_row`] (13 columns when [`needs_tangents`]`(materials)`,
    /// else 10) with `materials`, and checks that the backend found no invalid tuple: the
    /// generators only build valid ones, so an invalid count is a bug worth stopping for.
    pub fn evaluate(
        &mut self,
        rows: Vec<f32>,
        materials: &[Material],
        terms: bool,
    ) -> Result<Output> {
        self.cancel.check()?;
        let columns = if needs_tangents(materials) {
            COLUMNS_TANGENT
        } else {
            COLUMNS_PLAIN
        };
        let batch = Batch::new(
            rows,
            columns,
            materials.len(),
            &crate::batch::memory_source(),
        )?;
        let out = self
            .backend
            .evaluate(&batch, materials, &Request { terms })?;
        if out.counts.invalid > 0 {
            return Err(Error::Table(format!(
                "{}: {} of {} generated tuples came back invalid (first row {:?}); this is a bug",
                self.backend.name(),
                out.counts.invalid,
                out.counts.tuples,
                out.counts.first_invalid
            )));
        }
        Ok(out)
    }
}

/// Whether rows for `materials` carry a tangent (`t = +x`): when any is anisotropic.
pub fn needs_tangents(materials: &[Material]) -> bool {
    materials.iter().any(Material::is_anisotropic)
}
