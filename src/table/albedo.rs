//! Directional albedo `E(μ, α) = ∫ f(l, v) cos_i dω_l` of modern Cook–Torrance with F = 1
//! (FORMULAS.md §7), its cosine-weighted average `E_avg(α) = 2∫₀¹ E(μ) μ dμ` (Kulla & Conty
//! 2017, "Revisiting physically based shading at Imageworks"), and the importance-sampled
//! quasi-Monte Carlo integrator that [`super::dfg`] shares.
//!
//! The integrator: for each `(μ, α)`, `v = (√(1−μ²), 0, μ)`, `n = +z`; `N` Hammersley points
//! map to microfacet normals `h` — GGX through its distribution of visible normals (Heitz
//! 2018), Beckmann through `D cos_h` — and `l` is `v` reflected about `h`. The backend
//! evaluates `f(l, v)`; the host adds `f cos_i / pdf(l)` (times a per-sample weight of
//! `c = v·h`). Samples with `l` below the horizon contribute 0. The pdf is computed from
//! the f32 directions the backend sees, so the ratio is consistent. `E_avg` integrates
//! `E(μ)` over μ with [`AVERAGE_NODES`]-point Gauss–Legendre (measured: converged to
//! 1e-7; within 2e-6 of the independent integration).
//! [`DEFAULT_SAMPLES`] states the count and the accuracy measured for it.

use super::exr_out::{self, Channel, Layer, Provenance};
use super::{push_row, texel_centre, Grid, Runner, NORMAL};
use crate::batch::COLUMNS_PLAIN;
use crate::directions::{ImportanceJob, ImportancePoint};
use crate::error::{Error, Result};
pub use crate::importance::{hammersley, Lobe, Sample, Sampler, UnitSample, View};
use crate::material::{Geometry, Material};
use std::f64::consts::PI;
use std::path::PathBuf;

/// Samples per texel by default: 2¹⁶ Hammersley points.
///
/// Measured against an independent dense quadrature of the f64 reference (the ignored test
/// `accuracy_scan` in tests/tables.rs) on the CPU reference, largest |error| of E, A and B:
///
/// | model | 2¹⁴ points | 2¹⁶ points |
/// |---|---|---|
/// | GGX, smith-correlated, every texel of 32×32 | 9.4e-5 | 2.3e-5 |
/// | Beckmann, smith-correlated or smith, 32×32 | 6.3e-5 | 1.4e-5 |
/// | GGX, α = 1/1024 … 7/1024, μ = (i + ½)/32 | 1.0e-4 | 2.6e-5 |
/// | Beckmann, α = 1/1024 … 7/1024 | 1.9e-5 | 3.5e-6 |
///
/// So 2¹⁶ meets the 1e-4 target with a 4× margin for every α ≥ 1/1024 and μ ≥ 1/64. The
/// error comes from samples whose `l` crosses the horizon (a discontinuity the
/// low-discrepancy points resolve to about 1/N), not from the weights, which stay bounded
/// as α shrinks (GGX: `G/G1(v) ≤ 1`; Beckmann: `G (v·h)/(cos_o cos_h)` → G): small α needs
/// no more samples than large.
pub const DEFAULT_SAMPLES: u32 = 1 << 16;

/// Host bytes per texel of an integrated table: the point and its sampling constants
/// ([`View`], 152 bytes), its material index and f64 sums, the f32 result and its EXR copy.
pub const BYTES_PER_TEXEL: u64 = 256;

/// Gauss–Legendre nodes in μ for [`average_albedo`].
pub const AVERAGE_NODES: usize = 32;

/// The name of a geometry term as a materials file spells it.
pub fn geometry_name(g: Geometry) -> &'static str {
    g.toml_name()
}

/// The model an integrated table integrates: modern Cook–Torrance, F = 1, white, no diffuse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Microfacet {
    /// The distribution D.
    pub lobe: Lobe,
    /// The geometric attenuation G.
    pub geometry: Geometry,
}

impl Microfacet {
    /// The material of roughness `alpha`, built as materials-file TOML and validated by
    /// the same parser (so `smith-fast` with GGX is refused with the parser's message).
    pub fn material(&self, alpha: f64) -> Result<Material> {
        let toml = format!(
            "[[material]]\nname = \"{}\"\nmodel = \"cook-torrance\"\nconvention = \"modern\"\n\
             distribution = \"{}\"\nroughness = {alpha:?}\ngeometry = \"{}\"\nfresnel = \"none\"\n",
            self.describe(),
            self.lobe.name(),
            geometry_name(self.geometry),
        );
        let mut list = crate::material::parse_materials(&toml, "table").map_err(|e| {
            Error::Table(format!(
                "--distribution {} --geometry {}: {}",
                self.lobe.name(),
                geometry_name(self.geometry),
                e.message
            ))
        })?;
        Ok(list.remove(0))
    }

    /// `cook-torrance ggx smith-correlated F=1` (provenance and material names).
    pub fn describe(&self) -> String {
        format!(
            "cook-torrance {} {} F=1",
            self.lobe.name(),
            geometry_name(self.geometry)
        )
    }
}

/// `(1/N) Σ f cos_i/pdf · weight(c)` for each `(μ, α)` point: the integrals
/// `∫ f(l, v) cos_i · weight(v·h) dω_l` with `samples` points each, evaluated on the runner.
///
/// Every sample keeps its row (a below-horizon one is sent with weight 0: the backend
/// returns 0 for it at little cost), so the host fills each chunk's rows in parallel,
/// in place, on every core; the sums are f64 and independent of the thread count.
pub fn integrate<const K: usize>(
    runner: &mut Runner,
    spec: &Microfacet,
    points: &[(f64, f64)],
    samples: u32,
    what: &str,
    weight: impl Fn(f64) -> [f64; K] + Sync,
) -> Result<Vec<[f64; K]>> {
    integrate_with(
        runner,
        spec,
        Sampler::Visible,
        points,
        samples,
        what,
        weight,
    )
}

/// [`integrate`] drawing the normals with `sampler` (host-made directions on every
/// backend).
pub fn integrate_with<const K: usize>(
    runner: &mut Runner,
    spec: &Microfacet,
    sampler: Sampler,
    points: &[(f64, f64)],
    samples: u32,
    what: &str,
    weight: impl Fn(f64) -> [f64; K] + Sync,
) -> Result<Vec<[f64; K]>> {
    if samples == 0 {
        return Err(Error::Table("--samples must be at least 1".into()));
    }
    if sampler == Sampler::Engine && spec.lobe != Lobe::Ggx {
        return Err(Error::Table(format!(
            "--distribution {}: the engines' LUT integrator samples GGX only; use \
             --distribution ggx (or no --lut-style)",
            spec.lobe.name()
        )));
    }
    let (materials, index) = materials_for(spec, points)?;
    let plan = Plan {
        views: points
            .iter()
            .map(|&(mu, alpha)| View::sampled(spec.lobe, sampler, mu, alpha))
            .collect(),
        index: &index,
        units: (0..samples).map(|k| UnitSample::new(k, samples)).collect(),
    };
    let total = points.len() as u64 * u64::from(samples);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    runner.start(what, total);
    let mut sums = vec![[0.0f64; K]; points.len()];
    let mut next = 0u64;
    while next < total {
        let n = (total - next).min(runner.chunk_tuples() as u64) as usize;
        let mut rows = vec![0f32; n * COLUMNS_PLAIN];
        let mut weights = vec![[0.0f64; K]; n];
        let per_thread = n.div_ceil(threads);
        std::thread::scope(|s| {
            for (t, (r, w)) in rows
                .chunks_mut(per_thread * COLUMNS_PLAIN)
                .zip(weights.chunks_mut(per_thread))
                .enumerate()
            {
                let (plan, weight) = (&plan, &weight);
                let first = next + (t * per_thread) as u64;
                s.spawn(move || plan.generate(first, r, w, weight));
            }
        });
        let out = runner.evaluate(rows, &materials, false)?;
        for (r, w) in weights.iter().enumerate() {
            let p = ((next + r as u64) / u64::from(samples)) as usize;
            let f = f64::from(out.brdf[3 * r]);
            for (sum, wk) in sums[p].iter_mut().zip(w) {
                *sum += f * wk;
            }
        }
        runner.advance(n as u64);
        next += n as u64;
    }
    runner.finish();
    Ok(sums
        .into_iter()
        .map(|s| s.map(|x| x / f64::from(samples)))
        .collect())
}

/// What [`integrate`] generates: each point's sampling constants and material, and the
/// unit samples every point shares.
struct Plan<'a> {
    views: Vec<View>,
    index: &'a [usize],
    units: Vec<UnitSample>,
}

impl Plan<'_> {
    /// Fills `rows` (10 columns each) and `weights` (`cos_i/pdf · weight(c)`, 0 below the
    /// horizon) for the flattened (point, sample) indices from `first` on.
    fn generate<const K: usize>(
        &self,
        first: u64,
        rows: &mut [f32],
        weights: &mut [[f64; K]],
        weight: &(impl Fn(f64) -> [f64; K] + Sync),
    ) {
        let per_point = self.units.len() as u64;
        let mut row = Vec::with_capacity(COLUMNS_PLAIN);
        for (r, w) in weights.iter_mut().enumerate() {
            let g = first + r as u64;
            let (p, k) = ((g / per_point) as usize, (g % per_point) as usize);
            let view = &self.views[p];
            // Below the horizon: any valid direction there (f = 0), weight 0.
            let l = match view.sample(&self.units[k]) {
                Some(s) => {
                    *w = weight(s.c).map(|x| x * s.weight);
                    s.l
                }
                None => [0.0, 0.0, -1.0],
            };
            row.clear();
            push_row(&mut row, l, view.v, NORMAL, self.index[p], None);
            rows[r * COLUMNS_PLAIN..(r + 1) * COLUMNS_PLAIN].copy_from_slice(&row);
        }
    }
}

/// The integrals of [`integrate`] for the tables' two weightings at once — per point
/// `(1/N) Σ x` and `(1/N) Σ x (1 − c)⁵`, `x = f cos_i / pdf(l)` — with the sample
/// directions made by the backend itself ([`Runner::importance_sums`]: the Vulkan kernel
/// makes them on the device from the same Hammersley points and mappings), or `None` when
/// the backend has no such path.
pub fn backend_sums(
    runner: &mut Runner,
    spec: &Microfacet,
    points: &[(f64, f64)],
    samples: u32,
    what: &str,
) -> Option<Result<Vec<[f64; 2]>>> {
    let (materials, index) = match materials_for(spec, points) {
        Ok(x) => x,
        Err(e) => return Some(Err(e)),
    };
    let f32s = |a: [f64; 3]| a.map(|x| x as f32);
    let points: Vec<ImportancePoint> = points
        .iter()
        .zip(&index)
        .map(|(&(mu, alpha), &material)| {
            let view = View::new(spec.lobe, mu, alpha);
            ImportancePoint {
                v: f32s(view.v),
                g1: view.g1 as f32,
                frame: view.frame.map(f32s),
                s: view.s as f32,
                alpha: alpha as f32,
                material: material as u32,
                point: [mu, alpha],
            }
        })
        .collect();
    let job = ImportanceJob {
        ggx: spec.lobe == Lobe::Ggx,
        points: &points,
        materials: &materials,
        samples,
    };
    runner.importance_sums(what, &job)
}

/// One material per distinct α of `points`, and each point's index into that table.
fn materials_for(spec: &Microfacet, points: &[(f64, f64)]) -> Result<(Vec<Material>, Vec<usize>)> {
    let mut alphas: Vec<u64> = Vec::new();
    let mut materials = Vec::new();
    let mut index = Vec::with_capacity(points.len());
    for &(_, alpha) in points {
        let i = match alphas.iter().position(|&a| a == alpha.to_bits()) {
            Some(i) => i,
            None => {
                alphas.push(alpha.to_bits());
                materials.push(spec.material(alpha)?);
                alphas.len() - 1
            }
        };
        index.push(i);
    }
    Ok((materials, index))
}

/// Samples per block of the Vulkan importance kernel and the most blocks it takes in one
/// job (`SAMPLES_PER_BLOCK` and `MAX_GENERATED_TEXELS` of `src/gpu/evaluator/generated.rs`,
/// whose `importance_sums` sends larger jobs back to the host's tuples). A shard asks
/// [`device_takes`] about the whole table: without it, a band small enough for the device
/// would sum on the device while the whole table summed on the host, and the parts would
/// differ from the unsharded run in their last bits.
const KERNEL_BLOCK_SAMPLES: u32 = 256;
const KERNEL_MAX_BLOCKS: u64 = 1 << 24;

/// Whether an engine that makes its own importance samples takes a job of `points` points
/// of `samples` samples (else the samples go to it as host-made tuples).
pub fn device_takes(points: usize, samples: u32) -> bool {
    points as u64 * u64::from(samples.div_ceil(KERNEL_BLOCK_SAMPLES)) <= KERNEL_MAX_BLOCKS
}

/// `E(μ, α)` at each `(μ, α)` point.
pub fn directional_albedo(
    runner: &mut Runner,
    spec: &Microfacet,
    points: &[(f64, f64)],
    samples: u32,
) -> Result<Vec<f64>> {
    directional_albedo_of(runner, spec, points, points.len(), samples)
}

/// [`directional_albedo`] of `points`, a band of a table of `whole` points, each
/// computed as the whole table computes it ([`device_takes`]).
pub fn directional_albedo_of(
    runner: &mut Runner,
    spec: &Microfacet,
    points: &[(f64, f64)],
    whole: usize,
    samples: u32,
) -> Result<Vec<f64>> {
    if device_takes(whole, samples) {
        if let Some(sums) = backend_sums(runner, spec, points, samples, "albedo") {
            return Ok(sums?.into_iter().map(|[x, _]| x).collect());
        }
    }
    let e = integrate(runner, spec, points, samples, "albedo", |_| [1.0])?;
    Ok(e.into_iter().map(|[x]| x).collect())
}

/// `E_avg(α) = 2∫₀¹ E(μ) μ dμ` for each α: [`AVERAGE_NODES`]-point Gauss–Legendre in μ,
/// each `E(μ_k, α)` integrated with `samples` points.
pub fn average_albedo(
    runner: &mut Runner,
    spec: &Microfacet,
    alphas: &[f64],
    samples: u32,
) -> Result<Vec<f64>> {
    average_albedo_of(runner, spec, alphas, alphas.len(), samples)
}

/// [`average_albedo`] of `alphas`, a band of a table of `whole` α values, each computed as
/// the whole table computes it ([`device_takes`]).
pub fn average_albedo_of(
    runner: &mut Runner,
    spec: &Microfacet,
    alphas: &[f64],
    whole: usize,
    samples: u32,
) -> Result<Vec<f64>> {
    let nodes = gauss_legendre(AVERAGE_NODES);
    let points: Vec<(f64, f64)> = alphas
        .iter()
        .flat_map(|&a| nodes.iter().map(move |&(mu, _)| (mu, a)))
        .collect();
    let device = device_takes(whole * nodes.len(), samples);
    let sums = if device {
        backend_sums(runner, spec, &points, samples, "E_avg")
    } else {
        None
    };
    let e: Vec<[f64; 1]> = match sums {
        Some(sums) => sums?.into_iter().map(|[x, _]| [x]).collect(),
        None => integrate(runner, spec, &points, samples, "E_avg", |_| [1.0])?,
    };
    Ok(e.chunks(nodes.len())
        .map(|row| {
            row.iter()
                .zip(&nodes)
                .map(|([e], (mu, w))| 2.0 * mu * w * e)
                .sum()
        })
        .collect())
}

/// Gauss–Legendre nodes and weights on [0, 1]: Newton's method on `P_n` from the usual
/// starting guesses, to 1e-15.
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    // (P_n(z), P_n'(z)) by the three-term recurrence.
    let legendre = |z: f64| {
        let (mut p0, mut p1) = (1.0, z);
        for j in 2..=n {
            (p0, p1) = (
                p1,
                ((2 * j - 1) as f64 * z * p1 - (j - 1) as f64 * p0) / j as f64,
            );
        }
        (p1, n as f64 * (z * p1 - p0) / (z * z - 1.0))
    };
    (0..n)
        .map(|i| {
            let mut z = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            for _ in 0..100 {
                let (p, dp) = legendre(z);
                z -= p / dp;
                if (p / dp).abs() < 1e-15 {
                    break;
                }
            }
            let dp = legendre(z).1;
            ((1.0 - z) / 2.0, 1.0 / ((1.0 - z * z) * dp * dp))
        })
        .collect()
}

/// The `(μ, α)` texel centres of a table, row-major (row j ↔ α, column i ↔ μ); refused
/// before anything is allocated when the table's buffers (at [`BYTES_PER_TEXEL`]) would
/// not fit in the memory available, so no front end can abort on a size.
pub fn grid_points(grid: Grid) -> Result<Vec<(f64, f64)>> {
    super::check_memory(super::table_bytes(grid, BYTES_PER_TEXEL), "the table")?;
    Ok(grid_points_unchecked(grid))
}

/// [`grid_points`] without the memory check (for a grid already checked).
fn grid_points_unchecked(grid: Grid) -> Vec<(f64, f64)> {
    (0..grid.height)
        .flat_map(|j| {
            (0..grid.width)
                .map(move |i| (texel_centre(i, grid.width), texel_centre(j, grid.height)))
        })
        .collect()
}

/// What `vkbrdf table albedo` writes.
#[derive(Debug, Clone)]
pub struct AlbedoJob {
    /// The model.
    pub spec: Microfacet,
    /// Table size (x = μ, y = α).
    pub grid: Grid,
    /// Samples per texel.
    pub samples: u32,
    /// The axes (default [`super::axes::Axes::DEFAULT`]).
    pub axes: super::axes::Axes,
    /// Write float16.
    pub half: bool,
    /// The E table.
    pub output: PathBuf,
    /// The E_avg table (`H × 1`), when wanted.
    pub average: Option<PathBuf>,
}

impl AlbedoJob {
    /// Everything that can be checked before evaluating: the model is legal, the table
    /// fits in memory, the outputs can be written.
    pub fn check(&self) -> Result<()> {
        self.spec.material(0.5)?;
        self.axes.check(self.grid)?;
        super::check_memory(
            super::table_bytes(self.grid, BYTES_PER_TEXEL),
            "the albedo table",
        )?;
        super::check_exr_output(&self.output)?;
        self.average
            .as_deref()
            .map_or(Ok(()), super::check_exr_output)
    }

    /// [`AlbedoJob::check`] for the band `part` names: memory for its rows only, and .npy
    /// part names.
    pub fn check_part(&self, part: &super::shard::PartSpec) -> Result<()> {
        self.spec.material(0.5)?;
        self.axes.check(self.grid)?;
        let band = Grid {
            width: self.grid.width,
            height: part.band().len().max(1),
        };
        super::check_memory(
            super::table_bytes(band, BYTES_PER_TEXEL),
            "the albedo table's band",
        )?;
        super::shard::check_part_name(&self.output)?;
        super::check_output(&self.output)?;
        if let Some(avg) = &self.average {
            super::shard::check_part_name(avg)?;
            super::check_output(avg)?;
        }
        Ok(())
    }
}

/// Integrates and writes the albedo table (and E_avg), after [`AlbedoJob::check`].
pub fn write(runner: &mut Runner, job: &AlbedoJob) -> Result<()> {
    write_band(runner, job, None)
}

/// Integrates the band of roughness rows `part` names and writes it as a table part at
/// `job.output` (and E_avg's band, the same α, at `job.average`): `.npy` bands with
/// their sidecars ([`super::shard`]), after [`AlbedoJob::check`].
pub fn write_part(
    runner: &mut Runner,
    job: &AlbedoJob,
    part: &super::shard::PartSpec,
) -> Result<()> {
    write_band(runner, job, Some(part))
}

fn write_band(
    runner: &mut Runner,
    job: &AlbedoJob,
    part: Option<&super::shard::PartSpec>,
) -> Result<()> {
    match part {
        Some(part) => job.check_part(part)?,
        None => job.check()?,
    }
    let band = part.map_or(0..job.grid.height, |p| p.band());
    let points = &job.axes.points_of_rows(job.grid, band);
    let e = directional_albedo_of(runner, &job.spec, points, job.grid.texels(), job.samples)?;
    let backend = runner.backend_name();
    let provenance = |table: &str, parameterisation: &str, samples: String| Provenance {
        table: table.into(),
        material: job.spec.describe(),
        convention: "modern".into(),
        parameterisation: parameterisation.into(),
        samples,
        backend: backend.clone(),
    };
    let per_texel = format!(
        "{} per texel: Hammersley points, {}; f evaluated by the backend",
        job.samples,
        sampling(job.spec.lobe)
    );
    let e_provenance = provenance(
        "albedo",
        &format!(
            "Y = E(mu, alpha) = integral of f cos_i over the hemisphere (F = 1); {} (GGX alpha / Beckmann m), n = +z",
            job.axes.describe()
        ),
        per_texel.clone(),
    );
    let e_layers = vec![single("albedo", "Y", &e)];
    let mut staged = match part {
        Some(part) => super::shard::stage_exr_part(
            &job.output,
            part,
            job.grid.width,
            job.grid,
            &e_layers,
            &e_provenance,
            job.half,
            runner.cancel(),
        )?,
        None => {
            let (table, clamped) = exr_out::stage(
                &job.output,
                job.grid,
                e_layers,
                &e_provenance,
                job.half,
                runner.cancel(),
            )?;
            runner.warn_clamped(&job.output, &clamped);
            vec![table]
        }
    };
    if let Some(path) = &job.average {
        // Each row's α, in the table's own axes.
        let alphas: Vec<f64> = points
            .iter()
            .step_by(job.grid.width)
            .map(|&(_, alpha)| alpha)
            .collect();
        let avg = average_albedo_of(runner, &job.spec, &alphas, job.grid.height, job.samples)?;
        let avg_grid = Grid::new(job.grid.height, 1)?;
        let avg_layers = vec![single("albedo-average", "Y", &avg)];
        let avg_provenance = provenance(
            "albedo-average",
            &format!(
                "Y = E_avg(alpha) = 2 * integral of E(mu) mu dmu (Kulla-Conty); one row, column i = row i of the E table ({})",
                job.axes.describe()
            ),
            format!("{AVERAGE_NODES}-point Gauss-Legendre in mu, each E with {per_texel}"),
        );
        match part {
            // E_avg's column i is row i of E: its band is the same α, one texel per row.
            Some(part) => staged.extend(super::shard::stage_exr_part(
                path,
                part,
                1,
                avg_grid,
                &avg_layers,
                &avg_provenance,
                job.half,
                runner.cancel(),
            )?),
            None => {
                let (average, clamped) = exr_out::stage(
                    path,
                    avg_grid,
                    avg_layers,
                    &avg_provenance,
                    job.half,
                    runner.cancel(),
                )?;
                runner.warn_clamped(path, &clamped);
                staged.push(average);
            }
        }
    }
    // The table and its average appear together or not at all.
    crate::atomic::commit(staged)
}

/// How the lobe is sampled, for provenance.
pub fn sampling(lobe: Lobe) -> &'static str {
    match lobe {
        Lobe::Ggx => "GGX visible normals (Heitz 2018)",
        Lobe::Beckmann => "Beckmann D cos_h",
    }
}

/// A one-channel layer from f64 values.
pub fn single(layer: &str, channel: &str, values: &[f64]) -> Layer {
    Layer {
        name: layer.into(),
        channels: vec![Channel {
            name: channel.into(),
            values: values.iter().map(|&x| x as f32).collect(),
        }],
    }
}
