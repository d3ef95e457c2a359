//! Times the native CPU engine on the benchmark scenarios, variants interleaved round by
//! round (the machine is shared and noisy), with the largest relative error against the f64
//! reference and cycles per evaluation (time × the TSC frequency, read from /proc/cpuinfo).
//!
//! `cargo run --release --example cpu_engine_time -- [--with-peers] [--local-only] [TUPLES] [SCENARIO…]`
//! (default 4,194,304 tuples; lambert, mitsuba-beckmann, mitsuba-ggx). Variants:
//! - `rows fresh`: `evaluate` on 10-column rows, new output vectors every call;
//! - `rows reused`: `evaluate_into` the previous call's output;
//! - `local reused`: `evaluate_local_into` on the 6-column local form (N = +z);
//! - `columns reused`: `evaluate_columns_into` on the same L and V as two `(n, 3)` columns
//!   and N = (0, 0, 1) given once (the same 24 bytes a tuple, structure of arrays as
//!   Mitsuba's `wi`/`wo`);
//!
//! (`--local-only`: the local form on one thread's CPU time alone, for quick A/B rounds)
//! each on one thread as the calling thread's CPU time (/proc/thread-self/schedstat, which
//! other processes do not inflate) and on 1 and 2 threads as wall time (best round).
//! `--with-peers` adds the Vulkan kernel (lavapipe: `VK_DRIVER_FILES=…/lvp_icd.json`) and
//! the reference, as before.

use std::time::Instant;
use vkbrdf::backend::{Backend, Output, Request};
use vkbrdf::batch::columns::ColumnBatch;
use vkbrdf::bench::scenarios;
use vkbrdf::cpu::CpuEngine;
use vkbrdf::gpu::{DeviceSelector, VulkanBackend, VulkanOptions};
use vkbrdf::reference::CpuReference;

/// The clock in Hz from /proc/cpuinfo's "cpu MHz" (the TSC rate on this VM), if it says.
fn tsc_hz() -> Option<f64> {
    let info = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("cpu MHz"))?;
    let mhz = line.split(':').nth(1)?.trim();
    mhz.parse::<f64>().ok().map(|m| m * 1e6)
}

/// CPU time of the calling thread in seconds (/proc/thread-self/schedstat: nanoseconds
/// on the CPU), which other processes sharing the machine do not inflate.
fn thread_cpu() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| {
            s.split_whitespace()
                .next()
                .and_then(|x| x.parse::<f64>().ok())
        })
        .map_or(0.0, |ns| ns * 1e-9)
}

#[derive(Clone, Copy, PartialEq)]
enum Form {
    RowsFresh,
    RowsReused,
    LocalReused,
    ColumnsReused,
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let peers = args.iter().any(|a| a == "--with-peers");
    let local_only = args.iter().any(|a| a == "--local-only");
    args.retain(|a| a != "--with-peers" && a != "--local-only");
    let n: usize = args
        .first()
        .and_then(|a| a.parse().ok())
        .unwrap_or(4_194_304);
    let mut names: Vec<String> = args.iter().skip(1).cloned().collect();
    if names.is_empty() {
        names = ["lambert", "mitsuba-beckmann", "mitsuba-ggx"]
            .map(String::from)
            .to_vec();
    }
    let hz = tsc_hz();
    let mut vulkan = peers
        .then(|| VulkanBackend::new(DeviceSelector::from_env(), VulkanOptions::default()).ok())
        .flatten();
    println!(
        "instruction set: {}, clock {:?} GHz, {n} tuples; best round of interleaved variants",
        vkbrdf::cpu::instruction_set(),
        hz.map(|h| h / 1e9)
    );
    println!(
        "{:<18} {:<34} {:>12} {:>10} {:>12}",
        "scenario", "engine", "M evals/s", "cyc/eval", "max rel err"
    );
    for name in names {
        let s = scenarios::by_name(&name).unwrap_or_else(|| panic!("no scenario {name}"));
        let batch = scenarios::batch(&s, n, 42);
        let local = scenarios::local_batch(&s, n, 42);
        let req = Request::default();
        let reference = CpuReference::new()
            .evaluate(&batch, &s.materials, &req)
            .expect("reference");
        let report = |label: &str, secs: f64, out: &[f32]| {
            let err = out
                .iter()
                .zip(&reference.brdf)
                .map(|(&x, &r)| (f64::from(x) - f64::from(r)).abs() / f64::from(r).abs().max(1e-6))
                .fold(0.0, f64::max);
            let cyc = hz.map_or(String::from("-"), |h| format!("{:.1}", secs * h / n as f64));
            println!(
                "{:<18} {:<34} {:>12.1} {:>10} {:>12.2e}",
                name,
                label,
                n as f64 / secs / 1e6,
                cyc,
                err
            );
        };
        let mut forms = vec![Form::RowsFresh, Form::RowsReused];
        if local_only && local.is_some() {
            forms = vec![Form::LocalReused];
        } else if local.is_some() {
            forms.push(Form::LocalReused);
            forms.push(Form::ColumnsReused);
        }
        // The local form's L and V as two columns, N given once.
        let (cl, cv): (Vec<f32>, Vec<f32>) = match &local {
            Some(b) => {
                let rows = b.as_slice().chunks_exact(6);
                (
                    rows.clone().flat_map(|r| r[..3].to_vec()).collect(),
                    rows.flat_map(|r| r[3..].to_vec()).collect(),
                )
            }
            None => (Vec::new(), Vec::new()),
        };
        let z = [0.0f32, 0.0, 1.0];
        let m = [local.as_ref().map_or(0.0, |b| b.material() as f32)];
        let columns = local.as_ref().map(|_| {
            ColumnBatch::new(
                [&cl, &cv, &z],
                None,
                &m,
                n,
                &s.materials,
                std::path::Path::new("columns"),
            )
            .expect("columns")
        });
        let label = |f: Form| match f {
            Form::RowsFresh => "rows fresh",
            Form::RowsReused => "rows reused",
            Form::LocalReused => "local reused",
            Form::ColumnsReused => "columns reused",
        };
        // (form, threads, CPU time?) → best seconds per call, and the last output.
        let mut variants: Vec<(Form, usize, bool, f64, Output, CpuEngine)> = Vec::new();
        for &f in &forms {
            variants.push((
                f,
                1,
                true,
                f64::INFINITY,
                Output::default(),
                CpuEngine::with_threads(1),
            ));
            for threads in [1, 2].into_iter().filter(|_| !local_only) {
                variants.push((
                    f,
                    threads,
                    false,
                    f64::INFINITY,
                    Output::default(),
                    CpuEngine::with_threads(threads),
                ));
            }
        }
        // CPU time advances at scheduler ticks: a round of one variant is enough calls for
        // ~0.2 s of work.
        let reps = (8_000_000 / n).clamp(1, 200);
        for _round in 0..5 {
            for (f, _, cpu, best, out, e) in variants.iter_mut() {
                let (t, c) = (Instant::now(), thread_cpu());
                for _ in 0..reps {
                    match f {
                        Form::RowsFresh => {
                            *out = e.evaluate(&batch, &s.materials, &req).expect("engine")
                        }
                        Form::RowsReused => e
                            .evaluate_into(&batch, &s.materials, &req, out)
                            .expect("engine"),
                        Form::LocalReused => e
                            .evaluate_local_into(
                                local.as_ref().expect("local"),
                                &s.materials,
                                &req,
                                out,
                            )
                            .expect("engine"),
                        Form::ColumnsReused => e
                            .evaluate_columns_into(
                                columns.as_ref().expect("columns"),
                                &s.materials,
                                &req,
                                out,
                            )
                            .expect("engine"),
                    }
                }
                let secs = if *cpu {
                    thread_cpu() - c
                } else {
                    t.elapsed().as_secs_f64()
                };
                *best = best.min(secs / reps as f64);
            }
        }
        for (f, threads, cpu, best, out, _) in &variants {
            let l = if *cpu {
                format!("cpu {}, 1 thread, CPU time", label(*f))
            } else {
                format!("cpu {}, {threads} thread(s), wall", label(*f))
            };
            report(&l, *best, &out.brdf);
        }
        if let Some(v) = vulkan.as_mut() {
            let mut out = Vec::new();
            let mut best = f64::INFINITY;
            for _ in 0..3 {
                let t = Instant::now();
                out = v.evaluate(&batch, &s.materials, &req).expect("vulkan").brdf;
                best = best.min(t.elapsed().as_secs_f64());
            }
            report("vulkan end-to-end", best, &out);
            let k = v
                .kernel_seconds(&batch, &s.materials, &req, 3)
                .expect("kernel time");
            report("vulkan kernel-only", k, &out);
        }
        if peers {
            let mut r = CpuReference::new();
            let t = Instant::now();
            let out = r.evaluate(&batch, &s.materials, &req).expect("ref").brdf;
            report("reference, 2 threads", t.elapsed().as_secs_f64(), &out);
        }
    }
}
