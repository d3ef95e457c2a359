//! `vkbrdf stress`: the adversarial corpus on one or more backends, judged against the f64
//! reference; exit 1 when the policy (finite outputs, agreeing counts, zero rejects) fails.

use super::backend_choice::{self, BackendArgs, BackendKind, DeviceArgs};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `vkbrdf stress`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
The corpus crosses extreme materials (every parameter at the bounds the materials parser
accepts: roughness 1e-7 … 1e4, exponents to 1e24, IOR 1e-6 … 1e18, extinction to 1e18,
colours and weights to 1e18) with grazing angles from 1e-8, cosines down to the smallest
positive float32 (1e-20, 1e-30, 1e-38, 1e-45), exact normal incidence, the specular peak,
L = −V, backfacing, vector lengths 1e-20 … 1e20, zero, NaN, Inf and denormal components,
and tangents parallel to N. Outputs beyond float32's largest value are stored as it and
counted as saturated; the policy: no inf or NaN, and invalid and saturated counts equal to
the reference's.

Examples:
  vkbrdf stress --tuples 200000                  # Vulkan and the CPU reference
  vkbrdf stress --tuples 10000000 --backend vulkan --backend cpu --report stress.md")]
pub struct Args {
    /// Number of corpus tuples per backend.
    #[arg(long, short = 'n', default_value_t = 1_000_000)]
    pub tuples: usize,
    /// Backends to stress (repeat the flag for several).
    #[arg(long, value_enum)]
    pub backend: Vec<BackendKind>,
    /// Corpus seed.
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
    /// Write the Markdown report here (atomically).
    #[arg(long, value_name = "FILE.md")]
    pub report: Option<PathBuf>,
    /// Relative-error target marked in the table.
    #[arg(long, default_value_t = 1e-5)]
    pub target: f64,
    /// Tuples per evaluation call (bounds memory).
    #[arg(long, default_value_t = 1 << 20)]
    pub chunk: usize,
    /// Precision variant the backend evaluates (judged against the exact reference).
    #[arg(long, value_enum, default_value = "exact")]
    pub precision: super::eval::PrecisionArg,
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// Runs `vkbrdf stress`.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let kinds = if args.backend.is_empty() {
        vec![BackendKind::Cpu]
    } else {
        args.backend.clone()
    };
    let mut md = String::from("## Stress report\n\n");
    let mut ok = true;
    for kind in kinds {
        let mut backend = backend_choice::open(&BackendArgs {
            backend: Some(kind),
            device: args.device.clone(),
        })?;
        let bar = ProgressBar::new(args.tuples as u64).with_style(
            ProgressStyle::with_template(
                "{msg} [{bar:30}] {pos}/{len} tuples, {elapsed} (eta {eta})",
            )
            .expect("valid template"),
        );
        bar.set_message(format!("stress {}", backend.name()));
        let report = vkbrdf::stress::run_with(
            backend.as_mut(),
            args.precision.into(),
            args.tuples,
            args.seed,
            args.chunk,
            &mut |done| bar.set_position(done as u64),
        )?;
        bar.finish_and_clear();
        let section = report.to_markdown(args.target);
        println!("{section}");
        md += &section;
        md += "\n";
        if !report.policy_holds() {
            ok = false;
            eprintln!("stress: the policy fails on {}", report.backend);
        }
    }
    if let Some(path) = &args.report {
        vkbrdf::atomic::write(path, |w| std::io::Write::write_all(w, md.as_bytes()))?;
    }
    Ok(if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}
