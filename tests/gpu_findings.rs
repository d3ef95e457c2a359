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

/// Lobes far below every float: `cos_h^e` with e = 1e18 at a cosine of 1e-45 has the log
/// -1e20, and the kernel's f64 exp reduced that argument with an error of thousands (the
/// size of the argument's rounding), so e^r overflowed: the H200 (which fuses the reduction
/// into an FMA) returned 3.4e38 where the value is 0, 8 148 non-finite or saturated outputs
/// in 10 M stress tuples. Every value here is 0 in the reference; the kernel must agree
/// whichever way the reduction rounds. Lavapipe does not fuse it, and unfused the
/// remainder comes out <= 0, so this passes here with the old kernel too: on a GPU
/// (`cargo test` there, or `.ci/gpu-check`'s stress) it is the check.
#[test]
fn lobes_below_every_float_are_zero() {
    let Some(mut gpu) = common::vulkan() else {
        return;
    };
    let mut toml = String::new();
    let exponents = [1e12, 1e15, 3e16, 1e17, 7e17, 1e18];
    for (i, e) in exponents.iter().enumerate() {
        toml.push_str(&format!(
            "[[material]]\nname = \"b{i}\"\nmodel = \"blinn-phong\"\nexponent = {e:e}\n\n"
        ));
    }
    let materials = vkbrdf::material::parse_materials(&toml, "lobes.toml").expect("legal");
    let mut rows = Vec::new();
    // L ⟂ V, both grazing at cosines from 1e-45 to 1e-30: cos_h ≈ √2 · cos, ln_q ≈ -e · 100.
    for m in 0..exponents.len() {
        for k in 0..40 {
            let z = 1e-45f32 * 10f32.powf(k as f32 * 0.4);
            let phi = 0.1 + 0.037 * k as f32;
            rows.extend([
                phi.cos(),
                phi.sin(),
                z,
                -phi.sin(),
                phi.cos(),
                z,
                0.0,
                0.0,
                1.0,
                m as f32,
            ]);
        }
    }
    let batch = Batch::new(rows, 10, materials.len(), std::path::Path::new("test")).expect("batch");
    let want = CpuReference::new()
        .evaluate(&batch, &materials, &Request::default())
        .expect("reference");
    let out = gpu
        .evaluate(&batch, &materials, &Request::default())
        .expect("vulkan");
    assert_eq!(
        out.counts.saturated, want.counts.saturated,
        "saturated counts"
    );
    for (i, (g, w)) in out.brdf.iter().zip(&want.brdf).enumerate() {
        assert!(
            *w == 0.0,
            "value {i}: the reference {w} (the test expects 0)"
        );
        assert!(
            *g == 0.0,
            "value {i} (row {}): kernel {g}, reference 0",
            i / 3
        );
    }
}
