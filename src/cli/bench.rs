//! `vkbrdf bench`: the throughput report (table, JSON, SVG plots), peers in the same run.

use super::backend_choice::{open_vulkan, DeviceArgs};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::process::ExitCode;
use vkbrdf::backend::Request;
use vkbrdf::bench::{self, peers, plot, scenarios, ResultRow};
use vkbrdf::directions::SliceGrid;
use vkbrdf::features::FeatureSet;
use vkbrdf::gpu::VulkanBackend;
use vkbrdf::precision::Precision;
use vkbrdf::reference::CpuReference;

/// Arguments of `vkbrdf bench`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Measures, in one run: every scenario on Vulkan (end to end and kernel-only) and on the CPU
reference at batch sizes 1e3 … 1e7; max relative error against the f64 reference; the
specialised kernel against the all-features one; and the peers on the same directions —
Mitsuba 3's LLVM backend and NumPy (benches/peers/peer.py; run benches/peers/install.sh
once, else they are reported as skipped) and the memory-copy ceiling.

Examples:
  vkbrdf bench --quick                                  # under a minute
  vkbrdf bench --json bench.json --plot plots/")]
pub struct Args {
    /// Small sizes and few repeats (under a minute; CI runs it).
    #[arg(long)]
    pub quick: bool,
    /// Write the results as JSON here.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Write SVG plots into this directory.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Timed repeats per point (median reported), 1 to 1000.
    #[arg(long, allow_negative_numbers = true,
          value_parser = super::ranges::integer::<usize>(1, 1000))]
    pub repeats: Option<usize>,
    /// Only these scenarios (repeatable); default all.
    #[arg(long)]
    pub scenario: Vec<String>,
    /// Skip the external peers.
    #[arg(long)]
    pub no_peers: bool,
    /// Path of benches/peers/peer.py.
    #[arg(long, value_name = "PATH")]
    pub peers_script: Option<PathBuf>,
    #[command(flatten)]
    pub device: DeviceArgs,
}

#[derive(serde::Serialize)]
struct Report {
    device: String,
    results: Vec<ResultRow>,
    peers: Vec<peers::PeerRow>,
}

/// Runs `vkbrdf bench`.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    if let Some(path) = &args.json {
        vkbrdf::atomic::check_outputs(&[path.as_path()], &[])?;
    }
    let sizes: Vec<usize> = if args.quick {
        vec![1_000, 10_000, 100_000, 1 << 20]
    } else {
        vec![1_000, 10_000, 100_000, 1_000_000, 1 << 22, 10_000_000]
    };
    let cpu_max = if args.quick { 100_000 } else { 1_000_000 };
    let peer_n = if args.quick { 1 << 20 } else { 1 << 22 };
    // The specialisation, precision and peer comparisons run at `peer_n`, which the size
    // loop also measures: their exact rows are the ones to compare against.
    debug_assert!(sizes.contains(&peer_n));
    let repeats = args.repeats.unwrap_or(if args.quick { 3 } else { 7 });
    let mut list = scenarios::all();
    if !args.scenario.is_empty() {
        list.retain(|s| args.scenario.iter().any(|n| n == s.name));
        anyhow::ensure!(
            !list.is_empty(),
            "no scenario named {:?}; the scenarios are: {}",
            args.scenario,
            scenarios::all()
                .iter()
                .map(|s| s.name)
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let mut vulkan = match open_vulkan(&args.device) {
        Ok(v) => Some(v),
        Err(e) => {
            eprintln!("note: no Vulkan device ({e:#}); benchmarking the CPU reference only");
            None
        }
    };
    let mut cpu = CpuReference::new();
    let device = vulkan
        .as_ref()
        .map_or("none".to_string(), |v| v.device_name());
    let steps = list.len() * sizes.len() + list.len();
    let bar = ProgressBar::new(steps as u64).with_style(
        ProgressStyle::with_template("bench [{bar:30}] {pos}/{len} {msg} ({elapsed})")
            .expect("valid template"),
    );
    let mut results = Vec::new();
    for sc in &list {
        for &n in &sizes {
            bar.set_message(format!("{} × {n}", sc.name));
            let batch = scenarios::batch(sc, n, 42);
            let sample = 20_000;
            if let Some(v) = vulkan.as_mut() {
                let (secs, out) = bench::time_end_to_end(v, &batch, &sc.materials, repeats)?;
                let err = bench::max_rel_err(&batch, &sc.materials, &out.brdf, sample);
                results.push(row("vulkan", sc.name, "end-to-end", "exact", n, secs, err));
                let ksecs =
                    v.kernel_seconds(&batch, &sc.materials, &Request::default(), repeats)?;
                results.push(row("vulkan", sc.name, "kernel", "exact", n, ksecs, err));
            }
            if n <= cpu_max {
                let (secs, out) =
                    bench::time_end_to_end(&mut cpu, &batch, &sc.materials, repeats.min(3))?;
                let err = bench::max_rel_err(&batch, &sc.materials, &out.brdf, sample);
                results.push(row(
                    "cpu",
                    sc.name,
                    "end-to-end",
                    "f64 reference",
                    n,
                    secs,
                    err,
                ));
            }
            bar.inc(1);
        }
        if let Some(v) = vulkan.as_mut() {
            let rounds = if args.quick { 1 } else { 3 };
            compare_kernels(v, sc, peer_n, repeats, rounds, &bar, &mut results)?;
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    // The DFG table integrated on the device (importance-sampled directions made by the
    // kernel): evaluations per second of a 32×32 table, GGX + smith-correlated, F = 1.
    if let Some(v) = vulkan.as_mut() {
        use vkbrdf::table::albedo::{backend_sums, grid_points, Lobe, Microfacet};
        let spec = Microfacet {
            lobe: Lobe::Ggx,
            geometry: vkbrdf::material::Geometry::SmithCorrelated,
        };
        let points = grid_points(vkbrdf::table::Grid::new(32, 32)?);
        let samples = if args.quick { 1 << 12 } else { 1 << 16 };
        let mut runner = vkbrdf::table::Runner::new(v);
        let mut secs = Vec::new();
        for _ in 0..=repeats.min(3) {
            let t = std::time::Instant::now();
            backend_sums(&mut runner, &spec, &points, samples, "dfg")
                .expect("the Vulkan backend integrates on the device")?;
            secs.push(t.elapsed().as_secs_f64());
        }
        secs.remove(0); // compiles the kernel
        let evals = points.len() * samples as usize;
        let row = row(
            "vulkan",
            "dfg-table-ggx",
            "table-e2e",
            "exact",
            evals,
            bench::median(secs),
            f64::NAN,
        );
        results.push(row);
    }
    let mut peer_rows = Vec::new();
    let script = args
        .peers_script
        .clone()
        .unwrap_or_else(peers::default_script);
    for sc in list.iter().filter(|s| s.peer.is_some()) {
        let batch = scenarios::batch(sc, peer_n, 42);
        let ps = sc.peer.expect("filtered");
        for peer in ["mitsuba", "numpy"] {
            if args.no_peers {
                peer_rows.push(peers::PeerRow {
                    name: peer.into(),
                    scenario: ps.into(),
                    tuples: peer_n,
                    evals_per_s: None,
                    skipped: Some("--no-peers".into()),
                });
            } else {
                eprintln!("peer {peer} {ps} on {peer_n} tuples …");
                peer_rows.push(peers::run(&script, peer, ps, &batch, repeats));
            }
        }
    }
    peer_rows.push(peers::PeerRow {
        name: "memcpy".into(),
        scenario: "10 floats in, 3 out".into(),
        tuples: peer_n,
        evals_per_s: Some(bench::memcpy_ceiling(peer_n, 10, repeats)),
        skipped: None,
    });
    print_report(&results, &peer_rows, &list);
    let report = Report {
        device,
        results,
        peers: peer_rows,
    };
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&report)?;
        vkbrdf::atomic::write(path, |w| std::io::Write::write_all(w, text.as_bytes()))?;
        eprintln!("wrote {}", path.display());
    }
    if let Some(dir) = &args.plot {
        std::fs::create_dir_all(dir)?;
        plot::throughput(
            &dir.join("throughput.svg"),
            &report
                .results
                .iter()
                .filter(|r| r.precision != "specialised" && r.precision != "all-features")
                .cloned()
                .collect::<Vec<_>>(),
        )?;
        let largest: Vec<ResultRow> = report
            .results
            .iter()
            .filter(|r| {
                r.max_rel_err.is_finite()
                    && r.tuples
                        == sizes
                            .iter()
                            .copied()
                            .filter(|&n| r.backend != "cpu" || n <= cpu_max)
                            .max()
                            .unwrap_or(0)
            })
            .cloned()
            .collect();
        plot::pareto(&dir.join("pareto.svg"), &largest)?;
        plot::specialisation(
            &dir.join("specialisation.svg"),
            &report
                .results
                .iter()
                .filter(|r| r.precision == "specialised" || r.precision == "all-features")
                .cloned()
                .collect::<Vec<_>>(),
        )?;
        eprintln!(
            "wrote throughput.svg, pareto.svg, specialisation.svg in {}",
            dir.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The side-by-side kernel comparisons of one scenario at `n` tuples: specialised against
/// all-features, the fast variant against exact, and (single-material scenarios) the
/// table kernel that makes its own directions against the kernel reading tuples. The
/// kernels are timed in `rounds` interleaved rounds and each keeps its fastest median, so
/// that the machine's drift (±30 % between minutes here) hits every variant alike. The
/// end-to-end and error figures of the fast variant and of the table are measured once.
fn compare_kernels(
    v: &mut VulkanBackend,
    sc: &scenarios::Scenario,
    n: usize,
    repeats: usize,
    rounds: usize,
    bar: &ProgressBar,
    results: &mut Vec<ResultRow>,
) -> anyhow::Result<()> {
    let batch = scenarios::batch(sc, n, 42);
    let request = Request::default();
    // The fast variant on the same batch (same size, same seed) as the exact rows the size
    // loop measured, judged against the exact reference: the run-time/error chart's points.
    let fast = vkbrdf::precision::apply_all(&sc.materials, Precision::Fast);
    let fast = (fast != sc.materials).then_some(fast);
    if let Some(fast) = &fast {
        bar.set_message(format!("{} fast", sc.name));
        let (secs, out) = bench::time_end_to_end(v, &batch, fast, repeats)?;
        let err = bench::max_rel_err(&batch, &sc.materials, &out.brdf, 20_000);
        results.push(row("vulkan", sc.name, "end-to-end", "fast", n, secs, err));
    }
    // The half/difference slice of the scenario's material over a square grid of `n`
    // texels, directions made on the device: end to end (only the material goes in) once.
    let table = match sc.materials.as_slice() {
        [material] => {
            bar.set_message(format!("{} table kernel", sc.name));
            let side = (n as f64).sqrt().round() as u32;
            let grid = SliceGrid {
                width: side,
                height: side,
                linear: false,
            };
            let mut out = v.half_diff_slice(material, grid, &request)?;
            let mut secs = Vec::new();
            for _ in 0..repeats {
                let t = std::time::Instant::now();
                out = v.half_diff_slice(material, grid, &request)?;
                secs.push(t.elapsed().as_secs_f64());
            }
            let err = bench::slice_max_rel_err(material, grid, &out.brdf, 20_000);
            let texels = grid.texels() as usize;
            let e2e = bench::median(secs);
            results.push(row(
                "vulkan",
                sc.name,
                "table-e2e",
                "exact",
                texels,
                e2e,
                err,
            ));
            Some((material, grid, err))
        }
        _ => None,
    };
    bar.set_message(format!("{} kernels side by side", sc.name));
    let mut best = [f64::INFINITY; 4]; // specialised, all-features, table, fast
    for _ in 0..rounds {
        let t = v.kernel_seconds(&batch, &sc.materials, &request, repeats)?;
        best[0] = best[0].min(t);
        let t = v.kernel_seconds_with_features(
            &batch,
            &sc.materials,
            &request,
            repeats,
            FeatureSet::all(),
        )?;
        best[1] = best[1].min(t);
        if let Some((material, grid, _)) = table {
            best[2] = best[2].min(v.half_diff_kernel_seconds(material, grid, repeats)?);
        }
        if let Some(fast) = &fast {
            best[3] = best[3].min(v.kernel_seconds(&batch, fast, &request, repeats)?);
        }
    }
    results.push(row(
        "vulkan",
        sc.name,
        "kernel",
        "specialised",
        n,
        best[0],
        f64::NAN,
    ));
    results.push(row(
        "vulkan",
        sc.name,
        "kernel",
        "all-features",
        n,
        best[1],
        f64::NAN,
    ));
    if let Some((_, grid, err)) = table {
        let texels = grid.texels() as usize;
        results.push(row(
            "vulkan",
            sc.name,
            "table-kernel",
            "exact",
            texels,
            best[2],
            err,
        ));
    }
    if fast.is_some() {
        let err = results
            .iter()
            .rfind(|r| r.scenario == sc.name && r.precision == "fast")
            .map_or(f64::NAN, |r| r.max_rel_err);
        results.push(row("vulkan", sc.name, "kernel", "fast", n, best[3], err));
    }
    Ok(())
}

fn row(
    backend: &str,
    scenario: &str,
    mode: &str,
    precision: &str,
    tuples: usize,
    secs: f64,
    err: f64,
) -> ResultRow {
    ResultRow {
        backend: backend.into(),
        scenario: scenario.into(),
        mode: mode.into(),
        precision: precision.into(),
        tuples,
        evals_per_s: tuples as f64 / secs.max(1e-12),
        seconds_median: secs,
        max_rel_err: err,
    }
}

fn print_report(results: &[ResultRow], peers: &[peers::PeerRow], list: &[scenarios::Scenario]) {
    outln!(
        "{:<26} {:<7} {:<11} {:<13} {:>9} {:>12} {:>11}",
        "scenario",
        "backend",
        "mode",
        "variant",
        "tuples",
        "M evals/s",
        "max rel err"
    );
    for r in results {
        outln!(
            "{:<26} {:<7} {:<11} {:<13} {:>9} {:>12.2} {:>11.2e}",
            r.scenario,
            r.backend,
            r.mode,
            r.precision,
            r.tuples,
            r.evals_per_s / 1e6,
            r.max_rel_err
        );
    }
    outln!("\npeers (same directions, same run):");
    for p in peers {
        match (p.evals_per_s, &p.skipped) {
            (Some(v), _) => outln!(
                "  {:<8} {:<20} {:>9} tuples {:>10.2} M evals/s",
                p.name,
                p.scenario,
                p.tuples,
                v / 1e6
            ),
            (None, Some(why)) => outln!("  {:<8} {:<20} skipped: {why}", p.name, p.scenario),
            _ => {}
        }
    }
    outln!("\nratios, Vulkan over peer (same BRDF, same batch size):");
    for sc in list.iter().filter(|s| s.peer.is_some()) {
        for p in peers
            .iter()
            .filter(|p| Some(p.scenario.as_str()) == sc.peer)
        {
            let Some(pv) = p.evals_per_s else { continue };
            for mode in ["kernel", "end-to-end", "table-kernel", "table-e2e"] {
                if let Some(r) = results.iter().rfind(|r| {
                    r.backend == "vulkan"
                        && r.scenario == sc.name
                        && r.mode == mode
                        && r.precision == "exact"
                        && r.tuples == p.tuples
                }) {
                    outln!(
                        "  {:<18} vs {:<8} {:<11} {:.2}×",
                        sc.name,
                        p.name,
                        mode,
                        r.evals_per_s / pv
                    );
                }
            }
        }
    }
    if let Some((m, n)) = peers
        .iter()
        .find(|p| p.name == "memcpy")
        .and_then(|p| p.evals_per_s.map(|v| (v, p.tuples)))
    {
        if let Some(r) = results.iter().rfind(|r| {
            r.backend == "vulkan"
                && r.scenario == "lambert"
                && r.mode == "kernel"
                && r.precision == "exact"
                && r.tuples == n
        }) {
            outln!(
                "  lambert kernel vs memory-copy ceiling: {:.0} %",
                100.0 * r.evals_per_s / m
            );
        }
    }
}
