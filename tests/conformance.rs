//! Conformance of the Vulkan backend against the f64 reference, with the validation layer
//! on: every legal material combination within tolerance ([`vkbrdf::check`]), the GPU
//! structs' layout, the kernel's math helpers, specialisation, invalid / below-horizon
//! counts, the terms switch, streaming and buffer reuse, and zero validation warnings or
//! errors in every test (counted after the backend is dropped, so leaks count too).
//!
//! Without a Vulkan device these tests print a loud notice and return, unless
//! `VKBRDF_REQUIRE_VULKAN=1` (CI), where they fail.

#[path = "common/combinations.rs"]
mod combinations;
use std::time::Instant;
use vkbrdf::backend::{Backend, Output, Request};
use vkbrdf::batch::{memory_source, Batch};
use vkbrdf::check::{self, CheckOptions, CombinationReport};
use vkbrdf::features::FeatureSet;
use vkbrdf::gpu::kernel::spirv_names;
use vkbrdf::gpu::layout::{gpu_materials, GpuMaterial};
use vkbrdf::gpu::{DeviceSelector, ValidationCounter, VulkanBackend, VulkanOptions};
use vkbrdf::material::{parse_materials, presets, Material};
use vkbrdf::reference::{self, CpuReference};
use vkbrdf::Error;

/// Tuples per combination in the full conformance test.
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
    match VulkanBackend::new(DeviceSelector::from_env(), options) {
        Ok(b) => {
            assert!(
                b.validation_enabled(),
                "the validation layer is not installed (apt-get install vulkan-validationlayers): these tests need it"
            );
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

fn materials(toml: &str) -> Vec<Material> {
    parse_materials(toml, "test").expect("test materials are valid")
}

/// Every value of `out` within the conformance tolerance of the f64 reference
/// ([`check::allowed_error`]); invalid and below-horizon rows must be exactly 0.
fn assert_matches_reference(batch: &Batch, mats: &[Material], out: &Output) {
    for row in 0..batch.len() {
        let t = batch.tuple(row);
        let e = reference::evaluate_tuple(&t, &mats[t.material]);
        let s = check::f32_sensitivity(&t, &mats[t.material]);
        for (c, (&r, &sens)) in e.brdf.iter().zip(&s).enumerate() {
            let x = f64::from(out.brdf[row * 3 + c]);
            assert!(
                (x - r).abs() <= check::allowed_error(r, sens),
                "row {row} channel {c}: {x} vs {r} ({t:?})"
            );
        }
        if let Some(terms) = &out.terms {
            for (k, r) in e.terms().into_iter().enumerate() {
                let x = f64::from(terms[row * 6 + k]);
                assert!(
                    (x - r).abs() <= check::allowed_error(r, s[3 + k]),
                    "row {row} term {k}: {x} vs {r} ({t:?})"
                );
            }
        }
    }
}

#[test]
fn every_combination_matches_the_reference() {
    let Some(mut gpu) = vulkan(None) else { return };
    let options = CheckOptions {
        tuples: TUPLES_PER_COMBINATION,
        seed: 1,
        only: None,
    };
    eprintln!("tolerance: {}", check::tolerance());
    eprintln!("{}", CombinationReport::header());
    let reports =
        check::run(&mut gpu, &options, &mut |r| eprintln!("{}", r.row())).expect("check run");
    assert_eq!(reports.len(), combinations::check_combination_count());
    // And the spectral rows (FORMULAS.md §9), as `vkbrdf check` runs them after these.
    let mut reports = reports;
    reports.extend(
        check::spectral::run(&mut gpu, &options, &mut |r| eprintln!("{}", r.row()))
            .expect("spectral rows"),
    );
    assert_eq!(reports.len(), combinations::check_row_count());
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
    let well = reports
        .iter()
        .map(|r| r.max_rel_well_conditioned)
        .fold(0.0, f64::max);
    let mut columns = [0f64; 9];
    for r in &reports {
        for (c, m) in columns.iter_mut().zip(r.column_max) {
            *c = c.max(m);
        }
    }
    eprintln!("most tolerance used: {}", most_used.row());
    eprintln!("largest relative error where f32 inputs determine the value well: {well:.2e}");
    eprintln!(
        "largest relative error per column: {:?}",
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
    assert!(well <= check::RELATIVE_TOLERANCE);
    finish(gpu);
}

/// Probe: copies every field of every material back, as raw bits.
const LAYOUT_PROBE: &str = r#"#version 450
#include "layout.glsl"
layout(local_size_x_id = 0) in;
layout(std430, set = 0, binding = BINDING_MATERIALS) readonly buffer Materials { GpuMaterial materials[]; };
layout(std430, set = 0, binding = BINDING_BRDF) writeonly buffer Out { uint outp[]; };
layout(push_constant) uniform P { uint count; uint material_count; } p;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= p.material_count) { return; }
    GpuMaterial m = materials[i];
    uint o = i * 28u;
    for (uint k = 0u; k < 4u; k++) {
        outp[o + k] = floatBitsToUint(m.diffuse[k]);
        outp[o + 4u + k] = floatBitsToUint(m.specular[k]);
        outp[o + 8u + k] = floatBitsToUint(m.fresnel0[k]);
        outp[o + 12u + k] = floatBitsToUint(m.fresnel1[k]);
        outp[o + 16u + k] = floatBitsToUint(m.lobe[k]);
        outp[o + 20u + k] = floatBitsToUint(m.scale[k]);
        outp[o + 24u + k] = m.kind[k];
    }
}
"#;

#[test]
fn gpu_material_layout_round_trips() {
    let Some(mut gpu) = vulkan(None) else { return };
    // Every field distinct (so a swapped or shifted member shows), then real materials.
    let mut table = vec![GpuMaterial {
        diffuse: [1.0, 2.0, 3.0, 4.0],
        specular: [5.0, 6.0, 7.0, 8.0],
        fresnel0: [9.0, 10.0, 11.0, 12.0],
        fresnel1: [13.0, 14.0, 15.0, 16.0],
        lobe: [17.0, 18.0, 19.0, 20.0],
        scale: [21.0, 22.0, 23.0, 24.0],
        kind: [25, 26, 27, 0xdead_beef],
    }];
    table.extend(gpu_materials(&presets::all()));
    for c in check::combinations(3)
        .expect("combinations")
        .iter()
        .step_by(7)
    {
        table.extend(gpu_materials(&c.materials));
    }
    let out = gpu
        .run_probe(LAYOUT_PROBE, &table, &[0.0], table.len() * 28)
        .expect("layout probe");
    let got: Vec<u32> = out.iter().map(|x| x.to_bits()).collect();
    let want: &[u32] = bytemuck::cast_slice(&table);
    assert_eq!(got.len(), want.len());
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert_eq!(
            g,
            w,
            "material {} word {} (field {} component {})",
            i / 28,
            i % 28,
            i % 28 / 4,
            i % 4
        );
    }
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
    if (i * 7u >= p.count) { return; }
    float a = inp[i * 6u], e = inp[i * 6u + 1u], x = inp[i * 6u + 2u], y = inp[i * 6u + 3u];
    float s = inp[i * 6u + 4u], c = inp[i * 6u + 5u];
    outp[i * 7u] = erfc_nr(a);
    outp[i * 7u + 1u] = exp_acc(e);
    outp[i * 7u + 2u] = log_acc(x);
    outp[i * 7u + 3u] = log1p_acc(y);
    outp[i * 7u + 4u] = atan2_positive(s, c);
    outp[i * 7u + 5u] = exp(e);
    outp[i * 7u + 6u] = log(x);
}
"#;

/// erfc in f64 to ~1e-15: 1 − the Maclaurin series of erf for a < 2 (alternating terms
/// below 2^(2n+1)/n!, summed to convergence), Laplace's continued fraction beyond.
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

/// The error bounds stated in glsl/math.glsl, measured on the device: erfc relative
/// (≤ 6e-7 + 3 a² u), exp/log in ulps. Also prints what the
/// driver's own exp and log achieve (the reason the kernel has its own).
#[test]
fn math_helpers_are_accurate() {
    let Some(mut gpu) = vulkan(None) else { return };
    let n = 20000;
    let mut input = Vec::with_capacity(n * 6);
    for i in 0..n {
        let t = (i as f64 + 0.5) / n as f64;
        let theta = t * std::f64::consts::FRAC_PI_2;
        input.extend([
            (9.0 * t) as f32,           // erfc on [0, 9] (erfc(9.2) is subnormal in f32)
            (-87.0 + 175.0 * t) as f32, // exp on [-87, 88]
            10f64.powf(-30.0 + 60.0 * t) as f32, // log on [1e-30, 1e30]
            (-0.99 + 1.99 * t) as f32,  // log1p on [-0.99, 1]
            theta.sin() as f32,         // atan2(sin, cos) on [0, pi/2]
            theta.cos() as f32,
        ]);
    }
    let out = gpu
        .run_probe(MATH_PROBE, &[], &input, n * 7)
        .expect("math probe");
    let ulp = f64::from(f32::EPSILON) / 2.0;
    let mut worst = [0f64; 7];
    // erfc(a) = t exp(-a² + P(t)): evaluating the fit (1.2e-7) in f32 gives ~5e-7 near 0,
    // and rounding -a² costs a relative ~2 a² u more (Lambda_Beckmann needs erfc only in
    // absolute terms where a is large).
    let mut erfc_excess = 0f64;
    let mut bins = [0f64; 9];
    for i in 0..n {
        let p: Vec<f64> = input[i * 6..i * 6 + 6]
            .iter()
            .map(|&x| f64::from(x))
            .collect();
        let refs = [
            erfc_f64(p[0]),
            p[1].exp(),
            p[2].ln(),
            p[3].ln_1p(),
            p[4].atan2(p[5]),
            p[1].exp(),
            p[2].ln(),
        ];
        let erfc_rel = (f64::from(out[i * 7]) - refs[0]).abs() / refs[0];
        erfc_excess = erfc_excess.max(erfc_rel / (6e-7 + 3.0 * p[0] * p[0] * ulp));
        let bin = (p[0] as usize).min(8);
        bins[bin] = bins[bin].max(erfc_rel);
        for k in 0..7 {
            let x = f64::from(out[i * 7 + k]);
            // ln is measured relative to max(|ln x|, 1): near x = 1 its value is ~0, and
            // what matters there is the absolute error of the exponent it feeds.
            let scale = if k == 2 || k == 6 {
                refs[k].abs().max(1.0)
            } else {
                refs[k].abs()
            };
            worst[k] = worst[k].max((x - refs[k]).abs() / scale);
        }
    }
    eprintln!(
        "erfc by unit interval of a: {:?}",
        bins.map(|b| format!("{b:.1e}"))
    );
    let names = [
        "erfc_nr",
        "exp_acc",
        "log_acc",
        "log1p_acc",
        "atan2_positive",
        "exp (driver)",
        "log (driver)",
    ];
    for (name, w) in names.iter().zip(worst) {
        eprintln!(
            "{name:>16}: max relative error {w:.2e} ({:.1} ulp)",
            w / ulp
        );
    }
    assert!(
        erfc_excess <= 1.0,
        "erfc_nr exceeds 6e-7 + 3 a² u by a factor {erfc_excess}"
    );
    assert!(worst[1] <= 4.0 * ulp, "exp_acc: {:e}", worst[1]);
    assert!(worst[2] <= 4.0 * ulp, "log_acc: {:e}", worst[2]);
    assert!(worst[3] <= 8.0 * ulp, "log1p_acc: {:e}", worst[3]);
    assert!(worst[4] <= 8.0 * ulp, "atan2_positive: {:e}", worst[4]);
    finish(gpu);
}

const GGX_SCHLICK: &str = r#"
[[material]]
name = "ggx-schlick"
model = "cook-torrance"
distribution = "ggx"
roughness = 0.3
geometry = "smith-correlated"
fresnel = "schlick"
f0 = 0.04
"#;

#[test]
fn a_ggx_schlick_batch_runs_a_kernel_without_erf_conductor_or_ward() {
    let Some(mut gpu) = vulkan(None) else { return };
    let mats = materials(GGX_SCHLICK);
    let batch = vkbrdf::sample::sample_batch(1000, 1, 3, false);
    gpu.evaluate(&batch, &mats, &Request::default())
        .expect("evaluate");
    let features = gpu.last_features().expect("an evaluation ran");
    assert!(
        features.contains(FeatureSet::D_GGX) && features.contains(FeatureSet::F_SCHLICK),
        "{features}"
    );
    for absent in [
        FeatureSet::LAMBDA_BECKMANN,
        FeatureSet::F_CONDUCTOR,
        FeatureSet::WARD,
        FeatureSet::TERMS,
    ] {
        assert!(!features.contains(absent), "{features}");
    }
    let names = spirv_names(&gpu.spirv(features).expect("spirv"));
    let has = |prefix: &str| names.iter().any(|n| n.starts_with(prefix));
    assert!(
        has("ggx_d(") && has("schlick_f(") && has("ggx_lambda("),
        "{names:?}"
    );
    for absent in [
        "erfc_nr(",
        "beckmann_lambda(",
        "conductor_f(",
        "csqrt(",
        "model_ward(",
        "beckmann_d(",
        "gaussian_d(",
        "atan2_positive(",
        "Terms",
    ] {
        assert!(!has(absent), "{absent} is in the GGX + Schlick kernel");
    }
    // The all-features kernel does have them, so the test above is not vacuous.
    let all = spirv_names(&gpu.spirv(FeatureSet::all()).expect("spirv"));
    for present in ["erfc_nr(", "conductor_f(", "model_ward(", "Terms"] {
        assert!(
            all.iter().any(|n| n.starts_with(present)),
            "{present} missing from the all-features kernel"
        );
    }
    finish(gpu);
}

const MIXED: &str = r#"
[[material]]
name = "matte"
model = "lambert"
diffuse = [0.5, 0.4, 0.3]

[[material]]
name = "brushed"
model = "cook-torrance"
distribution = "ggx"
roughness = [0.05, 0.3]
geometry = "smith"
fresnel = "conductor"
ior = [0.2, 0.9, 1.1]
extinction = [3.6, 2.6, 2.3]

[[material]]
name = "ward"
model = "ward"
roughness = [0.2, 0.1]
specular = 0.3
diffuse = 0.2
"#;

/// Rows of every kind: valid, invalid (zero, NaN, inf in L, V, N; missing, zero or
/// parallel tangents for the anisotropic materials), below the horizon, and valid rows
/// whose vectors are 1e-20 or 1e20 long. The first invalid row is `first_invalid`.
fn mixed_batch(n: usize, first_invalid: usize) -> Batch<'static> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(9);
    let mut data = Vec::with_capacity(n * 13);
    for i in 0..n {
        let nrm = vkbrdf::sample::unit_vector(&mut rng);
        let mut l = vkbrdf::sample::unit_vector(&mut rng);
        let mut v = vkbrdf::sample::unit_vector(&mut rng);
        for w in [&mut l, &mut v] {
            let d: f64 = w.iter().zip(&nrm).map(|(a, b)| a * b).sum();
            if d < 0.05 && rng.random_bool(0.7) {
                *w = std::array::from_fn(|k| w[k] + (0.1 - d) * nrm[k]); // mostly above the horizon
            }
        }
        let mut row: Vec<f32> = l.iter().chain(&v).chain(&nrm).map(|&x| x as f32).collect();
        row.push(rng.random_range(0..3) as f32);
        let mut t = vkbrdf::sample::unit_vector(&mut rng).map(|x| x as f32);
        let kind = if i < first_invalid {
            rng.random_range(0..3)
        } else {
            rng.random_range(0..10)
        };
        match kind {
            1 => row[0..9].iter_mut().for_each(|x| *x *= 1e-20), // tiny: valid
            2 => row[0..9].iter_mut().for_each(|x| *x *= 1e20),  // huge: valid
            3 => row[0..3].fill(0.0),                            // zero L
            4 => row[4] = f32::NAN,                              // NaN in V
            5 => row[8] = f32::INFINITY,                         // inf in N
            // T = -2 N exactly (a power of two keeps it parallel in f32 and f64 alike;
            // FORMULAS.md's 1e-12 threshold is far below f32 resolution, so a T parallel
            // only up to f32 rounding is a tuple the two may classify differently).
            6 => t = [row[6], row[7], row[8]].map(|x| -2.0 * x),
            7 => t = [0.0; 3], // zero T
            _ => {}
        }
        row.extend(t);
        data.extend(row);
    }
    Batch::new(data, 13, 3, &memory_source()).expect("valid batch")
}

#[test]
fn invalid_and_below_horizon_counts_equal_the_reference() {
    // A 1 MiB budget: chunks of ~4000 rows, so the counts are summed over many chunks and
    // the first invalid row lies in a later one.
    let Some(mut gpu) = vulkan(Some(1 << 20)) else {
        return;
    };
    let mats = materials(MIXED);
    let batch = mixed_batch(60_000, 41_234);
    assert!(gpu.chunk_tuples(mats.len()).expect("chunking") < 10_000);
    let request = Request { terms: true };
    let out = gpu.evaluate(&batch, &mats, &request).expect("evaluate");
    let want = CpuReference::new()
        .evaluate(&batch, &mats, &request)
        .expect("reference");
    assert_eq!(out.counts, want.counts);
    assert!(
        out.counts.invalid > 5000 && out.counts.below_horizon > 5000,
        "{:?}",
        out.counts
    );
    assert!(out.counts.first_invalid.is_some_and(|r| r >= 41_234));
    assert_matches_reference(&batch, &mats, &out);
    finish(gpu);
}

#[test]
fn without_terms_no_terms_buffer_is_written() {
    let Some(mut gpu) = vulkan(None) else { return };
    let mats = materials(MIXED);
    let batch = mixed_batch(5000, 0);
    let plain = gpu
        .evaluate(&batch, &mats, &Request { terms: false })
        .expect("evaluate");
    assert!(plain.terms.is_none());
    let features = gpu.last_features().expect("ran");
    assert!(!features.contains(FeatureSet::TERMS));
    assert_eq!(
        gpu.buffer_bytes().terms,
        0,
        "a terms buffer was allocated without --terms"
    );
    assert!(!spirv_names(&gpu.spirv(features).expect("spirv"))
        .iter()
        .any(|n| n == "Terms"));
    let with = gpu
        .evaluate(&batch, &mats, &Request { terms: true })
        .expect("evaluate");
    assert_eq!(with.terms.as_ref().map(Vec::len), Some(5000 * 6));
    assert!(gpu.buffer_bytes().terms > 0);
    assert_eq!(plain.brdf, with.brdf, "writing terms changed the BRDF");
    assert_eq!(plain.counts, with.counts);
    finish(gpu);
}

#[test]
fn streaming_in_small_chunks_gives_the_same_result_within_the_budget() {
    let budget = 2 << 20;
    let (Some(mut small), Some(mut big)) = (vulkan(Some(budget)), vulkan(None)) else {
        return;
    };
    let mats = presets::all();
    let batch = vkbrdf::sample::sample_batch(150_000, mats.len(), 5, true);
    let request = Request { terms: true };
    let chunk = small.chunk_tuples(mats.len()).expect("chunking");
    assert!(chunk < 20_000, "{chunk}");
    let a = small.evaluate(&batch, &mats, &request).expect("evaluate");
    let b = big.evaluate(&batch, &mats, &request).expect("evaluate");
    assert!(big.chunk_tuples(mats.len()).expect("chunking") >= batch.len());
    assert_eq!(a, b, "chunked and single-chunk results differ");
    let bytes = small.buffer_bytes();
    assert!(
        bytes.total() <= budget,
        "{bytes:?} over the budget of {budget}"
    );
    finish(small);
    finish(big);
}

#[test]
fn buffers_regrow_and_rebind_between_calls() {
    // Alternate layouts (10/13 columns), sizes and terms on/off on one backend: every call
    // must see its own buffers. (A descriptor set once compared buffers by handle, and a
    // regrown buffer that reused a freed handle left the set pointing at freed memory.)
    let Some(mut gpu) = vulkan(Some(8 << 20)) else {
        return;
    };
    let combos = check::combinations(11).expect("combinations");
    let pick = |name: &str| {
        combos
            .iter()
            .find(|c| c.name == name)
            .expect("known combination")
    };
    let plan = [
        ("ward", 100),
        ("ward-aniso", 4000),
        ("lambert", 10),
        ("cook-torrance modern ggx-aniso smith conductor", 30_000),
        ("rtr", 7000),
        (
            "cook-torrance modern beckmann-aniso smith-fast schlick",
            500,
        ),
        (
            "cook-torrance seed gaussian cook-torrance dielectric",
            25_000,
        ),
    ];
    for (i, (name, n)) in plan.into_iter().enumerate() {
        let c = pick(name);
        let r = check::check_combination(&mut gpu, c, n, i as u64).expect("check");
        assert!(
            r.pass(),
            "{}\n{:?}",
            r.row(),
            r.worst.map(|w| w.to_string())
        );
        let batch = check::generate(c, n, i as u64).expect("batch");
        let plain = gpu
            .evaluate(&batch, &c.materials, &Request::default())
            .expect("evaluate");
        assert_matches_reference(&batch, &c.materials, &plain);
    }
    finish(gpu);
}

#[test]
fn the_all_features_kernel_matches_the_specialised_one() {
    let Some(mut gpu) = vulkan(None) else { return };
    let mats = presets::all();
    let batch = vkbrdf::sample::sample_batch(200_000, mats.len(), 8, false);
    let request = Request::default();
    let special = gpu.evaluate(&batch, &mats, &request).expect("evaluate");
    let special_features = gpu.last_features().expect("ran");
    let all = gpu
        .evaluate_with_features(&batch, &mats, &request, FeatureSet::all())
        .expect("evaluate");
    let all_features = gpu.last_features().expect("ran");
    assert!(
        all_features.contains(FeatureSet::WARD) && !special_features.contains(FeatureSet::WARD)
    );
    assert!(
        !all_features.contains(FeatureSet::TANGENTS),
        "the tangent layout follows the batch"
    );
    assert_eq!(special.counts, all.counts);
    for (i, (a, b)) in special.brdf.iter().zip(&all.brdf).enumerate() {
        assert!(
            (a - b).abs() <= 1e-6 * a.abs().max(1e-6),
            "row {}: {a} vs {b}",
            i / 3
        );
    }
    // The timing is informational (shared machines): median of 3 runs each.
    let mut time = |f: &mut dyn FnMut(&mut VulkanBackend)| {
        let mut t: Vec<f64> = (0..3)
            .map(|_| {
                let t0 = Instant::now();
                f(&mut gpu);
                t0.elapsed().as_secs_f64()
            })
            .collect();
        t.sort_by(f64::total_cmp);
        t[1]
    };
    let ts = time(&mut |g| {
        g.evaluate(&batch, &mats, &request).expect("evaluate");
    });
    let ta = time(&mut |g| {
        g.evaluate_with_features(&batch, &mats, &request, FeatureSet::all())
            .expect("evaluate");
    });
    eprintln!(
        "{} tuples of the presets: specialised {:.1} ms, all features {:.1} ms ({:.2}x)",
        batch.len(),
        ts * 1e3,
        ta * 1e3,
        ta / ts
    );
    finish(gpu);
}

#[test]
fn an_unknown_device_is_a_clear_error() {
    let Some(gpu) = vulkan(None) else { return };
    let name = gpu.device_name();
    finish(gpu);
    let err = VulkanBackend::new(
        Some("no-such-gpu-anywhere".parse().expect("selector")),
        VulkanOptions::default(),
    )
    .err()
    .expect("no such device");
    let msg = err.to_string();
    assert!(
        matches!(err, Error::NoDevice(_))
            && msg.contains("no-such-gpu-anywhere")
            && msg.contains(&name),
        "{msg}"
    );
    let by_index = VulkanBackend::new(Some(DeviceSelector::Index(0)), VulkanOptions::default())
        .expect("device 0");
    drop(by_index);
}
