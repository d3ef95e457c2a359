//! `vkbrdf bench`: the throughput report (table, JSON, SVG plots), peers in the same run.

use super::backend_choice::{open_vulkan, DeviceArgs};
use super::bandwidth::{print_bandwidth, BandwidthRow};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::process::ExitCode;
use vkbrdf::backend::Request;
use vkbrdf::bench::{self, peers, plot, scenarios, stages, ResultRow};
use vkbrdf::directions::SliceGrid;
use vkbrdf::features::FeatureSet;
use vkbrdf::gpu::VulkanBackend;
use vkbrdf::precision::Precision;
use vkbrdf::reference::CpuReference;

/// Arguments of `vkbrdf bench`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Measures, in one run: every scenario on Vulkan (end to end and kernel-only), on the native
CPU engine (backend `cpu`) and on the f64 reference (backend `reference`, `cpu` before the
engine existed; the JSON's schema_version is 2 since) at batch sizes 1e3 … 1e7; max relative error against the f64 reference; the
specialised kernel against the all-features one and (one material) against the kernel with
the material folded in as specialization constants, with its error; the sustained kernel rate on 1e8 tuples
(1e7 on a CPU device) against a device copy kernel moving the same bytes; the DFG table
at 128 × 128 × 1024 samples; and the peers on the same directions — Mitsuba 3's LLVM
backend and NumPy (benches/peers/peer.py; run benches/peers/install.sh once, else they are
reported as skipped), PyTorch eager and torch.compile on the GPU where python3 has torch
with CUDA, and the memory-copy ceiling.

Kernel-only times have the tuples resident in device-local memory and are read from device
timestamps around the dispatches (docs/THROUGHPUT.md says why).

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
    /// Tuples per sustained-kernel and device-copy timing (repeated dispatches over
    /// resident rows), 1e3 to 1e11; default 1e8 on a GPU, 1e7 on a CPU device (--quick: a
    /// tenth).
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          value_parser = super::ranges::integer::<usize>(1_000, 100_000_000_000))]
    pub sustained_tuples: Option<usize>,
    /// Only these scenarios (repeatable); default all.
    #[arg(long)]
    pub scenario: Vec<String>,
    /// Skip the external peers.
    #[arg(long)]
    pub no_peers: bool,
    /// Skip the CPU engine and reference rows (the device check on a GPU machine: its time
    /// is short).
    #[arg(long)]
    pub no_cpu: bool,
    /// Path of benches/peers/peer.py.
    #[arg(long, value_name = "PATH")]
    pub peers_script: Option<PathBuf>,
    /// Tuples of the streamed-eval stage table (read, engine, upload, kernel, readback,
    /// write and file-to-file end to end per engine), 1e3 to 1e9; default 2^22 (--quick:
    /// 2^20). The file goes to the temporary directory ($TMPDIR).
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          value_parser = super::ranges::integer::<usize>(1_000, 1_000_000_000))]
    pub stage_tuples: Option<usize>,
    /// Run only the equal-bytes comparison with Mitsuba (the CPU engine on the local form
    /// held as six columns, as Dr.Jit holds them, against Mitsuba's roughconductor on the
    /// same wi/wo, 4,194,304 and 262,144 tuples; 1 → 2 threads; Lambert against a copy of
    /// its bytes).
    #[arg(long)]
    pub equal_bytes_only: bool,
    /// Interleaved engine/Mitsuba pairs per equal-bytes point, 1 to 50: each rate is the
    /// median over the pairs and the ratio the median of the pairs' ratios (docs/ publish
    /// medians of 5: Dr.Jit's rate swings 2× between runs on a shared machine)
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=50))]
    pub pairs: u16,
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// The bench JSON's schema: 2 since the backend names became `vulkan`, `cpu` (the native
/// engine) and `reference` (the f64 judge; `cpu` in schema 1).
const SCHEMA_VERSION: u32 = 2;

#[derive(serde::Serialize)]
struct Report {
    schema_version: u32,
    device: String,
    results: Vec<ResultRow>,
    bandwidth: Vec<BandwidthRow>,
    stages: Vec<stages::StageRow>,
    peers: Vec<peers::PeerRow>,
    equal_bytes: Vec<bench::equal::EqualBytesRow>,
}

/// Runs `vkbrdf bench`.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    if let Some(path) = &args.json {
        vkbrdf::atomic::check_outputs(&[path.as_path()], &[])?;
    }
    if let Some(dir) = &args.plot {
        super::common::output_dir(dir, "--plot")?;
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
    let script = args
        .peers_script
        .clone()
        .unwrap_or_else(peers::default_script);
    let equal_sizes = if args.quick {
        [1 << 20, 1 << 16]
    } else {
        [1 << 22, 1 << 18]
    };
    if args.equal_bytes_only {
        let pairs = usize::from(args.pairs);
        let rows = bench::equal::rows(
            &script,
            &equal_sizes,
            repeats,
            args.no_peers,
            pairs,
            &mut |m| eprintln!("{m} …"),
        )?;
        outln!("{}", bench::equal::table(&rows));
        if let Some(path) = &args.json {
            let doc = serde_json::json!({
                "schema_version": SCHEMA_VERSION,
                "device": format!("cpu ({})", vkbrdf::cpu::instruction_set()),
                "equal_bytes": rows,
            });
            let text = serde_json::to_string_pretty(&doc)?;
            vkbrdf::atomic::write(path, |w| std::io::Write::write_all(w, text.as_bytes()))?;
            eprintln!("wrote {}", path.display());
        }
        return Ok(ExitCode::SUCCESS);
    }
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
    let mut engine = vkbrdf::backend_choice::cpu_engine()?;
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
            super::common::progress_message(&bar, format!("{} × {n}", sc.name));
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
            if !args.no_cpu {
                let (secs, out) =
                    bench::time_end_to_end(&mut engine, &batch, &sc.materials, repeats)?;
                let err = bench::max_rel_err(&batch, &sc.materials, &out.brdf, sample);
                results.push(row("cpu", sc.name, "end-to-end", "exact", n, secs, err));
            }
            if n <= cpu_max && !args.no_cpu {
                let (secs, out) =
                    bench::time_end_to_end(&mut cpu, &batch, &sc.materials, repeats.min(3))?;
                let err = bench::max_rel_err(&batch, &sc.materials, &out.brdf, sample);
                results.push(row(
                    "reference",
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
    let mut bandwidth = Vec::new();
    if let Some(v) = vulkan.as_mut() {
        let sustained = args.sustained_tuples.unwrap_or_else(|| {
            let base = if v.is_cpu_device() {
                10_000_000
            } else {
                100_000_000
            };
            if args.quick {
                base / 10
            } else {
                base
            }
        });
        bandwidth = sustained_rows(v, &list, *sizes.last().expect("sizes"), sustained, repeats)?;
        results.push(dfg_row(v, repeats)?);
    }
    let stage_rows = stage_rows(args, &list, vulkan.as_mut(), &mut engine, repeats)?;
    let mut peer_rows = Vec::new();
    for sc in list.iter().filter(|s| s.peer.is_some()) {
        let batch = scenarios::batch(sc, peer_n, 42);
        let ps = sc.peer.expect("filtered");
        for peer in ["mitsuba", "numpy", "torch", "torch-compile"] {
            if args.no_peers {
                peer_rows.push(peers::PeerRow {
                    name: peer.into(),
                    scenario: ps.into(),
                    tuples: peer_n,
                    evals_per_s: None,
                    skipped: Some("--no-peers".into()),
                    brdf: None,
                    max_rel_err: None,
                });
            } else {
                eprintln!("peer {peer} {ps} on {peer_n} tuples …");
                let mut r = peers::run(&script, peer, ps, &batch, repeats);
                if let Some(f) = r.brdf.take() {
                    r.max_rel_err = Some(bench::max_rel_err(&batch, &sc.materials, &f, 20_000));
                }
                peer_rows.push(r);
            }
        }
    }
    peer_rows.push(peers::PeerRow {
        name: "memcpy".into(),
        scenario: "10 floats in, 3 out".into(),
        tuples: peer_n,
        evals_per_s: Some(bench::memcpy_ceiling(peer_n, 10, repeats)),
        skipped: None,
        brdf: None,
        max_rel_err: None,
    });
    if !args.no_peers {
        // The GPU's own copy ceiling as PyTorch sees it (skipped without torch + CUDA).
        let batch = scenarios::batch(&list[0], peer_n, 42);
        eprintln!("peer torch-copy on {peer_n} tuples …");
        let mut r = peers::run(&script, "torch-copy", "beckmann", &batch, repeats);
        r.scenario = "52 B/tuple copied".into(); // not a BRDF: no ratio row
        peer_rows.push(r);
    }
    let equal_bytes = if args.no_cpu {
        Vec::new()
    } else {
        bench::equal::rows(
            &script,
            &equal_sizes,
            repeats,
            args.no_peers,
            usize::from(args.pairs),
            &mut |m| eprintln!("{m} …"),
        )?
    };
    print_report(&results, &peer_rows, &list);
    print_bandwidth(&bandwidth, &peer_rows);
    stages::print(&stage_rows);
    if !equal_bytes.is_empty() {
        outln!("\n{}", bench::equal::table(&equal_bytes));
    }
    let report = Report {
        schema_version: SCHEMA_VERSION,
        device,
        results,
        bandwidth,
        stages: stage_rows,
        peers: peer_rows,
        equal_bytes,
    };
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&report)?;
        vkbrdf::atomic::write(path, |w| std::io::Write::write_all(w, text.as_bytes()))?;
        eprintln!("wrote {}", path.display());
    }
    if let Some(dir) = &args.plot {
        super::common::output_dir(dir, "--plot")?;
        plot::throughput(
            &dir.join("throughput.svg"),
            &report
                .results
                .iter()
                .filter(|r| {
                    !["specialised", "all-features", "folded"].contains(&r.precision.as_str())
                })
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
                            .filter(|&n| r.backend != "reference" || n <= cpu_max)
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

/// The streamed-eval stage table: Lambert (memory-bound) and the Mitsuba GGX scenario
/// (compute-bound) when selected, else the first scenario; on each engine (the Vulkan
/// kernel with its sub-stages; the CPU engine unless `--no-cpu`), at the default memory
/// budget of `eval`.
fn stage_rows(
    args: &Args,
    list: &[scenarios::Scenario],
    mut vulkan: Option<&mut VulkanBackend>,
    engine: &mut vkbrdf::cpu::CpuEngine,
    repeats: usize,
) -> anyhow::Result<Vec<stages::StageRow>> {
    let n = args
        .stage_tuples
        .unwrap_or(if args.quick { 1 << 20 } else { 1 << 22 });
    let mut chosen: Vec<&scenarios::Scenario> = list
        .iter()
        .filter(|s| s.name == "lambert" || s.name == "mitsuba-ggx")
        .collect();
    if chosen.is_empty() {
        chosen.push(&list[0]);
    }
    let dir = tempfile::Builder::new()
        .prefix("vkbrdf-bench-stages")
        .tempdir()?;
    let budget = vkbrdf::stream::DEFAULT_MAX_MEMORY;
    let repeats = repeats.min(5);
    let mut rows = Vec::new();
    for sc in chosen {
        eprintln!("stages {} on {n} tuples …", sc.name);
        let batch = scenarios::batch(sc, n, 42);
        let mut engines = Vec::new();
        if let Some(v) = vulkan.as_deref_mut() {
            engines.push(stages::Engine::Vulkan(v));
        }
        if !args.no_cpu {
            engines.push(stages::Engine::Any(&mut *engine));
        }
        for e in engines {
            let (b, m) = (&batch, &sc.materials);
            rows.push(stages::measure(
                e,
                sc.name,
                b,
                m,
                dir.path(),
                budget,
                repeats,
            )?);
        }
    }
    Ok(rows)
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
        super::common::progress_message(bar, format!("{} fast", sc.name));
        let (secs, out) = bench::time_end_to_end(v, &batch, fast, repeats)?;
        let err = bench::max_rel_err(&batch, &sc.materials, &out.brdf, 20_000);
        results.push(row("vulkan", sc.name, "end-to-end", "fast", n, secs, err));
    }
    // The half/difference slice of the scenario's material over a square grid of `n`
    // texels, directions made on the device: end to end (only the material goes in) once.
    let table = match sc.materials.as_slice() {
        [material] => {
            super::common::progress_message(bar, format!("{} table kernel", sc.name));
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
    super::common::progress_message(bar, format!("{} kernels side by side", sc.name));
    let mut best = [f64::INFINITY; 5]; // specialised, all-features, table, fast, folded

    // One material: the kernel with it folded in (specialization constants) whatever the
    // batch's size, and that kernel's error.
    let folded_err = if let [m] = sc.materials.as_slice() {
        let usual = v.set_fold_material_min_tuples(0);
        let out = vkbrdf::backend::Backend::evaluate(v, &batch, std::slice::from_ref(m), &request);
        v.set_fold_material_min_tuples(usual);
        Some(bench::max_rel_err(
            &batch,
            &sc.materials,
            &out?.brdf,
            20_000,
        ))
    } else {
        None
    };
    for _ in 0..rounds {
        if folded_err.is_some() {
            let usual = v.set_fold_material_min_tuples(0);
            let t = v.kernel_seconds(&batch, &sc.materials, &request, repeats);
            v.set_fold_material_min_tuples(usual);
            best[4] = best[4].min(t?);
        }
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
    if let Some(err) = folded_err {
        results.push(row("vulkan", sc.name, "kernel", "folded", n, best[4], err));
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

/// The sustained kernel of each scenario on `total` tuples (resident rows: the batch of
/// `resident` tuples, as far as the device's limits allow), and the copy kernel for the same
/// row width, timed alternately so that drift hits both alike.
fn sustained_rows(
    v: &mut VulkanBackend,
    list: &[scenarios::Scenario],
    resident: usize,
    total: usize,
    repeats: usize,
) -> anyhow::Result<Vec<BandwidthRow>> {
    let bar = ProgressBar::new(list.len() as u64).with_style(
        ProgressStyle::with_template("sustained [{bar:30}] {pos}/{len} {msg} ({elapsed})")
            .expect("valid template"),
    );
    let repeats = repeats.min(5);
    let mut rows = Vec::new();
    for sc in list {
        super::common::progress_message(&bar, format!("{} × {total}", sc.name));
        let batch = scenarios::batch(sc, resident.min(total).min(v.resident_capacity(13)), 42);
        let k = v.kernel_timing(
            &batch,
            &sc.materials,
            &Request::default(),
            total,
            repeats,
            FeatureSet::EMPTY,
        )?;
        let c = v.copy_timing(batch.columns(), k.resident_tuples, total, repeats)?;
        let kernel_bytes = total as f64 * k.bytes_per_tuple as f64 / k.seconds;
        let copy_bytes = total as f64 * c.bytes_per_tuple as f64 / c.seconds;
        rows.push(BandwidthRow {
            scenario: sc.name.into(),
            tuples: total,
            resident_tuples: k.resident_tuples,
            bytes_per_tuple: k.bytes_per_tuple,
            clock: k.clock,
            kernel_evals_per_s: total as f64 / k.seconds,
            kernel_bytes_per_s: kernel_bytes,
            copy_bytes_per_s: copy_bytes,
            fraction_of_copy: kernel_bytes / copy_bytes,
        });
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(rows)
}

/// The DFG table integrated on the device (importance-sampled directions made by the
/// kernel): 128 × 128 points × 1024 samples, GGX + smith-correlated, F = 1, end to end.
fn dfg_row(v: &mut VulkanBackend, repeats: usize) -> anyhow::Result<ResultRow> {
    use vkbrdf::table::albedo::{backend_sums, grid_points, Lobe, Microfacet};
    let spec = Microfacet {
        lobe: Lobe::Ggx,
        geometry: vkbrdf::material::Geometry::SmithCorrelated,
    };
    let points = grid_points(vkbrdf::table::Grid::new(128, 128)?)?;
    let samples = 1024;
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
    Ok(row(
        "vulkan",
        "dfg-128x128x1024",
        "table-e2e",
        "exact",
        evals,
        bench::median(secs),
        f64::NAN,
    ))
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
        "{:<26} {:<9} {:<11} {:<13} {:>9} {:>12} {:>11}",
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
            "{:<26} {:<9} {:<11} {:<13} {:>9} {:>12.2} {:>11.2e}",
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
                "  {:<13} {:<20} {:>9} tuples {:>10.2} M evals/s{}",
                p.name,
                p.scenario,
                p.tuples,
                v / 1e6,
                p.max_rel_err
                    .map_or(String::new(), |e| format!("   max rel err {e:.2e}"))
            ),
            (None, Some(why)) => outln!("  {:<13} {:<20} skipped: {why}", p.name, p.scenario),
            _ => {}
        }
    }
    outln!("\nratios, vkbrdf over peer (same BRDF, same batch size):");
    for sc in list.iter().filter(|s| s.peer.is_some()) {
        for p in peers
            .iter()
            .filter(|p| Some(p.scenario.as_str()) == sc.peer)
        {
            let Some(pv) = p.evals_per_s else { continue };
            for (backend, mode) in [
                ("vulkan", "kernel"),
                ("vulkan", "end-to-end"),
                ("vulkan", "table-kernel"),
                ("vulkan", "table-e2e"),
                ("cpu", "end-to-end"),
            ] {
                if let Some(r) = results.iter().rfind(|r| {
                    r.backend == backend
                        && r.scenario == sc.name
                        && r.mode == mode
                        && r.precision == "exact"
                        && r.tuples == p.tuples
                }) {
                    outln!(
                        "  {:<18} vs {:<13} {:<6} {:<11} {:.2}×",
                        sc.name,
                        p.name,
                        backend,
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
