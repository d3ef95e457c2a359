//! Table generators (`vkbrdf table`): every kind writes a file that is read back (EXR
//! through the `exr` crate, MERL through the project's reader, PNG through `png`); albedo,
//! E_avg and DFG match an independent, much denser integration of the f64 reference to
//! 1e-4; the MERL export → import → lookup round trip returns the analytic values at the
//! bin sample points; bad input fails clearly and leaves no file.
//!
//! Each body takes `&mut dyn Backend` and runs on every backend (`common::backends()`:
//! the CPU reference, and Vulkan when a device exists or `VKBRDF_REQUIRE_VULKAN=1`).

mod common;

use exr::prelude::{AttributeValue, FlatSamples};
use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::{Path, PathBuf};
use vkbrdf::backend::Backend;
use vkbrdf::material::{presets, Geometry, Material};
use vkbrdf::reference::{self, frame};
use vkbrdf::table::albedo::{self, AlbedoJob, Lobe, Microfacet};
use vkbrdf::table::dfg::{self, DfgJob};
use vkbrdf::table::slice::{self, SliceJob, Spacing};
use vkbrdf::table::{merl, preview, Grid, Runner};

/// The accuracy the integrated tables promise (issue 6).
const ACCURACY: f64 = 1e-4;

// ---------------------------------------------------------------------------------------
// The independent integration: dense composite Gauss–Legendre over (θ_l, φ_l) of the f64
// reference, with sinh substitutions centred on the mirror direction that resolve the peak.

/// 8-point Gauss–Legendre on [−1, 1] (Abramowitz & Stegun table 25.4), typed in rather than
/// computed, so the check shares no code with the library's quadrature.
const GL8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];

/// `∫_a^b g` (componentwise) by `panels` panels of 8-point Gauss–Legendre.
fn composite<const K: usize>(
    a: f64,
    b: f64,
    panels: usize,
    mut g: impl FnMut(f64) -> [f64; K],
) -> [f64; K] {
    let h = (b - a) / panels as f64;
    let mut sum = [0.0; K];
    for p in 0..panels {
        let mid = a + (p as f64 + 0.5) * h;
        for &(x, w) in &GL8 {
            let y = g(mid + 0.5 * h * x);
            for k in 0..K {
                sum[k] += 0.5 * h * w * y[k];
            }
        }
    }
    sum
}

/// `[∫ f cos_i dω, ∫ f (1 − (1−c)⁵) cos_i dω, ∫ f (1−c)⁵ cos_i dω]` for `v` at cosine `mu`
/// (φ = 0) over the hemisphere, f from `reference::evaluate` in f64. The lobe sits at the
/// mirror direction (θ_o, φ = π) with widths ≈ 2α in θ and 2αμ/sin θ_o in φ (the reflection
/// compresses the out-of-plane spread by v·h ≈ μ); `θ = θ_o + w_θ sinh t` and
/// `φ = π − w_φ sinh s` put the quadrature points where the lobe is. Symmetric in φ.
fn independent(m: &Material, mu: f64, alpha: f64, panels: usize) -> [f64; 3] {
    let theta_o = mu.acos();
    let v = [theta_o.sin(), 0.0, mu];
    let wt = alpha.max(1e-4);
    let wp = (2.0 * alpha * mu / theta_o.sin().max(1e-9)).clamp(1e-7, 1.0);
    let (ta, tb) = (
        (-theta_o / wt).asinh(),
        ((FRAC_PI_2 - theta_o) / wt).asinh(),
    );
    let sb = (PI / wp).asinh();
    composite(ta, tb, panels, |t| {
        let theta = theta_o + wt * t.sinh();
        let jt = wt * t.cosh();
        composite(0.0, sb, panels, |s| {
            let phi = PI - wp * s.sinh();
            let l = [
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ];
            let e = reference::evaluate(l, v, [0.0, 0.0, 1.0], None, m);
            if e.brdf[0] == 0.0 {
                return [0.0; 3];
            }
            let h = frame::normalize([l[0] + v[0], l[1] + v[1], l[2] + v[2]]).unwrap();
            let w5 = (1.0 - frame::dot(v, h)).powi(5);
            let base = 2.0 * e.brdf[0] * theta.cos() * theta.sin() * wp * s.cosh() * jt;
            [base, base * (1.0 - w5), base * w5]
        })
    })
}

/// The independent values at 48 panels (384² points), asserting that 64 panels agree to
/// 1e-6 (so the reference itself is 100× better than the tolerance).
fn converged(m: &Material, mu: f64, alpha: f64) -> [f64; 3] {
    let coarse = independent(m, mu, alpha, 48);
    let fine = independent(m, mu, alpha, 64);
    for k in 0..3 {
        assert!(
            (coarse[k] - fine[k]).abs() < 1e-6,
            "independent integration not converged at mu={mu} alpha={alpha}: {coarse:?} vs {fine:?}"
        );
    }
    fine
}

/// Points covering grazing and normal views, tiny to full roughness; (0.39, 0.047) is the
/// worst texel of the 32×32 GGX scan.
const POINTS: [(f64, f64); 9] = [
    (1.0 / 64.0, 1.0 / 64.0),
    (1.0 / 64.0, 0.6),
    (0.05, 1.0 / 1024.0),
    (0.1, 0.0039),
    (0.390625, 0.046875),
    (0.5, 1.0 / 1024.0),
    (0.5, 0.2),
    (0.9, 0.5),
    (0.99, 0.99),
];

fn specs() -> [Microfacet; 3] {
    [
        Microfacet {
            lobe: Lobe::Ggx,
            geometry: Geometry::SmithCorrelated,
        },
        Microfacet {
            lobe: Lobe::Beckmann,
            geometry: Geometry::SmithCorrelated,
        },
        Microfacet {
            lobe: Lobe::Beckmann,
            geometry: Geometry::Smith,
        },
    ]
}

fn for_each_backend(body: impl Fn(&mut dyn Backend)) {
    for mut b in common::backends() {
        eprintln!("-- backend {}", b.name());
        body(b.as_mut());
    }
}

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

// ---------------------------------------------------------------------------------------
// Accuracy.

fn albedo_and_dfg_accuracy(backend: &mut dyn Backend) {
    let mut runner = Runner::new(backend);
    let mut worst = 0.0f64;
    for spec in specs() {
        let points: Vec<(f64, f64)> = POINTS.to_vec();
        let e = albedo::directional_albedo(&mut runner, &spec, &points, albedo::DEFAULT_SAMPLES)
            .unwrap();
        let ab = dfg::split_sum(&mut runner, &spec, &points, albedo::DEFAULT_SAMPLES).unwrap();
        for (p, &(mu, alpha)) in points.iter().enumerate() {
            let want = converged(&spec.material(alpha).unwrap(), mu, alpha);
            let got = [e[p], ab[p][0], ab[p][1]];
            for k in 0..3 {
                let err = (got[k] - want[k]).abs();
                worst = worst.max(err);
                assert!(
                    err <= ACCURACY,
                    "{} {}: mu={mu} alpha={alpha}: got {got:?}, independent {want:?}",
                    spec.describe(),
                    ["E", "A", "B"][k]
                );
            }
            assert!(
                e[p] <= 1.0 + ACCURACY,
                "E > 1 at mu={mu} alpha={alpha}: {}",
                e[p]
            );
            assert!(ab[p][0] >= 0.0 && ab[p][1] >= 0.0);
            assert!(ab[p][0] + ab[p][1] <= 1.0 + ACCURACY);
            assert!(
                (ab[p][0] + ab[p][1] - e[p]).abs() < 1e-9,
                "A + B must equal E"
            );
        }
    }
    eprintln!("albedo/DFG: max |error| vs independent integration = {worst:.2e}");
}

#[test]
fn albedo_and_dfg_match_independent_integration() {
    for_each_backend(albedo_and_dfg_accuracy);
}

fn average_accuracy(backend: &mut dyn Backend) {
    let mut runner = Runner::new(backend);
    let spec = specs()[0];
    let alphas = [0.05, 0.6];
    let got = albedo::average_albedo(&mut runner, &spec, &alphas, albedo::DEFAULT_SAMPLES).unwrap();
    for (a, &alpha) in alphas.iter().enumerate() {
        let m = spec.material(alpha).unwrap();
        // 2∫E μ dμ by 4 panels of 8-point Gauss–Legendre in μ, each E independent (24 panels).
        let [want] = composite(0.0, 1.0, 4, |mu| {
            [2.0 * mu * independent(&m, mu, alpha, 24)[0]]
        });
        eprintln!("E_avg({alpha}) = {} (independent {want})", got[a]);
        assert!(
            (got[a] - want).abs() <= ACCURACY,
            "E_avg({alpha}) = {}, independent {want}",
            got[a]
        );
        assert!(got[a] <= 1.0);
    }
}

#[test]
fn albedo_average_matches_independent_integration() {
    for_each_backend(average_accuracy);
}

// ---------------------------------------------------------------------------------------
// Files read back.

type Layers = Vec<(
    Option<String>,
    (usize, usize),
    HashMap<String, String>,
    Vec<(String, FlatSamples)>,
)>;

/// Every layer of an EXR: name, size, text attributes, channels.
fn read_exr(path: &Path) -> Layers {
    let image = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
    image
        .layer_data
        .into_iter()
        .map(|l| {
            let attrs = l
                .attributes
                .other
                .iter()
                .filter_map(|(k, v)| match v {
                    AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
                    _ => None,
                })
                .collect();
            let channels = l
                .channel_data
                .list
                .into_iter()
                .map(|c| (c.name.to_string(), c.sample_data))
                .collect();
            (
                l.attributes.layer_name.map(|n| n.to_string()),
                (l.size.0, l.size.1),
                attrs,
                channels,
            )
        })
        .collect()
}

fn f32s(s: &FlatSamples) -> Vec<f32> {
    s.values_as_f32().collect()
}

fn assert_provenance(attrs: &HashMap<String, String>, table: &str, material: &str) {
    for key in [
        "material",
        "convention",
        "parameterisation",
        "texelCentres",
        "samples",
        "version",
        "backend",
    ] {
        assert!(
            attrs.contains_key(&format!("vkbrdf.{key}")),
            "missing vkbrdf.{key} in {attrs:?}"
        );
    }
    assert_eq!(attrs["vkbrdf.table"], table);
    assert!(attrs["vkbrdf.material"].contains(material), "{attrs:?}");
    assert_eq!(attrs["vkbrdf.version"], env!("CARGO_PKG_VERSION"));
    assert!(attrs["vkbrdf.texelCentres"].contains("(i + 0.5)/W"));
}

fn albedo_file(backend: &mut dyn Backend) {
    let dir = tmp();
    let job = AlbedoJob {
        spec: specs()[0],
        grid: Grid::new(8, 4).unwrap(),
        samples: 1 << 14,
        axes: dfg::Axes::DEFAULT,
        half: false,
        output: dir.path().join("E.exr"),
        average: Some(dir.path().join("Eavg.exr")),
    };
    albedo::write(&mut Runner::new(backend), &job).unwrap();
    let layers = read_exr(&job.output);
    assert_eq!(layers.len(), 1);
    let (_, size, attrs, channels) = &layers[0];
    assert_eq!(*size, (8, 4));
    assert_provenance(attrs, "albedo", "ggx smith-correlated");
    assert!(attrs["vkbrdf.samples"].starts_with("16384 per texel"));
    assert_eq!(channels.len(), 1);
    assert_eq!(channels[0].0, "Y");
    assert!(matches!(channels[0].1, FlatSamples::F32(_)));
    let e = f32s(&channels[0].1);
    // Texel (i, j) is at (μ, α) = ((i+½)/8, (j+½)/4): spot-check one against the library.
    let mut runner = Runner::new(backend);
    let spot =
        albedo::directional_albedo(&mut runner, &job.spec, &[(5.5 / 8.0, 2.5 / 4.0)], 1 << 14)
            .unwrap();
    assert!((f64::from(e[2 * 8 + 5]) - spot[0]).abs() < 1e-6);
    assert!(
        e.iter()
            .all(|&x| (0.0..=1.0 + ACCURACY as f32).contains(&x)),
        "E out of [0, 1]: {e:?}"
    );
    let avg = read_exr(job.average.as_ref().unwrap());
    let (_, size, attrs, channels) = &avg[0];
    assert_eq!(*size, (4, 1), "E_avg is H x 1");
    assert_provenance(attrs, "albedo-average", "ggx");
    let eavg = f32s(&channels[0].1);
    assert!(
        eavg.windows(2).all(|w| w[1] < w[0]),
        "E_avg decreases with alpha: {eavg:?}"
    );
    assert!(eavg.iter().all(|&x| x > 0.0 && x <= 1.0));
}

#[test]
fn albedo_writes_a_valid_exr() {
    for_each_backend(albedo_file);
}

fn dfg_file(backend: &mut dyn Backend) {
    let dir = tmp();
    for half in [false, true] {
        let job = DfgJob {
            spec: specs()[0],
            grid: Grid::new(6, 5).unwrap(),
            samples: 1 << 12,
            axes: dfg::Axes::DEFAULT,
            layout: dfg::Layout::ScaleBias,
            sampler: albedo::Sampler::Visible,
            style: None,
            half,
            output: dir.path().join("dfg.exr"),
        };
        dfg::write(&mut Runner::new(backend), &job).unwrap();
        let layers = read_exr(&job.output);
        let (_, size, attrs, channels) = &layers[0];
        assert_eq!(*size, (6, 5));
        assert_provenance(attrs, "dfg", "ggx smith-correlated");
        let names: Vec<&str> = channels.iter().map(|c| c.0.as_str()).collect();
        assert_eq!(names, ["G", "R"]);
        assert_eq!(matches!(channels[0].1, FlatSamples::F16(_)), half);
        let (b, a) = (f32s(&channels[0].1), f32s(&channels[1].1));
        for (x, y) in a.iter().zip(&b) {
            assert!(*x >= 0.0 && *y >= 0.0 && x + y <= 1.0 + 1e-3, "A={x} B={y}");
        }
    }
}

#[test]
fn dfg_writes_a_valid_exr() {
    for_each_backend(dfg_file);
}

fn slice_file(backend: &mut dyn Backend) {
    let dir = tmp();
    let brushed = vkbrdf::material::parse_materials(
        "[[material]]\nname = \"brushed\"\npreset = \"aluminium\"\nroughness = [0.1, 0.4]\n",
        "test",
    )
    .unwrap()
    .remove(0);
    for (material, spacing) in [
        (presets::preset("gold").unwrap().unwrap(), Spacing::Sqrt),
        (brushed, Spacing::Linear),
    ] {
        let job = SliceJob {
            material: material.clone(),
            grid: Grid::new(12, 7).unwrap(),
            spacing,
            terms: true,
            half: false,
            output: dir.path().join("slice.exr"),
        };
        slice::write(&mut Runner::new(backend), &job).unwrap();
        let layers = read_exr(&job.output);
        assert_eq!(layers.len(), 2);
        let by_name: HashMap<String, _> = layers
            .iter()
            .map(|(n, size, attrs, ch)| (n.clone().unwrap(), (size, attrs, ch)))
            .collect();
        let (size, attrs, brdf) = by_name["brdf"];
        assert_eq!(*size, (12, 7));
        assert_provenance(attrs, "slice", &material.name);
        let names: Vec<&str> = brdf.iter().map(|c| c.0.as_str()).collect();
        assert_eq!(names, ["B", "G", "R"]);
        let terms = by_name["terms"].2;
        let names: Vec<&str> = terms.iter().map(|c| c.0.as_str()).collect();
        assert_eq!(names, ["D", "F.B", "F.G", "F.R", "G", "K"]);
        // Texel (i, j) against the reference at its half/difference angles, the directions
        // written out here rather than taken from `slice`: MERL's θ_h axis is x² · 90° on
        // `sqrt` spacing, x · 90° on linear; at φ_d = 90° with h = (sin θ_h, 0, cos θ_h),
        // l = (cos θ_d sin θ_h, sin θ_d, cos θ_d cos θ_h) and v is l with y negated.
        let red = f32s(&brdf[2].1);
        let d = f32s(&terms[0].1);
        for (i, j) in [(0, 0), (3, 2), (11, 6), (7, 5)] {
            let x = (i as f64 + 0.5) / 12.0;
            let th = match spacing {
                Spacing::Sqrt => x * x * FRAC_PI_2,
                Spacing::Linear => x * FRAC_PI_2,
            };
            let td = (j as f64 + 0.5) / 7.0 * FRAC_PI_2;
            let (sh, ch, sd, cd) = (th.sin(), th.cos(), td.sin(), td.cos());
            let (l, v) = ([cd * sh, sd, cd * ch], [cd * sh, -sd, cd * ch]);
            let e = reference::evaluate(l, v, [0.0, 0.0, 1.0], Some([1.0, 0.0, 0.0]), &material);
            let (got, want) = (f64::from(red[j * 12 + i]), e.brdf[0]);
            assert!(
                (got - want).abs() <= 1e-4 * want.abs() + 1e-6,
                "{} texel ({i},{j}): {got} vs {want}",
                material.name
            );
            assert!((f64::from(d[j * 12 + i]) - e.d).abs() <= 1e-4 * e.d.abs() + 1e-6);
        }
    }
}

#[test]
fn slice_writes_a_valid_exr_with_terms() {
    for_each_backend(slice_file);
}

#[test]
fn half_difference_frame_is_rusinkiewicz() {
    // φ_d = 90°: l and v symmetric about the plane of h and n, h = normalize(l + v).
    let (th, td) = (0.3, 0.7);
    let (l, v) = slice::from_half_diff(th, td, FRAC_PI_2);
    let h = frame::normalize([l[0] + v[0], l[1] + v[1], l[2] + v[2]]).unwrap();
    assert!((h[0] - th.sin()).abs() < 1e-12 && h[1].abs() < 1e-12);
    assert!((frame::dot(l, h) - td.cos()).abs() < 1e-12);
    assert!((l[1] - td.sin()).abs() < 1e-12 && (v[1] + td.sin()).abs() < 1e-12);
    let (th2, td2, pd2) = merl::half_diff(l, v, [0.0, 0.0, 1.0]).unwrap();
    assert!(
        (th2 - th).abs() < 1e-12 && (td2 - td).abs() < 1e-12 && (pd2 - FRAC_PI_2).abs() < 1e-12
    );
}

// ---------------------------------------------------------------------------------------
// MERL.

fn merl_round_trip(backend: &mut dyn Backend) {
    let cpu = backend.name().starts_with("cpu");
    let dir = tmp();
    let path = dir.path().join("plastic.binary");
    // Diffuse + specular, coloured: every channel and scale is exercised.
    let material = presets::preset("shiny-plastic").unwrap().unwrap();
    merl::write(&mut Runner::new(backend), &material, &path).unwrap();
    assert_eq!(
        std::fs::metadata(&path).unwrap().len() as usize,
        merl::FILE_BYTES
    );
    // The layout, read raw and with the directions built here from FORMULAS.md §7, not
    // through the library: header 90 90 180, bin (i,j,k) of channel c at
    // 12 + 8·(c·90·90·180 + k + 180·(j + 90·i)), value f/scale.
    let bytes = std::fs::read(&path).unwrap();
    let dims: Vec<i32> = (0..3)
        .map(|d| i32::from_le_bytes(bytes[4 * d..4 * d + 4].try_into().unwrap()))
        .collect();
    assert_eq!(dims, [90, 90, 180]);
    let scales = [1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0];
    for &(i, j, k) in &[
        (5, 10, 20),
        (60, 30, 100),
        (89, 2, 179),
        (20, 80, 0),
        (60, 60, 0),
    ] {
        let (th, td, pd) = (
            (i as f64 / 90.0).powi(2) * FRAC_PI_2,
            j as f64 * PI / 180.0,
            k as f64 * PI / 180.0,
        );
        let d = [td.sin() * pd.cos(), td.sin() * pd.sin(), td.cos()];
        let l = [
            d[0] * th.cos() + d[2] * th.sin(),
            d[1],
            -d[0] * th.sin() + d[2] * th.cos(),
        ];
        let h = [th.sin(), 0.0, th.cos()];
        let lh = frame::dot(l, h);
        let v = [2.0 * lh * h[0] - l[0], -l[1], 2.0 * lh * h[2] - l[2]];
        let want = reference::evaluate(l, v, [0.0, 0.0, 1.0], None, &material).brdf;
        for c in 0..3 {
            let at = 12 + 8 * (c * 90 * 90 * 180 + k + 180 * (j + 90 * i));
            let stored = f64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
            if l[2] <= 0.0 || v[2] <= 0.0 {
                assert_eq!(stored, -1.0);
            } else {
                let got = stored * scales[c];
                assert!(
                    (got - want[c]).abs() <= 1e-4 * want[c],
                    "raw bin ({i},{j},{k}) channel {c}: {got} vs {}",
                    want[c]
                );
            }
        }
    }
    let measured = merl::read(&path).unwrap();
    let (mut checked, mut invalid, mut worst) = (0usize, 0usize, 0.0f64);
    for i in 0..90 {
        for j in 0..90 {
            for k in 0..180 {
                let (l, v) = merl::bin_directions(i, j, k);
                let got = measured.lookup(l, v, [0.0, 0.0, 1.0]);
                let (lf, vf) = (
                    l.map(|x| f64::from(x as f32)),
                    v.map(|x| f64::from(x as f32)),
                );
                if lf[2] <= 0.0 || vf[2] <= 0.0 {
                    invalid += 1;
                    assert_eq!(
                        measured.stored(0, i, j, k),
                        -1.0,
                        "bin ({i},{j},{k}) below the horizon"
                    );
                    assert_eq!(got, [0.0; 3], "invalid samples read as 0");
                    continue;
                }
                // The analytic value at the directions the backend evaluated.
                let want = reference::evaluate(lf, vf, [0.0, 0.0, 1.0], None, &material).brdf;
                for c in 0..3 {
                    let rel = (got[c] - want[c]).abs() / want[c].abs().max(1e-6);
                    worst = worst.max(rel);
                    let tol = if cpu { 1e-6 } else { 1e-4 };
                    let grazing = lf[2].min(vf[2]) < vkbrdf::check::MIN_COS;
                    assert!(
                        rel <= tol || (!cpu && grazing),
                        "bin ({i},{j},{k}) channel {c}: lookup {} vs analytic {}",
                        got[c],
                        want[c]
                    );
                }
                checked += 1;
            }
        }
    }
    eprintln!(
        "MERL round trip: {checked} bins within tolerance (max rel {worst:.1e}), {invalid} invalid"
    );
    assert!(checked > 1_000_000 && invalid > 100_000);
    // Reciprocity fold: swapping l and v maps φ_d to φ_d + π, the same bin.
    let (l, v) = merl::bin_directions(40, 30, 20);
    assert_eq!(
        measured.lookup(l, v, [0.0, 0.0, 1.0]),
        measured.lookup(v, l, [0.0, 0.0, 1.0])
    );
    // The same lookup through an f32 batch, in a rotated frame (isotropy).
    let rot = |a: [f64; 3]| [a[2], a[0], a[1]];
    let mut rows = Vec::new();
    for &(i, j, k) in &[(10, 20, 30), (45, 10, 90), (70, 60, 170), (0, 5, 0)] {
        let (l, v) = merl::bin_directions(i, j, k);
        rows.extend(
            [rot(l), rot(v), rot([0.0, 0.0, 1.0])]
                .iter()
                .flatten()
                .map(|&x| x as f32),
        );
        rows.push(0.0);
    }
    let batch = vkbrdf::batch::Batch::new(rows, 10, 1, Path::new("test")).unwrap();
    let f = merl::evaluate_measured(&measured, &batch);
    for (r, &(i, j, k)) in [(10, 20, 30), (45, 10, 90), (70, 60, 170), (0, 5, 0)]
        .iter()
        .enumerate()
    {
        let (l, v) = merl::bin_directions(i, j, k);
        let want = measured.lookup(l, v, [0.0, 0.0, 1.0]);
        for c in 0..3 {
            assert!(
                (f64::from(f[3 * r + c]) - want[c]).abs() <= 1e-4 * want[c],
                "batch lookup ({i},{j},{k})"
            );
        }
    }
}

#[test]
fn merl_export_import_round_trip() {
    for_each_backend(merl_round_trip);
}

#[test]
fn merl_bins_follow_the_standard_lookup() {
    // Each bin's own sample point maps to that bin; points just above too.
    for (i, j, k) in [
        (0, 0, 0),
        (1, 1, 1),
        (89, 89, 179),
        (30, 45, 90),
        (2, 88, 179),
    ] {
        let (th, td, pd) = merl::bin_angles(i, j, k);
        assert_eq!(merl::bin_of(th, td, pd), (i, j, k));
        assert_eq!(
            merl::bin_of(th * 1.0001 + 1e-9, td + 1e-6, pd + 1e-6),
            (i, j, k)
        );
    }
    // θ_h index = sqrt(θ_h / (π/2)) · 90, truncated; φ_d folded into [0, π).
    assert_eq!(merl::bin_of(FRAC_PI_2 * 0.25, 0.0, 0.0).0, 45);
    assert_eq!(merl::bin_of(0.0, 0.0, -FRAC_PI_2).2, 90);
    assert_eq!(merl::bin_of(0.0, 0.0, PI + 0.5 * PI / 180.0).2, 0);
    assert_eq!(merl::bin_of(2.0, 2.0, 0.0), (89, 89, 0), "clamped");
}

#[test]
fn merl_reader_rejects_bad_files() {
    let dir = tmp();
    let missing = dir.path().join("missing.binary");
    let e = merl::read(&missing).unwrap_err().to_string();
    assert!(e.contains("missing.binary"), "{e}");

    let short = dir.path().join("short.binary");
    let mut bytes: Vec<u8> = [90i32, 90, 180]
        .iter()
        .flat_map(|d| d.to_le_bytes())
        .collect();
    bytes.extend(vec![0u8; 8000]);
    std::fs::write(&short, &bytes).unwrap();
    let e = merl::read(&short).unwrap_err().to_string();
    assert!(e.contains("short.binary") && e.contains("truncated"), "{e}");

    let dims = dir.path().join("dims.binary");
    bytes[8..12].copy_from_slice(&360i32.to_le_bytes());
    std::fs::write(&dims, &bytes).unwrap();
    let e = merl::read(&dims).unwrap_err().to_string();
    assert!(e.contains("dims.binary") && e.contains("90x90x360"), "{e}");

    let tiny = dir.path().join("tiny.binary");
    std::fs::write(&tiny, [1u8, 2, 3]).unwrap();
    assert!(merl::read(&tiny)
        .unwrap_err()
        .to_string()
        .contains("header"));
}

// ---------------------------------------------------------------------------------------
// Previews.

fn read_png(path: &Path) -> (u32, u32, Vec<u8>, HashMap<String, String>) {
    let decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let text = reader
        .info()
        .utf8_text
        .iter()
        .map(|t| (t.keyword.clone(), t.get_text().unwrap()))
        .collect();
    (info.width, info.height, buf, text)
}

fn previews(backend: &mut dyn Backend) {
    let dir = tmp();
    let job = preview::PreviewJob {
        material: presets::preset("copper").unwrap().unwrap(),
        sphere: Some(dir.path().join("sphere.png")),
        polar: Some(dir.path().join("polar.png")),
        size: 64,
        incidence_deg: 45.0,
        exposure: 1.0,
    };
    preview::write(&mut Runner::new(backend), &job).unwrap();
    let (w, h, rgb, text) = read_png(job.sphere.as_ref().unwrap());
    assert_eq!((w, h), (64, 64));
    assert_eq!(text["vkbrdf.material"], "copper");
    assert_eq!(text["vkbrdf.table"], "preview-sphere");
    let px = |x: usize, y: usize| &rgb[3 * (y * 64 + x)..3 * (y * 64 + x) + 3];
    assert_eq!(px(0, 0), [24, 24, 24], "background outside the sphere");
    assert!(
        px(24, 24)[0] > px(24, 24)[2],
        "copper is red toward the light: {:?}",
        px(24, 24)
    );
    assert_eq!(px(60, 40), [0, 0, 0], "facing away from the light: black");

    let (w, h, rgb, text) = read_png(job.polar.as_ref().unwrap());
    assert_eq!((w as usize, h as usize), preview::POLAR_SIZE);
    assert_eq!(text["vkbrdf.incidence"], "45 degrees");
    assert!(
        rgb.chunks(3).filter(|c| c[0] == 240 && c[1] == 70).count() > 100,
        "a red curve"
    );
    // A grey material draws one white curve.
    let steel = vkbrdf::material::parse_materials(
        "[[material]]\nname = \"steel\"\nmodel = \"phong\"\nexponent = 40\n",
        "test",
    )
    .unwrap()
    .remove(0);
    let canvas = preview::polar(&mut Runner::new(backend), &steel, 30.0).unwrap();
    let white = canvas
        .rgb
        .chunks(3)
        .filter(|c| c == &[240, 240, 240])
        .count();
    assert!(white > 100, "one white curve");
}

#[test]
fn previews_write_valid_pngs() {
    for_each_backend(previews);
}

// ---------------------------------------------------------------------------------------
// Bad input.

fn no_files_left(dir: &Path) {
    let left: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert!(left.is_empty(), "files left behind: {left:?}");
}

#[test]
fn unknown_material_names_the_choices() {
    let e = vkbrdf::table::load_material(None, "unobtainium")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("unobtainium") && e.contains("gold") && e.contains("presets"),
        "{e}"
    );
    let dir = tmp();
    let file = dir.path().join("m.toml");
    std::fs::write(
        &file,
        "[[material]]\nname = \"matte\"\nmodel = \"lambert\"\n",
    )
    .unwrap();
    let e = vkbrdf::table::load_material(Some(&file), "gold")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("gold") && e.contains("m.toml") && e.contains("matte"),
        "{e}"
    );
}

#[test]
fn bad_sizes_are_refused_before_allocating() {
    for s in ["0x32", "32x0", "0", "x", "32x", "-1x4", "ax4"] {
        let e = s.parse::<Grid>().unwrap_err().to_string();
        assert!(e.contains(s), "{s}: {e}");
    }
    assert_eq!("16x8".parse::<Grid>().unwrap(), Grid::new(16, 8).unwrap());
    assert_eq!("64".parse::<Grid>().unwrap(), Grid::new(64, 64).unwrap());
    let dir = tmp();
    let mut cpu = reference::CpuReference::new();
    let huge = Grid::new(1 << 29, 1 << 29).unwrap();
    let job = AlbedoJob {
        spec: specs()[0],
        grid: huge,
        samples: 16,
        axes: dfg::Axes::DEFAULT,
        half: false,
        output: dir.path().join("E.exr"),
        average: None,
    };
    let e = albedo::write(&mut Runner::new(&mut cpu), &job)
        .unwrap_err()
        .to_string();
    assert!(e.contains("memory") && e.contains("GiB"), "{e}");
    let slice_job = SliceJob {
        material: presets::preset("gold").unwrap().unwrap(),
        grid: huge,
        spacing: Spacing::Sqrt,
        terms: true,
        half: false,
        output: dir.path().join("S.exr"),
    };
    let e = slice::write(&mut Runner::new(&mut cpu), &slice_job)
        .unwrap_err()
        .to_string();
    assert!(e.contains("memory"), "{e}");
    let e = albedo::directional_albedo(&mut Runner::new(&mut cpu), &specs()[0], &[(0.5, 0.5)], 0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("samples"), "{e}");
    no_files_left(dir.path());
}

#[test]
fn illegal_model_is_refused() {
    let spec = Microfacet {
        lobe: Lobe::Ggx,
        geometry: Geometry::SmithFast,
    };
    let e = spec.material(0.5).unwrap_err().to_string();
    assert!(e.contains("smith-fast"), "{e}");
    let e = preview::polar(
        &mut Runner::new(&mut reference::CpuReference::new()),
        &presets::preset("gold").unwrap().unwrap(),
        95.0,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("incidence"), "{e}");
    let dir = tmp();
    let job = preview::PreviewJob {
        material: presets::preset("gold").unwrap().unwrap(),
        sphere: None,
        polar: None,
        size: 64,
        incidence_deg: 45.0,
        exposure: 1.0,
    };
    assert!(job.check().unwrap_err().to_string().contains("--sphere"));
    let job = preview::PreviewJob {
        sphere: Some(dir.path().join("s.png")),
        size: 1 << 20,
        ..job
    };
    let e = job.check().unwrap_err().to_string();
    assert!(e.contains("memory"), "{e}");
    let job = preview::PreviewJob {
        size: 64,
        exposure: f64::NAN,
        ..job
    };
    assert!(job.check().unwrap_err().to_string().contains("exposure"));
    no_files_left(dir.path());
}

#[test]
fn unwritable_paths_fail_before_work_and_leave_nothing() {
    let dir = tmp();
    let mut cpu = reference::CpuReference::new();
    let gold = presets::preset("gold").unwrap().unwrap();
    for output in [
        dir.path().join("no/such/dir/S.exr"),
        dir.path().to_path_buf(),
    ] {
        let job = SliceJob {
            material: gold.clone(),
            grid: Grid::new(4, 4).unwrap(),
            spacing: Spacing::Sqrt,
            terms: false,
            half: false,
            output: output.clone(),
        };
        // Refused as an unusable output (before any evaluation), naming it.
        let e = slice::write(&mut Runner::new(&mut cpu), &job).unwrap_err();
        assert!(matches!(e, vkbrdf::Error::Output { .. }), "{e}");
        assert!(e.to_string().contains(&*output.to_string_lossy()), "{e}");
        let e = merl::write(&mut Runner::new(&mut cpu), &gold, &output).unwrap_err();
        assert!(matches!(e, vkbrdf::Error::Output { .. }), "{e}");
    }
    no_files_left(dir.path());
    // A good file is not clobbered by a failing run.
    let good = dir.path().join("E.exr");
    std::fs::write(&good, b"keep me").unwrap();
    let job = AlbedoJob {
        spec: specs()[0],
        grid: Grid::new(1 << 29, 1 << 29).unwrap(),
        samples: 16,
        axes: dfg::Axes::DEFAULT,
        half: false,
        output: good.clone(),
        average: None,
    };
    assert!(albedo::write(&mut Runner::new(&mut cpu), &job).is_err());
    assert_eq!(std::fs::read(&good).unwrap(), b"keep me");
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "no temporary file left"
    );
}

#[test]
fn gauss_legendre_integrates_polynomials_exactly() {
    let nodes = albedo::gauss_legendre(albedo::AVERAGE_NODES);
    assert!((nodes.iter().map(|n| n.1).sum::<f64>() - 1.0).abs() < 1e-14);
    // Exact to degree 2n − 1 = 63: ∫₀¹ x^63 dx = 1/64.
    let m: f64 = nodes.iter().map(|&(x, w)| w * x.powi(63)).sum();
    assert!((m - 1.0 / 64.0).abs() < 1e-14, "{m}");
    // Hammersley points are a (0, 2)-net: every 1/N × 1 column and 1 × 1/N row holds one.
    let n = 256;
    let mut rows = vec![0; n];
    for k in 0..n as u32 {
        let (u1, u2) = albedo::hammersley(k, n as u32);
        assert!(((u1 * n as f64) as usize) == k as usize);
        rows[(u2 * n as f64) as usize] += 1;
    }
    assert!(rows.iter().all(|&c| c == 1));
}

/// Largest relative difference of `got` from `want` over values above `floor`·max(want).
fn max_rel_diff(got: &[f32], want: &[f32], floor: f64) -> f64 {
    let peak = want.iter().fold(0.0f64, |m, &w| m.max(f64::from(w).abs()));
    got.iter()
        .zip(want)
        .filter(|(_, &w)| f64::from(w).abs() > floor * peak)
        .map(|(&g, &w)| ((f64::from(g) - f64::from(w)) / f64::from(w)).abs())
        .fold(0.0, f64::max)
}

/// The Vulkan kernel makes the slice's directions on the device (`half_diff_row` in
/// glsl/generators.glsl, f32 polynomials for sin/cos); the host makes them in f64
/// (`from_half_diff`). Both, over whole 90×90 slices of sharp, rough, anisotropic and
/// exponent-based materials, must agree with the f64 reference at the host's directions.
/// f32 directions move a value by ~1e-7 × its angular slope (≤ 1e-5 relative even at
/// α = 0.01's peak; measured ≤ 6.3e-6, as close as the host-made tuples' 5.2e-6), so 3e-5
/// catches a wrong angle, mapping or texel order.
#[test]
fn device_made_slice_directions_match_the_host() {
    let Some(mut gpu) = common::vulkan() else {
        return;
    };
    let mut cpu = vkbrdf::reference::CpuReference::new();
    let body = |name: &str, extra: &str| {
        vkbrdf::material::parse_materials(
            &format!("[[material]]\nname = \"{name}\"\n{extra}\n"),
            "test",
        )
        .unwrap()
        .remove(0)
    };
    let materials = [
        presets::preset("gold").unwrap().unwrap(),
        body("sharp", "preset = \"silver\"\nroughness = 0.01"),
        body("brushed", "preset = \"aluminium\"\nroughness = [0.05, 0.5]"),
        body(
            "beckmann",
            "model = \"cook-torrance\"\nconvention = \"modern\"\ndistribution = \"beckmann\"\nroughness = 0.2\ngeometry = \"smith\"\nfresnel = \"dielectric\"\nior = 1.5",
        ),
        body("phong", "model = \"blinn-phong\"\nexponent = 200"),
    ];
    let grid = Grid::new(90, 90).unwrap();
    for m in &materials {
        for spacing in [Spacing::Sqrt, Spacing::Linear] {
            let (made, made_terms) =
                slice::compute(&mut Runner::new(&mut gpu), m, grid, spacing, true).unwrap();
            let (sent, _) =
                slice::compute_from_tuples(&mut Runner::new(&mut gpu), m, grid, spacing, true)
                    .unwrap();
            let (want, want_terms) =
                slice::compute(&mut Runner::new(&mut cpu), m, grid, spacing, true).unwrap();
            let made_err = max_rel_diff(&made, &want, 1e-6);
            let sent_err = max_rel_diff(&sent, &want, 1e-6);
            let d = |t: &[f32]| t.iter().step_by(6).copied().collect::<Vec<f32>>();
            let d_err = max_rel_diff(&d(&made_terms.unwrap()), &d(&want_terms.unwrap()), 1e-6);
            eprintln!(
                "{} {spacing:?}: device-made {made_err:.1e} (D {d_err:.1e}), host-made {sent_err:.1e}",
                m.name
            );
            assert!(made_err <= 3e-5 && d_err <= 3e-5, "{} {spacing:?}", m.name);
        }
    }
    // Grid shapes that exercise the kernel's texel -> (column, row) split (an f32 quotient
    // corrected to the exact one), across chunk boundaries (2^18 texels per chunk).
    for (w, h) in [(1, 5), (5, 1), (7, 13), (257, 3), (1000, 600)] {
        let grid = Grid::new(w, h).unwrap();
        let m = &materials[0];
        let (made, _) =
            slice::compute(&mut Runner::new(&mut gpu), m, grid, Spacing::Sqrt, false).unwrap();
        let (want, _) =
            slice::compute(&mut Runner::new(&mut cpu), m, grid, Spacing::Sqrt, false).unwrap();
        let err = max_rel_diff(&made, &want, 1e-6);
        assert!(err <= 3e-5, "{w}x{h}: {err:.1e}");
    }
}

/// The integrated tables need an importance sampler per distribution; those without one
/// (charlie, gaussian, blinn) are refused with the reason, exit 2, nothing written. The new
/// geometry terms need none of their own: a small schlick-smith / neubelt albedo table is
/// made, and stays in [0, 1] (both conserve energy with GGX, tests/properties.rs).
#[test]
fn integrated_tables_refuse_a_distribution_without_a_sampler() {
    let dir = tmp();
    let out = dir.path().join("t.exr");
    for kind in ["albedo", "dfg"] {
        for d in ["charlie", "gaussian", "blinn"] {
            let o = common::vkbrdf(&[
                "table",
                kind,
                "--distribution",
                d,
                "--output",
                common::path(&out),
                "--backend",
                "cpu",
            ]);
            let err = common::stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{kind} {d}: {err}");
            assert!(
                err.contains(&format!("--distribution {d}"))
                    && err.contains("only ggx and beckmann have a sampler"),
                "{kind} {d}: {err}"
            );
            assert!(!out.exists(), "{kind} {d} wrote its output");
        }
    }
    for g in [Geometry::SchlickSmith, Geometry::Neubelt] {
        let spec = Microfacet {
            lobe: Lobe::of(vkbrdf::material::DistributionKind::Ggx).unwrap(),
            geometry: g,
        };
        spec.material(0.5).unwrap();
        let mut cpu = vkbrdf::reference::CpuReference::new();
        let points = albedo::grid_points(Grid::new(4, 4).unwrap()).unwrap();
        let e =
            albedo::directional_albedo(&mut Runner::new(&mut cpu), &spec, &points, 1024).unwrap();
        assert!(
            e.iter().all(|&x| (0.0..=1.0 + 1e-3).contains(&x)),
            "{}: {e:?}",
            g.toml_name()
        );
    }
}
