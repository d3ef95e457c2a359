//! The kernel's f32 frame (devices without shaderFloat64, or `VKBRDF_DISABLE_FLOAT64=1`;
//! issue 14): its float-float helpers are error-free on the device, and with the frame
//! forced on, conformance and the stress corpus hold within 2x of the float64 frame.

mod common;

use std::process::{Command, Output};

/// `vkbrdf ARGS` with the kernel's f32 frame forced (`VKBRDF_DISABLE_FLOAT64=1`).
fn vkbrdf_f32(args: &[&str]) -> Output {
    vkbrdf_f32_env(args, &[])
}

/// `vkbrdf ARGS` with the f32 frame forced and the extra environment `env`.
fn vkbrdf_f32_env(args: &[&str], env: &[(&str, &str)]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
        .args(args)
        .env("VKBRDF_DISABLE_FLOAT64", "1")
        .envs(env.iter().copied())
        .output()
        .expect("run vkbrdf")
}

/// The float64 frame's maximum relative error per (quantity, regime) over the 10M-tuple
/// stress corpus, copied from docs/stress-10m-float64.md (written by `vkbrdf stress
/// --tuples 10000000 --backend vulkan` on lavapipe with shaderFloat64; HTSG's rows since it
/// joined the corpus, the spectral pass's since it was added, 2026-12-02). The corpus is
/// chunkable (tests/stress.rs), so its first 200,000 rows are rows of that run.
const FLOAT64_MAX: [(&str, &str, f64); 52] = [
    ("D", "well-conditioned", 6.77e-6),
    ("D", "grazing", 8.65e-6),
    ("D", "near-peak", 9.60e-7),
    ("D", "extreme roughness", 6.69e-6),
    ("D", "extreme IOR", 4.60e-6),
    ("F", "well-conditioned", 5.36e-7),
    ("F", "grazing", 5.34e-7),
    ("F", "near-peak", 5.62e-7),
    ("F", "extreme roughness", 7.80e-7),
    ("F", "extreme IOR", 7.65e-7),
    ("G", "well-conditioned", 5.43e-7),
    ("G", "grazing", 5.08e-7),
    ("G", "near-peak", 4.92e-7),
    ("G", "extreme roughness", 1.40e-6),
    ("G", "extreme IOR", 4.99e-7),
    ("K", "well-conditioned", 5.30e-7),
    ("K", "grazing", 3.41e-6),
    ("K", "near-peak", 5.46e-7),
    ("K", "extreme roughness", 1.57e-5),
    ("K", "extreme IOR", 1.30e-6),
    ("f: blinn-phong", "well-conditioned", 2.51e-6),
    ("f: blinn-phong", "grazing", 8.65e-6),
    ("f: blinn-phong", "near-peak", 2.00e-7),
    ("f: blinn-phong", "extreme roughness", 1.75e-6),
    ("f: cook-torrance", "well-conditioned", 1.24e-6),
    ("f: cook-torrance", "grazing", 1.43e-5),
    ("f: cook-torrance", "near-peak", 7.01e-7),
    ("f: cook-torrance", "extreme roughness", 1.33e-5),
    ("f: cook-torrance", "extreme IOR", 2.14e-6),
    ("f: htsg", "well-conditioned", 8.31e-6),
    ("f: htsg", "grazing", 7.52e-6),
    ("f: htsg", "near-peak", 1.41e-6),
    ("f: htsg", "extreme roughness", 2.92e-6),
    ("f: htsg", "extreme IOR", 8.72e-8),
    ("f: spectral", "well-conditioned", 7.16e-7),
    ("f: spectral", "grazing", 6.48e-7),
    ("f: spectral", "near-peak", 5.37e-7),
    ("f: lambert", "well-conditioned", 4.03e-8),
    ("f: lambert", "grazing", 4.03e-8),
    ("f: lambert", "near-peak", 4.03e-8),
    ("f: phong", "well-conditioned", 7.87e-7),
    ("f: phong", "grazing", 6.15e-7),
    ("f: phong", "near-peak", 1.63e-7),
    ("f: phong", "extreme roughness", 2.05e-6),
    ("f: rtr", "well-conditioned", 2.75e-6),
    ("f: rtr", "grazing", 1.85e-6),
    ("f: rtr", "near-peak", 9.25e-8),
    ("f: rtr", "extreme roughness", 3.46e-6),
    ("f: ward", "well-conditioned", 3.26e-6),
    ("f: ward", "grazing", 7.75e-6),
    ("f: ward", "near-peak", 2.55e-7),
    ("f: ward", "extreme roughness", 2.87e-6),
];

const FF_PROBE: &str = r#"#version 450
#include "ff.glsl"
layout(local_size_x_id = 0) in;
layout(std430, set = 0, binding = BINDING_TUPLES) readonly buffer In { float inp[]; };
layout(std430, set = 0, binding = BINDING_BRDF) writeonly buffer Out { float outp[]; };
layout(push_constant) uniform P { uint count; uint material_count; } p;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i * 8u >= p.count) { return; }
    vec3 a = vec3(inp[i * 6u], inp[i * 6u + 1u], inp[i * 6u + 2u]);
    vec3 b = vec3(inp[i * 6u + 3u], inp[i * 6u + 4u], inp[i * 6u + 5u]);
    vec2 pr = two_prod(a.x, b.x);
    vec2 s = two_sum(a.x, b.x);
    vec2 d = dot_ff(a, b);
    vec2 q = ff_div(vec2(a.x, a.y * 1e-8), vec2(b.x, b.y * 1e-8));
    outp[i * 8u] = pr.x;
    outp[i * 8u + 1u] = pr.y;
    outp[i * 8u + 2u] = s.x;
    outp[i * 8u + 3u] = s.y;
    outp[i * 8u + 4u] = d.x;
    outp[i * 8u + 5u] = d.y;
    outp[i * 8u + 6u] = q.x;
    outp[i * 8u + 7u] = q.y;
}
"#;

#[test]
fn float_float_helpers_are_error_free_on_the_device() {
    let Some(mut gpu) = common::vulkan() else {
        return;
    };
    let n = 4096;
    let mut input = Vec::with_capacity(n * 6);
    let mut x = 0x2545_f491_u32;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        (f64::from(x) / f64::from(u32::MAX) * 2.0 - 1.0) as f32
    };
    for _ in 0..n {
        // b nearly parallel to a, so that the dot products cancel.
        let a = [next(), next(), next()];
        let b = [a[0] * (1.0 + next() * 1e-3), a[1] * 0.5 + next(), a[2]];
        let b = [b[0], b[1], -(a[0] * b[0] + a[1] * b[1]) / a[2]];
        input.extend(a);
        input.extend(b);
    }
    let out = gpu
        .run_probe(FF_PROBE, &[], &input, n * 8)
        .expect("ff probe");
    let mut worst_dot = 0f64;
    for i in 0..n {
        let v: Vec<f64> = input[i * 6..i * 6 + 6]
            .iter()
            .map(|&x| f64::from(x))
            .collect();
        let o: Vec<f64> = out[i * 8..i * 8 + 8]
            .iter()
            .map(|&x| f64::from(x))
            .collect();
        // A product of two floats is exact in f64, so hi + lo must equal it exactly.
        assert_eq!(o[0] + o[1], v[0] * v[3], "two_prod({}, {})", v[0], v[3]);
        assert_eq!(o[0], f64::from(input[i * 6] * input[i * 6 + 3]));
        // Likewise a sum of two floats (their exponents here differ by far less than 29).
        assert_eq!(o[2] + o[3], v[0] + v[3], "two_sum({}, {})", v[0], v[3]);
        // The dot product: its 3 products are exact in f64, their sum to ~1e-16 absolute.
        let exact = v[0] * v[3] + v[1] * v[4] + v[2] * v[5];
        let scale = (v[0] * v[3]).abs() + (v[1] * v[4]).abs() + (v[2] * v[5]).abs();
        worst_dot = worst_dot.max(((o[4] + o[5]) - exact).abs() / scale);
    }
    eprintln!("dot_ff: worst error {worst_dot:e} of the sum of |products|");
    assert!(worst_dot < 1e-15, "dot_ff error {worst_dot:e}");
}

#[test]
fn conformance_passes_with_the_f32_frame() {
    if common::vulkan().is_none() {
        return;
    }
    let out = vkbrdf_f32(&["check"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "vkbrdf check fails with the f32 frame:\n{text}\n{}",
        common::stderr(&out)
    );
    // Every row but the two measured (MERL) combinations, which the kernel reads from
    // tables the f32 frame does not change: the other combinations and the spectral rows.
    let expected = format!(
        "{} pass, 0 fail",
        common::combinations::check_row_count() - 2
    );
    assert!(text.contains(&expected), "{expected}:\n{text}");
}

#[test]
fn stress_stays_within_twice_the_float64_frame() {
    if common::vulkan().is_none() {
        return;
    }
    assert_stress_within_twice_float64(&[]);
}

/// The same on a device that flushes f32 subnormals to zero, as GPUs do (NVIDIA's compute
/// shaders flush in arithmetic and in conversions): `VKBRDF_EMULATE_FTZ=1` runs lavapipe's
/// kernel threads with x86 flush-to-zero and denormals-are-zero. The f32 frame there lost
/// every cosine of 1e-38 or 1e-45 (the corpus's tiny cosines are subnormal components of
/// L or V): 2.24 M of 10 M tuples below the horizon where the reference has 1.83 M,
/// 0.20 M saturated where it has 0.49 M, and D, F, G, K 1.0 off in every grazing row —
/// the counts an NVIDIA H200 gave.
#[test]
fn stress_holds_under_flush_to_zero() {
    if common::vulkan().is_none() {
        return;
    }
    assert_stress_within_twice_float64(&[("VKBRDF_EMULATE_FTZ", "1")]);
}

/// `VKBRDF_EMULATE_FTZ=1` is in force (the test above would pass vacuously if it were
/// not): a Phong material of exponent 0 and specular colour 1e-38 has the subnormal BRDF
/// 1e-38/pi, a product formed on the device, which lavapipe returns as is and returns as
/// 0 with flush-to-zero (as a GPU does).
#[test]
fn flush_to_zero_emulation_flushes_subnormal_outputs() {
    if common::vulkan().is_none() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let materials = dir.path().join("m.toml");
    std::fs::write(
        &materials,
        "[[material]]\nname = \"dim\"\nmodel = \"phong\"\nexponent = 0\nspecular = 1e-38\n",
    )
    .expect("write materials");
    let tuples = dir.path().join("t.npy");
    let row = [0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0];
    vkbrdf::batch::write_npy_f32(&tuples, &row, 10).expect("write tuples");
    let brdf = |ftz: &str| {
        let out_path = dir.path().join(format!("brdf-{ftz}.npy"));
        let out = vkbrdf_f32_env(
            &[
                "eval",
                "--backend",
                "vulkan",
                "-m",
                common::path(&materials),
                "-i",
                common::path(&tuples),
                "-o",
                common::path(&out_path),
            ],
            &[("VKBRDF_EMULATE_FTZ", ftz)],
        );
        assert!(out.status.success(), "{}", common::stderr(&out));
        vkbrdf::batch::read_npy_f32(&out_path).expect("read brdf").0[0]
    };
    let plain = brdf("0");
    let expected = 1e-38 / std::f64::consts::PI;
    assert!(
        (plain as f64 - expected).abs() < 1e-3 * expected,
        "lavapipe without the emulation: {plain:e}, expected {expected:e}"
    );
    assert_eq!(brdf("1"), 0.0, "VKBRDF_EMULATE_FTZ=1 did not flush");
}

/// Runs the stress corpus's first 200,000 rows with the f32 frame (and `env`) and asserts
/// the policy (exit 0, no non-finite output) and every row's maximum within twice the
/// float64 frame's.
fn assert_stress_within_twice_float64(env: &[(&str, &str)]) {
    let dir = tempfile::tempdir().expect("tempdir");
    let report = dir.path().join("stress.md");
    // The devices listing names the frame the kernel gets: the override really is in force.
    let devices = vkbrdf_f32_env(&["devices"], env);
    let listing = String::from_utf8_lossy(&devices.stdout);
    assert!(listing.contains("VKBRDF_DISABLE_FLOAT64=1"), "{listing}");
    let out = vkbrdf_f32_env(
        &[
            "stress",
            "--tuples",
            "200000",
            "--backend",
            "vulkan",
            "--report",
            common::path(&report),
        ],
        env,
    );
    let text = std::fs::read_to_string(&report).expect("stress report");
    // Exit 0: the policy holds (finite outputs, invalid and saturated counts equal to the
    // reference's, no non-zero output for a rejected tuple).
    assert!(out.status.success(), "{}\n{text}", common::stderr(&out));
    assert!(text.contains("non-finite outputs: **0**"), "{text}");
    let mut rows = 0;
    for line in text.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        // | quantity | regime | values | max rel err | p99 rel err | <= 1e-5 |
        if cells.len() != 8 || cells[3].parse::<u64>().is_err() {
            continue;
        }
        let max: f64 = cells[4].parse().expect("max rel err");
        let &(_, _, float64) = FLOAT64_MAX
            .iter()
            .find(|(q, r, _)| *q == cells[1] && *r == cells[2])
            .unwrap_or_else(|| {
                panic!(
                    "row {} / {} not in the float64 baseline",
                    cells[1], cells[2]
                )
            });
        assert!(
            max <= 2.0 * float64,
            "{} / {}: max rel err {max:e} with the f32 frame, float64 frame {float64:e}\n{text}",
            cells[1],
            cells[2]
        );
        rows += 1;
    }
    assert!(rows >= 40, "only {rows} error rows in the report:\n{text}");
}
