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
accepts: roughness 1e-7 … 1e4, exponents to 1e18, IOR 1e-6 … 1e18, extinction to 1e18,
colours and weights to 1e18) with grazing angles from 1e-8, cosines down to the smallest
positive float32 (1e-20, 1e-30, 1e-38, 1e-45), exact normal incidence, the specular peak,
L = −V, backfacing, vector lengths 1e-20 … 1e20, zero, NaN, Inf and denormal components,
and tangents parallel to N. Outputs beyond float32's largest value are stored as it and
counted as saturated; the policy: no inf or NaN, and invalid and saturated counts equal to
the reference's.

Examples:
  vkbrdf stress --tuples 200000                  # Vulkan, the CPU engine, the reference
  vkbrdf stress --tuples 10000000 --backend cpu --backend vulkan --report stress.md

`--backend cpu` is the native CPU engine; the f64 reference is `--backend reference` (it
was `cpu` before the engine existed).")]
pub struct Args {
    /// Number of corpus tuples per backend, 1 to 10^10 (evaluated in chunks).
    #[arg(long, short = 'n', default_value_t = 1_000_000, allow_negative_numbers = true,
          value_parser = super::ranges::integer::<usize>(1, super::ranges::MAX_STRESS_TUPLES))]
    pub tuples: usize,
    /// Backends to stress (repeat the flag for several).
    #[arg(long, value_enum)]
    pub backend: Vec<BackendKind>,
    /// Corpus seed, 0 to 2^64 − 1.
    #[arg(long, default_value_t = 7, allow_negative_numbers = true,
          value_parser = super::ranges::integer::<u64>(0, u64::MAX))]
    pub seed: u64,
    /// Write the Markdown report here (atomically).
    #[arg(long, value_name = "FILE.md")]
    pub report: Option<PathBuf>,
    /// Relative-error target marked in the table, in (0, 1].
    #[arg(long, default_value_t = 1e-5, allow_negative_numbers = true,
          value_parser = super::ranges::real(0.0, 1.0, true, false))]
    pub target: f64,
    /// Tuples per evaluation call (bounds memory), 1 to 2^26.
    #[arg(long, default_value_t = 1 << 20, allow_negative_numbers = true,
          value_parser = super::ranges::integer::<usize>(1, 1 << 26))]
    pub chunk: usize,
    /// Precision variant the backend evaluates (judged against the exact reference).
    #[arg(long, value_enum, default_value = "exact")]
    pub precision: super::eval::PrecisionArg,
    #[command(flatten)]
    pub device: DeviceArgs,
    /// Print the summary as JSON on standard output (per backend: the counts, the policy,
    /// the error per quantity and regime); the Markdown goes to standard error.
    #[arg(long)]
    pub json: bool,
}

/// Runs `vkbrdf stress`.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    if let Some(path) = &args.report {
        vkbrdf::atomic::check_outputs(&[path.as_path()], &[])?;
    }
    let open = |kind| {
        backend_choice::open(&BackendArgs {
            backend: Some(kind),
            device: args.device.clone(),
        })
    };
    // Default: every backend this machine has — the Vulkan kernel when a device opens,
    // the native CPU engine, and the reference (which judges itself against its own
    // invariants).
    let backends = if args.backend.is_empty() {
        let mut list = Vec::new();
        match open(BackendKind::Vulkan) {
            Ok(b) => list.push(b),
            Err(e) => eprintln!(
                "note: stressing the CPU engine and the reference only: no Vulkan device ({e:#})"
            ),
        }
        list.push(open(BackendKind::Cpu)?);
        list.push(open(BackendKind::Reference)?);
        list
    } else {
        args.backend
            .iter()
            .map(|&k| open(k))
            .collect::<anyhow::Result<Vec<_>>>()?
    };
    let mut md = String::from("## Stress report\n\n");
    let mut ok = true;
    let mut json = Vec::new();
    for mut backend in backends {
        let bar = ProgressBar::new(args.tuples as u64).with_style(
            ProgressStyle::with_template(
                "{msg} [{bar:30}] {pos}/{len} tuples, {elapsed} (eta {eta})",
            )
            .expect("valid template"),
        );
        super::common::progress_message(&bar, format!("stress {}", backend.name()));
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
        if args.json {
            eprintln!("{section}");
            json.push(report_json(&report, args.target));
        } else {
            outln!("{section}");
        }
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
    if args.json {
        let doc = serde_json::json!({
            "tuples": args.tuples,
            "seed": args.seed,
            "precision": format!("{:?}", args.precision).to_lowercase(),
            "target": args.target,
            "backends": json,
            "ok": ok,
        });
        outln!("{}", serde_json::to_string_pretty(&doc)?);
    }
    Ok(if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// One backend's stress report as JSON: the counts beside the reference's, the policy, and
/// the relative error (max, p99, count, and whether within `target`) per quantity and
/// regime.
fn report_json(r: &vkbrdf::stress::StressReport, target: f64) -> serde_json::Value {
    let pair = |(backend, reference): (u64, u64)| serde_json::json!({"backend": backend, "reference": reference});
    let errors: Vec<serde_json::Value> = r
        .errors
        .iter()
        .map(|((quantity, regime), e)| {
            serde_json::json!({
                "quantity": quantity,
                "regime": regime.label(),
                "values": e.count,
                "max_rel": e.max,
                "p99_rel": e.p99(),
                "within_target": e.max <= target,
            })
        })
        .collect();
    serde_json::json!({
        "backend": r.backend,
        "tuples": r.tuples,
        "non_finite": r.non_finite,
        "invalid": pair(r.invalid),
        "below_horizon": pair(r.below_horizon),
        "saturated": pair(r.saturated),
        "exact": r.exact,
        "nonzero_rejects": r.nonzero_rejects,
        "ambiguous_horizon": r.ambiguous_horizon,
        "policy_holds": r.policy_holds(),
        "errors": errors,
    })
}
