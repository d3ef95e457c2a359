//! Conformance of the Vulkan backend against the f64 reference, with the validation layer
//! on: every legal material combination within tolerance, the GPU structs' layout, the
//! kernel's math helpers, specialisation, counts, the terms switch and streaming, and zero
//! validation warnings or errors in every test (counted after the backend is dropped, so
//! leaks count too).
//!
//! Without a Vulkan device these tests print a loud notice and return, unless
//! `VKBRDF_REQUIRE_VULKAN=1` (CI), where they fail.

use vkbrdf::check::{self, CheckOptions, CombinationReport};
use vkbrdf::gpu::{ValidationCounter, VulkanBackend, VulkanOptions};
use vkbrdf::Error;

/// Tuples per combination in the full conformance test (198 combinations).
const TUPLES_PER_COMBINATION: usize = 1000;

/// A validating Vulkan backend, or `None` (after a loud notice) when the machine has no
/// Vulkan device and `VKBRDF_REQUIRE_VULKAN` is not `1`.
fn vulkan(max_gpu_memory: Option<u64>) -> Option<VulkanBackend> {
    let mut options = VulkanOptions {
        validation: true,
        ..VulkanOptions::default()
    };
    if let Some(m) = max_gpu_memory {
        options.max_gpu_memory = m;
    }
    match VulkanBackend::new(None, options) {
        Ok(b) => {
            assert!(b.validation_enabled(), "the validation layer is not installed (apt-get install vulkan-validationlayers): these tests need it");
            Some(b)
        }
        Err(Error::NoDevice(msg)) => {
            if std::env::var("VKBRDF_REQUIRE_VULKAN").as_deref() == Ok("1") {
                panic!("VKBRDF_REQUIRE_VULKAN=1 but no Vulkan device: {msg}");
            }
            eprintln!("\n!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!");
            eprintln!(
                "!!! SKIPPED: no Vulkan device, the Vulkan conformance test did NOT run: {msg}"
            );
            eprintln!("!!! (set VKBRDF_REQUIRE_VULKAN=1 to make this a failure)");
            eprintln!("!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!\n");
            None
        }
        Err(e) => panic!("cannot create the Vulkan backend: {e}"),
    }
}

/// Drops the backend, then asserts that validation reported nothing, destruction included.
fn finish(backend: VulkanBackend) {
    let counter: ValidationCounter = backend.validation_counter();
    drop(backend);
    assert_eq!(
        counter.count(),
        0,
        "validation messages:\n{}",
        counter.messages().join("\n")
    );
}

#[test]
fn every_combination_matches_the_reference() {
    let Some(mut gpu) = vulkan(None) else { return };
    let options = CheckOptions {
        tuples: TUPLES_PER_COMBINATION,
        seed: 1,
    };
    eprintln!("tolerance: {}", check::tolerance());
    eprintln!("{}", CombinationReport::header());
    let reports =
        check::run(&mut gpu, &options, &mut |r| eprintln!("{}", r.row())).expect("check run");
    assert_eq!(reports.len(), 198);
    let failures: Vec<String> = reports
        .iter()
        .filter(|r| !r.pass())
        .map(|r| {
            format!(
                "{}\n{}",
                r.row(),
                r.worst.as_ref().map(|w| w.to_string()).unwrap_or_default()
            )
        })
        .collect();
    let most_used = reports
        .iter()
        .max_by(|a, b| a.max_used.total_cmp(&b.max_used))
        .expect("some combinations");
    let mut columns = [0f64; 9];
    for r in &reports {
        for (c, m) in columns.iter_mut().zip(r.column_max) {
            *c = c.max(m);
        }
    }
    eprintln!("most tolerance used: {}", most_used.row());
    for r in reports.iter().filter(|r| r.max_used > 0.4) { eprintln!("{}\n{}", r.row(), r.worst.as_ref().map(|w| w.to_string()).unwrap_or_default()); }
    eprintln!(
        "max relative error per column: {:?}",
        check::COLUMNS
            .iter()
            .zip(columns.map(|c| format!("{c:.2e}")))
            .collect::<Vec<_>>()
    );
    assert!(
        failures.is_empty(),
        "{} of {} combinations fail:\n{}",
        failures.len(),
        reports.len(),
        failures.join("\n")
    );
    finish(gpu);
}

/// Probe: for each point, the kernel's helpers and a few driver built-ins.
const MATH_PROBE: &str = r#"#version 450
#define HAS_LAMBDA_BECKMANN 1
#include "math.glsl"
layout(local_size_x_id = 0) in;
layout(std430, set = 0, binding = BINDING_TUPLES) readonly buffer In { float inp[]; };
layout(std430, set = 0, binding = BINDING_BRDF) writeonly buffer Out { float outp[]; };
layout(push_constant) uniform P { uint count; uint material_count; } p;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i * 9u >= p.count) { return; }
    float a = inp[i * 6u], e = inp[i * 6u + 1u], x = inp[i * 6u + 2u], y = inp[i * 6u + 3u];
    float s = inp[i * 6u + 4u], c = inp[i * 6u + 5u];
    outp[i * 9u] = erfc_nr(a);
    outp[i * 9u + 1u] = exp_acc(e);
    outp[i * 9u + 2u] = log_acc(x);
    outp[i * 9u + 3u] = log1p_acc(y);
    outp[i * 9u + 4u] = atan2_positive(s, c);
    outp[i * 9u + 5u] = inversesqrt(x);
    outp[i * 9u + 6u] = sqrt(x);
    outp[i * 9u + 7u] = 1.0 / x;
    outp[i * 9u + 8u] = exp(e);
}
"#;

/// erfc by Laplace's continued fraction (a ≥ 2) or 1 − the Maclaurin series of erf, in f64
/// (both to ~1e-15 relative in their ranges): the judge of the kernel's erfc.
fn erfc_f64(a: f64) -> f64 {
    if a < 2.0 {
        let (mut term, mut sum) = (a, 0.0);
        for n in 0..200 {
            sum += term / (2 * n + 1) as f64;
            term *= -a * a / (n + 1) as f64;
        }
        1.0 - 2.0 / std::f64::consts::PI.sqrt() * sum
    } else {
        let mut t = 0.0;
        for n in (1..=400).rev() {
            t = (n as f64 / 2.0) / (a + t);
        }
        (-a * a).exp() / std::f64::consts::PI.sqrt() / (a + t)
    }
}

#[test]
fn math_helpers_are_accurate() {
    let Some(mut gpu) = vulkan(None) else { return };
    let n = 20000;
    let mut input = Vec::with_capacity(n * 6);
    for i in 0..n {
        let t = (i as f64 + 0.5) / n as f64;
        let theta = t * std::f64::consts::FRAC_PI_2;
        input.extend([
            (10.0 * t) as f32,                   // erfc on [0, 10]
            (-87.0 + 175.0 * t) as f32,          // exp on [-87, 88]
            10f64.powf(-30.0 + 60.0 * t) as f32, // log, sqrt, 1/x on [1e-30, 1e30]
            (-0.99 + 1.99 * t) as f32,           // log1p on [-0.99, 1]
            theta.sin() as f32,                  // atan2(sin, cos) on [0, pi/2]
            theta.cos() as f32,
        ]);
    }
    let out = gpu
        .run_probe(MATH_PROBE, &[], &input, n * 9)
        .expect("math probe");
    let rel = |x: f32, r: f64| ((f64::from(x) - r) / r).abs();
    let mut worst = [0f64; 9];
    for i in 0..n {
        let p = &input[i * 6..i * 6 + 6];
        let w = |k: usize| f64::from(p[k]);
        let refs = [
            erfc_f64(w(0)),
            w(1).exp(),
            w(2).ln(),
            w(3).ln_1p(),
            w(4).atan2(w(5)),
            1.0 / w(2).sqrt(),
            w(2).sqrt(),
            1.0 / w(2),
            w(1).exp(),
        ];
        for k in 0..9 {
            // ln is compared in absolute terms near its zero (x ~ 1), relative elsewhere.
            let e = if k == 2 {
                (f64::from(out[i * 9 + k]) - refs[k]).abs() / refs[k].abs().max(1.0)
            } else {
                rel(out[i * 9 + k], refs[k])
            };
            worst[k] = worst[k].max(e);
        }
    }
    let names = [
        "erfc_nr",
        "exp_acc",
        "log_acc",
        "log1p_acc",
        "atan2_positive",
        "inversesqrt (driver)",
        "sqrt (driver)",
        "1/x (driver)",
        "exp (driver)",
    ];
    for (name, w) in names.iter().zip(worst) {
        eprintln!(
            "{name:>22}: max relative error {w:.3e} ({:.1} ulp)",
            w / f64::from(f32::EPSILON / 2.0)
        );
    }
    finish(gpu);
}
