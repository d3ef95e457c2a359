//! Digests of an engine's outputs on the stress corpus, one material at a time (so each
//! material's own kernel variant or lanes run): `cargo run --release --example corpus_digest
//! -- [TUPLES] [vulkan|cpu]` (default 200,000 on `vulkan`). Prints, per material, an FNV-1a
//! hash of the BRDF and term bits and the counts, then the whole mixed batch's. Two builds
//! that print the same lines computed the same bits: the check behind a "same bits" claim
//! for a GLSL change (run it once plain, once with VKBRDF_DISABLE_FLOAT64=1 for the f32
//! frame, on each commit) or a CPU engine change (once per `VKBRDF_CPU_ISA`).
use vkbrdf::backend::{Backend, Request};
use vkbrdf::batch::Batch;
use vkbrdf::cpu::CpuEngine;
use vkbrdf::gpu::{VulkanBackend, VulkanOptions};

fn fnv(hash: &mut u64, values: &[f32]) {
    for v in values {
        for b in v.to_bits().to_le_bytes() {
            *hash = (*hash ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
}

fn main() -> vkbrdf::Result<()> {
    let engine = std::env::args().nth(2).unwrap_or_else(|| "vulkan".into());
    let n: usize = match std::env::args().nth(1) {
        None => 200_000,
        Some(a) => a.parse().unwrap_or_else(|_| {
            eprintln!("not a tuple count: {a}");
            std::process::exit(2);
        }),
    };
    let (materials, batch, _) = vkbrdf::stress::corpus::corpus(n, 7);
    let columns = batch.columns();
    let mut backend: Box<dyn Backend> = match engine.as_str() {
        "vulkan" => Box::new(VulkanBackend::new(None, VulkanOptions::default())?),
        "cpu" => Box::new(CpuEngine::new()),
        other => {
            eprintln!("not an engine: {other} (vulkan or cpu)");
            std::process::exit(2);
        }
    };
    let request = Request { terms: true };
    let mut total = 0xcbf2_9ce4_8422_2325u64;
    for (index, material) in materials.iter().enumerate() {
        // This material's rows, its index rewritten to 0 (a batch of one material).
        let mut rows: Vec<f32> = Vec::new();
        for row in batch.as_slice().chunks_exact(columns) {
            if row[9] as usize == index {
                rows.extend_from_slice(row);
                let last = rows.len() - columns + 9;
                rows[last] = 0.0;
            }
        }
        if rows.is_empty() {
            continue;
        }
        let count = rows.len() / columns;
        let one = Batch::new(rows, columns, 1, std::path::Path::new("corpus"))?;
        let out = backend.evaluate(&one, std::slice::from_ref(material), &request)?;
        let mut hash = 0xcbf2_9ce4_8422_2325u64;
        fnv(&mut hash, &out.brdf);
        fnv(&mut hash, out.terms.as_deref().unwrap_or(&[]));
        fnv(&mut total, &out.brdf);
        let c = out.counts;
        println!(
            "material {index:3} rows {count:6} digest {hash:016x} invalid {} below {} saturated {}",
            c.invalid, c.below_horizon, c.saturated
        );
    }
    println!("all {total:016x}");
    let out = backend.evaluate(&batch, &materials, &request)?;
    let mut mixed = 0xcbf2_9ce4_8422_2325u64;
    fnv(&mut mixed, &out.brdf);
    fnv(&mut mixed, out.terms.as_deref().unwrap_or(&[]));
    println!("mixed {mixed:016x}");
    Ok(())
}
