//! The split-sum DFG table (Karis 2013, "Real Shading in Unreal Engine 4"): under Schlick's
//! Fresnel the directional albedo is `E(μ, α) = F0·A + B` with
//!
//! - `A = ∫ (f/F) (1 − (1 − c)⁵) cos_i dω_l` (the scale, channel `R`),
//! - `B = ∫ (f/F) (1 − c)⁵ cos_i dω_l` (the bias, channel `G`),
//!
//! `c = v·h`. `f/F` is f of the same model with F = 1, evaluated by the backend; the
//! `(1 − c)⁵` weights come from `c` computed on the host for each sample direction. The
//! integrator, sample count and accuracy are [`super::albedo`]'s.

use super::albedo::{self, grid_points, Microfacet};
use super::exr_out::{self, Channel, Layer, Provenance};
use super::{Grid, Runner};
use crate::error::Result;
use std::path::PathBuf;

/// `(1 − c)⁵`: Schlick's weight of `1 − F0` (Schlick 1994).
pub fn schlick_weight(c: f64) -> f64 {
    (1.0 - c).clamp(0.0, 1.0).powi(5)
}

/// `[A, B]` at each `(μ, α)` point, with `samples` points each.
pub fn split_sum(
    runner: &mut Runner,
    spec: &Microfacet,
    points: &[(f64, f64)],
    samples: u32,
) -> Result<Vec<[f64; 2]>> {
    if let Some(sums) = albedo::backend_sums(runner, spec, points, samples, "dfg") {
        // A = Σ x (1 − w) = Σ x − Σ x w, B = Σ x w.
        return Ok(sums?.into_iter().map(|[x, xw]| [x - xw, xw]).collect());
    }
    albedo::integrate(runner, spec, points, samples, "dfg", |c| {
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
    /// Write float16.
    pub half: bool,
    /// The DFG table.
    pub output: PathBuf,
}

impl DfgJob {
    /// Everything that can be checked before evaluating: the model is legal, the table
    /// fits in memory, the output can be written.
    pub fn check(&self) -> Result<()> {
        self.spec.material(0.5)?;
        let bytes = super::table_bytes(self.grid, albedo::BYTES_PER_TEXEL + 16);
        super::check_memory(bytes, "the DFG table")?;
        super::check_output(&self.output)
    }
}

/// Integrates and writes the DFG table, after [`DfgJob::check`].
pub fn write(runner: &mut Runner, job: &DfgJob) -> Result<()> {
    job.check()?;
    let ab = split_sum(runner, &job.spec, &grid_points(job.grid), job.samples)?;
    let channel = |name: &str, k: usize| Channel {
        name: name.into(),
        values: ab.iter().map(|v| v[k] as f32).collect(),
    };
    let provenance = Provenance {
        table: "dfg".into(),
        material: job.spec.describe(),
        convention: "modern".into(),
        parameterisation: "split sum (Karis 2013): R = A = integral of f/F (1 - (1-c)^5) cos_i, G = B = integral of f/F (1-c)^5 cos_i, c = v.h, so E = F0 A + B under Schlick; x = mu = cos_o, y = alpha, n = +z".into(),
        samples: format!(
            "{} per texel: Hammersley points, {}; f evaluated by the backend",
            job.samples,
            albedo::sampling(job.spec.lobe)
        ),
        backend: runner.backend_name(),
    };
    let layer = Layer {
        name: "dfg".into(),
        channels: vec![channel("R", 0), channel("G", 1)],
    };
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
