//! Half/difference slices (Rusinkiewicz 1998, "A new change of variables for efficient BRDF
//! representation"): f over `(θ_h, θ_d)` at `φ_d = 90°`, `φ_h = 0`.
//!
//! Column i ↔ `x = (i + 0.5)/W`, `θ_h = x² · π/2` (the square-root spacing MERL uses, which
//! puts half the columns within 22.5° of the normal) or `θ_h = x · π/2` (`--linear`); row j ↔
//! `y = (j + 0.5)/H`, `θ_d = y · π/2`. Channels R, G, B hold f; with terms, a second layer
//! `terms` holds D, G, F.R, F.G, F.B, K.

use super::exr_out::{self, Channel, Layer, Provenance};
use super::{needs_tangents, push_row, texel_centre, Grid, Runner, NORMAL};
use crate::backend::TERM_COLUMNS;
use crate::directions::SliceGrid;
use crate::error::Result;
use crate::material::Material;
use std::f64::consts::FRAC_PI_2;
use std::path::{Path, PathBuf};

/// Default slice size, 90 × 90 (MERL's θ_h and θ_d resolution).
pub const DEFAULT_SIZE: usize = 90;

/// How column x maps to θ_h.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spacing {
    /// `θ_h = x² · π/2` (MERL).
    Sqrt,
    /// `θ_h = x · π/2`.
    Linear,
}

/// θ_h of column coordinate `x` in [0, 1].
pub fn theta_h(x: f64, spacing: Spacing) -> f64 {
    match spacing {
        Spacing::Sqrt => x * x * FRAC_PI_2,
        Spacing::Linear => x * FRAC_PI_2,
    }
}

pub use crate::directions::from_half_diff;

pub use super::TANGENT;

/// f (n × 3, row-major texels) and, when `terms`, the terms (n × 6) of the slice: with
/// the directions made by the backend where it can ([`Runner::half_diff_slice`]; the
/// Vulkan kernel makes them on the device), else by [`compute_from_tuples`].
pub fn compute(
    runner: &mut Runner,
    material: &Material,
    grid: Grid,
    spacing: Spacing,
    terms: bool,
) -> Result<(Vec<f32>, Option<Vec<f32>>)> {
    compute_band(runner, material, grid, spacing, terms, 0..grid.height)
}

/// [`compute`] with the directions made on the host by [`from_half_diff`] and sent to the
/// backend as tuples (every backend can; the reference for the device-made directions).
pub fn compute_from_tuples(
    runner: &mut Runner,
    material: &Material,
    grid: Grid,
    spacing: Spacing,
    terms: bool,
) -> Result<(Vec<f32>, Option<Vec<f32>>)> {
    texels_from_tuples(runner, material, grid, spacing, terms, 0..grid.texels())
}

/// [`compute_from_tuples`] for the row-major texels `texels` only.
fn texels_from_tuples(
    runner: &mut Runner,
    material: &Material,
    grid: Grid,
    spacing: Spacing,
    terms: bool,
    texels: std::ops::Range<usize>,
) -> Result<(Vec<f32>, Option<Vec<f32>>)> {
    let materials = std::slice::from_ref(material);
    let tangent = needs_tangents(materials).then_some(TANGENT);
    let n = texels.len();
    let mut brdf = Vec::with_capacity(n * 3);
    let mut term_values = Vec::with_capacity(if terms { n * TERM_COLUMNS } else { 0 });
    runner.start("slice", n as u64);
    let (mut next, n) = (texels.start, texels.end);
    while next < n {
        let end = n.min(next + runner.chunk_tuples());
        let mut rows = Vec::with_capacity((end - next) * 13);
        for t in next..end {
            let (i, j) = (t % grid.width, t / grid.width);
            let th = theta_h(texel_centre(i, grid.width), spacing);
            let td = texel_centre(j, grid.height) * FRAC_PI_2;
            let (l, v) = from_half_diff(th, td, FRAC_PI_2);
            push_row(&mut rows, l, v, NORMAL, 0, tangent);
        }
        let out = runner.evaluate(rows, materials, terms)?;
        brdf.extend_from_slice(&out.brdf);
        if let Some(t) = out.terms {
            term_values.extend_from_slice(&t);
        }
        runner.advance((end - next) as u64);
        next = end;
    }
    runner.finish();
    Ok((brdf, terms.then_some(term_values)))
}

/// [`compute`] for the θ_d rows `rows` only (a shard's band), each texel computed as the
/// whole slice computes it: where the backend makes the directions itself for the whole
/// grid, it makes the whole slice and the band is cut from it (the device's directions
/// differ from the host's in their last bits, so a band must not switch paths); else the
/// band's tuples alone are built and evaluated.
pub fn compute_band(
    runner: &mut Runner,
    material: &Material,
    grid: Grid,
    spacing: Spacing,
    terms: bool,
    rows: std::ops::Range<usize>,
) -> Result<(Vec<f32>, Option<Vec<f32>>)> {
    if rows.is_empty() {
        return Ok((Vec::new(), terms.then(Vec::new)));
    }
    // Every front end (the CLI, Python, a library caller) gets the memory check before
    // the band's outputs are allocated: an allocation that fails aborts the process.
    let channels: u64 = if terms { 3 + TERM_COLUMNS as u64 } else { 3 };
    let band = super::Grid {
        width: grid.width,
        height: rows.len(),
    };
    super::check_memory(super::table_bytes(band, 4 * channels), "the slice")?;
    let texels = rows.start * grid.width..rows.end * grid.width;
    if let (Ok(width), Ok(height)) = (u32::try_from(grid.width), u32::try_from(grid.height)) {
        let slice = SliceGrid {
            width,
            height,
            linear: spacing == Spacing::Linear,
        };
        runner.start("slice", slice.texels());
        if let Some(out) = runner.half_diff_slice(material, slice, terms) {
            let out = out?;
            runner.advance(slice.texels());
            runner.finish();
            // The band in place: the whole slice is returned without a copy.
            let band = |mut v: Vec<f32>, per: usize| {
                v.truncate(texels.end * per);
                v.drain(..texels.start * per);
                v
            };
            return Ok((band(out.brdf, 3), out.terms.map(|t| band(t, TERM_COLUMNS))));
        }
    }
    texels_from_tuples(runner, material, grid, spacing, terms, texels)
}

/// What `vkbrdf table slice` writes.
#[derive(Debug, Clone)]
pub struct SliceJob {
    /// The material.
    pub material: Material,
    /// Table size (x ↔ θ_h, y ↔ θ_d).
    pub grid: Grid,
    /// θ_h spacing.
    pub spacing: Spacing,
    /// Add the `terms` layer.
    pub terms: bool,
    /// Write float16.
    pub half: bool,
    /// The EXR file.
    pub output: PathBuf,
}

impl SliceJob {
    /// Everything that can be checked before evaluating: the table fits in memory (f32
    /// results, their per-channel copies and the EXR encoder's: 12 bytes per value), the
    /// output can be written.
    pub fn check(&self) -> Result<()> {
        let channels = if self.terms { 3 + TERM_COLUMNS } else { 3 };
        super::check_memory(
            super::table_bytes(self.grid, 12 * channels as u64),
            "the slice",
        )?;
        super::check_exr_output(&self.output)
    }

    /// [`SliceJob::check`] for the band `part` names: memory for its rows (and for the
    /// whole slice's f32 results where the backend may make the whole slice itself,
    /// [`compute_band`]; up to 2²⁴ texels), and that the part can be written.
    pub fn check_part(&self, part: &super::shard::PartSpec) -> Result<()> {
        let channels = (if self.terms { 3 + TERM_COLUMNS } else { 3 }) as u64;
        let band = Grid {
            width: self.grid.width,
            height: part.band().len().max(1),
        };
        let whole = self.grid.width as u128 * self.grid.height as u128;
        let generated = if whole <= 1 << 24 {
            whole * 4 * channels as u128
        } else {
            0
        };
        let bytes = super::table_bytes(band, 12 * channels).map(|b| b + generated);
        super::check_memory(bytes, "the slice's band")?;
        super::shard::check_part_name(&self.output)?;
        super::check_output(&self.output)
    }
}

/// Evaluates and writes the slice, after [`SliceJob::check`].
pub fn write(runner: &mut Runner, job: &SliceJob) -> Result<()> {
    write_with_png(runner, job, None)
}

/// [`write()`], and the slice as a PNG at `png` too when given: pixel `(i, j)` is texel
/// `(i, j)` (θ_h across, θ_d down, row 0 at θ_d = 0), showing `π·f` through
/// [`super::preview::display_srgb8`] (a white Lambertian, f = 1/π, is display white; values
/// above 1 keep their hue). The EXR and the PNG appear together or not at all.
pub fn write_with_png(runner: &mut Runner, job: &SliceJob, png: Option<&Path>) -> Result<()> {
    job.check()?;
    if let Some(p) = png {
        super::check_output(p)?;
    }
    let (brdf, terms) = compute(runner, &job.material, job.grid, job.spacing, job.terms)?;
    let layers = layers(&brdf, terms.as_deref());
    let (provenance, spacing) = provenance(runner, job);
    let (staged, clamped) = exr_out::stage(
        &job.output,
        job.grid,
        layers,
        &provenance,
        job.half,
        runner.cancel(),
    )?;
    runner.warn_clamped(&job.output, &clamped);
    let mut staged = vec![staged];
    if let Some(p) = png {
        let mut canvas = super::preview::Canvas::new(job.grid.width, job.grid.height, [0, 0, 0]);
        for (t, rgb) in brdf.chunks_exact(3).enumerate() {
            let c = super::preview::display_srgb8(std::array::from_fn(|k| {
                f64::from(rgb[k]) * std::f64::consts::PI
            }));
            canvas.put((t % job.grid.width) as i64, (t / job.grid.width) as i64, c);
        }
        let mut text = super::preview::provenance(&job.material, "slice", &provenance.backend);
        text.push((
            "vkbrdf.parameterisation",
            format!(
                "pixel = pi * f (1/sr) in display sRGB (1 = white, brighter pixels scaled to keep their hue); column i: {spacing} at x = (i + 0.5)/W; row j: theta_d = (j + 0.5)/H * pi/2, row 0 at the top; phi_d = pi/2"
            ),
        ));
        staged.push(super::preview::stage_png(
            p,
            &canvas,
            &text,
            runner.cancel(),
        )?);
    }
    crate::atomic::commit(staged)
}

/// Evaluates the band of θ_d rows `part` names and writes it as a table part at
/// `job.output` (a `.npy` band and its sidecar: [`super::shard`]), after
/// [`SliceJob::check`].
pub fn write_part(
    runner: &mut Runner,
    job: &SliceJob,
    part: &super::shard::PartSpec,
) -> Result<()> {
    job.check_part(part)?;
    let (brdf, terms) = compute_band(
        runner,
        &job.material,
        job.grid,
        job.spacing,
        job.terms,
        part.band(),
    )?;
    let layers = layers(&brdf, terms.as_deref());
    let (provenance, _) = provenance(runner, job);
    let staged = super::shard::stage_exr_part(
        &job.output,
        part,
        job.grid.width,
        job.grid,
        &layers,
        &provenance,
        job.half,
        runner.cancel(),
    )?;
    crate::atomic::commit(staged)
}

/// The slice's layers: `brdf` (R, G, B) and, with terms, `terms`.
fn layers(brdf: &[f32], terms: Option<&[f32]>) -> Vec<Layer> {
    let mut layers = vec![interleaved("brdf", brdf, &["R", "G", "B"])];
    if let Some(t) = terms {
        layers.push(interleaved(
            "terms",
            t,
            &["D", "G", "F.R", "F.G", "F.B", "K"],
        ));
    }
    layers
}

/// The slice's provenance, and its θ_h spacing in words.
fn provenance(runner: &Runner, job: &SliceJob) -> (Provenance, &'static str) {
    let spacing = match job.spacing {
        Spacing::Sqrt => "theta_h = x^2 * pi/2 (MERL square-root spacing)",
        Spacing::Linear => "theta_h = x * pi/2 (linear)",
    };
    let provenance = Provenance {
        table: "slice".into(),
        material: job.material.name.clone(),
        convention: super::convention_name(&job.material).into(),
        parameterisation: format!(
            "f (1/sr, no cosine) over half/difference angles (Rusinkiewicz 1998): {spacing}, theta_d = y * pi/2, phi_d = pi/2, phi_h = 0; n = +z, t = +x{}",
            if job.terms { "; layer terms: D, G, F.R, F.G, F.B, K" } else { "" }
        ),
        samples: "1 point sample at each texel centre".into(),
        backend: runner.backend_name(),
    };
    (provenance, spacing)
}

/// A layer from `n × k` interleaved values, one channel per name.
fn interleaved(layer: &str, values: &[f32], names: &[&str]) -> Layer {
    let k = names.len();
    Layer {
        name: layer.into(),
        channels: names
            .iter()
            .enumerate()
            .map(|(c, name)| Channel {
                name: (*name).into(),
                values: values.iter().skip(c).step_by(k).copied().collect(),
            })
            .collect(),
    }
}
