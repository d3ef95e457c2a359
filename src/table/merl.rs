//! MERL binary BRDFs (Matusik, Pfister, Brand & McMillan 2003, "A data-driven reflectance
//! model"): export of an analytic material (FORMULAS.md §7). The format itself, reading and
//! lookup live with the materials ([`crate::material::merl`], re-exported here).
//!
//! Layout: three little-endian int32 dimensions `90, 90, 180` (θ_h, θ_d, φ_d), then the R,
//! G and B blocks of `90·90·180` little-endian f64, bin `(i, j, k)` at
//! `k + 180·(j + 90·i)`. Bin `(i, j, k)` is sampled at `θ_h = (i/90)²·π/2`,
//! `θ_d = j·(π/2)/90`, `φ_d = k·π/180`, `φ_h = 0` ([`bin_directions`]); the stored value
//! is `f / scale` ([`SCALES`]), and `−1` where either direction is below the horizon.
//!
//! Lookup is MERL's own (`BRDFRead.cpp`): the half/difference angles of `(l, v)` in the
//! frame of `n`, bin indices by truncation (θ_h through the square root), `φ_d` folded into
//! `[0, π)` by reciprocity; negative (invalid or unmeasured) samples read as 0. One
//! deviation, documented at [`BIN_TOLERANCE`]: a point a hair below a bin's lower edge
//! counts as in that bin, so the bins' own sample points always find their bin.

pub use super::merl_file::{write_values, write_values_cancellable};
use super::{as_f32, needs_tangents, push_row, Runner, NORMAL, TANGENT};
use crate::batch::Batch;
use crate::directions::from_half_diff;
use crate::error::Result;
pub use crate::material::merl::{
    bin_angles, bin_index, bin_of, half_diff, read, read_from, MeasuredMerl, BIN_TOLERANCE,
    FILE_BYTES, INVALID, PHI_D_BINS, SAMPLES, SCALES, THETA_D_BINS, THETA_H_BINS,
};
use crate::material::Material;
use std::path::Path;
/// `(l, v)` of bin `(i, j, k)`'s sample point (`n = +z`, `φ_h = 0`).
pub fn bin_directions(i: usize, j: usize, k: usize) -> ([f64; 3], [f64; 3]) {
    let (th, td, pd) = bin_angles(i, j, k);
    from_half_diff(th, td, pd)
}

/// The stored values (R, G, B blocks, `f / scale` or [`INVALID`]) of `material`,
/// evaluated on the runner. MERL is isotropic: anisotropic materials are sampled at
/// `φ_h = 0` with `t = +x`.
pub fn compute(runner: &mut Runner, material: &Material) -> Result<Vec<f64>> {
    compute_band(runner, material, 0..THETA_H_BINS)
}

/// [`compute`] for the θ_h bins `band` only: the R, G and B blocks of those bins
/// (`3 · |band| · 90 · 180` values), each bin evaluated as in the whole table.
pub fn compute_band(
    runner: &mut Runner,
    material: &Material,
    band: std::ops::Range<usize>,
) -> Result<Vec<f64>> {
    let materials = std::slice::from_ref(material);
    let tangent = needs_tangents(materials).then_some(TANGENT);
    if tangent.is_some() {
        runner.warn(format!(
            "material `{}` is anisotropic, but MERL is an isotropic format: it was sampled at φ_h = 0 only (half vector in the plane of the tangent t = +x and n = +z), so the file holds one azimuth of the material, not an average over φ_h",
            material.name
        ));
    }
    let row = PHI_D_BINS * THETA_D_BINS;
    let (first, last) = (band.start * row, band.end * row);
    let n = last - first;
    let mut values = vec![INVALID; 3 * n];
    runner.start("merl", n as u64);
    let mut next = first;
    while next < last {
        let end = last.min(next + runner.chunk_tuples());
        let mut rows = Vec::with_capacity((end - next) * 13);
        let mut bins = Vec::with_capacity(end - next);
        for b in next..end {
            let (i, j, k) = (
                b / (PHI_D_BINS * THETA_D_BINS),
                (b / PHI_D_BINS) % THETA_D_BINS,
                b % PHI_D_BINS,
            );
            let (l, v) = bin_directions(i, j, k);
            // The horizon test on the directions the backend sees (f32).
            if as_f32(l)[2] > 0.0 && as_f32(v)[2] > 0.0 {
                push_row(&mut rows, l, v, NORMAL, 0, tangent);
                bins.push(b);
            }
        }
        if !bins.is_empty() {
            let out = runner.evaluate(rows, materials, false)?;
            for (r, &b) in bins.iter().enumerate() {
                for c in 0..3 {
                    values[c * n + b - first] = f64::from(out.brdf[3 * r + c]) / SCALES[c];
                }
            }
        }
        runner.advance((end - next) as u64);
        next = end;
    }
    runner.finish();
    Ok(values)
}

/// Everything that can be checked before evaluating: memory for the table (the values
/// and one chunk) and that `path` can be written.
pub fn check(path: &Path) -> Result<()> {
    let chunk = super::table_bytes(super::Grid::new(1, 1)?, 0).unwrap_or(0);
    super::check_memory(Some(FILE_BYTES as u128 + chunk), "the MERL table")?;
    super::check_output(path)
}

/// Exports `material` as a MERL binary at `path` (atomically), after [`check`].
pub fn write(runner: &mut Runner, material: &Material, path: &Path) -> Result<()> {
    check(path)?;
    let values = compute(runner, material)?;
    write_values_cancellable(path, &values, runner.cancel())
}

/// Evaluates the θ_h bins `part` names and writes them as a MERL part at `path` (a MERL
/// binary of the band, dimensions `rows 90 180`, and its sidecar: [`super::shard`]), after
/// [`check`].
pub fn write_part(
    runner: &mut Runner,
    material: &Material,
    path: &Path,
    part: &super::shard::PartSpec,
) -> Result<()> {
    check(path)?;
    let values = compute_band(runner, material, part.band())?;
    let engine = runner.backend_name();
    super::shard::write_merl_part(path, part, &values, &engine, runner.cancel())
}

/// f (n × 3, RGB, 1/sr) of `merl` at every tuple of `batch` (material column and tangents
/// ignored: the data is one isotropic material).
pub fn evaluate_measured(merl: &MeasuredMerl, batch: &Batch) -> Vec<f32> {
    let w = |a: [f32; 3]| a.map(f64::from);
    (0..batch.len())
        .flat_map(|r| {
            let t = batch.tuple(r);
            merl.lookup(w(t.l), w(t.v), w(t.n)).map(|x| x as f32)
        })
        .collect()
}
