//! The command line through real files: generate → eval → read back, compared with the
//! reference; exit codes; atomic output; `--strict`.

mod common;
use common::{eval, path, vkbrdf};

use std::path::Path;
use std::process::Output;
use vkbrdf::batch::{read_npy_f32, write_npy_f32, Batch};

const MATERIALS: &str = r#"
[[material]]
name = "matte"
model = "lambert"
diffuse = [0.8, 0.5, 0.2]

[[material]]
name = "phong"
model = "phong"
exponent = 30
diffuse = 0.2

[[material]]
name = "blinn-phong"
model = "blinn-phong"
exponent = 50

[[material]]
name = "rtr"
model = "rtr"
exponent = 20
diffuse = [0.1, 0.2, 0.3]

[[material]]
name = "brushed"
model = "ward"
roughness = [0.1, 0.4]

[[material]]
name = "plastic"
preset = "shiny-plastic"

[[material]]
name = "gold"
preset = "gold"

[[material]]
name = "seed"
model = "cook-torrance"
convention = "seed"
distribution = "beckmann"
roughness = 0.3
geometry = "cook-torrance"
fresnel = "dielectric"
ior = 1.5
"#;

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn setup(dir: &Path) -> (String, String, Batch<'static>) {
    let m = dir.join("m.toml");
    std::fs::write(&m, MATERIALS).unwrap();
    let t = dir.join("t.npy");
    let o = vkbrdf(&[
        "generate",
        "--materials",
        m.to_str().unwrap(),
        "--tuples",
        "2000",
        "--tangents",
        "--output",
        t.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    // Append an invalid row (NaN in L) and a below-horizon row (L = −N).
    let (mut data, shape) = read_npy_f32(&t).unwrap();
    assert_eq!(shape, vec![2000, 13]);
    data.extend([
        f32::NAN,
        0.0,
        1.0,
        0.0,
        0.0,
        1.0,
        0.0,
        0.0,
        1.0,
        0.0,
        1.0,
        0.0,
        0.0,
    ]);
    data.extend([
        0.0, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0, 0.0,
    ]);
    write_npy_f32(&t, &data, 13).unwrap();
    let batch = Batch::new(data, 13, 8, &t).unwrap();
    (
        m.to_str().unwrap().to_string(),
        t.to_str().unwrap().to_string(),
        batch,
    )
}

#[test]
fn eval_round_trip_matches_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let (m, t, batch) = setup(dir.path());
    let materials = vkbrdf::material::parse_materials(MATERIALS, "m.toml").unwrap();
    let brdf = dir.path().join("brdf.npy");
    let terms = dir.path().join("terms.npy");
    let o = vkbrdf(&[
        "eval",
        "--backend",
        "reference",
        "-m",
        &m,
        "-i",
        &t,
        "-o",
        brdf.to_str().unwrap(),
        "--terms",
        terms.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let msg = text(&o);
    assert!(
        msg.contains("2002 tuples")
            && msg.contains("1 invalid")
            && msg.contains("1 below the horizon"),
        "{msg}"
    );
    let (f, fshape) = read_npy_f32(&brdf).unwrap();
    let (g, gshape) = read_npy_f32(&terms).unwrap();
    assert_eq!(fshape, vec![2002, 3]);
    assert_eq!(gshape, vec![2002, 6]);
    for i in 0..batch.len() {
        let tuple = batch.tuple(i);
        let r = vkbrdf::reference::evaluate_tuple(&tuple, &materials[tuple.material]);
        let terms_ref = r.terms();
        let expect = r.brdf.iter().chain(terms_ref.iter()).copied();
        let got = f[3 * i..3 * i + 3]
            .iter()
            .chain(&g[6 * i..6 * i + 6])
            .map(|&x| x as f64);
        for (col, (e, a)) in expect.zip(got).enumerate() {
            // The CPU backend's files hold exactly the reference value rounded once to f32.
            assert!(
                a == e as f32 as f64,
                "row {i} column {col}: file {a}, reference {e}, tuple {tuple:?}"
            );
        }
    }
    assert!(
        f[3 * 2000..].iter().all(|&x| x == 0.0),
        "invalid and below-horizon rows are 0"
    );
}

#[test]
fn strict_refuses_invalid_tuples_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (m, t, _) = setup(dir.path());
    let brdf = dir.path().join("brdf.npy");
    let o = vkbrdf(&[
        "eval",
        "--backend",
        "reference",
        "--strict",
        "-m",
        &m,
        "-i",
        &t,
        "-o",
        brdf.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("first invalid row: 2000"), "{}", text(&o));
    assert!(!brdf.exists(), "--strict must not write output");
}

#[test]
fn errors_exit_2_name_the_file_and_leave_existing_output_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let (m, t, _) = setup(dir.path());
    let brdf = dir.path().join("brdf.npy");
    std::fs::write(&brdf, b"precious").unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(
        &bad,
        "[[material]]\nname = \"x\"\nmodel = \"lambert\"\nroughness = 1\n",
    )
    .unwrap();
    let o = vkbrdf(&[
        "eval",
        "--backend",
        "reference",
        "-m",
        bad.to_str().unwrap(),
        "-i",
        &t,
        "-o",
        brdf.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o).contains("bad.toml:4") && text(&o).contains("roughness"),
        "{}",
        text(&o)
    );
    assert_eq!(std::fs::read(&brdf).unwrap(), b"precious");
    // An unwritable output directory: a clear error, no stray temporary file.
    let o = vkbrdf(&[
        "eval",
        "--backend",
        "reference",
        "-m",
        &m,
        "-i",
        &t,
        "-o",
        "/nonexistent-dir/brdf.npy",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o).contains("/nonexistent-dir/brdf.npy"),
        "{}",
        text(&o)
    );
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains("partial"))
        .collect();
    assert!(leftovers.is_empty());
}

#[test]
fn help_teaches_with_examples() {
    for cmd in ["eval", "materials", "generate", "demo"] {
        let o = vkbrdf(&[cmd, "--help"]);
        assert!(o.status.success());
        assert!(
            text(&o).contains("Example"),
            "`vkbrdf {cmd} --help` has no example"
        );
    }
    let o = vkbrdf(&["materials"]);
    for p in vkbrdf::material::presets::NAMES {
        assert!(text(&o).contains(p), "preset {p} not listed");
    }
}

#[test]
fn merl_export_then_eval_as_a_measured_material_returns_the_analytic_values() {
    let dir = tempfile::tempdir().unwrap();
    let binary = dir.path().join("gold.binary");
    let o = vkbrdf(&[
        "table",
        "merl",
        "--material",
        "gold",
        "--backend",
        "reference",
        "--output",
        binary.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let m = dir.path().join("measured.toml");
    std::fs::write(
        &m,
        "[[material]]\nname = \"measured-gold\"\nmodel = \"merl\"\nfile = \"gold.binary\"\n",
    )
    .unwrap();
    // Tuples at bin sample points (FORMULAS.md §7), built here from the bin angles.
    let mut rows = Vec::new();
    let mut dirs = Vec::new();
    for i in (0..90).step_by(7) {
        for j in (0..90).step_by(11) {
            for k in (0..180).step_by(23) {
                let th = (i as f64 / 90.0).powi(2) * std::f64::consts::FRAC_PI_2;
                let td = j as f64 * std::f64::consts::FRAC_PI_2 / 90.0;
                let pd = k as f64 * std::f64::consts::PI / 180.0;
                let d = [td.sin() * pd.cos(), td.sin() * pd.sin(), td.cos()];
                // l = R_y(θ_h) d; h = R_y(θ_h) z; v = 2 (l·h) h − l.
                let l = [
                    th.cos() * d[0] + th.sin() * d[2],
                    d[1],
                    -th.sin() * d[0] + th.cos() * d[2],
                ];
                let h = [th.sin(), 0.0, th.cos()];
                let lh = l[0] * h[0] + l[1] * h[1] + l[2] * h[2];
                let v = [
                    2.0 * lh * h[0] - l[0],
                    2.0 * lh * h[1] - l[1],
                    2.0 * lh * h[2] - l[2],
                ];
                if l[2] > 1e-3 && v[2] > 1e-3 {
                    rows.extend(l.iter().chain(&v).map(|&x| x as f32));
                    rows.extend([0.0, 0.0, 1.0, 0.0]);
                    dirs.push((l, v));
                }
            }
        }
    }
    let t = dir.path().join("t.npy");
    write_npy_f32(&t, &rows, 10).unwrap();
    let out = dir.path().join("f.npy");
    let o = eval(&m, &t, &["-o", path(&out)]);
    assert!(o.status.success(), "{}", text(&o));
    let (f, _) = read_npy_f32(&out).unwrap();
    let gold = vkbrdf::material::presets::preset("gold").unwrap().unwrap();
    assert!(dirs.len() > 300, "{} sample points", dirs.len());
    for (r, (l, v)) in dirs.iter().enumerate() {
        let want = vkbrdf::reference::evaluate(*l, *v, [0.0, 0.0, 1.0], None, &gold);
        for c in 0..3 {
            let got = f[3 * r + c] as f64;
            let rel = (got - want.brdf[c]).abs() / want.brdf[c].abs().max(1e-6);
            assert!(
                rel < 1e-5,
                "bin sample {r} channel {c}: measured {got}, analytic {} (l {l:?}, v {v:?})",
                want.brdf[c]
            );
        }
    }
}

/// Without a GPU, `auto` runs the CPU engine and the demo prints, beside it, the same work
/// timed on the Vulkan kernel's CPU device (lavapipe); with a GPU, `auto` runs the kernel
/// and no comparison is printed.
#[test]
fn demo_names_its_engine_and_the_lavapipe_figure_beside_it() {
    let Some(v) = common::vulkan() else {
        return;
    };
    let gpu = !v.is_cpu_device();
    drop(v);
    let out = common::vkbrdf(&["demo", "--no-tables", "--tuples", "5000", "--check", "10"]);
    assert!(out.status.success(), "demo: {}", common::stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    let first = text.lines().next().unwrap_or("");
    if gpu {
        assert!(first.contains(" on vulkan"), "{text}");
        assert!(
            !text.contains("the same tuples on the Vulkan kernel"),
            "{text}"
        );
    } else {
        assert!(first.contains(" on cpu ("), "the CPU engine ran: {text}");
        let line = text
            .lines()
            .find(|l| l.contains("the same tuples on the Vulkan kernel"))
            .unwrap_or_else(|| panic!("no lavapipe line: {text}"));
        assert!(
            line.contains("M tuples/s") && line.contains("× the CPU engine's time"),
            "{line}"
        );
    }
}
