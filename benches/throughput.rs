//! Criterion benchmarks (seeded inputs): every backend on the benchmark scenarios at batch
//! sizes from 1e3 to 1e7 tuples — end to end (host arrays in, host arrays out) on both
//! backends (the CPU reference up to 1e5: it is the judge, not a contender), and
//! kernel-only on Vulkan (tuples resident on the device, dispatch + wait timed, as
//! `VulkanBackend::kernel_seconds` measures it). `vkbrdf bench` is the user-facing report
//! (peers, errors, plots); this file keeps the same measurements under criterion.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::time::Duration;
use vkbrdf::backend::{Backend, Request};
use vkbrdf::bench::scenarios;
use vkbrdf::gpu::{VulkanBackend, VulkanOptions};
use vkbrdf::reference::CpuReference;

fn throughput(c: &mut Criterion) {
    let mut backends: Vec<(&str, Box<dyn Backend>)> = vec![("cpu", Box::new(CpuReference::new()))];
    match VulkanBackend::new(None, VulkanOptions::default()) {
        Ok(v) => backends.push(("vulkan", Box::new(v))),
        Err(e) => eprintln!("no Vulkan device, benchmarking the CPU only: {e}"),
    }
    // A second backend for the kernel-only figures (its own resident buffers).
    let mut kernel = VulkanBackend::new(None, VulkanOptions::default()).ok();
    for scenario in scenarios::all() {
        let mut group = c.benchmark_group(scenario.name);
        group.sample_size(10);
        for &n in &[1_000usize, 10_000, 100_000, 1_000_000, 10_000_000] {
            let batch = scenarios::batch(&scenario, n, 42);
            group.throughput(Throughput::Elements(n as u64));
            for (name, backend) in backends.iter_mut() {
                if *name == "cpu" && n > 100_000 {
                    continue;
                }
                group.bench_with_input(BenchmarkId::new(*name, n), &batch, |b, batch| {
                    b.iter(|| {
                        backend
                            .evaluate(batch, &scenario.materials, &Request::default())
                            .expect("evaluate")
                    })
                });
            }
            if let Some(v) = kernel.as_mut() {
                group.bench_with_input(BenchmarkId::new("vulkan-kernel", n), &batch, |b, batch| {
                    b.iter_custom(|iters| {
                        let median = v
                            .kernel_seconds(
                                batch,
                                &scenario.materials,
                                &Request::default(),
                                iters as usize,
                            )
                            .expect("kernel timing");
                        Duration::from_secs_f64(median * iters as f64)
                    })
                });
            }
        }
        group.finish();
    }
}

criterion_group!(benches, throughput);
criterion_main!(benches);
