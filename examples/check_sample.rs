//! Checks an `eval` output against the f64 reference on every k-th tuple (large files).
//! Usage: cargo run --release --example check_sample -- M.toml TUPLES.npy BRDF.npy [STEP]
use std::path::Path;
use vkbrdf::stats::{relative_error, ErrorStats};

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
    let mut stats = ErrorStats::default();
    for i in (0..batch.len()).step_by(step) {
        let t = batch.tuple(i);
        let r = vkbrdf::reference::evaluate_tuple(&t, &materials[t.material]);
        for c in 0..3 {
            stats.add(
                relative_error(brdf[3 * i + c] as f64, r.brdf[c], 1e-6),
                i as u64,
            );
        }
    }
    println!(
        "{} values checked: max rel err {:.2e}, p99 {:.2e} (worst row {:?})",
        stats.count,
        stats.max,
        stats.p99(),
        stats.worst
    );
    Ok(())
}
