//! Checks an `eval` output against the f64 reference on every k-th tuple (large files).
//! Usage: cargo run --release --example check_sample -- M.toml TUPLES.npy BRDF.npy [STEP]
use std::path::Path;

fn main() -> vkbrdf::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    assert!(
        a.len() >= 4,
        "usage: check_sample M.toml TUPLES.npy BRDF.npy [STEP]"
    );
    let step: usize = a.get(4).and_then(|s| s.parse().ok()).unwrap_or(1000);
    let materials = vkbrdf::material::load_materials(Path::new(&a[1]))?;
    let batch = vkbrdf::batch::Batch::read_npy(Path::new(&a[2]), materials.len())?;
    let (brdf, _) = vkbrdf::batch::read_npy_f32(Path::new(&a[3]))?;
    let sample = batch.len().div_ceil(step);
    let stats = vkbrdf::bench::brdf_error_stats(&batch, &materials, &brdf, sample);
    println!(
        "{} values checked: max rel err {:.2e}, p99 {:.2e} (worst row {:?})",
        stats.count,
        stats.max,
        stats.p99(),
        stats.worst
    );
    Ok(())
}
