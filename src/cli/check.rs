//! `vkbrdf check`: the conformance table — every legal material combination evaluated on
//! the Vulkan backend (or `--backend cpu`, the native engine) and compared with the f64
//! reference ([`vkbrdf::check`]).

use std::process::ExitCode;
use std::time::Instant;
use vkbrdf::backend::Backend;
use vkbrdf::check::{self, CheckOptions, CombinationReport};
use vkbrdf::gpu::{DeviceSelector, VulkanBackend, VulkanOptions};

/// Arguments of `vkbrdf check`.
#[derive(clap::Args, Debug, Clone)]
#[command(after_help = "\
Every legal combination of model, distribution, geometry, Fresnel term, convention and
anisotropy (315, the HTSG model among them), and measured (MERL) materials with each lookup (merl nearest, merl
linear: two analytic materials exported to MERL in memory; skipped, with the reason, on a
device without 64-bit floats), is evaluated on seeded random tuples (random lengths, cos_i and cos_o at
least 1e-3, roughness at least 0.01, exponents up to 20000) and compared with the f64 CPU
reference, value by value: the RGB BRDF and the terms D, G, F_r, F_g, F_b, K.

Columns: max rel and p99 rel are |x - ref| / max(|ref|, 1e-6). A value passes when
  |x - ref| <= 1e-5 * max(|ref|, 1e-6) + 4 * S,
where S is how much the exact value moves when the inputs and the unit vectors derived
from them are perturbed by one f32 rounding: 1e-5 relative where f32 inputs determine the
value well, more only near grazing mirror geometry with sharp lobes, where no f32
evaluation can do better. `tol used` is the largest |x - ref| / allowed (1 = at the limit).
Failing combinations are followed by their worst tuple (inputs and material).

--backend cpu checks the native CPU engine instead of the Vulkan kernel (auto: the one
`--backend auto` picks on the evaluating commands; reference: the judge against itself).

Exit status: 0 every combination passes, 1 some fail (or --validation reported a
message), 2 error (no Vulkan device, bad arguments).

Examples:
  vkbrdf check                               # 2000 tuples per combination
  vkbrdf check --tuples 20000 --seed 7       # a longer run with other random draws
  vkbrdf check --filter ggx-aniso --verbose  # one family, worst tuple of each
  vkbrdf check --device llvmpipe --validation
  vkbrdf check --backend cpu                 # the native CPU engine")]
pub struct Args {
    /// Vulkan device: an index or part of a name from `vkbrdf devices` (default: a GPU if
    /// present, else lavapipe; the environment variable VKBRDF_DEVICE does the same).
    #[arg(long, value_name = "NAME|INDEX")]
    pub device: Option<DeviceSelector>,
    /// Random tuples per combination, 1 to 10,000,000.
    #[arg(long, value_name = "N", default_value_t = 2000, allow_negative_numbers = true,
          value_parser = super::ranges::integer::<usize>(1, super::ranges::MAX_CHECK_TUPLES))]
    pub tuples: usize,
    /// Seed of the random materials and tuples, 0 to 2^64 − 1 (the same seed gives the
    /// same table).
    #[arg(long, default_value_t = 1, allow_negative_numbers = true,
          value_parser = super::ranges::integer::<u64>(0, u64::MAX))]
    pub seed: u64,
    /// Only the combinations whose name contains this text, e.g. `ward`, `ggx-aniso`,
    /// `seed beckmann`.
    #[arg(long, value_name = "TEXT")]
    pub filter: Option<String>,
    /// Print the worst tuple of every combination, not only of failing ones.
    #[arg(long)]
    pub verbose: bool,
    /// Engine to check: `vulkan` (default), `cpu` (the native CPU engine), `auto` or
    /// `reference`.
    #[arg(long, value_enum)]
    pub backend: Option<super::backend_choice::BackendKind>,
    /// Run with the Vulkan validation layer and fail if it reports any warning or error
    /// (also enabled by VKBRDF_VALIDATION=1).
    #[arg(long)]
    pub validation: bool,
    /// Print the summary as JSON on standard output (every combination's figures, the
    /// skipped ones, the totals); the table goes to standard error.
    #[arg(long)]
    pub json: bool,
}

/// Runs `vkbrdf check`.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    use super::backend_choice::{auto_choice, BackendKind, DeviceArgs};
    let options = VulkanOptions {
        validation: args.validation || vkbrdf::gpu::validation_from_env(),
        ..VulkanOptions::default()
    };
    let device_args = DeviceArgs {
        device: args.device.clone(),
        ..DeviceArgs::default()
    };
    let vulkan = match args.backend.unwrap_or(BackendKind::Vulkan) {
        BackendKind::Vulkan => true,
        BackendKind::Auto => auto_choice(&device_args).0,
        BackendKind::Cpu | BackendKind::Reference => false,
    };
    let (mut gpu, counter): (Box<dyn Backend>, _) = if vulkan {
        let g = VulkanBackend::new(args.device.clone(), options)?;
        let c = g.validation_counter();
        (Box::new(g), Some(c))
    } else if args.backend == Some(BackendKind::Reference) {
        (Box::new(vkbrdf::reference::CpuReference::new()), None)
    } else {
        (Box::new(vkbrdf::backend_choice::cpu_engine()?), None)
    };
    let check_options = CheckOptions {
        tuples: args.tuples,
        seed: args.seed,
        only: args.filter.clone(),
    };
    // With --json the prose goes to standard error, the JSON alone to standard output.
    let json = args.json;
    let say = |line: String| {
        if json {
            eprintln!("{line}");
        } else {
            outln!("{line}");
        }
    };
    let backend_name = gpu.name();
    say(format!("backend:   {backend_name}"));
    say("reference: cpu-reference (f64)".into());
    say(format!("tolerance: {}", check::tolerance()));
    say(String::new());
    say(CombinationReport::header());
    let t0 = Instant::now();
    let verbose = args.verbose;
    let mut done = 0usize;
    let mut row = |r: &CombinationReport| {
        done += 1;
        super::common::set_status(format!(
            "{done} combinations done, the last {}",
            r.combination
        ));
        say(r.row());
        if verbose || !r.pass() {
            if let Some(w) = &r.worst {
                say(w.to_string());
            }
        }
    };
    super::common::set_status("preparing the kernels (a first run compiles them)");
    let (mut reports, skipped) = check::run_with_skips(gpu.as_mut(), &check_options, &mut row)?;
    // Then the spectral rows (FORMULAS.md §9): the spectral presets at 95 wavelengths.
    reports.extend(check::spectral::run(
        gpu.as_mut(),
        &check_options,
        &mut row,
    )?);
    let elapsed = t0.elapsed().as_secs_f64();
    drop(gpu);
    for (name, why) in &skipped {
        say(format!("{name:<54} skipped: {why}"));
    }
    if reports.is_empty() && skipped.is_empty() {
        anyhow::bail!("--filter {:?} matches no combination (names look like `cook-torrance modern ggx-aniso smith conductor`)", args.filter.as_deref().unwrap_or(""));
    }
    let failed = reports.iter().filter(|r| !r.pass()).count();
    let saturated = reports
        .iter()
        .fold((0, 0), |(a, b), r| (a + r.saturated.0, b + r.saturated.1));
    let max_rel = reports.iter().map(|r| r.max_rel).fold(0.0, f64::max);
    let max_used = reports.iter().map(|r| r.max_used).fold(0.0, f64::max);
    let well = reports
        .iter()
        .map(|r| r.max_rel_well_conditioned)
        .fold(0.0, f64::max);
    say(String::new());
    let skipped_note = if skipped.is_empty() {
        String::new()
    } else {
        format!(", {} skipped", skipped.len())
    };
    say(format!(
        "{} combinations × {} tuples in {elapsed:.1} s: {} pass, {failed} fail{skipped_note}; most tolerance used {max_used:.3}",
        reports.len(),
        args.tuples,
        reports.len() - failed
    ));
    say(format!(
        "saturated tuples (an output beyond f32::MAX, stored as f32::MAX): {} (reference {})",
        saturated.0, saturated.1
    ));
    say(format!("largest relative error {max_rel:.2e} overall, {well:.2e} where f32 inputs determine the value well"));
    let messages = counter.as_ref().map_or(0, |c| c.count());
    if let Some(counter) = counter.as_ref().filter(|_| messages > 0) {
        say(format!(
            "validation layer: {messages} warning(s)/error(s); the first:\n{}",
            counter.messages().join("\n")
        ));
    }
    if json {
        let combinations: Vec<serde_json::Value> = reports
            .iter()
            .map(|r| {
                serde_json::json!({
                    "name": r.combination,
                    "tuples": r.tuples,
                    "pass": r.pass(),
                    "max_rel": r.max_rel,
                    "p99_rel": r.p99_rel,
                    "column_max_rel": check::COLUMNS.iter().zip(r.column_max)
                        .map(|(c, x)| (c.to_string(), serde_json::json!(x)))
                        .collect::<serde_json::Map<_, _>>(),
                    "tolerance_used": r.max_used,
                    "max_rel_well_conditioned": r.max_rel_well_conditioned,
                    "counts_match": r.counts_match,
                    "saturated": {"backend": r.saturated.0, "reference": r.saturated.1},
                    "worst": r.worst.as_ref().map(|w| serde_json::json!({
                        "row": w.row,
                        "column": w.column,
                        "value": w.value,
                        "reference": w.reference,
                        "allowed": w.allowed,
                        "material": w.material.name,
                    })),
                })
            })
            .collect();
        let doc = serde_json::json!({
            "backend": backend_name,
            "reference": "cpu-reference (f64)",
            "tolerance": check::tolerance(),
            "tuples_per_combination": args.tuples,
            "seed": args.seed,
            "seconds": elapsed,
            "combinations": combinations,
            "skipped": skipped.iter().map(|(name, why)| serde_json::json!({
                "name": name, "reason": why,
            })).collect::<Vec<_>>(),
            "passed": reports.len() - failed,
            "failed": failed,
            "saturated": {"backend": saturated.0, "reference": saturated.1},
            "max_rel": max_rel,
            "max_rel_well_conditioned": well,
            "most_tolerance_used": max_used,
            "validation_messages": messages,
            "ok": failed == 0 && messages == 0,
        });
        outln!("{}", serde_json::to_string_pretty(&doc)?);
    }
    Ok(if failed == 0 && messages == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}
