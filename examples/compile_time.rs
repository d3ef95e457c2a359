//! Profiling aid: where a one-shot evaluation's time goes — shaderc's GLSL → SPIR-V, the
//! driver's pipeline creation, and the evaluation itself — for a batch of `TUPLES` tuples
//! (default 1,000,000) of the mixed materials file in docs/MATERIALS.md, or of gold.
//! Usage: cargo run --release --example compile_time -- [MATERIALS.toml] [TUPLES]
use std::time::Instant;
use vkbrdf::backend::{Backend, Request};
use vkbrdf::features::FeatureSet;
use vkbrdf::gpu::{VulkanBackend, VulkanOptions};

fn main() -> vkbrdf::Result<()> {
    let mut args = std::env::args().skip(1);
    let materials = match args.next() {
        Some(path) => {
            let text = std::fs::read_to_string(&path).expect("readable materials file");
            vkbrdf::material::parse_materials(&text, &path).expect("valid materials")
        }
        None => vec![vkbrdf::material::presets::preset("gold").unwrap()?],
    };
    let n = args
        .next()
        .and_then(|a| a.parse().ok())
        .unwrap_or(1_000_000);
    let tangents = materials.iter().any(|m| m.is_anisotropic());
    let batch = vkbrdf::sample::sample_batch(n, materials.len(), 1, tangents);
    let request = Request { terms: true };
    let features = FeatureSet::of_batch(&batch, &materials, &request);
    let t = Instant::now();
    vkbrdf::gpu::kernel::compile_kernel(features, true)?;
    let compile = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let mut gpu = VulkanBackend::new(None, VulkanOptions::default())?;
    let open = t.elapsed().as_secs_f64();
    let mut times = Vec::new();
    for _ in 0..3 {
        let t = Instant::now();
        gpu.evaluate(&batch, &materials, &request)?;
        times.push(t.elapsed().as_secs_f64());
    }
    println!(
        "{n} tuples, {} materials: shaderc alone {compile:.3} s; device open {open:.3} s; evaluate 1st {:.3} s (with shaderc + pipeline), 2nd {:.3} s, 3rd {:.3} s",
        materials.len(),
        times[0],
        times[1],
        times[2]
    );
    Ok(())
}
