//! Times the native CPU engine on the benchmark scenarios, 1 and 2 threads, beside the f64
//! reference, with the largest relative error against the reference and cycles per
//! evaluation (time × the TSC frequency, read from /proc/cpuinfo when it says).
//!
//! `cargo run --release --example cpu_engine_time -- [TUPLES] [SCENARIO…]`; with a Vulkan
//! device (lavapipe: `VK_DRIVER_FILES=/usr/share/vulkan/icd.d/lvp_icd.json`) the kernel's
//! end-to-end and kernel-only rates too.
//! (default 4,194,304 tuples; lambert, mitsuba-beckmann, mitsuba-ggx).

use std::time::Instant;
use vkbrdf::backend::{Backend, Request};
use vkbrdf::bench::scenarios;
use vkbrdf::cpu::CpuEngine;
use vkbrdf::gpu::{DeviceSelector, VulkanBackend, VulkanOptions};
use vkbrdf::reference::CpuReference;

fn best_of(reps: usize, f: &mut dyn FnMut()) -> f64 {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

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

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
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
    // The Vulkan kernel beside it when a device opens (lavapipe: VK_DRIVER_FILES=…/lvp_icd.json).
    let mut vulkan = VulkanBackend::new(DeviceSelector::from_env(), VulkanOptions::default()).ok();
    println!("instruction set: {}, clock {:?} GHz, {n} tuples; M evals/s from wall time (best of 5) unless marked CPU time", vkbrdf::cpu::instruction_set(), hz.map(|h| h / 1e9));
    println!(
        "{:<18} {:<22} {:>12} {:>10} {:>12}",
        "scenario", "engine", "M evals/s", "cyc/eval", "max rel err"
    );
    for name in names {
        let s = scenarios::by_name(&name).unwrap_or_else(|| panic!("no scenario {name}"));
        let batch = scenarios::batch(&s, n, 42);
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
                "{:<18} {:<22} {:>12.1} {:>10} {:>12.2e}",
                name,
                label,
                n as f64 / secs / 1e6,
                cyc,
                err
            );
        };
        {
            // One thread runs on this thread: its CPU time, not the wall clock.
            let mut e = CpuEngine::with_threads(1);
            let mut out = Vec::new();
            // The mean over enough calls for ~1 s of work: schedstat advances at scheduler
            // ticks, too coarsely for one short call.
            let reps = (40_000_000 / n).clamp(5, 400);
            let t = thread_cpu();
            for _ in 0..reps {
                out = e.evaluate(&batch, &s.materials, &req).expect("engine").brdf;
            }
            report(
                "cpu, 1 thread, CPU time",
                (thread_cpu() - t) / reps as f64,
                &out,
            );
        }
        for threads in [1, 2] {
            let mut e = CpuEngine::with_threads(threads);
            let mut out = Vec::new();
            let secs = best_of(5, &mut || {
                out = e.evaluate(&batch, &s.materials, &req).expect("engine").brdf
            });
            report(&format!("cpu, {threads} thread(s)"), secs, &out);
        }
        if let Some(v) = vulkan.as_mut() {
            let mut out = Vec::new();
            let secs = best_of(3, &mut || {
                out = v.evaluate(&batch, &s.materials, &req).expect("vulkan").brdf
            });
            report("vulkan end-to-end", secs, &out);
            let k = v
                .kernel_seconds(&batch, &s.materials, &req, 3)
                .expect("kernel time");
            report("vulkan kernel-only", k, &out);
        }
        let mut r = CpuReference::new();
        let mut out = Vec::new();
        let secs = best_of(2, &mut || {
            out = r.evaluate(&batch, &s.materials, &req).expect("ref").brdf
        });
        report("reference, 2 threads", secs, &out);
    }
}
