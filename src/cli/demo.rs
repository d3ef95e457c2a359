//! `vkbrdf demo`: the built-in default job. Every preset on seeded sample directions,
//! evaluated on the chosen backend and checked against the f64 reference on a sample; then
//! the default table set: the split-sum DFG LUT, an albedo table with its average, and a
//! slice plus preview pictures of the gold preset.

use super::backend_choice::{self, BackendArgs};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;
use vkbrdf::backend::{Backend, Request};
use vkbrdf::material::presets;

/// Arguments of `vkbrdf demo`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Example:
  vkbrdf demo --tuples 2000000")]
pub struct Args {
    /// Number of sample tuples (spread evenly over the presets), 1 to 100,000,000.
    #[arg(long, short = 'n', default_value_t = 1_000_000, allow_negative_numbers = true,
          value_parser = super::ranges::integer::<usize>(1, super::ranges::MAX_IN_MEMORY_TUPLES))]
    pub tuples: usize,
    /// Tuples per preset re-evaluated on the f64 reference for the error column, 1 to
    /// 10,000,000 (a check of nothing would pass having checked nothing).
    #[arg(long, default_value_t = 2000, allow_negative_numbers = true,
          value_parser = super::ranges::integer::<usize>(1, super::ranges::MAX_CHECK_TUPLES))]
    pub check: usize,
    /// Directory for the default table set.
    #[arg(long, default_value = "vkbrdf-out", value_name = "DIR")]
    pub out_dir: PathBuf,
    /// Skip the table set (only the preset summary).
    #[arg(long)]
    pub no_tables: bool,
    #[command(flatten)]
    pub backend: BackendArgs,
}

/// Runs `vkbrdf demo`.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    super::common::output_dir(&args.out_dir, "--out-dir")?;
    let materials = presets::all();
    let batch = vkbrdf::sample::sample_batch(args.tuples, materials.len(), 2026, false);
    let mut backend = backend_choice::open(&args.backend)?;
    // Warm-up on a small batch: compiles and caches the kernel, so the timing below is the
    // evaluation alone.
    let warm = vkbrdf::sample::sample_batch(1024, materials.len(), 1, false);
    backend.evaluate(&warm, &materials, &Request::default())?;
    let t = Instant::now();
    let out = backend.evaluate(&batch, &materials, &Request::default())?;
    let secs = t.elapsed().as_secs_f64();
    outln!(
        "{} tuples of {} presets on {}: {:.3} s ({:.1} M tuples/s); {} below the horizon, {} invalid",
        batch.len(),
        materials.len(),
        backend.name(),
        secs,
        batch.len() as f64 / secs.max(1e-9) / 1e6,
        out.counts.below_horizon,
        out.counts.invalid
    );
    if args.backend.backend.is_none() && !backend_choice::auto_choice(&args.backend.device).0 {
        beside_lavapipe(&args.backend.device, &batch, &materials, secs);
    }
    outln!(
        "{:<15} {:>9} {:>27} {:>12} {:>13}",
        "preset",
        "tuples",
        "mean f (R, G, B) 1/sr",
        "max f (G)",
        "max rel err"
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
        outln!(
            "{:<15} {:>9} {:>27} {:>12.4} {:>13.2e}",
            m.name,
            rows.len(),
            format!("({:.4}, {:.4}, {:.4})", mean[0], mean[1], mean[2]),
            max_g,
            max_rel
        );
    }
    if !args.no_tables {
        tables(backend.as_mut(), &args.out_dir)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// `auto` chose the CPU engine (no GPU): the same work on the Vulkan kernel's CPU device
/// (lavapipe), timed the same way, so the user sees what the engine choice gained. Says
/// so and moves on when no Vulkan device exists.
fn beside_lavapipe(
    device: &backend_choice::DeviceArgs,
    batch: &vkbrdf::batch::Batch,
    materials: &[vkbrdf::material::Material],
    engine_secs: f64,
) {
    let timed = || -> anyhow::Result<(String, f64)> {
        let mut v = backend_choice::open_vulkan(device)?;
        v.set_cancel(super::common::cancel());
        let warm = vkbrdf::sample::sample_batch(1024, materials.len(), 1, false);
        v.evaluate(&warm, materials, &Request::default())?;
        let t = Instant::now();
        v.evaluate(batch, materials, &Request::default())?;
        Ok((v.device_name(), t.elapsed().as_secs_f64()))
    };
    match timed() {
        Ok((name, secs)) => outln!(
            "  (no GPU, so `auto` ran the CPU engine; the same tuples on the Vulkan kernel ({name}): {:.3} s ({:.1} M tuples/s), {:.2}× the CPU engine's time)",
            secs,
            batch.len() as f64 / secs.max(1e-9) / 1e6,
            secs / engine_secs.max(1e-9)
        ),
        Err(e) => outln!("  (no GPU, so `auto` ran the CPU engine; no Vulkan device to compare with: {e:#})"),
    }
}

/// The default table set, each file timed.
fn tables(backend: &mut dyn vkbrdf::backend::Backend, dir: &std::path::Path) -> anyhow::Result<()> {
    use vkbrdf::material::Geometry;
    use vkbrdf::table::{albedo, dfg, preview, slice, Grid, Runner};
    super::common::output_dir(dir, "--out-dir")?;
    let ggx = albedo::Microfacet {
        lobe: albedo::Lobe::Ggx,
        geometry: Geometry::SmithCorrelated,
    };
    let grid = Grid {
        width: 32,
        height: 32,
    };
    let gold = presets::preset("gold").expect("listed")?;
    let dfg_job = dfg::DfgJob {
        spec: ggx,
        grid,
        samples: albedo::DEFAULT_SAMPLES,
        axes: dfg::Axes::DEFAULT,
        layout: dfg::Layout::ScaleBias,
        sampler: albedo::Sampler::Visible,
        style: None,
        half: false,
        output: dir.join("dfg.exr"),
    };
    let albedo_job = albedo::AlbedoJob {
        spec: ggx,
        grid,
        samples: albedo::DEFAULT_SAMPLES,
        axes: dfg::Axes::DEFAULT,
        half: false,
        output: dir.join("albedo.exr"),
        average: Some(dir.join("albedo-average.exr")),
    };
    let slice_job = slice::SliceJob {
        material: gold.clone(),
        grid: Grid {
            width: 90,
            height: 90,
        },
        spacing: slice::Spacing::Sqrt,
        terms: true,
        half: false,
        output: dir.join("slice-gold.exr"),
    };
    let preview_job = preview::PreviewJob {
        material: gold,
        sphere: Some(dir.join("gold-sphere.png")),
        polar: Some(dir.join("gold-polar.png")),
        size: 256,
        incidence_deg: 45.0,
        exposure: 1.0,
    };
    dfg_job.check()?;
    albedo_job.check()?;
    slice_job.check()?;
    preview_job.check()?;
    outln!("\ntables on {} (in {}):", backend.name(), dir.display());
    let mut runner = Runner::new(backend).with_progress(true);
    let t = Instant::now();
    dfg::write(&mut runner, &dfg_job)?;
    outln!(
        "  {:<32} {:>6.2} s  split-sum DFG, GGX + smith-correlated, 32×32 (R = A, G = B)",
        "dfg.exr",
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    albedo::write(&mut runner, &albedo_job)?;
    outln!(
        "  {:<32} {:>6.2} s  E(μ, α) and E_avg(α), GGX + smith-correlated, F = 1",
        "albedo.exr, albedo-average.exr",
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    slice::write_with_png(&mut runner, &slice_job, Some(&dir.join("slice-gold.png")))?;
    outln!(
        "  {:<32} {:>6.2} s  gold, f(θ_h, θ_d) at φ_d = 90°, 90×90, with terms, and as a picture",
        "slice-gold.exr, slice-gold.png",
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    preview::write(&mut runner, &preview_job)?;
    outln!(
        "  {:<32} {:>6.2} s  gold: lit sphere and polar lobe at 45°",
        "gold-sphere.png, gold-polar.png",
        t.elapsed().as_secs_f64()
    );
    Ok(())
}
