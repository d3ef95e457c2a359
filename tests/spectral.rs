//! Spectral evaluation (FORMULAS.md §9): the CIE reductions against published and
//! independently computed values, spectral gold on every engine within §1's rule of the
//! reference, and the errors a user meets.

mod common;

use common::rule::assert_within_rule;
use rand::{Rng, SeedableRng};
use vkbrdf::backend::{Backend, Request};
use vkbrdf::batch::{memory_source, Batch};
use vkbrdf::material::{load_materials, parse_materials, presets, Material};
use vkbrdf::spectral::colour::{filament_f0, mitsuba};
use vkbrdf::spectral::Wavelengths;
use vkbrdf::spectral_eval::{Colour, SpectralJob};

fn data(p: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/spectral")
        .join(p)
}

fn index_of(m: &Material) -> &vkbrdf::spectral::IndexSpectrum {
    &m.spectral.as_ref().expect("a spectral material").index
}

/// pbrt-v4's metal spectra, F0 reduced to sRGB under D65 (Filament's reduction):
/// Lagarde's "metal reflectance" table to its three decimals (gold, whose red is above 1,
/// divided by its largest channel, as the table is), and the independent NumPy reduction of
/// `tests/data/spectral/expected_values.py` (its output `expected_values.txt`) to 1e-6.
#[test]
fn pbrt_metal_spectra_give_lagardes_table() {
    let metals = load_materials(&data("pbrt-v4-metals.toml")).unwrap();
    let lagarde = [
        (
            "au-pbrt",
            [1.000, 0.766, 0.336],
            [1.021989507, 0.782426043, 0.343391211],
        ),
        (
            "ag-pbrt",
            [0.972, 0.960, 0.915],
            [0.971589956, 0.959926925, 0.915225272],
        ),
        (
            "cu-pbrt",
            [0.955, 0.637, 0.538],
            [0.955496809, 0.637590894, 0.538111794],
        ),
        (
            "al-pbrt",
            [0.913, 0.921, 0.925],
            [0.913247021, 0.921489151, 0.924365465],
        ),
    ];
    for (name, table, numpy) in lagarde {
        let m = metals.iter().find(|m| m.name == name).unwrap();
        let f0 = filament_f0(index_of(m)).unwrap();
        for c in 0..3 {
            assert!(
                (f0[c] - numpy[c]).abs() < 1e-6,
                "{name}: {f0:?} vs NumPy {numpy:?}"
            );
        }
        let top = f0.iter().copied().fold(0.0, f64::max);
        let shown = f0.map(|x| if top > 1.0 { x / top } else { x });
        for c in 0..3 {
            assert!(
                (shown[c] - table[c]).abs() <= 1e-3,
                "{name}: {shown:?} vs Lagarde {table:?}"
            );
        }
    }
}

/// The shipped CC0 data sets (Johnson & Christy, Rakić): the same reductions, reported
/// beside pbrt's (the data sets differ by up to 0.06), each pinned to the NumPy values.
#[test]
fn shipped_data_sets_reduce_as_numpy_does() {
    let cases = [
        (
            "gold-spectral",
            [1.037638110, 0.728341021, 0.364570759],
            [0.126403075, 0.466020644, 1.342886765],
            [4.240598208, 2.209071668, 1.645462032],
        ),
        (
            "copper-spectral",
            [0.931792841, 0.622665890, 0.522272535],
            [0.281152712, 0.987103758, 1.179513147],
            [3.923042544, 2.459886031, 2.138870623],
        ),
        (
            "aluminium-spectral",
            [0.907411342, 0.915844644, 0.922249161],
            [1.744888742, 0.933032637, 0.532421169],
            [f64::NAN; 3],
        ),
    ];
    for (name, f0_want, n_want, k_want) in cases {
        let m = presets::preset(name).unwrap().unwrap();
        let f0 = filament_f0(index_of(&m)).unwrap();
        let (n, k) = mitsuba(index_of(&m)).unwrap();
        for c in 0..3 {
            assert!((f0[c] - f0_want[c]).abs() < 1e-6, "{name} F0 {f0:?}");
            assert!((n[c] - n_want[c]).abs() < 1e-6, "{name} n {n:?}");
            assert!(
                k_want[c].is_nan() || (k[c] - k_want[c]).abs() < 1e-6,
                "{name} k {k:?}"
            );
        }
        // The material's RGB form is Mitsuba's: the exact conductor with those n, k.
        match &m.cook_torrance().unwrap().fresnel {
            vkbrdf::material::Fresnel::Conductor { ior, extinction } => {
                assert_eq!((*ior, *extinction), (n, k), "{name}");
            }
            other => panic!("{name}: {other:?}"),
        }
    }
}

/// Tuples where gold's terms are hardest: half vectors drawn around the normal (the peak),
/// grazing views, and directions from the whole hemisphere.
fn tuples(n: usize) -> Batch<'static> {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(28);
    let mut rows = Vec::with_capacity(n * 10);
    for i in 0..n {
        let unit = |rng: &mut rand_pcg::Pcg64Mcg| loop {
            let v: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
            let l2 = v.iter().map(|x| x * x).sum::<f64>();
            if l2 > 1e-4 && l2 <= 1.0 {
                let l = l2.sqrt();
                break [v[0] / l, v[1] / l, v[2].abs() / l];
            }
        };
        let l = unit(&mut rng);
        let v = match i % 3 {
            // The mirror of l about a half vector within ~0.3 rad of n: the specular peak.
            0 => {
                let (a, b) = (rng.random_range(-0.3..0.3), rng.random_range(-0.3..0.3));
                let h = [a, b, 1.0f64];
                let hl = (h.iter().map(|x| x * x).sum::<f64>()).sqrt();
                let h = h.map(|x| x / hl);
                let d = 2.0 * (l[0] * h[0] + l[1] * h[1] + l[2] * h[2]);
                [d * h[0] - l[0], d * h[1] - l[1], d * h[2] - l[2]]
            }
            // Grazing view.
            1 => {
                let phi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                [phi.cos(), phi.sin(), rng.random_range(1e-4..0.05)]
            }
            _ => unit(&mut rng),
        };
        rows.extend([l[0], l[1], l[2], v[0], v[1], v[2], 0.0, 0.0, 1.0].map(|x| x as f32));
        rows.push(0.0);
    }
    Batch::new(rows, 10, 1, &memory_source()).unwrap()
}

/// FORMULAS.md §9's evaluation on every engine: each wavelength triplet the engines
/// evaluate is within §1's rule of the reference (values and terms), and the spectral
/// outputs are those triplets' channels.
#[test]
fn spectral_gold_on_every_engine_within_the_rule() {
    let gold = vec![presets::preset("gold-spectral").unwrap().unwrap()];
    let job = SpectralJob::new(&gold, Wavelengths::cie(), None).unwrap();
    let batch = tuples(3000);
    let mut reference = vkbrdf::reference::CpuReference::new();
    let refs: Vec<_> = job
        .triplets()
        .iter()
        .map(|m| {
            reference
                .evaluate(&batch, m, &Request { terms: true })
                .unwrap()
        })
        .collect();
    let mut engines: Vec<Box<dyn Backend>> = vkbrdf::cpu::isa::Isa::available_all()
        .into_iter()
        .map(|isa| Box::new(vkbrdf::cpu::CpuEngine::with_isa(2, isa)) as Box<dyn Backend>)
        .collect();
    if let Some(v) = common::vulkan() {
        engines.push(Box::new(v));
    }
    for engine in &mut engines {
        let name = engine.name();
        let mut worst = 0f64;
        for (t, m) in job.triplets().iter().enumerate() {
            let out = engine
                .evaluate(&batch, m, &Request { terms: true })
                .unwrap();
            worst = worst.max(assert_within_rule(
                &format!("{name} triplet {t}"),
                &batch,
                m,
                &out,
                &refs[t],
            ));
        }
        eprintln!("{name}: largest relative error over 95 wavelengths {worst:.2e}");
        // The engine's own spectral way (factored: D, G, K once, F per λ) against the
        // reference's triplets, value by value, by the rule with each channel's S_in.
        assert!(job.is_factored());
        let spectra = job.evaluate(engine.as_mut(), &batch).unwrap();
        let mut worst_f = 0f64;
        for r in 0..batch.len() {
            let tuple = batch.tuple(r);
            for (t, m) in job.triplets().iter().enumerate() {
                let s = vkbrdf::check::f32_sensitivity(&tuple, &m[0]);
                for (j, &sj) in s.iter().enumerate().take(3) {
                    let l = 3 * t + j;
                    if l >= 95 {
                        break;
                    }
                    let (x, want) = (
                        f64::from(spectra.brdf[r * 95 + l]),
                        f64::from(refs[t].brdf[r * 3 + j]),
                    );
                    let allowed = vkbrdf::check::allowed_error(want, sj);
                    assert!(
                        (x - want).abs() <= allowed,
                        "{name} factored: row {r} λ {} nm: {x} vs {want} (allowed {allowed:e})",
                        360 + 5 * l
                    );
                    worst_f = worst_f.max((x - want).abs() / want.abs().max(1e-6));
                }
            }
        }
        eprintln!("{name}: factored way, largest relative error {worst_f:.2e}");
    }
}

/// `--color`: the engines' sRGB within 1e-5 relative (plus the floor) of the reference's,
/// and a white Lambert surface reduces to sRGB (1, 1, 1)/π under D65.
#[test]
fn colour_reductions_agree_and_white_is_white() {
    let white = parse_materials(
        "[[material]]\nname = \"w\"\nmodel = \"lambert\"\ndiffuse = 1\n",
        "t",
    )
    .unwrap();
    let job = SpectralJob::new(
        &white,
        Wavelengths::cie(),
        Some((Colour::Srgb, vkbrdf::spectral::cie::Illuminant::D65)),
    )
    .unwrap();
    let batch = tuples(30);
    let out = job
        .evaluate(&mut vkbrdf::reference::CpuReference::new(), &batch)
        .unwrap();
    // Rows below the horizon are 0; every other is white.
    let lit: Vec<f32> = out.brdf.iter().copied().filter(|&x| x != 0.0).collect();
    assert!(lit.len() > 30, "{} lit values", lit.len());
    for x in lit {
        let want = 1.0 / std::f32::consts::PI;
        assert!((x - want).abs() < 5e-4 * want, "{x}");
    }
    let gold = vec![presets::preset("gold-spectral").unwrap().unwrap()];
    let job = SpectralJob::new(
        &gold,
        Wavelengths::cie(),
        Some((Colour::Srgb, Default::default())),
    )
    .unwrap();
    let batch = tuples(600);
    let r = job
        .evaluate(&mut vkbrdf::reference::CpuReference::new(), &batch)
        .unwrap();
    let mut cpu = vkbrdf::cpu::CpuEngine::new();
    let c = job.evaluate(&mut cpu, &batch).unwrap();
    for i in 0..r.brdf.len() {
        let (x, y) = (f64::from(c.brdf[i]), f64::from(r.brdf[i]));
        assert!(
            (x - y).abs() <= 1e-5 * y.abs().max(1e-6) + 1e-6 * y.abs(),
            "value {i}: {x} vs {y}"
        );
    }
}

/// Every spectral form the issue names: inline rows, a refractiveindex.info file, a
/// Sellmeier glass, Filament's reduction; and the errors, each naming what and where.
#[test]
fn spectral_materials_parse_and_bad_ones_are_named() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("au.yml"),
        include_str!("../src/spectral/data/au-johnson-christy.yml"),
    )
    .unwrap();
    let toml = r#"
[[material]]
name = "rows"
model = "cook-torrance"
distribution = "ggx"
roughness = 0.2
geometry = "smith-correlated"
fresnel = "conductor"
ior = [[300, 1.5, 1.9], [400, 1.5, 1.9], [700, 0.2, 3.9], [900, 0.1, 5.0]]

[[material]]
name = "file"
preset = "gold"
ior = { file = "au.yml" }
extinction = [[300, 2.0], [900, 4.0]]
rgb_reduction = "filament"
"#;
    std::fs::write(dir.path().join("m.toml"), toml).unwrap();
    let m = load_materials(&dir.path().join("m.toml")).unwrap();
    assert_eq!(index_of(&m[0]).at(550.0).unwrap(), (0.85, 2.9));
    assert!(matches!(
        m[1].cook_torrance().unwrap().fresnel,
        vkbrdf::material::Fresnel::Schlick { .. }
    ));
    assert_eq!(index_of(&m[1]).at(600.0).unwrap().1, 3.0);
    // Glass: Malitson's Sellmeier n at 589.3 nm in the spectral form.
    let glass = presets::preset("glass-spectral").unwrap().unwrap();
    let at = vkbrdf::material::spectral::spectral_form(&glass)
        .unwrap()
        .at([589.3, 486.1, 656.3])
        .unwrap();
    match at.cook_torrance().unwrap().fresnel {
        vkbrdf::material::Fresnel::Dielectric { ior } => {
            assert!((ior[0] - 1.4584).abs() < 1e-4, "{ior:?}")
        }
        other => panic!("{other:?}"),
    }
    let bad = |body: &str| {
        parse_materials(&format!("[[material]]\nname = \"x\"\n{body}"), "bad.toml")
            .unwrap_err()
            .to_string()
    };
    let e = bad("preset = \"gold\"\nior = \"unobtainium\"");
    assert!(
        e.contains("bad.toml") && e.contains("ior") && e.contains("au-johnson-christy"),
        "{e}"
    );
    let e = bad("preset = \"gold\"\nior = [[400, 1.5, 1.9], [300, 0.2, 3.9]]");
    assert!(e.contains("does not increase"), "{e}");
    let e = bad("preset = \"gold\"\nior = \"al-rakic\"\nrgb_reduction = \"pbrt\"");
    assert!(
        e.contains("rgb_reduction") && e.contains("mitsuba, filament"),
        "{e}"
    );
    // Outside the data: an error naming the material, the wavelength and the data's range.
    let rows = vec![m[0].clone()];
    let e = SpectralJob::new(&rows, "250,500".parse().unwrap(), None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("material `rows`") && e.contains("250 nm") && e.contains("300–900"),
        "{e}"
    );
    // The RGB form integrates over the CIE grid: data that does not cover it is refused.
    let e = bad("preset = \"gold\"\nior = [[400, 1.5, 1.9], [700, 0.2, 3.9]]");
    assert!(e.contains("360 nm") && e.contains("400–700"), "{e}");
    // An RGB index is not up-sampled; measured data has no spectral form.
    // (An error when a row uses it: a table may hold RGB materials beside spectral ones.)
    let gold = vec![presets::preset("gold").unwrap().unwrap()];
    let job = SpectralJob::new(&gold, Wavelengths::cie(), None).unwrap();
    let mut cpu = vkbrdf::cpu::CpuEngine::new();
    let e = job.evaluate(&mut cpu, &tuples(3)).unwrap_err().to_string();
    assert!(
        e.contains("material `gold`") && e.contains("gold-spectral"),
        "{e}"
    );
    // --color needs the CIE grid.
    let g = vec![presets::preset("gold-spectral").unwrap().unwrap()];
    let e = SpectralJob::new(
        &g,
        "400:700:10".parse().unwrap(),
        Some((Colour::Xyz, Default::default())),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("360:830:5"), "{e}");
}

/// A temporary directory holding `m.toml`: one material `g`, the preset `gold-spectral`.
fn gold_spectral_file() -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m.toml");
    std::fs::write(
        &m,
        "[[material]]\nname = \"g\"\npreset = \"gold-spectral\"\n",
    )
    .unwrap();
    (dir, m)
}

/// The command line: (n, W) and (n, 3) outputs, and the refusal of terms with spectra.
#[test]
fn eval_writes_spectra_and_colours() {
    let (dir, m) = gold_spectral_file();
    let t = dir.path().join("t.npy");
    assert!(common::generate(&m, 500, &t).status.success());
    // Each run on cpu, and the shape its .npy header states.
    let shape_of = |out: &std::path::Path, option: [&str; 2]| {
        let mut args = vec!["-o", common::path(out), "--backend", "cpu"];
        args.extend(option);
        let o = common::eval(&m, &t, &args);
        assert!(o.status.success(), "{}", common::stderr(&o));
        String::from_utf8_lossy(&std::fs::read(out).unwrap()[..128]).into_owned()
    };
    let s = dir.path().join("s.npy");
    assert!(shape_of(&s, ["--wavelengths", "400:700:100"]).contains("(500, 4)"));
    let c = dir.path().join("c.npy");
    assert!(shape_of(&c, ["--color", "srgb"]).contains("(500, 3)"));
    let terms = dir.path().join("terms.npy");
    let o = common::eval(
        &m,
        &t,
        &[
            "-o",
            common::path(&s),
            "--wavelengths",
            "500",
            "--terms",
            common::path(&terms),
        ],
    );
    assert!(
        !o.status.success() && common::stderr(&o).contains("terms"),
        "{}",
        common::stderr(&o)
    );
}

/// Where D·G·K alone exceeds f32::MAX (cosines of 1e-45, K = 1/(4 cos cos)): the factored
/// way must not multiply a saturated basis by F (the stress corpus found water at 3 % of
/// f32::MAX where f itself is beyond it, and so f32::MAX). Every engine, against the
/// reference's triplets.
#[test]
fn a_saturated_basis_does_not_saturate_f() {
    let water = vec![presets::preset("water-spectral").unwrap().unwrap()];
    let job = SpectralJob::new(&water, "380,590,800".parse().unwrap(), None).unwrap();
    let row = [
        0.230_087_25f32,
        1e-45,
        0.97317,
        0.97317,
        1e-45,
        -0.230_087_25,
        0.0,
        1.0,
        0.0,
        0.0,
    ];
    let batch = Batch::new(row.to_vec(), 10, 1, &memory_source()).unwrap();
    let want = vkbrdf::reference::CpuReference::new()
        .evaluate(&batch, &job.triplets()[0], &Request::default())
        .unwrap();
    assert!(want.brdf[0] > 1e30, "{:?}", want.brdf);
    let mut engines: Vec<Box<dyn Backend>> = vec![Box::new(vkbrdf::cpu::CpuEngine::new())];
    if let Some(v) = common::vulkan() {
        engines.push(Box::new(v));
    }
    for e in &mut engines {
        let got = job.evaluate(e.as_mut(), &batch).unwrap();
        for j in 0..3 {
            let (x, r) = (got.brdf[j], want.brdf[j]);
            assert!(
                ((x - r) / r).abs() < 1e-5,
                "{}: λ {j}: {x} vs {r}",
                e.name()
            );
        }
    }
}

/// The local-frame form (6 columns, N = +z, one material) evaluates spectra as its
/// 10-column rows do, on the factored way (the CPU engine reads it as it is) and on the
/// reference's triplets.
#[test]
fn local_frame_spectra_equal_the_rows() {
    let (dir, m) = gold_spectral_file();
    let batch = tuples(400);
    let (mut local, mut rows) = (Vec::new(), Vec::new());
    for r in batch.as_slice().chunks(10) {
        local.extend_from_slice(&r[..6]);
        rows.extend_from_slice(r);
    }
    let (l, t) = (dir.path().join("l.npy"), dir.path().join("t.npy"));
    vkbrdf::batch::write_npy_f32(&l, &local, 6).unwrap();
    vkbrdf::batch::write_npy_f32(&t, &rows, 10).unwrap();
    for backend in ["cpu", "reference"] {
        let (a, b) = (dir.path().join("a.npy"), dir.path().join("b.npy"));
        for (input, out) in [(&l, &a), (&t, &b)] {
            let args = [
                "-o",
                common::path(out),
                "--wavelengths",
                "400:700:50",
                "--backend",
                backend,
            ];
            let o = common::eval(&m, input, &args);
            assert!(o.status.success(), "{}", common::stderr(&o));
        }
        assert_eq!(
            std::fs::read(&a).unwrap(),
            std::fs::read(&b).unwrap(),
            "{backend}"
        );
    }
}
