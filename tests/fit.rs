//! `vkbrdf fit`: round trips from known materials (the data made by vkbrdf, the fit asked
//! to recover the parameters it was made with), a model that cannot represent the data,
//! and bad input. Reduced-resolution angle grids keep them fast; one full MERL table goes
//! through the command line.

use std::process::Command;
use vkbrdf::backend::{Backend, Request};
use vkbrdf::batch::{memory_source, Batch};
use vkbrdf::fit::{self, data::FitData, losses::Loss, params::Param, params::Space};
use vkbrdf::material::{parse_materials, Material};
use vkbrdf::reference::CpuReference;

fn material(toml: &str) -> Material {
    parse_materials(&format!("[[material]]\nname = \"m\"\n{toml}"), "test")
        .unwrap()
        .remove(0)
}

/// A uniform angle grid: θ_i, θ_o in (0, 85°), φ in [0, π]; `n = 16` per axis.
fn grid(n: usize) -> Vec<f32> {
    let mut rows = Vec::new();
    let t = |k: usize| (k as f64 + 0.5) / n as f64 * 85f64.to_radians();
    for a in 0..n {
        for b in 0..n {
            for c in 0..n {
                let (ti, to, p) = (t(a), t(b), c as f64 / (n - 1) as f64 * std::f64::consts::PI);
                let l = [ti.sin(), 0.0, ti.cos()];
                let v = [to.sin() * p.cos(), to.sin() * p.sin(), to.cos()];
                rows.extend(l.iter().chain(&v).map(|&x| x as f32));
            }
        }
    }
    rows
}

/// f of `m` at the local rows, by the f64 reference (independent of the engine the fit
/// runs on), times `1 + noise·u`, u uniform in [−1, 1] (seeded).
fn measure(m: &Material, local: &[f32], noise: f64) -> Vec<f32> {
    use rand::{Rng, SeedableRng};
    let rows: Vec<f32> = local
        .chunks_exact(6)
        .flat_map(|r| r.iter().copied().chain([0.0, 0.0, 1.0, 0.0]))
        .collect();
    let batch = Batch::new(rows, 10, 1, &memory_source()).unwrap();
    let out = CpuReference::new()
        .evaluate(&batch, std::slice::from_ref(m), &Request::default())
        .unwrap();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
    out.brdf
        .iter()
        .map(|&f| (f as f64 * (1.0 + noise * rng.random_range(-1.0..=1.0))) as f32)
        .collect()
}

fn run_fit(
    start: &Material,
    free: &[Param],
    data: &FitData,
    loss: Loss,
    starts: usize,
) -> fit::FitResult {
    let space = Space::new(start, free, &[], loss.is_quadratic()).unwrap();
    let mut engine = vkbrdf::backend_choice::cpu_engine().unwrap();
    let options = fit::Options {
        loss,
        starts,
        ..fit::Options::default()
    };
    fit::fit(
        data,
        &space,
        &options,
        &mut engine,
        &vkbrdf::cancel::Cancel::new(),
        &mut |_| {},
    )
    .unwrap()
}

fn roughness(m: &Material) -> f64 {
    fit::params::get(m, Param::Roughness)[0]
}

fn f0(m: &Material) -> [f64; 3] {
    use vkbrdf::material::Fresnel;
    let ct = m.cook_torrance().unwrap();
    let f = match ct.fresnel {
        Fresnel::Schlick { f0 } => f0,
        Fresnel::Conductor { ior, extinction } => vkbrdf::material::f0_from_ior(ior, extinction),
        Fresnel::Dielectric { ior } => vkbrdf::material::f0_from_ior(ior, [0.0; 3]),
        Fresnel::None => [1.0; 3],
    };
    std::array::from_fn(|c| f[c] * m.specular[c] * ct.specular_weight)
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs()
}

struct Case {
    truth: &'static str,
    start: &'static str,
    free: &'static [Param],
}

const GGX_CONDUCTOR: Case = Case {
    truth: "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 0.25\ngeometry = \"smith-correlated\"\nfresnel = \"conductor\"\nior = [0.2, 0.5, 1.3]\nextinction = [3.4, 2.5, 1.8]",
    start: "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 0.6\ngeometry = \"smith-correlated\"\nfresnel = \"conductor\"\nior = [1.0, 1.0, 1.0]\nextinction = [2.0, 2.0, 2.0]",
    free: &[Param::Roughness, Param::Ior, Param::Extinction],
};

const BECKMANN_PLASTIC: Case = Case {
    truth: "model = \"cook-torrance\"\ndistribution = \"beckmann\"\nroughness = 0.15\ngeometry = \"smith\"\nfresnel = \"dielectric\"\nior = 1.5\ndiffuse = [0.6, 0.2, 0.1]\ndiffuse_weight = 0.9\nspecular_weight = 1.0",
    start: "model = \"cook-torrance\"\ndistribution = \"beckmann\"\nroughness = 0.4\ngeometry = \"smith\"\nfresnel = \"dielectric\"\nior = 2.0\ndiffuse = [0.3, 0.3, 0.3]\ndiffuse_weight = 1.0",
    free: &[Param::Roughness, Param::Ior, Param::Diffuse],
};

const GGX_SCHLICK: Case = Case {
    truth: "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 0.35\ngeometry = \"smith-correlated\"\nfresnel = \"schlick\"\nf0 = [0.9, 0.6, 0.3]\ndiffuse = [0.05, 0.1, 0.2]\ndiffuse_weight = 1.0",
    start: "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 0.1\ngeometry = \"smith-correlated\"\nfresnel = \"schlick\"\nf0 = 0.5\ndiffuse_weight = 0.0",
    free: &[Param::Roughness, Param::F0, Param::Diffuse, Param::Specular],
};

fn round_trip(case: &Case, noise: f64, tol: f64) {
    let (truth, start) = (material(case.truth), material(case.start));
    let local = grid(16);
    let values = measure(&truth, &local, noise);
    let data = FitData::from_tuples(&local, 6, &values, None, None, "grid".as_ref()).unwrap();
    let r = run_fit(&start, case.free, &data, Loss::L2, 4);
    assert_recovered(&r, &truth, noise, tol);
}

/// The fit `r` of data made from `truth` (with `noise`): its roughness and F0 within `tol`,
/// its loss at the engine's rounding without noise, and below the start's.
fn assert_recovered(r: &fit::FitResult, truth: &Material, noise: f64, tol: f64) {
    let (got, want) = (roughness(&r.material), roughness(truth));
    assert!(close(got, want, tol), "roughness {got} vs {want}");
    let (a, b) = (f0(&r.material), f0(truth));
    for c in 0..3 {
        assert!(close(a[c], b[c], tol), "F0 {a:?} vs {b:?}");
    }
    if noise == 0.0 {
        assert!(
            r.metrics.l2_relative <= 1e-6,
            "L2/energy {}",
            r.metrics.l2_relative
        );
    }
    assert!(r.metrics.l2 < r.start_metrics.l2);
}

#[test]
fn ggx_conductor_round_trip() {
    round_trip(&GGX_CONDUCTOR, 0.0, 0.01);
    round_trip(&GGX_CONDUCTOR, 0.01, 0.05);
}

#[test]
fn beckmann_plastic_round_trip() {
    round_trip(&BECKMANN_PLASTIC, 0.0, 0.01);
    round_trip(&BECKMANN_PLASTIC, 0.01, 0.05);
}

#[test]
fn ggx_schlick_round_trip_with_linear_f0_and_albedos() {
    round_trip(&GGX_SCHLICK, 0.0, 0.01);
    round_trip(&GGX_SCHLICK, 0.01, 0.05);
}

#[test]
fn e2_with_the_albedos_nonlinear_recovers_the_roughness() {
    let (truth, start) = (material(GGX_SCHLICK.truth), material(GGX_SCHLICK.start));
    let local = grid(10);
    let values = measure(&truth, &local, 0.0);
    let data = FitData::from_tuples(&local, 6, &values, None, None, "grid".as_ref()).unwrap();
    let r = run_fit(&start, GGX_SCHLICK.free, &data, Loss::E2, 2);
    assert!(
        close(roughness(&r.material), 0.35, 0.01),
        "{}",
        roughness(&r.material)
    );
}

#[test]
fn blinn_phong_on_ggx_converges_no_worse_than_the_best_of_20_random_starts() {
    use rand::{Rng, SeedableRng};
    let truth = material(GGX_SCHLICK.truth);
    let local = grid(12);
    let values = measure(&truth, &local, 0.0);
    let data = FitData::from_tuples(&local, 6, &values, None, None, "grid".as_ref()).unwrap();
    let free = [Param::Exponent, Param::Diffuse, Param::Specular];
    let start = material("model = \"blinn-phong\"\nexponent = 10\ndiffuse = 0.1");
    let r = run_fit(&start, &free, &data, Loss::L2, 8);
    assert!(
        r.metrics.l2_relative > 1e-4,
        "Blinn-Phong cannot represent GGX: {}",
        r.metrics.l2_relative
    );
    let mut rng = rand_pcg::Pcg64::seed_from_u64(99);
    let best_random = (0..20)
        .map(|_| {
            let e: f64 = (rng.random_range(0.0..10f64.ln())).exp() * 10.0;
            let s = material(&format!(
                "model = \"blinn-phong\"\nexponent = {e}\ndiffuse = 0.1"
            ));
            run_fit(&s, &free, &data, Loss::L2, 1).metrics.l2
        })
        .fold(f64::INFINITY, f64::min);
    assert!(
        r.metrics.l2 <= best_random * (1.0 + 1e-6),
        "{} vs {best_random}",
        r.metrics.l2
    );
}

#[test]
fn bad_input_is_refused_with_its_reason() {
    let m = material(GGX_SCHLICK.start);
    let e = Space::new(&m, &[], &[], true).unwrap_err().to_string();
    assert!(e.contains("no free parameter"), "{e}");
    let e = Space::new(
        &m,
        &[Param::Roughness],
        &[(Param::Roughness, 0.2, 0.9)],
        true,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("outside the bounds"), "{e}");
    let e = Space::new(&m, &[Param::Ior], &[], true)
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a parameter"), "{e}");
    let local = grid(4);
    let mut values = vec![0.1f32; local.len() / 2];
    values[5] = f32::NAN;
    let e = FitData::from_tuples(&local, 6, &values, None, None, "v.npy".as_ref())
        .unwrap_err()
        .to_string();
    assert!(e.contains("row 1") && e.contains("not finite"), "{e}");
    let invalid = vkbrdf::material::merl::MeasuredMerl::from_values(
        vec![-1.0; 3 * vkbrdf::material::merl::SAMPLES],
        "x.binary".as_ref(),
    )
    .unwrap();
    let e = FitData::from_merl(&invalid, None).unwrap_err().to_string();
    assert!(e.contains("no valid sample"), "{e}");
}

fn vkbrdf_cmd() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_vkbrdf"));
    c.env("VK_DRIVER_FILES", "/nonexistent")
        .env_remove("VKBRDF_DEVICE");
    c
}

#[test]
fn cli_fits_a_full_merl_table_and_its_material_evaluates() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n);
    std::fs::write(
        p("m.toml"),
        format!(
            "[[material]]\nname = \"truth\"\n{}\n\n[[material]]\nname = \"start\"\n{}\n",
            GGX_SCHLICK.truth, GGX_SCHLICK.start
        ),
    )
    .unwrap();
    let ok = vkbrdf_cmd()
        .args(["table", "merl", "--backend", "cpu", "-m"])
        .arg(p("m.toml"))
        .args(["--material", "truth", "-o"])
        .arg(p("t.binary"))
        .status()
        .unwrap();
    assert!(ok.success());
    let out = vkbrdf_cmd()
        .args([
            "fit",
            "--backend",
            "cpu",
            "--free",
            "roughness,f0,diffuse,specular",
            "--material",
            "start",
            "--starts",
            "2",
            "--merl",
        ])
        .arg(p("t.binary"))
        .arg("-m")
        .arg(p("m.toml"))
        .arg("--out-materials")
        .arg(p("fit.toml"))
        .arg("--report")
        .arg(p("fit.md"))
        .arg("--residual")
        .arg(p("r.exr"))
        .arg("--residual-png")
        .arg(p("r.png"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let fitted = vkbrdf::material::load_materials(&p("fit.toml"))
        .unwrap()
        .remove(0);
    assert!(
        close(roughness(&fitted), 0.35, 0.01),
        "{}",
        roughness(&fitted)
    );
    let (a, b) = (f0(&fitted), f0(&material(GGX_SCHLICK.truth)));
    for c in 0..3 {
        assert!(close(a[c], b[c], 0.01), "{a:?} vs {b:?}");
    }
    let report = std::fs::read_to_string(p("fit.md")).unwrap();
    assert!(report.contains("Ngan L2") && !report.contains("Interrupted"));
    assert!(p("r.exr").is_file() && p("r.png").is_file());
    // A file of the wrong size: exit 2, the reason, nothing written.
    std::fs::write(p("short.binary"), [0u8; 100]).unwrap();
    let out = vkbrdf_cmd()
        .args([
            "fit",
            "--backend",
            "cpu",
            "--free",
            "roughness",
            "--material",
            "start",
            "--merl",
        ])
        .arg(p("short.binary"))
        .arg("-m")
        .arg(p("m.toml"))
        .arg("--out-materials")
        .arg(p("bad.toml"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a MERL BRDF"));
    assert!(!p("bad.toml").exists());
}

/// A MERL table made by `vkbrdf table merl` from `case.truth`, every 17th valid bin (about
/// 65,000; the bins' own solid angles keep the loss's scale), fitted back within `tol`;
/// with `noise` the values are multiplied by `1 + noise·u` (u uniform in [−1, 1]).
fn merl_round_trip(case: &Case, noise: f64, tol: f64) {
    use rand::{Rng, SeedableRng};
    let dir = tempfile::tempdir().unwrap();
    let (toml, table) = (dir.path().join("m.toml"), dir.path().join("t.binary"));
    std::fs::write(
        &toml,
        format!("[[material]]\nname = \"truth\"\n{}\n", case.truth),
    )
    .unwrap();
    let ok = vkbrdf_cmd()
        .args(["table", "merl", "--backend", "cpu", "-m"])
        .arg(&toml)
        .args(["--material", "truth", "-o"])
        .arg(&table)
        .status()
        .unwrap();
    assert!(ok.success());
    let merl = vkbrdf::material::merl::read(&table).unwrap();
    let mut data = FitData::from_merl(&merl, None).unwrap().subsample(17);
    let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
    for v in &mut data.values {
        for c in v.iter_mut() {
            *c *= 1.0 + noise * rng.random_range(-1.0..=1.0);
        }
    }
    let (truth, start) = (material(case.truth), material(case.start));
    let r = run_fit(&start, case.free, &data, Loss::L2, 2);
    assert_recovered(&r, &truth, noise, tol);
}

#[test]
fn merl_round_trips_of_a_ggx_conductor_and_a_beckmann_plastic() {
    for case in [&GGX_CONDUCTOR, &BECKMANN_PLASTIC] {
        merl_round_trip(case, 0.0, 0.01);
        merl_round_trip(case, 0.01, 0.05);
    }
}
