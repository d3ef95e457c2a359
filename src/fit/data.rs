//! The measurements a fit reads: directions in the local frame (n = +z), measured RGB f
//! and each sample's solid-angle measure, from a MERL binary ([`FitData::from_merl`]) or
//! from tuples and values ([`FitData::from_tuples`]). Samples that cannot be compared —
//! a negative (invalid) MERL bin, a direction at or below the horizon, beyond the grazing
//! cut-off — are masked (left out and counted); data that cannot be fitted at all (NaN
//! values, zero or non-finite directions, nothing left) is an error naming the row.

use crate::batch::LocalBatch;
use crate::error::{Error, Result};
use crate::material::merl::{self, MeasuredMerl, PHI_D_BINS, SAMPLES, THETA_D_BINS, THETA_H_BINS};
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::{Path, PathBuf};

/// The per-sample weights the losses use (docs/FITTING.md, "Losses").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Measure {
    /// Each sample's own solid angle (a MERL bin's 4-D extent, or `--weights`): every loss
    /// uses it in place of the `sin θ` factors.
    Given,
    /// A uniform angle grid: Ngan's L2 weighs by `sin θ_i sin θ_o`, Löw's E1, E2 and the
    /// relative RMS by `sin θ_i`.
    AngleGrid,
}

/// Measured samples ready for a fit.
#[derive(Debug, Clone)]
pub struct FitData {
    /// Where the data came from (errors and the report name it).
    pub source: PathBuf,
    /// The directions as a local-frame batch (`Lx Ly Lz Vx Vy Vz`, unit length, f32).
    pub batch: LocalBatch,
    /// Measured f per sample, RGB, 1/sr.
    pub values: Vec<[f64; 3]>,
    /// `cos θ_i` per sample (from the f32 directions, in f64).
    pub cos_i: Vec<f64>,
    /// `v·h` per sample: the cosine Schlick's Fresnel reads.
    pub cos_d: Vec<f64>,
    /// `(θ_h, θ_d)` per sample, radians: where the residual slice puts it.
    pub angles: Vec<(f64, f64)>,
    /// Ngan's L2 weight per sample (the solid-angle measure).
    pub weight_l2: Vec<f64>,
    /// Löw's E1/E2 and the relative RMS's weight per sample.
    pub weight_e: Vec<f64>,
    /// How the weights were made.
    pub measure: Measure,
    /// Samples read, before masking.
    pub read: usize,
    /// Samples masked (invalid, below the horizon, beyond the cut-off).
    pub masked: usize,
}

/// The solid-angle measure of MERL bin `(i, j)` (any φ_d bin): `∫ dω_i dω_o` over the
/// bin, `4 cos θ_d dω_h dω_d` (Rusinkiewicz 1998) integrated over its θ_h and θ_d extent,
/// its φ_d width (twice: reciprocity folds φ_d into `[0, π)`) and φ_h's 2π.
pub fn merl_bin_measure(i: usize, j: usize) -> f64 {
    let th = |i: usize| (i as f64 / THETA_H_BINS as f64).powi(2) * FRAC_PI_2;
    let td = |j: usize| j as f64 * FRAC_PI_2 / THETA_D_BINS as f64;
    let h = th(i).cos() - th(i + 1).cos();
    // ∫ 4 cos θ sin θ dθ = cos 2a − cos 2b.
    let d = (2.0 * td(j)).cos() - (2.0 * td(j + 1)).cos();
    2.0 * PI * h * d * (2.0 * PI / PHI_D_BINS as f64)
}

impl FitData {
    /// Every valid bin of a MERL table (all three channels ≥ 0, both directions above
    /// the horizon in f32, `θ_i, θ_o ≤ max_theta`), each weighted by its own solid angle
    /// ([`merl_bin_measure`]).
    pub fn from_merl(table: &MeasuredMerl, max_theta: Option<f64>) -> Result<FitData> {
        let source = table.source().to_owned();
        let mut b = Builder::new(SAMPLES);
        for i in 0..THETA_H_BINS {
            for j in 0..THETA_D_BINS {
                let w = merl_bin_measure(i, j);
                for k in 0..PHI_D_BINS {
                    let stored = [0, 1, 2].map(|c| table.stored(c, i, j, k));
                    if stored.iter().any(|s| !s.is_finite()) {
                        return Err(Error::Table(format!(
                            "{}: bin (theta_h {i}, theta_d {j}, phi_d {k}) holds a non-finite value {:?}; a MERL table marks invalid bins with negative values",
                            source.display(),
                            stored
                        )));
                    }
                    if stored.iter().any(|&s| s < 0.0) {
                        b.masked += 1;
                        continue;
                    }
                    let (th, td, pd) = merl::bin_angles(i, j, k);
                    let (l, v) = crate::directions::from_half_diff(th, td, pd);
                    let f = [0, 1, 2].map(|c| table.value(c, i, j, k));
                    b.push(l, v, f, Some(w), max_theta);
                }
            }
        }
        b.finish(source, Measure::Given)
    }

    /// Tuples (`n × 6` local rows, or `n × 10`/`n × 13` rows whose N is any normal: they are
    /// turned into its frame) with measured values (`n × 3`) and optional weights (`n`).
    /// A zero or non-finite direction, a NaN or infinite value, a weight that is negative
    /// or not finite: an error naming the row. Negative values mark invalid samples
    /// (masked, as MERL's); so do rows at or below the horizon.
    pub fn from_tuples(
        tuples: &[f32],
        columns: usize,
        values: &[f32],
        weights: Option<&[f32]>,
        max_theta: Option<f64>,
        source: &Path,
    ) -> Result<FitData> {
        let bad = |message: String| Error::Batch {
            path: source.to_owned(),
            message,
        };
        if !matches!(columns, 6 | 10 | 13) || !tuples.len().is_multiple_of(columns) {
            return Err(bad(format!(
                "tuples must have 6 (Lx Ly Lz Vx Vy Vz), 10 or 13 columns; got {columns}"
            )));
        }
        let n = tuples.len() / columns;
        if values.len() != 3 * n {
            return Err(bad(format!(
                "{n} tuples but {} values: --values must be (n, 3) with the same n",
                values.len()
            )));
        }
        if let Some(w) = weights {
            if w.len() != n {
                return Err(bad(format!(
                    "{n} tuples but {} weights: --weights must hold one per tuple",
                    w.len()
                )));
            }
        }
        let mut b = Builder::new(n);
        for r in 0..n {
            let row = &tuples[r * columns..(r + 1) * columns];
            let at = |k: usize| [row[k], row[k + 1], row[k + 2]].map(f64::from);
            let nrm = if columns == 6 { [0.0, 0.0, 1.0] } else { at(6) };
            let (l, v, nrm) = match (
                crate::vector::normalize(at(0)),
                crate::vector::normalize(at(3)),
                crate::vector::normalize(nrm),
            ) {
                (Some(l), Some(v), Some(n)) => (l, v, n),
                _ => {
                    return Err(bad(format!(
                        "row {r}: L, V or N is zero or not finite ({row:?})"
                    )))
                }
            };
            let f = [0, 1, 2].map(|c| f64::from(values[3 * r + c]));
            if f.iter().any(|x| !x.is_finite()) {
                return Err(bad(format!(
                    "row {r}: value {f:?} is not finite (NaN or infinite); mark an invalid sample with a negative value"
                )));
            }
            let w = match weights {
                Some(w) => {
                    let w = f64::from(w[r]);
                    if !(w.is_finite() && w >= 0.0) {
                        return Err(bad(format!("row {r}: weight {w} must be finite and >= 0")));
                    }
                    Some(w)
                }
                None => None,
            };
            if f.iter().any(|&x| x < 0.0) {
                b.masked += 1;
                continue;
            }
            let (l, v) = (to_frame(l, nrm), to_frame(v, nrm));
            b.push(l, v, f, w, max_theta);
        }
        let measure = if weights.is_some() {
            Measure::Given
        } else {
            Measure::AngleGrid
        };
        b.finish(source.to_owned(), measure)
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether no sample is left.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Every `step`-th sample, weights multiplied by `step` (the losses keep their
    /// scale): the coarse data the multi-start phase runs on.
    pub fn subsample(&self, step: usize) -> FitData {
        let step = step.max(1);
        let keep: Vec<usize> = (0..self.len()).step_by(step).collect();
        let pick = |x: &[f64]| {
            keep.iter()
                .map(|&i| x[i] * step as f64)
                .collect::<Vec<f64>>()
        };
        let rows: Vec<f32> = keep.iter().flat_map(|&i| self.batch.row(i)).collect();
        FitData {
            source: self.source.clone(),
            batch: LocalBatch::new(rows, 0, &[dummy()], &self.source).expect("whole rows"),
            values: keep.iter().map(|&i| self.values[i]).collect(),
            cos_i: keep.iter().map(|&i| self.cos_i[i]).collect(),
            cos_d: keep.iter().map(|&i| self.cos_d[i]).collect(),
            angles: keep.iter().map(|&i| self.angles[i]).collect(),
            weight_l2: pick(&self.weight_l2),
            weight_e: pick(&self.weight_e),
            measure: self.measure,
            read: self.read,
            masked: self.masked,
        }
    }
}

/// A Lambert material: what [`LocalBatch::new`] checks the material index against (the
/// fit evaluates the batch with a table of one material, index 0).
fn dummy() -> crate::material::Material {
    crate::material::Material {
        name: "fit".into(),
        model: crate::material::Model::Lambert,
        diffuse: [0.0; 3],
        specular: [1.0; 3],
        precision: crate::material::precision::Precision::Exact,
        spectral: None,
    }
}

/// `w` in a frame whose z axis is the unit normal `n` (any tangent: the models fitted are
/// isotropic).
fn to_frame(w: [f64; 3], n: [f64; 3]) -> [f64; 3] {
    let helper = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let t = crate::vector::normalize(crate::vector::cross(helper, n)).expect("n is unit");
    let b = crate::vector::cross(n, t);
    let d = crate::vector::dot;
    [d(w, t), d(w, b), d(w, n)]
}

struct Builder {
    rows: Vec<f32>,
    values: Vec<[f64; 3]>,
    cos_i: Vec<f64>,
    cos_d: Vec<f64>,
    angles: Vec<(f64, f64)>,
    weight_l2: Vec<f64>,
    weight_e: Vec<f64>,
    masked: usize,
}

impl Builder {
    fn new(capacity: usize) -> Builder {
        Builder {
            rows: Vec::with_capacity(6 * capacity),
            values: Vec::with_capacity(capacity),
            cos_i: Vec::with_capacity(capacity),
            cos_d: Vec::with_capacity(capacity),
            angles: Vec::with_capacity(capacity),
            weight_l2: Vec::with_capacity(capacity),
            weight_e: Vec::with_capacity(capacity),
            masked: 0,
        }
    }

    /// One sample at unit local `l`, `v`; masked when below the horizon (as the engines
    /// see it, in f32) or beyond `max_theta`.
    fn push(
        &mut self,
        l: [f64; 3],
        v: [f64; 3],
        f: [f64; 3],
        weight: Option<f64>,
        max_theta: Option<f64>,
    ) {
        let (l32, v32) = (l.map(|x| x as f32), v.map(|x| x as f32));
        let (l, v) = (l32.map(f64::from), v32.map(f64::from));
        let (Some(l), Some(v)) = (crate::vector::normalize(l), crate::vector::normalize(v)) else {
            self.masked += 1;
            return;
        };
        let limit = max_theta.map_or(0.0, f64::cos);
        if l32[2] <= 0.0 || v32[2] <= 0.0 || l[2] < limit || v[2] < limit {
            self.masked += 1;
            return;
        }
        let Some((th, td, _)) = merl::half_diff(l, v, [0.0, 0.0, 1.0]) else {
            self.masked += 1;
            return;
        };
        let h = crate::vector::normalize(std::array::from_fn(|i| l[i] + v[i])).expect("above");
        self.rows.extend_from_slice(&l32);
        self.rows.extend_from_slice(&v32);
        self.values.push(f);
        self.cos_i.push(l[2]);
        self.cos_d.push(crate::vector::dot(v, h).clamp(0.0, 1.0));
        self.angles.push((th, td));
        let sin = |z: f64| (1.0 - z * z).max(0.0).sqrt();
        match weight {
            Some(w) => {
                self.weight_l2.push(w);
                self.weight_e.push(w);
            }
            None => {
                self.weight_l2.push(sin(l[2]) * sin(v[2]));
                self.weight_e.push(sin(l[2]));
            }
        }
    }

    fn finish(self, source: PathBuf, measure: Measure) -> Result<FitData> {
        if self.values.is_empty() {
            return Err(Error::Table(format!(
                "{}: no valid sample to fit: all {} samples are invalid (negative), below the horizon or beyond the grazing cut-off",
                source.display(),
                self.masked
            )));
        }
        let total: f64 = self.weight_l2.iter().sum();
        if total <= 0.0 {
            return Err(Error::Table(format!(
                "{}: every valid sample has weight 0 (samples at the normal on an angle grid, or --weights of zeros): nothing to fit",
                source.display()
            )));
        }
        let batch = LocalBatch::new(self.rows, 0, &[dummy()], &source)?;
        let read = self.values.len() + self.masked;
        Ok(FitData {
            source,
            batch,
            values: self.values,
            cos_i: self.cos_i,
            cos_d: self.cos_d,
            angles: self.angles,
            weight_l2: self.weight_l2,
            weight_e: self.weight_e,
            measure,
            read,
            masked: self.masked,
        })
    }
}
