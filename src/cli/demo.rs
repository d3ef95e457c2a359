//! `vkbrdf demo`: the built-in default job. Every preset on seeded sample directions,
//! evaluated on the chosen backend and checked against the f64 reference on a sample.

use super::backend_choice::{self, BackendArgs};
use std::process::ExitCode;
use std::time::Instant;
use vkbrdf::backend::Request;
use vkbrdf::material::presets;

/// Arguments of `vkbrdf demo`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Example:
  vkbrdf demo --tuples 2000000")]
pub struct Args {
    /// Number of sample tuples (spread evenly over the presets).
    #[arg(long, short = 'n', default_value_t = 1_000_000)]
    pub tuples: usize,
    /// Tuples per preset re-evaluated on the f64 reference for the error column.
    #[arg(long, default_value_t = 2000)]
    pub check: usize,
    #[command(flatten)]
    pub backend: BackendArgs,
}

/// Runs `vkbrdf demo`.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let materials = presets::all();
    let batch = vkbrdf::sample::sample_batch(args.tuples, materials.len(), 2026, false);
    let mut backend = backend_choice::open(&args.backend)?;
    let t = Instant::now();
    let out = backend.evaluate(&batch, &materials, &Request::default())?;
    let secs = t.elapsed().as_secs_f64();
    println!(
        "{} tuples of {} presets on {}: {:.3} s ({:.1} M tuples/s); {} below the horizon, {} invalid",
        batch.len(),
        materials.len(),
        backend.name(),
        secs,
        batch.len() as f64 / secs.max(1e-9) / 1e6,
        out.counts.below_horizon,
        out.counts.invalid
    );
    println!(
        "{:<15} {:>9} {:>27} {:>12} {:>13}",
        "preset", "tuples", "mean f (R, G, B) 1/sr", "max f (G)", "max rel err"
    );
    for (mi, m) in materials.iter().enumerate() {
        let rows: Vec<usize> = (0..batch.len())
            .filter(|&i| batch.material(i) == mi)
            .collect();
        let mut mean = [0f64; 3];
        let mut max_g = 0f64;
        for &i in &rows {
            for (c, m) in mean.iter_mut().enumerate() {
                *m += out.brdf[3 * i + c] as f64 / rows.len() as f64;
            }
            max_g = max_g.max(out.brdf[3 * i + 1] as f64);
        }
        let mut max_rel = 0f64;
        for &i in rows.iter().take(args.check) {
            let r = vkbrdf::reference::evaluate_tuple(&batch.tuple(i), m);
            for c in 0..3 {
                let rel =
                    (out.brdf[3 * i + c] as f64 - r.brdf[c]).abs() / r.brdf[c].abs().max(1e-6);
                max_rel = max_rel.max(rel);
            }
        }
        println!(
            "{:<15} {:>9} {:>27} {:>12.4} {:>13.2e}",
            m.name,
            rows.len(),
            format!("({:.4}, {:.4}, {:.4})", mean[0], mean[1], mean[2]),
            max_g,
            max_rel
        );
    }
    Ok(ExitCode::SUCCESS)
}
