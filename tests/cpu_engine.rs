//! The native CPU engine (`vkbrdf::cpu::CpuEngine`) against the f64 reference: every legal
//! combination under the conformance rule, the stress corpus (no non-finite output, counts
//! equal), results independent of the thread count, mixed-material batches, cancellation.

mod common;

use common::materials;
use common::mixed::{mixed_batch, uniform};
use vkbrdf::backend::{Backend, Request};
use vkbrdf::batch::{memory_source, Batch};
use vkbrdf::cancel::Cancel;
use vkbrdf::check::{self, CheckOptions};
use vkbrdf::cpu::plan::Plan;
use vkbrdf::cpu::CpuEngine;
use vkbrdf::material::Material;
use vkbrdf::reference::CpuReference;

#[test]
fn every_combination_matches_the_reference_on_every_instruction_set() {
    // The best variant at the check's full size, the others (scalar always) at a third.
    for isa in vkbrdf::cpu::Isa::available_all() {
        let tuples = if isa == vkbrdf::cpu::Isa::best() {
            3000
        } else {
            1000
        };
        every_combination_matches_the_reference(CpuEngine::with_isa(2, isa), tuples);
    }
}

fn every_combination_matches_the_reference(mut engine: CpuEngine, tuples: usize) {
    eprintln!("{}", engine.name());
    let options = CheckOptions {
        tuples,
        seed: 7,
        only: None,
    };
    let mut tally = vkbrdf::cpu::Tally::default();
    let reports = check::run(&mut engine.clone(), &options, &mut |_| {}).expect("check run");
    assert_eq!(
        reports.len(),
        common::combinations::check_combination_count()
    );
    // The lanes made the numbers: in the groups they run, the reference re-did few tuples.
    for c in check::combinations(options.seed).expect("combinations") {
        let batch = check::generate(&c, 2000, 1).expect("batch");
        engine
            .evaluate(&batch, &c.materials, &Request { terms: true })
            .expect("evaluate");
        let t = engine.last_tally();
        tally.lanes += t.lanes;
        tally.rescued += t.rescued;
        tally.reference += t.reference;
    }
    eprintln!("{tally:?}");
    assert!(tally.lanes > 100_000, "{tally:?}");
    assert!(tally.rescued * 50 < tally.lanes, "{tally:?}");
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
    assert!(
        failures.is_empty(),
        "{}: {} of {} combinations fail:\n{}",
        engine.name(),
        failures.len(),
        reports.len(),
        failures.join("\n")
    );
    let well = reports
        .iter()
        .map(|r| r.max_rel_well_conditioned)
        .fold(0.0, f64::max);
    assert!(
        well <= check::RELATIVE_TOLERANCE,
        "well-conditioned error {well:e}"
    );
}

#[test]
fn every_group_runs_in_the_lanes_measured_ones_included() {
    let combos = check::combinations(1).expect("combinations");
    // Every model (HTSG included), distribution, geometry, Fresnel term, convention and
    // anisotropy, and the measured (MERL) tables, in the lanes.
    for c in &combos {
        for m in &c.materials {
            assert!(Plan::for_material(m).is_simd(), "{}: {}", c.name, m.name);
        }
    }
    assert_eq!(
        combos.len(),
        common::combinations::check_combination_count()
    );
}

#[test]
fn measured_lookups_in_the_lanes_are_the_references() {
    let mut engine = CpuEngine::with_threads(2);
    let mut reference = CpuReference::new();
    let request = Request { terms: true };
    let mut seen = 0;
    for c in check::combinations(3).expect("combinations") {
        if !c.name.starts_with("merl") {
            continue;
        }
        seen += 1;
        let linear = c.name.contains("linear");
        let batch = check::generate(&c, 200_000, 11).expect("batch");
        let got = engine.evaluate(&batch, &c.materials, &request).unwrap();
        let tally = engine.last_tally();
        let want = reference.evaluate(&batch, &c.materials, &request).unwrap();
        assert_eq!(got.counts, want.counts, "{}", c.name);
        assert_eq!(tally.reference, 0, "{}: {tally:?}", c.name);
        assert!(tally.rescued * 10 < tally.lanes, "{}: {tally:?}", c.name);
        let mut differ = 0;
        for (i, (a, b)) in got.brdf.iter().zip(&want.brdf).enumerate() {
            // Nearest: the bin's value, so the same bits. Linear: weights from angles
            // that differ by rounding, so within an f32 ulp.
            let close = if linear {
                (a - b).abs() <= f32::EPSILON * b.abs()
            } else {
                a.to_bits() == b.to_bits()
            };
            if !close {
                differ += 1;
                eprintln!("{} tuple {}: {a:e} vs {b:e}", c.name, i / 3);
            }
        }
        assert_eq!(differ, 0, "{}: {differ} values differ", c.name);
        assert!(
            got.terms == want.terms,
            "{}: the terms are D = 0, G = F = K = 1",
            c.name
        );
    }
    assert_eq!(seen, 2, "the nearest and linear combinations");
}

#[test]
#[allow(clippy::needless_range_loop)] // column c indexes the output and the sensitivities
fn mixed_materials_give_the_reference_counts_and_values_for_any_thread_count() {
    let (batch, mats) = mixed_batch(70_001);
    let request = Request { terms: true };
    let reference = CpuReference::new()
        .evaluate(&batch, &mats, &request)
        .expect("reference");
    let one = CpuEngine::with_threads(1)
        .evaluate(&batch, &mats, &request)
        .expect("one thread");
    let mut engine = CpuEngine::with_threads(3);
    let three = engine
        .evaluate(&batch, &mats, &request)
        .expect("three threads");
    assert_eq!(one, three, "the thread count changed a result");
    // The engine keeps its grouped-order scratch between calls: a smaller mixed batch
    // after a larger one, and one without terms, come out as from a fresh engine.
    let (small, _) = mixed_batch(20_011);
    for terms in [false, true] {
        let r = Request { terms };
        let again = engine.evaluate(&small, &mats, &r).expect("again");
        let fresh = CpuEngine::with_threads(3)
            .evaluate(&small, &mats, &r)
            .expect("fresh");
        assert_eq!(again, fresh, "terms {terms}");
    }
    assert_eq!(one.counts, reference.counts);
    assert!(one.counts.invalid > 0 && one.counts.below_horizon > 0);
    assert_eq!(one.counts.first_invalid, Some(7));
    common::rule::assert_within_rule("mixed batch", &batch, &mats, &one, &reference);
}

/// Anisotropic materials (and an isotropic one) on 13-column rows whose tangents include
/// ones parallel to N and zero (invalid, FORMULAS.md §1) and ones within 1e-7 of N's
/// direction (valid, for the reference to take), or on 10-column rows (no tangent: every
/// anisotropic tuple invalid). Also returns how many tuples are invalid by construction.
fn tangent_batch(n: usize, columns: usize) -> (Batch<'static>, Vec<Material>, u64) {
    let mats = materials(
        r#"
        [[material]]
        name = "ggx-aniso"
        model = "cook-torrance"
        distribution = "ggx"
        geometry = "smith-correlated"
        fresnel = "conductor"
        ior = [0.2, 0.9, 1.1]
        extinction = [3.9, 2.4, 2.2]
        roughness = [0.1, 0.5]
        [[material]]
        name = "beckmann-aniso"
        model = "cook-torrance"
        distribution = "beckmann"
        geometry = "smith-fast"
        fresnel = "schlick"
        f0 = 0.04
        roughness = [0.6, 0.05]
        [[material]]
        name = "ward-aniso"
        model = "ward"
        roughness = [0.3, 0.08]
        diffuse = [0.2, 0.2, 0.2]
        [[material]]
        name = "ggx"
        model = "cook-torrance"
        distribution = "ggx"
        geometry = "smith"
        fresnel = "none"
        roughness = 0.3
        "#,
    );
    let mut rnd = uniform(777);
    let mut rows = Vec::with_capacity(n * columns);
    let mut invalid = 0;
    for i in 0..n {
        let l = [rnd(), rnd(), rnd().abs() + 0.01];
        let v = [rnd(), rnd(), rnd().abs() + 0.01];
        let nrm = [0.1 * rnd(), 0.1 * rnd(), 1.0];
        let material = (i * 5) % 4;
        let mut t = [rnd(), rnd(), rnd()];
        let mut bad = false;
        if i % 89 == 5 {
            t = nrm.map(|x| 2.0 * x); // exactly parallel to N: invalid
            bad = true;
        } else if i % 83 == 2 {
            t = [0.0; 3]; // zero: invalid
            bad = true;
        } else if i % 79 == 1 {
            // Parallel but for 3x's rounding: valid, unless every product rounds exactly
            // (then T × N is exactly 0).
            t = nrm.map(|x| 3.0 * x);
            let p = |a: usize, b: usize| f64::from(t[a]) * f64::from(nrm[b]);
            bad = p(1, 2) == p(2, 1) && p(2, 0) == p(0, 2) && p(0, 1) == p(1, 0);
        }
        invalid += u64::from((bad || columns == 10) && material != 3);
        rows.extend_from_slice(&l);
        rows.extend_from_slice(&v);
        rows.extend_from_slice(&nrm);
        rows.push(material as f32);
        if columns == 13 {
            rows.extend_from_slice(&t);
        }
    }
    let batch = Batch::new(rows, columns, mats.len(), &memory_source()).expect("batch");
    (batch, mats, invalid)
}

#[test]
fn anisotropic_lanes_give_the_reference_counts_and_values_with_and_without_tangents() {
    let request = Request { terms: true };
    for columns in [13, 10] {
        let (batch, mats, invalid) = tangent_batch(20_011, columns);
        let reference = CpuReference::new()
            .evaluate(&batch, &mats, &request)
            .expect("reference");
        let mut engine = CpuEngine::with_threads(1);
        let one = engine
            .evaluate(&batch, &mats, &request)
            .expect("one thread");
        let tally = engine.last_tally();
        let three = CpuEngine::with_threads(3)
            .evaluate(&batch, &mats, &request)
            .expect("three threads");
        assert_eq!(one, three, "the thread count changed a result");
        assert_eq!(one.counts, reference.counts, "{columns} columns");
        assert_eq!(one.counts.invalid, invalid, "{columns} columns");
        if columns == 13 {
            // The lanes took all but the invalid, nearly parallel and below-horizon tuples.
            assert!(tally.rescued * 10 < tally.lanes, "{tally:?}");
        }
        let what = format!("{columns} columns");
        common::rule::assert_within_rule(&what, &batch, &mats, &one, &reference);
    }
}

#[test]
fn without_terms_the_brdf_and_counts_are_the_same() {
    let (batch, mats) = mixed_batch(5_000);
    let with = CpuEngine::new()
        .evaluate(&batch, &mats, &Request { terms: true })
        .expect("with terms");
    let without = CpuEngine::new()
        .evaluate(&batch, &mats, &Request { terms: false })
        .expect("without terms");
    assert!(without.terms.is_none());
    assert_eq!(with.brdf, without.brdf);
    assert_eq!(with.counts, without.counts);
}

#[test]
fn a_cancelled_token_stops_the_evaluation() {
    let (batch, mats) = mixed_batch(50_000);
    let mut engine = CpuEngine::new();
    let cancel = Cancel::new();
    engine.set_cancel(cancel.clone());
    cancel.cancel();
    let r = engine.evaluate(&batch, &mats, &Request::default());
    assert!(matches!(r, Err(vkbrdf::Error::Cancelled)), "{r:?}");
}

#[test]
fn an_empty_batch_gives_empty_outputs() {
    let (_, mats) = mixed_batch(1);
    let batch = Batch::new(Vec::new(), 10, mats.len(), &memory_source()).expect("batch");
    let out = CpuEngine::new()
        .evaluate(&batch, &mats, &Request { terms: true })
        .expect("empty");
    assert!(out.brdf.is_empty());
    assert_eq!(out.counts.tuples, 0);
}

#[test]
fn the_stress_corpus_keeps_the_policy_with_every_count_equal() {
    const TUPLES: usize = 200_000;
    let mut engine = CpuEngine::new();
    let report = vkbrdf::stress::run(&mut engine, TUPLES, 7, 1 << 16, &mut |_| {}).expect("stress");
    assert_eq!(report.tuples, TUPLES as u64);
    assert_eq!(report.non_finite, 0, "{}", report.to_markdown(1e-5));
    assert_eq!(report.invalid.0, report.invalid.1);
    assert_eq!(report.saturated.0, report.saturated.1);
    // Every lane the f32 path cannot decide goes to the reference, which decides the
    // status: even the below-horizon count is the reference's, ambiguous tuples included.
    assert_eq!(report.below_horizon.0, report.below_horizon.1);
    assert!(report.policy_holds(), "{}", report.to_markdown(1e-5));
    assert!(report.saturated.1 > 0 && report.invalid.1 > 0);
    // Accuracy, which the policy does not judge: every quantity in every regime within
    // 1e-5 relative (the rule's relative part; at 10^7 tuples the engine's worst is 6e-6,
    // docs/stress-10m-cpu.md). Lanes that should have gone to the reference — an N of
    // length 1e-43, whose cosines the f64 frame once made +inf — show up here as errors
    // of 1e24, and a frame 5e-15 off as 2e-4 in RTR at e = 1e18.
    for ((quantity, regime), stats) in &report.errors {
        assert!(
            stats.max <= 1e-5,
            "{quantity} / {}: relative error {:.2e}\n{}",
            regime.label(),
            stats.max,
            report.to_markdown(1e-5)
        );
    }
}

// ---------------------------------------------------------------------------------------
// The CLI: `--backend auto|vulkan|cpu|reference`.

fn eval_json(
    dir: &std::path::Path,
    backend: Option<&str>,
    env: &[(&str, &str)],
) -> serde_json::Value {
    let m = dir.join("m.toml");
    std::fs::write(
        &m,
        "[[material]]\nname = \"metal\"\nmodel = \"cook-torrance\"\ndistribution = \"ggx\"\n\
         geometry = \"smith\"\nfresnel = \"conductor\"\nior = [0.2, 0.9, 1.1]\n\
         extinction = [3.9, 2.4, 2.2]\nroughness = 0.3\n",
    )
    .unwrap();
    let t = dir.join("t.npy");
    if !t.exists() {
        assert!(common::generate(&m, 5000, &t).status.success());
    }
    let out = dir.join(format!("brdf-{}.npy", backend.unwrap_or("default")));
    let mut args = vec![
        "eval",
        "-m",
        common::path(&m),
        "-i",
        common::path(&t),
        "-o",
        common::path(&out),
        "--json",
    ];
    if let Some(b) = backend {
        args.extend_from_slice(&["--backend", b]);
    }
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
        .args(&args)
        .env_remove("VKBRDF_DEVICE")
        .envs(env.iter().copied())
        .output()
        .expect("run vkbrdf");
    assert!(o.status.success(), "{:?}: {}", backend, common::stderr(&o));
    serde_json::from_slice(&o.stdout).expect("JSON summary")
}

#[test]
fn backend_cpu_is_the_engine_and_reference_is_the_f64_judge() {
    let dir = tempfile::tempdir().unwrap();
    let cpu = eval_json(dir.path(), Some("cpu"), &[]);
    let reference = eval_json(dir.path(), Some("reference"), &[]);
    let engine = cpu["engine"].as_str().unwrap();
    assert!(engine.starts_with("cpu ("), "{cpu}");
    assert!(
        reference["engine"]
            .as_str()
            .unwrap()
            .starts_with("cpu-reference"),
        "{reference}"
    );
    let (a, _) = vkbrdf::batch::read_npy_f32(&dir.path().join("brdf-cpu.npy")).unwrap();
    let (b, _) = vkbrdf::batch::read_npy_f32(&dir.path().join("brdf-reference.npy")).unwrap();
    assert_eq!(a.len(), b.len());
    assert_ne!(
        a, b,
        "the engine computes in f32: some value differs from the f64 judge's"
    );
    for (x, r) in a.iter().zip(&b) {
        let (x, r) = (f64::from(*x), f64::from(*r));
        assert!((x - r).abs() <= 1e-5 * r.abs().max(1e-6), "{x} vs {r}");
    }
}

#[test]
fn auto_picks_the_engine_without_a_gpu_and_vulkan_for_a_named_device() {
    let has_gpu = vkbrdf::gpu::list_devices().is_ok_and(|l| {
        l.iter()
            .any(|d| d.device_type == "discrete GPU" || d.device_type == "integrated GPU")
    });
    let dir = tempfile::tempdir().unwrap();
    let default = eval_json(dir.path(), None, &[]);
    let auto = eval_json(dir.path(), Some("auto"), &[]);
    assert_eq!(default["engine"], auto["engine"]);
    let name = auto["engine"].as_str().unwrap();
    if has_gpu {
        assert!(!name.starts_with("cpu"), "{name}");
    } else {
        assert!(name.starts_with("cpu ("), "{name}");
    }
    // A named device means Vulkan, whatever its type.
    if let Some(d) = vkbrdf::gpu::list_devices()
        .ok()
        .and_then(|l| l.first().cloned())
    {
        let index = d.index.to_string();
        let named = eval_json(
            dir.path(),
            Some("auto"),
            &[("VKBRDF_DEVICE", index.as_str())],
        );
        assert!(
            named["engine"].as_str().unwrap().starts_with("vulkan"),
            "{named}"
        );
    }
}

#[test]
fn help_and_devices_announce_the_names() {
    let help = common::vkbrdf(&["eval", "--help"]);
    let text = String::from_utf8_lossy(&help.stdout);
    for word in ["auto", "vulkan", "reference", "`cpu` meant it"] {
        assert!(text.contains(word), "eval --help lacks {word:?}: {text}");
    }
    let bad = common::vkbrdf(&["eval", "--backend", "gpu", "-m", "x", "-i", "y", "-o", "z"]);
    assert_eq!(bad.status.code(), Some(2));
    let err = common::stderr(&bad);
    assert!(err.contains("auto") && err.contains("reference"), "{err}");
    if vkbrdf::gpu::list_devices().is_ok_and(|l| !l.is_empty()) {
        let d = common::vkbrdf(&["devices"]);
        let text = String::from_utf8_lossy(&d.stdout);
        assert!(text.contains("--backend auto (the default) runs"), "{text}");
    }
}

#[test]
fn check_runs_on_the_engine() {
    let o = common::vkbrdf(&[
        "check",
        "--backend",
        "cpu",
        "--tuples",
        "300",
        "--filter",
        "beckmann",
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{text}{}", common::stderr(&o));
    assert!(text.contains("backend:   cpu ("), "{text}");
    assert!(text.contains(" 0 fail"), "{text}");
}

#[test]
fn evaluate_into_a_reused_output_equals_evaluate() {
    use vkbrdf::backend::Output;
    let (batch, mats) = mixed_batch(30_000);
    let mut engine = CpuEngine::with_threads(2);
    for terms in [true, false, true] {
        let request = Request { terms };
        let want = engine.evaluate(&batch, &mats, &request).expect("evaluate");
        let mut out = Output {
            brdf: vec![-1.0; 5],
            terms: Some(vec![f32::NAN; 300_000]),
            ..Output::default()
        };
        engine
            .evaluate_into(&batch, &mats, &request, &mut out)
            .expect("into");
        assert_eq!(out, want, "terms {terms}");
        // And again into the same buffers.
        engine
            .evaluate_into(&batch, &mats, &request, &mut out)
            .expect("into");
        assert_eq!(out, want, "terms {terms}, reused");
    }
}

// ---------------------------------------------------------------------------------------
// Tables: the engine makes a slice's directions itself.

#[test]
fn the_engine_made_slice_is_the_host_made_one_bit_for_bit() {
    use vkbrdf::table::slice::{self, Spacing};
    use vkbrdf::table::{Grid, Runner};
    let mats = materials(
        r#"
        [[material]]
        name = "metal"
        preset = "gold"
        [[material]]
        name = "brushed"
        preset = "aluminium"
        roughness = [0.05, 0.5]
        [[material]]
        name = "phong"
        model = "blinn-phong"
        exponent = 200
        [[material]]
        name = "glass"
        preset = "glass"
        "#,
    );
    let mut engine = CpuEngine::with_threads(3);
    assert!(engine.generated_directions().is_some());
    for m in &mats {
        // Shapes with tail blocks and several chunks (16,384 texels a chunk).
        for (w, h) in [(90, 90), (7, 13), (257, 3), (1000, 70)] {
            let grid = Grid::new(w, h).unwrap();
            for spacing in [Spacing::Sqrt, Spacing::Linear] {
                let made =
                    slice::compute(&mut Runner::new(&mut engine), m, grid, spacing, true).unwrap();
                let sent = slice::compute_from_tuples(
                    &mut Runner::new(&mut engine),
                    m,
                    grid,
                    spacing,
                    true,
                )
                .unwrap();
                assert_eq!(made.0.len(), w * h * 3);
                assert!(
                    made == sent,
                    "{} {w}x{h} {spacing:?}: the engine's directions differ",
                    m.name
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Tables: the engine makes the albedo and DFG tables' importance samples itself.

/// `(μ, α)` points from grazing to normal view and from α = 2⁻¹⁰ to 1.
fn importance_points() -> Vec<(f64, f64)> {
    let mut points = Vec::new();
    for mu in [0.004, 0.03, 0.31, 0.77, 1.0] {
        for alpha in [1.0 / 1024.0, 0.02, 0.3, 0.81, 1.0] {
            points.push((mu, alpha));
        }
    }
    points
}

#[test]
fn the_engine_made_importance_sums_are_the_host_made_ones() {
    use vkbrdf::material::Geometry;
    use vkbrdf::table::albedo::{self, Lobe, Microfacet};
    use vkbrdf::table::dfg::schlick_weight;
    use vkbrdf::table::Runner;
    let points = importance_points();
    // A fused group of each distribution, and a two-pass one (schlick-smith, neubelt).
    let specs = [
        (Lobe::Ggx, Geometry::SmithCorrelated),
        (Lobe::Beckmann, Geometry::Smith),
        (Lobe::Beckmann, Geometry::SmithFast),
        (Lobe::Ggx, Geometry::SchlickSmith),
        (Lobe::Beckmann, Geometry::Neubelt),
    ];
    let mut engine = CpuEngine::with_threads(3);
    let mut one = CpuEngine::with_threads(1);
    for (lobe, geometry) in specs {
        let spec = Microfacet { lobe, geometry };
        // One block of samples (the engine's sums are the host's bits), and several with
        // a partial last one (block sums added in order: equal to rounding).
        for samples in [1000, 4096, 3 * 4096 + 17] {
            let what = format!("{lobe:?} {geometry:?} {samples} samples");
            let made =
                albedo::backend_sums(&mut Runner::new(&mut engine), &spec, &points, samples, "t")
                    .expect("the engine makes the samples")
                    .unwrap();
            let alone =
                albedo::backend_sums(&mut Runner::new(&mut one), &spec, &points, samples, "t")
                    .expect("the engine makes the samples")
                    .unwrap();
            assert!(made == alone, "{what}: the thread count changed the sums");
            let sent = albedo::integrate(
                &mut Runner::new(&mut engine),
                &spec,
                &points,
                samples,
                "t",
                |c| [1.0, schlick_weight(c)],
            )
            .unwrap();
            assert_eq!(made.len(), points.len());
            for (p, (m, s)) in made.iter().zip(&sent).enumerate() {
                for k in 0..2 {
                    let (a, b) = (m[k], s[k]);
                    assert!(a.is_finite() && a >= 0.0, "{what}: point {p} sum {k} = {a}");
                    if samples <= 4096 {
                        assert_eq!(a.to_bits(), b.to_bits(), "{what}: point {p} sum {k}");
                    } else {
                        // Block sums added in another order: measured up to 9.2e-15.
                        assert!(
                            (a - b).abs() <= 3e-14 * b.abs(),
                            "{what}: point {p} sum {k}: {a} vs {b}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn a_cancelled_token_stops_the_importance_sums() {
    use vkbrdf::backend::GeneratedDirections;
    use vkbrdf::material::Geometry;
    use vkbrdf::table::albedo::{self, Lobe, Microfacet};
    use vkbrdf::table::Runner;
    let spec = Microfacet {
        lobe: Lobe::Ggx,
        geometry: Geometry::SmithCorrelated,
    };
    let cancel = Cancel::new();
    let mut engine = CpuEngine::with_threads(2);
    let _: Option<&mut dyn GeneratedDirections> = engine.generated_directions();
    cancel.cancel();
    let mut runner = Runner::new(&mut engine).with_cancel(cancel);
    let r = albedo::backend_sums(&mut runner, &spec, &importance_points(), 1 << 16, "t")
        .expect("the engine makes the samples");
    assert!(
        matches!(r, Err(vkbrdf::Error::Cancelled)),
        "got {:?}",
        r.map(|s| s.len())
    );
}
