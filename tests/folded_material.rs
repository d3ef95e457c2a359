//! A batch of one material is evaluated by a kernel with the material folded in as
//! specialization constants (docs/VULKAN.md, "Specialised kernels"): the compiler then
//! folds the material's arithmetic, which may round differently from the kernel that reads
//! the material table. These tests hold the folded kernels to FORMULAS.md §1's rule on each
//! check combination's hardest tuples, and hold the folding to its budget: a caller that
//! changes the material from batch to batch (a fit) must not compile a kernel each time.

mod common;

use common::rule::assert_within_rule;
use std::collections::BTreeSet;
use vkbrdf::backend::{Backend, Request};
use vkbrdf::batch::Batch;
use vkbrdf::check;
use vkbrdf::gpu::{DeviceSelector, VulkanBackend, VulkanOptions, FOLDED_MATERIALS_MAX};
use vkbrdf::material::{parse_materials, Material};
use vkbrdf::reference::CpuReference;

/// The Vulkan backend (validation on) folding every single-material batch of at least
/// `min_tuples` rows, or `None` as `common::vulkan` decides.
fn vulkan_folding(min_tuples: usize) -> Option<VulkanBackend> {
    let options = VulkanOptions {
        validation: true,
        fold_material_min_tuples: min_tuples,
        ..VulkanOptions::default()
    };
    match VulkanBackend::new(DeviceSelector::from_env(), options) {
        Ok(b) => Some(b),
        Err(e) => {
            drop(common::vulkan()); // panics under VKBRDF_REQUIRE_VULKAN=1, else says it skips
            eprintln!("no Vulkan device: {e}");
            None
        }
    }
}

/// The rows of `batch` that use material `k`, as a batch of that one material.
fn one_material(batch: &Batch, k: usize) -> Batch<'static> {
    let cols = batch.columns();
    let mut rows = Vec::new();
    for row in batch.as_slice().chunks(cols) {
        if row[9] as usize == k {
            let at = rows.len() + 9;
            rows.extend_from_slice(row);
            rows[at] = 0.0;
        }
    }
    Batch::new(rows, cols, 1, std::path::Path::new("one material")).expect("valid")
}

#[test]
fn folded_kernels_are_within_the_rule_on_every_term() {
    // Combinations chosen until every word of their names (the model, the convention and
    // each term) has been seen: every term's code runs folded at least once.
    let mut seen = BTreeSet::new();
    let chosen: Vec<check::Combination> = check::combinations(11)
        .expect("combinations")
        .into_iter()
        .filter(|c| {
            let words: Vec<String> = c.name.split_whitespace().map(String::from).collect();
            let new = words.iter().any(|w| !seen.contains(w));
            seen.extend(words);
            new
        })
        .collect();
    assert!(
        chosen.len() > FOLDED_MATERIALS_MAX,
        "the budget is crossed below"
    );
    let mut reference = CpuReference::new();
    let request = Request { terms: true };
    for group in chosen.chunks(FOLDED_MATERIALS_MAX) {
        let Some(mut gpu) = vulkan_folding(0) else {
            return;
        };
        for (i, c) in group.iter().enumerate() {
            let batch = one_material(&check::generate(c, 30_000, i as u64).expect("batch"), 0);
            let mats = &c.materials[..1];
            let out = gpu.evaluate(&batch, mats, &request).expect("evaluate");
            assert!(gpu.last_material_folded(), "{}: not folded", c.name);
            let want = reference
                .evaluate(&batch, mats, &request)
                .expect("reference");
            assert_eq!(out.counts, want.counts, "{}", c.name);
            assert_within_rule(&c.name, &batch, mats, &out, &want);
        }
    }
}

/// `n` GGX materials that differ only in their roughness.
fn distinct_materials(n: usize) -> Vec<Material> {
    (0..n)
        .map(|i| {
            let toml = format!(
                "[[material]]\nname = \"m{i}\"\nmodel = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = {}\ngeometry = \"smith\"\nfresnel = \"schlick\"\nf0 = 0.04\n",
                0.1 + 0.01 * i as f64
            );
            parse_materials(&toml, "test").expect("valid").remove(0)
        })
        .collect()
}

#[test]
fn folding_stops_at_its_budget_and_below_its_size() {
    let Some(mut gpu) = vulkan_folding(1_000) else {
        return;
    };
    let mats = distinct_materials(FOLDED_MATERIALS_MAX + 2);
    let batch = vkbrdf::sample::sample_batch(1_000, 1, 3, false);
    let small = vkbrdf::sample::sample_batch(999, 1, 3, false);
    let request = Request::default();
    let mut table_gpu = vulkan_folding(usize::MAX).expect("a device, as above");
    for (i, m) in mats.iter().enumerate() {
        let one = std::slice::from_ref(m);
        let out = gpu.evaluate(&batch, one, &request).expect("evaluate");
        assert_eq!(
            gpu.last_material_folded(),
            i < FOLDED_MATERIALS_MAX,
            "material {i}: folded only while the budget lasts"
        );
        let table = table_gpu.evaluate(&batch, one, &request).expect("evaluate");
        assert!(!table_gpu.last_material_folded());
        // Bit for bit on lavapipe (measured); a compiler that fuses the folded constants
        // differently moves the last bits only: 4 ulps.
        for (a, b) in out.brdf.iter().zip(&table.brdf) {
            assert!((a - b).abs() <= 4.0 * f32::EPSILON * b.abs(), "{a} vs {b}");
        }
    }
    // A material folded before is reused, past the budget too.
    gpu.evaluate(&batch, &mats[..1], &request)
        .expect("evaluate");
    assert!(gpu.last_material_folded());
    // Below the size, no fold; several materials, no fold.
    gpu.evaluate(&small, &mats[..1], &request)
        .expect("evaluate");
    assert!(!gpu.last_material_folded());
    let two = vkbrdf::sample::sample_batch(1_000, 2, 3, false);
    gpu.evaluate(&two, &mats[..2], &request).expect("evaluate");
    assert!(!gpu.last_material_folded());
}

/// A folded kernel takes 1–4 rows an invocation (`VulkanOptions::folded_tuples_per_invocation`,
/// rows `stride` apart): every row is evaluated once, whatever the batch's length and its
/// chunks, and the counts and the first invalid row are the reference's — with invalid
/// rows placed on each side of the strides' boundaries, and batches shorter than the
/// rows an invocation takes.
#[test]
fn several_rows_an_invocation_evaluate_every_row_once() {
    let c = check::combinations(1)
        .expect("combinations")
        .into_iter()
        .find(|c| c.name.contains("ggx") && c.name.contains("conductor"))
        .expect("a GGX conductor combination");
    let mats = &c.materials[..1];
    let mut reference = CpuReference::new();
    let request = Request { terms: true };
    for per_invocation in 1..=4u32 {
        let options = VulkanOptions {
            validation: true,
            fold_material_min_tuples: 0,
            folded_tuples_per_invocation: Some(per_invocation),
            // 1 MiB: a 30,011-row batch goes through in several chunks, each its own
            // dispatch and stride.
            max_gpu_memory: 1 << 20,
            ..VulkanOptions::default()
        };
        let Ok(mut gpu) = VulkanBackend::new(DeviceSelector::from_env(), options) else {
            drop(common::vulkan());
            return;
        };
        for n in [1usize, 2, 3, 5, 4_099, 30_011] {
            // Every row of the combination's tuples with its first material.
            let generated = check::generate(&c, n, 7).expect("batch");
            assert_eq!(generated.len(), n);
            let mut rows = generated.as_slice().to_vec();
            for row in rows.chunks_exact_mut(10) {
                row[9] = 0.0;
            }
            // Invalid rows at the ends of the strides (n = 4,099, 4 a lane: stride 1,025).
            let stride = n.div_ceil(per_invocation as usize);
            for r in [stride.saturating_sub(1), stride, 2 * stride + 1, n - 1] {
                if r < n && n > 3 {
                    rows[r * 10] = f32::NAN;
                }
            }
            let batch = Batch::new(rows, 10, 1, std::path::Path::new("strides")).expect("valid");
            let out = gpu.evaluate(&batch, mats, &request).expect("evaluate");
            assert!(gpu.last_material_folded());
            let want = reference
                .evaluate(&batch, mats, &request)
                .expect("reference");
            let what = format!("{per_invocation} rows an invocation, {n} rows");
            assert_eq!(out.counts, want.counts, "{what}");
            assert_within_rule(&what, &batch, mats, &out, &want);
        }
    }
}

/// A folded conductor with a fitted polynomial takes F from it where c ≥ 0.1 and from the
/// metal form below (`conductor_f_poly`, glsl/terms.glsl): both sides of that threshold, the fitted
/// interval's ends and normal incidence, at D's peak and on its slopes, with N = +z (the
/// local frames) and with a tilted N (the general frame), for GGX and Beckmann on the
/// bench's metal, copper and gold — within the rule and with the reference's counts.
#[test]
fn a_folded_conductors_polynomial_is_within_the_rule_at_its_threshold() {
    let Some(mut gpu) = vulkan_folding(0) else {
        return;
    };
    let metals = [
        ("[0.2, 0.92, 1.1]", "[3.9, 2.45, 2.14]"),
        ("[0.27, 0.68, 1.2]", "[3.61, 2.63, 2.3]"),
        ("[0.18, 0.42, 1.37]", "[3.42, 2.35, 1.77]"),
    ];
    let below = f32::from_bits(0.1f32.to_bits() - 1);
    let above = f32::from_bits(0.1f32.to_bits() + 1);
    let cs = [
        0.05, 0.0919, below, 0.1, above, 0.3, 0.546875, 0.9, 0.999, 1.0,
    ];
    // N = +z, and N tilted (the rows rotated about the x axis by 0.4 rad).
    let (s, co) = (0.4f32.sin(), 0.4f32.cos());
    let tilt = |w: [f32; 3]| [w[0], co * w[1] - s * w[2], s * w[1] + co * w[2]];
    let mut reference = CpuReference::new();
    let request = Request { terms: true };
    for (ior, extinction) in metals {
        for (dist, geometry, m) in [("ggx", "smith", 0.3), ("beckmann", "smith-fast", 0.1)] {
            let toml = format!(
                "[[material]]\nname = \"metal\"\nmodel = \"cook-torrance\"\ndistribution = \"{dist}\"\nroughness = {m}\ngeometry = \"{geometry}\"\nfresnel = \"conductor\"\nior = {ior}\nextinction = {extinction}\n"
            );
            let mats = parse_materials(&toml, "test").expect("valid");
            let mut rows = Vec::new();
            for &c in &cs {
                let (cd, sd) = (f64::from(c), (1.0 - f64::from(c) * f64::from(c)).sqrt());
                for tan_h in [0.0, m, 3.0 * m] {
                    let th = f64::atan(tan_h);
                    // h in the xz plane, l and v either side of it along y.
                    let h = [th.sin(), 0.0, th.cos()];
                    let l = [cd * h[0], sd, cd * h[2]].map(|x| x as f32);
                    let v = [cd * h[0], -sd, cd * h[2]].map(|x| x as f32);
                    for tilted in [false, true] {
                        let (l, v, n) = if tilted {
                            (tilt(l), tilt(v), tilt([0.0, 0.0, 1.0]))
                        } else {
                            (l, v, [0.0, 0.0, 1.0])
                        };
                        rows.extend_from_slice(&[l, v, n].concat());
                        rows.push(0.0);
                    }
                }
            }
            let batch = Batch::new(rows, 10, 1, std::path::Path::new("threshold")).expect("valid");
            let out = gpu.evaluate(&batch, &mats, &request).expect("evaluate");
            assert!(gpu.last_material_folded());
            let want = reference
                .evaluate(&batch, &mats, &request)
                .expect("reference");
            let what = format!("{dist}, η = {ior} + {extinction}i");
            assert_eq!(out.counts, want.counts, "{what}");
            assert_within_rule(&what, &batch, &mats, &out, &want);
        }
    }
}
