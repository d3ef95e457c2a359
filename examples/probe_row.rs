//! Debug aid: evaluates stress-corpus rows on an engine and the reference and prints both.
//! Usage: cargo run --release --example probe_row -- [--cpu] ROW [ROW …] (Vulkan unless
//! `--cpu`, the native CPU engine).
use vkbrdf::backend::{Backend, Request};
use vkbrdf::gpu::{VulkanBackend, VulkanOptions};

fn main() -> vkbrdf::Result<()> {
    let rows: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let mut gpu: Box<dyn Backend> = if std::env::args().any(|a| a == "--cpu") {
        Box::new(vkbrdf::cpu::CpuEngine::new())
    } else {
        Box::new(VulkanBackend::new(None, VulkanOptions::default())?)
    };
    for row in rows {
        let (materials, batch, cases) = vkbrdf::stress::corpus::corpus_rows(row..row + 1, 7);
        let out = gpu.evaluate(&batch, &materials, &Request { terms: true })?;
        let t = batch.tuple(0);
        let r = vkbrdf::reference::evaluate_tuple(&t, &materials[t.material]);
        println!(
            "row {row} {:?} material {:?}: {:?}",
            cases[0], materials[t.material], t
        );
        println!(
            "  {} brdf {:?} terms {:?} counts {:?}",
            gpu.name(),
            out.brdf,
            out.terms,
            out.counts
        );
        println!("  reference {r:?}");
    }
    Ok(())
}
