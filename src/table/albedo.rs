//! Directional albedo `E(μ, α) = ∫ f(l, v) cos_i dω_l` of modern Cook–Torrance with F = 1
//! (FORMULAS.md §7), its cosine-weighted average `E_avg(α) = 2∫₀¹ E(μ) μ dμ` (Kulla & Conty
//! 2017, "Revisiting physically based shading at Imageworks"), and the importance-sampled
//! quasi-Monte Carlo integrator that [`super::dfg`] shares.
//!
//! The integrator: for each `(μ, α)`, `v = (√(1−μ²), 0, μ)`, `n = +z`; `N` Hammersley points
//! map to microfacet normals `h` — GGX through its distribution of visible normals (Heitz
//! 2018), Beckmann through `D cos_h` — and `l` is `v` reflected about `h`. The backend
//! evaluates `f(l, v)`; the host adds `f cos_i / pdf(l)` (times a per-sample weight of
//! `c = v·h`). Samples with `l` below the horizon contribute 0 and are not sent. The pdf is
//! computed from the f32 directions the backend sees, so the ratio is consistent.
//! [`DEFAULT_SAMPLES`] states the count and the accuracy measured for it.

use super::exr_out::{self, Channel, Layer, Provenance};
use super::{as_f32, push_row, texel_centre, Grid, Runner};
use crate::error::{Error, Result};
use crate::material::{Geometry, Material};
use crate::reference::distribution::{beckmann_d, ggx_d};
use crate::reference::frame::{dot, normalize};
use crate::reference::geometry::ggx_lambda;
use std::f64::consts::{PI, TAU};
use std::path::PathBuf;

/// Samples per texel by default: 2¹⁴ Hammersley points. Measured against an independent
/// dense quadrature of the f64 reference (tests/tables.rs): the error is below 1e-4
/// absolute for α ≥ 1/64 at every μ ≥ 1/64, for E and for the DFG A and B.
pub const DEFAULT_SAMPLES: u32 = 1 << 14;

/// Gauss–Legendre nodes in μ for [`average_albedo`].
pub const AVERAGE_NODES: usize = 32;

/// The microfacet distribution of an integrated table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Lobe {
    /// GGX / Trowbridge–Reitz, sampled by its visible normals.
    Ggx,
    /// Beckmann (modern convention, `k = π`), sampled by `D cos_h`.
    Beckmann,
}

impl Lobe {
    /// The materials-file name (`ggx`, `beckmann`).
    pub fn name(self) -> &'static str {
        match self {
            Lobe::Ggx => "ggx",
            Lobe::Beckmann => "beckmann",
        }
    }
}

/// The name of a geometry term as a materials file spells it.
pub fn geometry_name(g: Geometry) -> &'static str {
    match g {
        Geometry::None => "none",
        Geometry::CookTorrance => "cook-torrance",
        Geometry::Smith => "smith",
        Geometry::SmithCorrelated => "smith-correlated",
        Geometry::SmithFast => "smith-fast",
    }
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
        let mut list = crate::material::parse_materials(&toml, "the table's model")?;
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

/// Point `k` of the `n`-point Hammersley set, `((k + ½)/n, radical inverse₂(k))`.
pub fn hammersley(k: u32, n: u32) -> (f64, f64) {
    (
        (f64::from(k) + 0.5) / f64::from(n),
        f64::from(k.reverse_bits()) * (1.0 / 4_294_967_296.0),
    )
}

/// Heitz 2018, "Sampling the GGX Distribution of Visible Normals" (JCGT 7(4)): a normal
/// `h` distributed as `G1(v) max(0, v·h) D(h) / cos_o`, from `(u1, u2)` in [0, 1)².
pub fn sample_ggx_vndf(v: [f64; 3], alpha: f64, u1: f64, u2: f64) -> [f64; 3] {
    let vh = normalize([alpha * v[0], alpha * v[1], v[2]]).unwrap_or([0.0, 0.0, 1.0]);
    let len2 = vh[0] * vh[0] + vh[1] * vh[1];
    let t1 = if len2 > 0.0 {
        let inv = 1.0 / len2.sqrt();
        [-vh[1] * inv, vh[0] * inv, 0.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let t2 = crate::reference::frame::cross(vh, t1);
    let (r, phi) = (u1.sqrt(), TAU * u2);
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh[2]);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let p3 = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    let nh: [f64; 3] = std::array::from_fn(|i| p1 * t1[i] + p2 * t2[i] + p3 * vh[i]);
    normalize([alpha * nh[0], alpha * nh[1], nh[2].max(0.0)]).unwrap_or([0.0, 0.0, 1.0])
}

/// Beckmann normals distributed as `D(h) cos_h`: `tan²θ = −α² ln(1 − u1)`, `φ = 2π u2`.
pub fn sample_beckmann(alpha: f64, u1: f64, u2: f64) -> [f64; 3] {
    let tan2 = -alpha * alpha * (-u1).ln_1p();
    let cos = 1.0 / (1.0 + tan2).sqrt();
    let sin = (tan2 / (1.0 + tan2)).sqrt();
    let phi = TAU * u2;
    [sin * phi.cos(), sin * phi.sin(), cos]
}

/// One importance sample: the light direction, `cos_i / pdf(l)`, and `c = v·h`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Direction toward the light (unit; the backend reads it rounded to f32).
    pub l: [f64; 3],
    /// `cos_i / pdf(l)`, from the f32-rounded directions.
    pub weight: f64,
    /// `c = v·h`, from the f32-rounded directions.
    pub c: f64,
}

/// The `k`-th of `n` samples for view `v` and roughness `alpha`, or `None` when `l` falls
/// below the horizon (f = 0 there).
pub fn sample(lobe: Lobe, v: [f64; 3], alpha: f64, k: u32, n: u32) -> Option<Sample> {
    let (u1, u2) = hammersley(k, n);
    let h = match lobe {
        Lobe::Ggx => sample_ggx_vndf(v, alpha, u1, u2),
        Lobe::Beckmann => sample_beckmann(alpha, u1, u2),
    };
    let vh = dot(v, h);
    let l: [f64; 3] = std::array::from_fn(|i| 2.0 * vh * h[i] - v[i]);
    // What the backend sees: f32 directions, normalised in f64.
    let (lf, vf) = (normalize(as_f32(l))?, normalize(as_f32(v))?);
    let (cos_i, cos_o) = (lf[2], vf[2]);
    if cos_i <= 0.0 || cos_o <= 0.0 {
        return None;
    }
    let hf = normalize(std::array::from_fn(|i| lf[i] + vf[i]))?;
    let (cos_h, sin2_h, c) = (hf[2], hf[0] * hf[0] + hf[1] * hf[1], dot(vf, hf));
    let pdf = match lobe {
        Lobe::Ggx => {
            let tan2_o = (vf[0] * vf[0] + vf[1] * vf[1]) / (cos_o * cos_o);
            let g1 = 1.0 / (1.0 + ggx_lambda(alpha * alpha * tan2_o));
            g1 * ggx_d(cos_h, sin2_h, alpha) / (4.0 * cos_o)
        }
        Lobe::Beckmann => beckmann_d(cos_h, sin2_h, alpha, PI) * cos_h / (4.0 * c),
    };
    let weight = cos_i / pdf;
    weight.is_finite().then_some(Sample { l, weight, c })
}

/// The view direction of cosine `mu` in the `xz` plane.
pub fn view(mu: f64) -> [f64; 3] {
    [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu]
}

/// `(1/N) Σ f cos_i/pdf · weight(c)` for each `(μ, α)` point: the integrals
/// `∫ f(l, v) cos_i · weight(v·h) dω_l` with `samples` points each, evaluated on the runner.
pub fn integrate<const K: usize>(
    runner: &mut Runner,
    spec: &Microfacet,
    points: &[(f64, f64)],
    samples: u32,
    what: &str,
    weight: impl Fn(f64) -> [f64; K],
) -> Result<Vec<[f64; K]>> {
    if samples == 0 {
        return Err(Error::Table("--samples must be at least 1".into()));
    }
    let (materials, index) = materials_for(spec, points)?;
    let total = points.len() as u64 * u64::from(samples);
    runner.start(what, total);
    let mut sums = vec![[0.0f64; K]; points.len()];
    let mut next = 0u64;
    while next < total {
        let end = total.min(next + runner.chunk_tuples() as u64);
        let mut rows = Vec::with_capacity((end - next) as usize * 10);
        let mut meta: Vec<(usize, [f64; K])> = Vec::with_capacity((end - next) as usize);
        for g in next..end {
            let p = (g / u64::from(samples)) as usize;
            let k = (g % u64::from(samples)) as u32;
            let (mu, alpha) = points[p];
            if let Some(s) = sample(spec.lobe, view(mu), alpha, k, samples) {
                push_row(&mut rows, s.l, view(mu), index[p], None);
                meta.push((p, weight(s.c).map(|w| w * s.weight)));
            }
        }
        if !meta.is_empty() {
            let out = runner.evaluate(rows, &materials, false)?;
            for (r, (p, w)) in meta.iter().enumerate() {
                let f = f64::from(out.brdf[3 * r]);
                for (sum, wk) in sums[*p].iter_mut().zip(w) {
                    *sum += f * wk;
                }
            }
        }
        runner.advance(end - next);
        next = end;
    }
    runner.finish();
    Ok(sums
        .into_iter()
        .map(|s| s.map(|x| x / f64::from(samples)))
        .collect())
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

/// `E(μ, α)` at each `(μ, α)` point.
pub fn directional_albedo(
    runner: &mut Runner,
    spec: &Microfacet,
    points: &[(f64, f64)],
    samples: u32,
) -> Result<Vec<f64>> {
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
    let nodes = gauss_legendre(AVERAGE_NODES);
    let points: Vec<(f64, f64)> = alphas
        .iter()
        .flat_map(|&a| nodes.iter().map(move |&(mu, _)| (mu, a)))
        .collect();
    let e = integrate(runner, spec, &points, samples, "E_avg", |_| [1.0])?;
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

/// The `(μ, α)` texel centres of a table, row-major (row j ↔ α, column i ↔ μ).
pub fn grid_points(grid: Grid) -> Vec<(f64, f64)> {
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
    /// Write float16.
    pub half: bool,
    /// The E table.
    pub output: PathBuf,
    /// The E_avg table (`H × 1`), when wanted.
    pub average: Option<PathBuf>,
}

/// Integrates and writes the albedo table (and E_avg), refusing oversized grids first.
pub fn write(runner: &mut Runner, job: &AlbedoJob) -> Result<()> {
    super::check_memory(super::table_bytes(job.grid, 1), "the albedo table")?;
    job.spec.material(0.5)?;
    let e = directional_albedo(runner, &job.spec, &grid_points(job.grid), job.samples)?;
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
    exr_out::write(
        &job.output,
        job.grid,
        vec![single("albedo", "Y", &e)],
        &provenance(
            "albedo",
            "Y = E(mu, alpha) = integral of f cos_i over the hemisphere (F = 1); x = mu = cos_o, y = alpha (GGX alpha / Beckmann m), n = +z",
            per_texel.clone(),
        ),
        job.half,
    )?;
    if let Some(path) = &job.average {
        let alphas: Vec<f64> = (0..job.grid.height)
            .map(|j| texel_centre(j, job.grid.height))
            .collect();
        let avg = average_albedo(runner, &job.spec, &alphas, job.samples)?;
        exr_out::write(
            path,
            Grid::new(job.grid.height, 1)?,
            vec![single("albedo-average", "Y", &avg)],
            &provenance(
                "albedo-average",
                "Y = E_avg(alpha) = 2 * integral of E(mu) mu dmu (Kulla-Conty); x = alpha (column i <-> alpha = (i + 0.5)/W), one row",
                format!("{AVERAGE_NODES}-point Gauss-Legendre in mu, each E with {per_texel}"),
            ),
            job.half,
        )?;
    }
    Ok(())
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
