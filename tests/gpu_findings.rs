//! What the first run on a real GPU (an NVIDIA H200, docs/GPU.md) found, pinned here on
//! lavapipe: GPUs flush f32 subnormals to zero, and `VKBRDF_EMULATE_FTZ=1` runs lavapipe's
//! kernel threads that way (the H200's failing counts reproduced exactly).

mod common;

use vkbrdf::backend::{Backend, Request};
use vkbrdf::batch::Batch;
use vkbrdf::reference::CpuReference;

fn rel(a: f32, b: f32) -> f64 {
    (f64::from(a) - f64::from(b)).abs() / f64::from(b).abs().max(1e-6)
}

/// A direction scaled into the f32 subnormal range is the same direction: the kernel reads
/// the input bits and rescales them exactly (a GPU flushes subnormal arithmetic operands,
/// which made 0.67 M of 10 M stress tuples invalid on the H200).
#[test]
fn subnormal_scaled_vectors_give_the_unscaled_result() {
    let Some(mut gpu) = common::vulkan() else {
        return;
    };
    let materials = vec![vkbrdf::material::presets::preset("gold")
        .expect("preset")
        .expect("valid")];
    let l = [0.3f32, -0.2, 0.9];
    let v = [-0.4f32, 0.1, 0.8];
    let n = [0.05f32, 0.02, 1.0];
    let mut rows = Vec::new();
    for scale in [1.0f32, 1e-40, 3e-45] {
        let s = |w: [f32; 3]| w.map(|x| x * scale);
        rows.extend(s(l));
        rows.extend(s(v));
        rows.extend(s(n));
        rows.push(0.0);
    }
    assert!(
        rows[10] != 0.0 && rows[10].abs() < f32::MIN_POSITIVE,
        "scaled into subnormals"
    );
    let batch = Batch::new(rows, 10, materials.len(), std::path::Path::new("test")).expect("batch");
    let out = gpu
        .evaluate(&batch, &materials, &Request::default())
        .expect("vulkan");
    let want = CpuReference::new()
        .evaluate(&batch, &materials, &Request::default())
        .expect("reference");
    assert_eq!(out.counts.invalid, 0);
    for (i, (g, w)) in out.brdf.iter().zip(&want.brdf).enumerate() {
        assert!(rel(*g, *w) < 1e-5, "value {i}: kernel {g}, reference {w}");
    }
}

/// The stress policy with lavapipe's kernel threads in flush-to-zero mode
/// (`VKBRDF_EMULATE_FTZ=1`), as a GPU runs f32: on the H200, 96 620 of 10 M corpus tuples
/// came out NaN or inf (index-matched Fresnel at c = 1e-45, lobes of 1e-38 times 1/cos of
/// 1e38); the first 300 000 corpus rows hold such tuples (2 846 non-finite outputs with
/// the kernel before the fix).
#[test]
fn stress_policy_holds_with_flush_to_zero() {
    if common::vulkan().is_none() {
        return;
    }
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
        .args(["stress", "--tuples", "300000", "--backend", "vulkan"])
        .env("VKBRDF_EMULATE_FTZ", "1")
        .env_remove("VKBRDF_DISABLE_FLOAT64")
        .output()
        .expect("vkbrdf runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("non-finite outputs: **0**"),
        "stress under flush-to-zero: {}\n{}",
        text,
        common::stderr(&out)
    );
}
