//! Batches that mix materials are uploaded grouped by material (`BUCKETED`) and their
//! outputs put back in place: every output must land on its own row, across chunk
//! boundaries, with terms, and the first invalid row reported must be the first in the
//! batch's order, not in the upload order.

mod common;

use vkbrdf::backend::{Backend, Request, TERM_COLUMNS};
use vkbrdf::batch::Batch;
use vkbrdf::features::FeatureSet;
use vkbrdf::gpu::{DeviceSelector, VulkanBackend, VulkanOptions};
use vkbrdf::material::parse_materials;
use vkbrdf::reference::CpuReference;

const MATERIALS: &str = r#"
[[material]]
name = "matte"
model = "lambert"
diffuse = [0.5, 0.4, 0.3]

[[material]]
name = "gold"
preset = "gold"

[[material]]
name = "brushed"
model = "ward"
roughness = [0.1, 0.4]
specular = [0.5, 0.5, 0.5]

[[material]]
name = "plastic"
model = "blinn-phong"
exponent = 60
"#;

/// A batch of `n` rows cycling through the 4 materials in a scrambled order, with invalid
/// rows at 7 (material 3, last in the upload order) and from 100 on (material 0, first).
fn batch(n: usize) -> Batch<'static> {
    let sampled = vkbrdf::sample::sample_batch(n, 4, 11, true);
    let cols = sampled.columns();
    let mut data = sampled.as_slice().to_vec();
    for (i, row) in data.chunks_mut(cols).enumerate() {
        row[9] = ((i * 7 + i / 3) % 4) as f32;
    }
    data[7 * cols + 9] = 3.0;
    data[7 * cols] = f32::NAN;
    for i in (100..n).step_by(50_021) {
        data[i * cols + 9] = 0.0;
        data[i * cols + 3] = 0.0;
        data[i * cols + 4] = 0.0;
        data[i * cols + 5] = 0.0;
    }
    Batch::new(data, cols, 4, std::path::Path::new("bucketing")).unwrap()
}

#[test]
fn grouped_uploads_put_every_output_back_in_place() {
    let materials = parse_materials(MATERIALS, "bucketing.toml").unwrap();
    let Some(_) = common::vulkan() else { return };
    // A small memory budget: the 300,000 rows stream through several chunks.
    let options = VulkanOptions {
        max_gpu_memory: 16 << 20,
        validation: true,
        ..VulkanOptions::default()
    };
    let mut gpu = VulkanBackend::new(DeviceSelector::from_env(), options).unwrap();
    let chunk = gpu.chunk_tuples(materials.len()).unwrap();
    let n = 300_000;
    assert!(
        chunk < n / 2,
        "want several chunks, got {chunk} tuples per chunk"
    );
    let batch = batch(n);
    let request = Request { terms: true };
    let features = FeatureSet::of_batch(&batch, &materials, &request);
    assert!(features.contains(FeatureSet::BUCKETED));

    let got = gpu.evaluate(&batch, &materials, &request).unwrap();
    let want = CpuReference::new()
        .evaluate(&batch, &materials, &request)
        .unwrap();
    assert_eq!(got.counts, want.counts);
    assert_eq!(got.counts.first_invalid, Some(7));
    assert!(got.counts.invalid >= 6);

    // Row by row: a value that landed on another row would be off by far more than f32.
    let close = |g: f32, w: f32| (g - w).abs() <= 1e-4 * w.abs().max(1e-3);
    for (i, (g, w)) in got.brdf.chunks(3).zip(want.brdf.chunks(3)).enumerate() {
        assert!(
            g.iter().zip(w).all(|(&g, &w)| close(g, w)),
            "row {i} (material {}): {g:?} vs {w:?}",
            batch.material(i)
        );
    }
    let (gt, wt) = (got.terms.unwrap(), want.terms.unwrap());
    for (i, (g, w)) in gt
        .chunks(TERM_COLUMNS)
        .zip(wt.chunks(TERM_COLUMNS))
        .enumerate()
    {
        // D first: the term that differs most between the four models.
        assert!(close(g[0], w[0]), "row {i} D: {} vs {}", g[0], w[0]);
    }
    assert_eq!(gpu.validation_message_count(), 0);
}
