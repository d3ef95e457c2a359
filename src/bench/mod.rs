//! `vkbrdf bench`: throughput of every backend on the benchmark scenarios, against error,
//! against the peers (Mitsuba 3 LLVM, NumPy, the memory-copy ceiling) measured in the same
//! run, and specialised against all-features kernels. Results go to a table, JSON and SVG
//! plots ([`plot`]).

pub mod equal;
pub mod peers;
pub mod plot;
pub mod scenarios;
pub mod stages;

use crate::backend::{Backend, Output, Request};
use crate::batch::Batch;
use crate::error::Result;
use crate::material::Material;
use crate::stats::{relative_error, ErrorStats};
use std::time::Instant;

/// Absolute floor of the benchmark's relative error (1/sr): Mitsuba zeroes D·cos θ_h below
/// 1e-20 and f32 carries 7 digits, so values under 1e-6 are compared absolutely.
pub const ERROR_FLOOR: f64 = 1e-6;

/// One measured point.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ResultRow {
    /// Backend name (`vulkan`, `cpu`).
    pub backend: String,
    /// Scenario name.
    pub scenario: String,
    /// `kernel` (data resident on the device) or `end-to-end` (host arrays in and out).
    pub mode: String,
    /// Precision variant (`exact`; `all-features` for the unspecialised kernel).
    pub precision: String,
    /// Tuples per call.
    pub tuples: usize,
    /// Median tuples per second.
    pub evals_per_s: f64,
    /// Median seconds per call.
    pub seconds_median: f64,
    /// Max relative error against the f64 reference (floor [`ERROR_FLOOR`]) on a sample.
    pub max_rel_err: f64,
}

pub use crate::stats::median;

/// Times `backend.evaluate` `repeats` times after one warm-up call (which compiles and
/// caches the pipeline); returns the median seconds and the last output.
pub fn time_end_to_end(
    backend: &mut dyn Backend,
    batch: &Batch,
    materials: &[Material],
    repeats: usize,
) -> Result<(f64, Output)> {
    let request = Request::default();
    let mut out = backend.evaluate(batch, materials, &request)?;
    let mut secs = Vec::with_capacity(repeats);
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        out = backend.evaluate(batch, materials, &request)?;
        secs.push(t.elapsed().as_secs_f64());
    }
    Ok((median(secs), out))
}

/// Max relative error of `brdf` against the reference on at most `sample` evenly spaced rows.
pub fn max_rel_err(batch: &Batch, materials: &[Material], brdf: &[f32], sample: usize) -> f64 {
    brdf_error_stats(batch, materials, brdf, sample).max
}

/// Relative-error statistics (floor [`ERROR_FLOOR`]) of `brdf` against the reference on at
/// most `sample` evenly spaced rows of `batch`.
pub fn brdf_error_stats(
    batch: &Batch,
    materials: &[Material],
    brdf: &[f32],
    sample: usize,
) -> ErrorStats {
    // Rows cycle through the materials (row i uses material i mod M in the generated
    // batches), so a step sharing a factor with M would sample only some materials: take
    // the first step from len/sample on that is coprime with M.
    let mut step = (batch.len() / sample.max(1)).max(1);
    while gcd(step, materials.len().max(1)) != 1 {
        step += 1;
    }
    let mut stats = ErrorStats::default();
    for i in (0..batch.len()).step_by(step) {
        let t = batch.tuple(i);
        let r = crate::reference::evaluate_tuple(&t, &materials[t.material]);
        for c in 0..3 {
            stats.add(
                relative_error(brdf[3 * i + c] as f64, r.brdf[c], ERROR_FLOOR),
                i as u64,
            );
        }
    }
    stats
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// Tuples/s of a memory copy moving the bytes a kernel must read and write for `tuples`
/// tuples of `columns` floats in and 3 out: a copy of half that many bytes reads and writes
/// them once each. Median of `repeats` after a warm-up.
pub fn memcpy_ceiling(tuples: usize, columns: usize, repeats: usize) -> f64 {
    let bytes = tuples * (columns + 3) * 4 / 2;
    let src = vec![1u8; bytes];
    let mut dst = vec![0u8; bytes];
    dst.copy_from_slice(&src);
    let mut secs = Vec::new();
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        dst.copy_from_slice(&src);
        std::hint::black_box(&mut dst);
        secs.push(t.elapsed().as_secs_f64());
    }
    tuples as f64 / median(secs)
}

/// Max relative error (floor [`ERROR_FLOOR`]) of a half/difference slice's `brdf` (as
/// [`crate::backend::GeneratedDirections::half_diff_slice`] returns it) against the reference at the
/// host's directions ([`crate::table::slice::from_half_diff`]), on at most `sample`
/// evenly spaced texels.
pub fn slice_max_rel_err(
    material: &Material,
    grid: crate::directions::SliceGrid,
    brdf: &[f32],
    sample: usize,
) -> f64 {
    use crate::table::slice::{from_half_diff, theta_h, Spacing, TANGENT};
    use std::f64::consts::FRAC_PI_2;
    let spacing = if grid.linear {
        Spacing::Linear
    } else {
        Spacing::Sqrt
    };
    let (w, h) = (grid.width as usize, grid.height as usize);
    let n = w * h;
    let mut stats = ErrorStats::default();
    for g in (0..n).step_by((n / sample.max(1)).max(1)) {
        let (i, j) = (g % w, g / w);
        let th = theta_h((i as f64 + 0.5) / w as f64, spacing);
        let td = (j as f64 + 0.5) / h as f64 * FRAC_PI_2;
        let (l, v) = from_half_diff(th, td, FRAC_PI_2);
        let r = crate::reference::evaluate(l, v, [0.0, 0.0, 1.0], Some(TANGENT), material);
        for c in 0..3 {
            stats.add(
                relative_error(f64::from(brdf[3 * g + c]), r.brdf[c], ERROR_FLOOR),
                g as u64,
            );
        }
    }
    stats.max
}
