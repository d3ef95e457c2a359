//! A batch mixing one material per `check` combination, uniformly shuffled, against the same
//! tuples sorted by material: the "mixed within 2× of sorted" measurement of the CPU-engine
//! and kernel issues. Each engine evaluates both forms in interleaved rounds (the machine is
//! shared and noisy); the median of each form is printed, and the ratio.
//!
//! `cargo run --release --example mixed_batch -- [TUPLES] [ROUNDS]` (default 2,000,000
//! tuples with tangents, 3 rounds); the Vulkan rows need a device (lavapipe:
//! `VK_DRIVER_FILES=/usr/share/vulkan/icd.d/lvp_icd.json`).

use rand::seq::SliceRandom;
use rand::SeedableRng;
use std::time::Instant;
use vkbrdf::backend::{Backend, Request};
use vkbrdf::batch::Batch;
use vkbrdf::cpu::CpuEngine;
use vkbrdf::gpu::{DeviceSelector, VulkanBackend, VulkanOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args.first().map_or(Ok(2_000_000), |s| s.parse())?;
    let rounds: usize = args.get(1).map_or(Ok(3), |s| s.parse())?;
    let materials: Vec<_> = vkbrdf::check::combinations(1)?
        .into_iter()
        .map(|c| c.materials[0].clone())
        .collect();
    let count = materials.len();
    let base = vkbrdf::sample::sample_batch(n, count, 1, true);
    let columns = base.columns();
    let rows: Vec<&[f32]> = base.as_slice().chunks_exact(columns).collect();
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut rand_pcg::Pcg64Mcg::seed_from_u64(7));
    let gather = |order: &[usize]| -> Vec<f32> {
        order
            .iter()
            .flat_map(|&i| rows[i].iter().copied())
            .collect()
    };
    let source = std::path::Path::new("mixed");
    let mixed = Batch::new(gather(&order), columns, count, source)?;
    order.sort_by_key(|&i| rows[i][9] as usize); // stable: each material's rows in order
    let sorted = Batch::new(gather(&order), columns, count, source)?;
    println!("{n} tuples, {count} materials (one per check combination), tangents");
    let mut engines: Vec<Box<dyn Backend>> = vec![Box::new(CpuEngine::new())];
    match VulkanBackend::new(DeviceSelector::from_env(), VulkanOptions::default()) {
        Ok(v) => engines.push(Box::new(v)),
        Err(e) => println!("(no Vulkan row: {e})"),
    }
    let request = Request::default();
    for engine in &mut engines {
        // Warm: kernels compiled, pools started, pages faulted in.
        engine.evaluate(&mixed, &materials, &request)?;
        engine.evaluate(&sorted, &materials, &request)?;
        let (mut m, mut s) = (Vec::new(), Vec::new());
        for _ in 0..rounds {
            for (batch, times) in [(&mixed, &mut m), (&sorted, &mut s)] {
                let t = Instant::now();
                engine.evaluate(batch, &materials, &request)?;
                times.push(t.elapsed().as_secs_f64());
            }
        }
        let (m, s) = (vkbrdf::stats::median(m), vkbrdf::stats::median(s));
        println!(
            "  {:<44} mixed {:7.3} s ({:6.1} M/s)  sorted {:7.3} s ({:6.1} M/s)  mixed/sorted time {:.2}",
            engine.name(),
            m,
            n as f64 / m / 1e6,
            s,
            n as f64 / s / 1e6,
            m / s
        );
    }
    Ok(())
}
