//! Evaluates stress-corpus rows (seed 7) on the Vulkan kernel and on the f64 reference, with
//! the terms, and prints both: `cargo run --release --example probe_corpus -- ROW...`.
//! With VKBRDF_EMULATE_FTZ=1 (and VKBRDF_DISABLE_FLOAT64=1) it shows a row as a GPU sees it.
use vkbrdf::backend::{Backend, Request};
use vkbrdf::gpu::{VulkanBackend, VulkanOptions};
use vkbrdf::reference::CpuReference;

fn main() -> vkbrdf::Result<()> {
    let mut gpu = VulkanBackend::new(None, VulkanOptions::default())?;
    let mut cpu = CpuReference::new();
    for arg in std::env::args().skip(1) {
        let Ok(row) = arg.parse::<usize>() else {
            eprintln!("not a row number: {arg}");
            std::process::exit(2);
        };
        let (materials, batch, cases) = vkbrdf::stress::corpus::corpus_rows(row..row + 1, 7);
        let request = Request { terms: true };
        let a = gpu.evaluate(&batch, &materials, &request)?;
        let b = cpu.evaluate(&batch, &materials, &request)?;
        let m = batch.as_slice()[9] as usize;
        println!("row {row} ({:?}) material {:?}", cases[0], materials[m]);
        println!("  tuple  {:?}", batch.as_slice());
        println!("  kernel brdf {:?} terms D G F F F K {:?}", a.brdf, a.terms);
        println!("  ref    brdf {:?} terms D G F F F K {:?}", b.brdf, b.terms);
    }
    Ok(())
}
