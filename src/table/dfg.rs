//! The split-sum DFG table (Karis 2013, "Real Shading in Unreal Engine 4"): under Schlick's
//! Fresnel the directional albedo is `E(μ, α) = F0·A + B` with
//!
//! - `A = ∫ (f/F) (1 − (1 − c)⁵) cos_i dω_l` (the scale, channel `R`),
//! - `B = ∫ (f/F) (1 − c)⁵ cos_i dω_l` (the bias, channel `G`),
//!
//! `c = v·h`. `f/F` is f of the same model with F = 1, evaluated by the backend; the
//! `(1 − c)⁵` weights come from `c` computed on the host for each sample direction. The
//! integrator, sample count and accuracy are [`super::albedo`]'s.
//!
//! Engines index their LUTs their own way ([`Axes`], [`Layout`], [`LutStyle`]): by
//! perceptual roughness `r` with `α = r²`, over texel centres or both endpoints, with R = A,
//! G = B (UE4) or R = B, G = A + B (Filament).

use super::albedo::{self, Microfacet, Sampler};
use super::exr_out::{self, Channel, Layer, Provenance};
use super::{Grid, Runner};
use crate::error::{Error, Result};
use crate::material::Geometry;
use std::path::PathBuf;

pub use super::axes::{Axes, RoughnessAxis, Sampling, ENDPOINT_FLOOR};

/// Which integral goes in which channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// R = A (scale), G = B (bias): `E = F0·R + G` (Karis 2013, UE4).
    ScaleBias,
    /// R = B, G = A + B: `E = (1 − F0)·R + F0·G = mix(R, G, F0)` (Filament's
    /// multiple-scattering layout, `DFV_Multiscatter`).
    Filament,
}

/// An engine's published LUT choices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LutStyle {
    /// UE4 (Karis 2013, "Real Shading in Unreal Engine 4", `IntegrateBRDF`): x = NoV,
    /// y = Roughness (α = r²) at texel centres, Schlick–Smith G with k = α/2, R = A,
    /// G = B, 1024 samples.
    Ue4,
    /// Filament (`CubemapIBL::DFG` with `--ibl-dfg-multiscatter`, as its CMakeLists
    /// builds the engine's LUT): x = NoV at centres, rows per [`Sampling::Filament`]
    /// (α = r²), height-correlated Smith–GGX, R = B, G = A + B, 1024 samples, 128×128.
    Filament,
}

impl LutStyle {
    /// `ue4` or `filament`.
    pub fn name(self) -> &'static str {
        match self {
            LutStyle::Ue4 => "ue4",
            LutStyle::Filament => "filament",
        }
    }

    /// The engine's samples per texel (both: 1024).
    pub fn samples(self) -> u32 {
        1024
    }

    /// The engine's geometry term.
    pub fn geometry(self) -> Geometry {
        match self {
            LutStyle::Ue4 => Geometry::SchlickSmith,
            LutStyle::Filament => Geometry::SmithCorrelated,
        }
    }

    /// The engine's axes.
    pub fn axes(self) -> Axes {
        Axes {
            roughness: RoughnessAxis::Perceptual,
            sampling: match self {
                LutStyle::Ue4 => Sampling::Centres,
                LutStyle::Filament => Sampling::Filament,
            },
        }
    }

    /// The engine's channel layout.
    pub fn layout(self) -> Layout {
        match self {
            LutStyle::Ue4 => Layout::ScaleBias,
            LutStyle::Filament => Layout::Filament,
        }
    }

    /// The table size the engine ships, where it publishes one (Filament: 128×128 on
    /// desktop, `DFG_LUT_SIZE`); UE4's course notes name none.
    pub fn size(self) -> Option<Grid> {
        match self {
            LutStyle::Ue4 => None,
            LutStyle::Filament => Some(Grid {
                width: 128,
                height: 128,
            }),
        }
    }
}

pub use crate::importance::schlick_weight;

/// `[A, B]` at each `(μ, α)` point, with `samples` points each.
pub fn split_sum(
    runner: &mut Runner,
    spec: &Microfacet,
    points: &[(f64, f64)],
    samples: u32,
) -> Result<Vec<[f64; 2]>> {
    split_sum_with(runner, spec, Sampler::Visible, points, samples)
}

/// [`split_sum`] drawing the normals with `sampler` ([`Sampler::Engine`]: host-made
/// directions, evaluated by the backend).
pub fn split_sum_with(
    runner: &mut Runner,
    spec: &Microfacet,
    sampler: Sampler,
    points: &[(f64, f64)],
    samples: u32,
) -> Result<Vec<[f64; 2]>> {
    split_sum_of(runner, spec, sampler, points, points.len(), samples)
}

/// [`split_sum_with`] of `points`, a band of a table of `whole` points, each computed as
/// the whole table computes it ([`albedo::device_takes`]).
pub fn split_sum_of(
    runner: &mut Runner,
    spec: &Microfacet,
    sampler: Sampler,
    points: &[(f64, f64)],
    whole: usize,
    samples: u32,
) -> Result<Vec<[f64; 2]>> {
    if sampler == Sampler::Visible && albedo::device_takes(whole, samples) {
        if let Some(sums) = albedo::backend_sums(runner, spec, points, samples, "dfg") {
            // A = Σ x (1 − w) = Σ x − Σ x w, B = Σ x w.
            return Ok(sums?.into_iter().map(|[x, xw]| [x - xw, xw]).collect());
        }
    }
    albedo::integrate_with(runner, spec, sampler, points, samples, "dfg", |c| {
        let w = schlick_weight(c);
        [1.0 - w, w]
    })
}

/// What `vkbrdf table dfg` writes.
#[derive(Debug, Clone)]
pub struct DfgJob {
    /// The model (default GGX + smith-correlated).
    pub spec: Microfacet,
    /// Table size (x = μ, y = α).
    pub grid: Grid,
    /// Samples per texel.
    pub samples: u32,
    /// The axes (default [`Axes::DEFAULT`]).
    pub axes: Axes,
    /// The channel layout (default [`Layout::ScaleBias`]).
    pub layout: Layout,
    /// The integrator (default [`Sampler::Visible`]; [`LutStyle`] tables use
    /// [`Sampler::Engine`]).
    pub sampler: Sampler,
    /// The engine style the table follows, for provenance.
    pub style: Option<LutStyle>,
    /// Write float16.
    pub half: bool,
    /// The DFG table.
    pub output: PathBuf,
}

impl DfgJob {
    /// Everything that can be checked before evaluating: the model is legal, the table
    /// fits in memory, the output can be written.
    pub fn check(&self) -> Result<()> {
        self.check_model()?;
        let bytes = super::table_bytes(self.grid, albedo::BYTES_PER_TEXEL + 16);
        super::check_memory(bytes, "the DFG table")?;
        super::check_exr_output(&self.output)
    }

    /// [`DfgJob::check`] for the band `part` names: memory for its rows only, and a .npy
    /// part name.
    pub fn check_part(&self, part: &super::shard::PartSpec) -> Result<()> {
        self.check_model()?;
        let band = Grid {
            width: self.grid.width,
            height: part.band().len().max(1),
        };
        super::check_memory(
            super::table_bytes(band, albedo::BYTES_PER_TEXEL + 16),
            "the DFG table's band",
        )?;
        super::shard::check_part_name(&self.output)?;
        super::check_output(&self.output)
    }

    /// The model is legal, the sampler can draw it, the axes can place the grid.
    fn check_model(&self) -> Result<()> {
        self.spec.material(0.5)?;
        self.axes.check(self.grid)?;
        if self.sampler == Sampler::Engine && self.spec.lobe != albedo::Lobe::Ggx {
            return Err(Error::Table(format!(
                "--distribution {}: the engines' LUT integrator samples GGX only",
                self.spec.lobe.name()
            )));
        }
        Ok(())
    }
}

/// Integrates and writes the DFG table, after [`DfgJob::check`].
pub fn write(runner: &mut Runner, job: &DfgJob) -> Result<()> {
    write_band(runner, job, None)
}

/// Integrates the band of roughness rows `part` names and writes it as a table part at
/// `job.output` (a `.npy` band and its sidecar: [`super::shard`]), after [`DfgJob::check`].
pub fn write_part(runner: &mut Runner, job: &DfgJob, part: &super::shard::PartSpec) -> Result<()> {
    write_band(runner, job, Some(part))
}

fn write_band(
    runner: &mut Runner,
    job: &DfgJob,
    part: Option<&super::shard::PartSpec>,
) -> Result<()> {
    match part {
        Some(part) => job.check_part(part)?,
        None => job.check()?,
    }
    let band = part.map_or(0..job.grid.height, |p| p.band());
    let points = &job.axes.points_of_rows(job.grid, band);
    let ab = split_sum_of(
        runner,
        &job.spec,
        job.sampler,
        points,
        job.grid.texels(),
        job.samples,
    )?;
    let channel = |name: &str, value: fn(&[f64; 2]) -> f64| Channel {
        name: name.into(),
        values: ab.iter().map(|v| value(v) as f32).collect(),
    };
    let (channels, layout) = match job.layout {
        Layout::ScaleBias => (
            [channel("R", |v| v[0]), channel("G", |v| v[1])],
            "R = A = integral of f/F (1 - (1-c)^5) cos_i, G = B = integral of f/F (1-c)^5 cos_i, c = v.h, so E = F0 A + B under Schlick",
        ),
        Layout::Filament => (
            [channel("R", |v| v[1]), channel("G", |v| v[0] + v[1])],
            "R = B = integral of f/F (1-c)^5 cos_i, G = A + B = integral of f/F cos_i, c = v.h, so E = (1 - F0) R + F0 G = mix(R, G, F0) under Schlick (Filament's layout)",
        ),
    };
    let style = job
        .style
        .map_or(String::new(), |s| format!("--lut-style {}: ", s.name()));
    let provenance = Provenance {
        table: "dfg".into(),
        material: job.spec.describe(),
        convention: "modern".into(),
        parameterisation: format!(
            "{style}split sum (Karis 2013): {layout}; {}, n = +z",
            job.axes.describe()
        ),
        samples: match job.sampler {
            Sampler::Visible => format!(
                "{} per texel: Hammersley points, {}; f evaluated by the backend",
                job.samples,
                albedo::sampling(job.spec.lobe)
            ),
            Sampler::Engine => format!(
                "{} per texel: the engines' estimator, Hammersley (k/N, radical inverse), GGX D cos_h; f evaluated by the backend",
                job.samples
            ),
        },
        backend: runner.backend_name(),
    };
    let layer = Layer {
        name: "dfg".into(),
        channels: channels.into(),
    };
    if let Some(part) = part {
        let staged = super::shard::stage_exr_part(
            &job.output,
            part,
            job.grid.width,
            job.grid,
            &[layer],
            &provenance,
            job.half,
            runner.cancel(),
        )?;
        return crate::atomic::commit(staged);
    }
    let clamped = exr_out::write(
        &job.output,
        job.grid,
        vec![layer],
        &provenance,
        job.half,
        runner.cancel(),
    )?;
    runner.warn_clamped(&job.output, &clamped);
    Ok(())
}
