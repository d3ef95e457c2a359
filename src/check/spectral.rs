//! `check`'s spectral rows (FORMULAS.md §9): each spectral preset (and an up-sampled RGB
//! plastic) at the 95 CIE wavelengths through the backend's own spectral way — the factored
//! one on an engine: D, G, K once per tuple, F per wavelength — judged value by value by
//! §1's rule against the reference's RGB evaluations of the materials at the wavelengths.

use super::{
    allowed_error, combinations, f32_sensitivity, generate, spectral_materials, spectral_name,
    CheckOptions, Combination, CombinationReport, WorstCase, CONDITIONING_FACTOR, FLOOR,
    MATERIALS_PER_COMBINATION, RELATIVE_TOLERANCE,
};
use crate::backend::{Backend, Request};
use crate::error::Result;
use crate::material::presets;
use crate::spectral::Wavelengths;
use crate::spectral_eval::SpectralJob;
use crate::stats::{relative_error, ErrorStats};

/// The spectral rows of [`spectral_materials`] that `options.only` selects, after the
/// combinations of [`super::run`] (seeded after them), `progress` called after each.
pub fn run(
    backend: &mut dyn Backend,
    options: &CheckOptions,
    progress: &mut dyn FnMut(&CombinationReport),
) -> Result<Vec<CombinationReport>> {
    let after = combinations(options.seed)?.len() as u64;
    let mut reports = Vec::new();
    for (i, m) in spectral_materials().enumerate() {
        if options
            .only
            .as_deref()
            .is_none_or(|o| spectral_name(m).contains(o))
        {
            let seed = options.seed.wrapping_add(after + i as u64);
            let r = check_material(backend, m, options.tuples, seed)?;
            progress(&r);
            reports.push(r);
        }
    }
    Ok(reports)
}

/// One spectral row on `backend`, `tuples` tuples from `seed` (drawn as `check` draws a
/// combination's: around the peak, grazing, uniform). Its errors are the f(λ) values'; the
/// per-column maxima hold the largest in column 0 (f), the terms being RGB outputs.
pub fn check_material(
    backend: &mut dyn Backend,
    material: &str,
    tuples: usize,
    seed: u64,
) -> Result<CombinationReport> {
    let m = presets::preset(material).expect("a preset name")?;
    let c = Combination {
        name: spectral_name(material),
        materials: vec![m; MATERIALS_PER_COMBINATION],
        anisotropic: false,
    };
    let batch = generate(&c, tuples, seed)?;
    let job = SpectralJob::new(&c.materials, Wavelengths::cie(), None)?;
    let out = job.evaluate(backend, &batch)?;
    let mut reference = crate::reference::CpuReference::new();
    let refs = job
        .triplets()
        .iter()
        .map(|m| reference.evaluate(&batch, m, &Request::default()))
        .collect::<Result<Vec<_>>>()?;
    let w = job.wavelengths().len();
    let (mut rel, mut used) = (ErrorStats::default(), ErrorStats::default());
    let mut well_conditioned = 0f64;
    for row in 0..batch.len() {
        let tuple = batch.tuple(row);
        for (t, mats) in job.triplets().iter().enumerate() {
            let s = f32_sensitivity(&tuple, &mats[tuple.material]);
            for (j, &sj) in s.iter().enumerate().take(3.min(w - 3 * t)) {
                let l = 3 * t + j;
                let r = f64::from(refs[t].brdf[3 * row + j]);
                let x = f64::from(out.brdf[w * row + l]);
                let err = relative_error(x, r, FLOOR);
                rel.add(err, (row * w + l) as u64);
                let abs = if x.is_finite() {
                    (x - r).abs()
                } else {
                    f64::INFINITY
                };
                used.add(abs / allowed_error(r, sj), (row * w + l) as u64);
                if CONDITIONING_FACTOR * sj < RELATIVE_TOLERANCE * r.abs().max(FLOOR) {
                    well_conditioned = well_conditioned.max(err);
                }
            }
        }
    }
    let worst = used.worst.filter(|_| used.max > 0.0).map(|k| {
        let (row, l) = (k as usize / w, k as usize % w);
        let tuple = batch.tuple(row);
        let (t, j) = (l / 3, l % 3);
        let material = job.triplets()[t][tuple.material].clone();
        let reference = f64::from(refs[t].brdf[3 * row + j]);
        WorstCase {
            row,
            column: ["brdf_r", "brdf_g", "brdf_b"][j],
            value: f64::from(out.brdf[w * row + l]),
            reference,
            allowed: allowed_error(reference, f32_sensitivity(&tuple, &material)[j]),
            tuple,
            material,
        }
    });
    let (a, b) = (out.counts, refs[0].counts);
    let mut column_max = [0f64; 9];
    column_max[0] = rel.max;
    Ok(CombinationReport {
        combination: c.name,
        tuples: batch.len(),
        max_rel: rel.max,
        p99_rel: rel.p99(),
        column_max,
        max_used: used.max,
        max_rel_well_conditioned: well_conditioned,
        saturated: (a.saturated, b.saturated),
        counts_match: a.invalid == b.invalid
            && a.below_horizon == b.below_horizon
            && a.first_invalid == b.first_invalid,
        worst,
    })
}
