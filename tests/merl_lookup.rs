//! Measured (MERL) materials: the reference's two lookups (nearest, MERL's own, and linear,
//! FORMULAS.md §7), the materials-file key that chooses one, the Vulkan kernel's lookup held
//! to the reference, and the error of each lookup on analytic materials exported to MERL
//! and read back, by angle band (the table in docs/TABLES.md).

mod common;

use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::Arc;
use vkbrdf::backend::{Backend, Request};
use vkbrdf::material::merl::{self, Lookup, MeasuredMerl, SAMPLES, SCALES};
use vkbrdf::material::{presets, Material, Measured, Model};
use vkbrdf::reference::{self, CpuReference};
use vkbrdf::table::Runner;

/// A table whose stored value at bin (i, j, k) is `(1 + i + 2j + 3·tri(k))·(c + 1)` with
/// tri(k) = min(k, 180 − k): linear in i and j, continuous across φ_d's wrap.
fn synthetic() -> MeasuredMerl {
    let mut values = vec![0.0; 3 * SAMPLES];
    for c in 0..3 {
        for i in 0..90 {
            for j in 0..90 {
                for k in 0..180 {
                    let tri = k.min(180 - k) as f64;
                    values[c * SAMPLES + merl::bin_index(i, j, k)] =
                        (1.0 + i as f64 + 2.0 * j as f64 + 3.0 * tri) * (c as f64 + 1.0);
                }
            }
        }
    }
    MeasuredMerl::from_values(values, std::path::Path::new("<synthetic>")).unwrap()
}

/// The angles of continuous bin coordinates (x, y, z).
fn angles(x: f64, y: f64, z: f64) -> (f64, f64, f64) {
    let u = x / 90.0;
    (u * u * FRAC_PI_2, y / 90.0 * FRAC_PI_2, z / 180.0 * PI)
}

#[test]
fn linear_lookup_interpolates_between_sample_points() {
    let t = synthetic();
    let expect = |x: f64, y: f64, tri: f64, c: usize| {
        (1.0 + x + 2.0 * y + 3.0 * tri) * (c as f64 + 1.0) * SCALES[c]
    };
    // Inside the table: exact for a function linear in the index coordinates.
    for &(x, y, z) in &[(10.25, 20.5, 30.75), (0.5, 0.0, 0.0), (45.0, 44.9, 100.2)] {
        let (th, td, pd) = angles(x, y, z);
        let got = t.linear_half_diff(th, td, pd);
        let tri = z.min(180.0 - z);
        for (c, g) in got.iter().enumerate() {
            let want = expect(x, y, tri, c);
            assert!(
                (g - want).abs() <= 1e-9 * want,
                "({x}, {y}, {z}) channel {c}: {g} vs {want}"
            );
        }
    }
    // φ_d wraps: halfway between k = 179 and k = 180 ≡ 0 is the mean of their values.
    let (th, td, pd) = angles(3.0, 4.0, 179.5);
    let got = t.linear_half_diff(th, td, pd);
    let want = 0.5 * (expect(3.0, 4.0, 1.0, 0) + expect(3.0, 4.0, 0.0, 0));
    assert!((got[0] - want).abs() <= 1e-9 * want, "{} vs {want}", got[0]);
    // Beyond the last sample point θ_h and θ_d hold index 89.
    let (th, td, pd) = angles(89.7, 89.9, 0.0);
    let got = t.linear_half_diff(th, td, pd);
    let want = expect(89.0, 89.0, 0.0, 0);
    assert!((got[0] - want).abs() <= 1e-9 * want, "{} vs {want}", got[0]);
    // At sample points the two lookups agree; between them nearest truncates.
    let (th, td, pd) = angles(12.0, 7.0, 33.0);
    assert_eq!(
        t.lookup_half_diff(th, td, pd),
        t.linear_half_diff(th, td, pd)
    );
    let (th, td, pd) = angles(12.6, 7.6, 33.6);
    let nearest = t.lookup_half_diff(th, td, pd)[0];
    assert!((nearest - expect(12.0, 7.0, 33.0, 0)).abs() <= 1e-9 * nearest);
}

#[test]
fn negative_samples_read_as_zero_in_both_lookups() {
    let mut values = vec![2.0; 3 * SAMPLES];
    values[merl::bin_index(10, 10, 10)] = merl::INVALID;
    let t = MeasuredMerl::from_values(values, std::path::Path::new("<t>")).unwrap();
    let (th, td, pd) = angles(10.5, 10.0, 10.0);
    assert_eq!(t.lookup_half_diff(th, td, pd)[0], 0.0);
    let lin = t.linear_half_diff(th, td, pd)[0];
    assert!((lin - 0.5 * 2.0 * SCALES[0]).abs() < 1e-12, "{lin}");
}

fn write_merl(dir: &std::path::Path, values: &[f64]) -> std::path::PathBuf {
    let path = dir.join("m.binary");
    vkbrdf::table::merl::write_values(&path, values).unwrap();
    path
}

#[test]
fn the_lookup_key_chooses_and_bad_values_are_named() {
    let dir = tempfile::tempdir().unwrap();
    write_merl(dir.path(), &vec![1.0; 3 * SAMPLES]);
    let base = dir.path();
    let parse = |body: &str| {
        vkbrdf::material::parse_materials_in(
            &format!("[[material]]\nname = \"m\"\n{body}\n"),
            "test.toml",
            base,
        )
    };
    let lookup_of = |m: &Material| match &m.model {
        Model::Measured(d) => d.lookup,
        _ => panic!("not measured"),
    };
    let m = parse("model = \"merl\"\nfile = \"m.binary\"").unwrap();
    assert_eq!(lookup_of(&m[0]), Lookup::Nearest);
    let m = parse("model = \"merl\"\nfile = \"m.binary\"\nlookup = \"linear\"").unwrap();
    assert_eq!(lookup_of(&m[0]), Lookup::Linear);
    let e = parse("model = \"merl\"\nfile = \"m.binary\"\nlookup = \"cubic\"")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("lookup") && e.contains("nearest") && e.contains("linear"),
        "{e}"
    );
    let e = parse("model = \"lambert\"\nlookup = \"linear\"")
        .unwrap_err()
        .to_string();
    assert!(e.contains("lookup"), "{e}");
}

/// `material` exported to MERL through the reference, as a measured material read by
/// `lookup` (in memory).
fn exported(material: &Material, lookup: Lookup) -> Material {
    let mut reference = CpuReference::new();
    let values = vkbrdf::table::merl::compute(&mut Runner::new(&mut reference), material).unwrap();
    let source = std::path::PathBuf::from(format!("<{}>", material.name));
    let data = Arc::new(MeasuredMerl::from_values(values, &source).unwrap());
    measured(&data, &source, lookup, &material.name)
}

fn measured(
    data: &Arc<MeasuredMerl>,
    path: &std::path::Path,
    lookup: Lookup,
    name: &str,
) -> Material {
    Material {
        name: format!("{name} ({})", lookup.toml_name()),
        model: Model::Measured(Measured {
            path: path.to_owned(),
            data: data.clone(),
            lookup,
        }),
        diffuse: [0.0; 3],
        specular: [1.0; 3],
        precision: vkbrdf::material::precision::Precision::Exact,
        spectral: None,
    }
}

#[test]
fn measured_materials_evaluate_on_vulkan_and_agree_with_the_reference() {
    let Some(mut gpu) = common::vulkan() else {
        return;
    };
    let gold = presets::preset("gold").unwrap().unwrap();
    let nearest = exported(&gold, Lookup::Nearest);
    let Model::Measured(d) = &nearest.model else {
        unreachable!()
    };
    let linear = measured(&d.data, &d.path, Lookup::Linear, "gold");
    let plastic = exported(
        &presets::preset("shiny-plastic").unwrap().unwrap(),
        Lookup::Linear,
    );
    // Two tables, both lookups, and an analytic material in one (bucketed) batch.
    let materials = vec![nearest, gold.clone(), linear, plastic];
    let batch = vkbrdf::sample::sample_batch(40_000, materials.len(), 3, false);
    for round in 0..2 {
        let out = gpu
            .evaluate(&batch, &materials, &Request { terms: true })
            .unwrap();
        let mut worst = 0.0f64;
        for r in 0..batch.len() {
            let t = batch.tuple(r);
            let e = reference::evaluate_tuple(&t, &materials[t.material]);
            for c in 0..3 {
                let (got, want) = (f64::from(out.brdf[3 * r + c]), e.brdf[c]);
                let err = (got - want).abs() / want.abs().max(1e-6);
                worst = worst.max(err);
                // The contract's relative tolerance (check::RELATIVE_TOLERANCE): the kernel
                // reads the table in f32 and interpolates in f32.
                assert!(
                    err <= 1e-5,
                    "row {r} ({}) channel {c}: vulkan {got}, reference {want}",
                    materials[t.material].name
                );
            }
        }
        eprintln!("round {round}: largest relative difference from the reference {worst:.2e}");
    }
    // Two tables, uploaded once for both batches.
    assert_eq!(gpu.measured_uploads(), 2);
}

/// Relative error of each lookup against the analytic material, by the band of
/// max(θ_i, θ_o): returns per band (label, samples, median nearest, p99 nearest, median
/// linear, p99 linear).
#[allow(clippy::type_complexity)]
fn band_errors(material: &Material) -> Vec<(&'static str, usize, f64, f64, f64, f64)> {
    use rand::{Rng, SeedableRng};
    let near = exported(material, Lookup::Nearest);
    let Model::Measured(d) = &near.model else {
        unreachable!()
    };
    let bands: [(&str, f64, f64); 5] = [
        ("0-30°", 0.0, 30.0),
        ("30-60°", 30.0, 60.0),
        ("60-75°", 60.0, 75.0),
        ("75-85°", 75.0, 85.0),
        ("85-90°", 85.0, 90.0),
    ];
    let mut errs: Vec<(Vec<f64>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); bands.len()];
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
    let n = [0.0, 0.0, 1.0];
    while errs.iter().any(|e| e.0.len() < 4000) {
        let dir = |rng: &mut rand_pcg::Pcg64Mcg| {
            let z: f64 = rng.random_range(0.0..1.0);
            let phi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
            let r = (1.0 - z * z).sqrt();
            [r * phi.cos(), r * phi.sin(), z]
        };
        let (l, v) = (dir(&mut rng), dir(&mut rng));
        let theta = l[2].min(v[2]).acos().to_degrees();
        let Some(b) = bands
            .iter()
            .position(|&(_, lo, hi)| theta >= lo && theta < hi)
        else {
            continue;
        };
        if errs[b].0.len() >= 4000 {
            continue;
        }
        let want = reference::evaluate(l, v, n, None, material).brdf;
        let got_n = d.data.lookup_with(Lookup::Nearest, l, v, n);
        let got_l = d.data.lookup_with(Lookup::Linear, l, v, n);
        let rel = |g: [f64; 3]| {
            (0..3)
                .map(|c| (g[c] - want[c]).abs() / want[c].abs().max(1e-6))
                .fold(0.0, f64::max)
        };
        errs[b].0.push(rel(got_n));
        errs[b].1.push(rel(got_l));
    }
    let q = |mut v: Vec<f64>, p: f64| {
        v.sort_by(f64::total_cmp);
        v[((v.len() - 1) as f64 * p) as usize]
    };
    bands
        .iter()
        .zip(errs)
        .map(|(&(label, _, _), (en, el))| {
            (
                label,
                en.len(),
                q(en.clone(), 0.5),
                q(en, 0.99),
                q(el.clone(), 0.5),
                q(el, 0.99),
            )
        })
        .collect()
}

/// The linear lookup is closer to the analytic material than MERL's nearest-bin lookup at
/// the median in every band where the nearest one is off by more than f32 round-off, for a
/// glossy metal and a plastic (the figures of docs/TABLES.md, printed with --nocapture).
#[test]
fn linear_lookup_beats_nearest_on_exported_materials() {
    for name in ["gold", "shiny-plastic"] {
        let m = presets::preset(name).unwrap().unwrap();
        eprintln!(
            "{name}: band | samples | nearest median | nearest p99 | linear median | linear p99"
        );
        for (label, count, nm, n99, lm, l99) in band_errors(&m) {
            eprintln!("| {label} | {count} | {nm:.2e} | {n99:.2e} | {lm:.2e} | {l99:.2e} |");
            // Where both are at f32 round-off (a plastic's flat diffuse region) they tie.
            assert!(
                lm < nm || (nm < 1e-6 && lm < 1e-6),
                "{name} {label}: linear median {lm:e} not below nearest {nm:e}"
            );
        }
    }
}

#[test]
fn materials_file_merl_runs_through_parse() {
    // A measured material named in a materials file reaches the reference with its lookup.
    let dir = tempfile::tempdir().unwrap();
    let mut values = vec![1.0; 3 * SAMPLES];
    values[merl::bin_index(0, 0, 0)] = 5.0;
    write_merl(dir.path(), &values);
    let list = vkbrdf::material::parse_materials_in(
        "[[material]]\nname = \"m\"\nmodel = \"merl\"\nfile = \"m.binary\"\nlookup = \"linear\"\n",
        "t.toml",
        dir.path(),
    )
    .unwrap();
    // At normal incidence and view: bin (0, 0, 0) exactly.
    let e = reference::evaluate(
        [0.0, 0.0, 1.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, 1.0],
        None,
        &list[0],
    );
    assert!((e.brdf[0] - 5.0 * SCALES[0]).abs() < 1e-15, "{:?}", e.brdf);
}

/// A measured material's half/difference slice made on the device (the kernel makes the
/// directions itself) equals the reference's slice, both lookups.
#[test]
fn measured_slice_on_vulkan_matches_the_reference() {
    use vkbrdf::table::slice::{compute, Spacing};
    use vkbrdf::table::Grid;
    let Some(mut gpu) = common::vulkan() else {
        return;
    };
    let gold = presets::preset("gold").unwrap().unwrap();
    let nearest = exported(&gold, Lookup::Nearest);
    let Model::Measured(d) = &nearest.model else {
        unreachable!()
    };
    let linear = measured(&d.data, &d.path, Lookup::Linear, "gold");
    let grid = Grid::new(64, 48).unwrap();
    for m in [&nearest, &linear] {
        let (want, _) = compute(
            &mut Runner::new(&mut CpuReference::new()),
            m,
            grid,
            Spacing::Sqrt,
            false,
        )
        .unwrap();
        let (got, _) = compute(&mut Runner::new(&mut gpu), m, grid, Spacing::Sqrt, false).unwrap();
        for (k, (g, w)) in got.iter().zip(&want).enumerate() {
            let err = (f64::from(*g) - f64::from(*w)).abs() / f64::from(w.abs()).max(1e-6);
            assert!(
                err <= 1e-5,
                "{} texel {}: vulkan {g}, reference {w}",
                m.name,
                k / 3
            );
        }
    }
}
