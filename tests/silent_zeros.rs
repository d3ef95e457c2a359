//! Silent zeros become errors or warnings: an anisotropic material without tangents, a
//! MERL export of an anisotropic material, float16 overflow in `table --half`, a MERL
//! `file` that cannot be read.

mod common;
use common::{eval, generate, path, stderr, vkbrdf};

use exr::prelude::FlatSamples;
use std::path::Path;
use vkbrdf::batch::{check_tangent_rows, read_npy_f32, write_npy_f32, Batch};
use vkbrdf::material::{parse_materials, Material};
use vkbrdf::reference::CpuReference;
use vkbrdf::table::exr_out::HALF_MAX;
use vkbrdf::table::slice::{self, SliceJob, Spacing};
use vkbrdf::table::{merl, Grid, Runner};
use vkbrdf::Error;

const MATERIALS: &str = r#"
[[material]]
name = "matte"
model = "lambert"
diffuse = 0.5

[[material]]
name = "brushed"
model = "ward"
roughness = [0.1, 0.4]

[[material]]
name = "gold"
preset = "gold"
"#;

const ISOTROPIC: &str = r#"
[[material]]
name = "matte"
model = "lambert"
diffuse = 0.5

[[material]]
name = "gold"
preset = "gold"
"#;

fn materials() -> Vec<Material> {
    parse_materials(MATERIALS, "m.toml").unwrap()
}

/// `n` plain rows (L = V = N = +z) with material `material(i)`.
fn rows(n: usize, material: impl Fn(usize) -> usize) -> Vec<f32> {
    (0..n)
        .flat_map(|i| {
            [
                0.0,
                0.0,
                1.0,
                0.0,
                0.0,
                1.0,
                0.0,
                0.0,
                1.0,
                material(i) as f32,
            ]
        })
        .collect()
}

// ---------------------------------------------------------------------------------------
// Anisotropic materials need tangent columns.

#[test]
fn an_anisotropic_row_without_tangents_is_a_batch_error_naming_the_material() {
    let m = materials();
    let path = Path::new("t.npy");
    // Row 5 is the first to use `brushed` (index 1).
    let data = rows(40, |i| if i >= 5 && i % 5 == 0 { 1 } else { 0 });
    let batch = Batch::new(data.clone(), 10, m.len(), path).unwrap();
    let e = batch.check_tangents(&m, path).unwrap_err();
    assert!(matches!(e, Error::Batch { .. }), "{e:?}");
    let msg = e.to_string();
    for f in [
        "t.npy",
        "row 5",
        "`brushed`",
        "anisotropic",
        "tangent",
        "(n, 13)",
    ] {
        assert!(msg.contains(f), "`{msg}` lacks `{f}`");
    }
    // Chunk by chunk (as a streaming reader would): the row is the batch row.
    assert!(check_tangent_rows(&data[..50], 10, 0, &m, path).is_ok());
    let e = check_tangent_rows(&data[50..], 10, 5, &m, path).unwrap_err();
    assert!(e.to_string().contains("row 5:"), "{e}");
    let e = check_tangent_rows(&data[100..], 10, 10, &m, path).unwrap_err();
    assert!(e.to_string().contains("row 10:"), "{e}");
}

#[test]
fn tangents_are_needed_only_where_a_row_uses_an_anisotropic_material() {
    let m = materials();
    let path = Path::new("t.npy");
    // The table defines `brushed`, no row uses it.
    let plain = Batch::new(rows(30, |i| [0, 2][i % 2]), 10, m.len(), path).unwrap();
    assert!(plain.check_tangents(&m, path).is_ok());
    // With tangent columns every material is fine.
    let with_t: Vec<f32> = rows(30, |i| i % 3)
        .chunks(10)
        .flat_map(|r| r.iter().copied().chain([1.0, 0.0, 0.0]))
        .collect();
    let tangents = Batch::new(with_t, 13, m.len(), path).unwrap();
    assert!(tangents.check_tangents(&m, path).is_ok());
    // An empty batch and a table without anisotropic materials.
    let empty = Batch::new(vec![], 10, m.len(), path).unwrap();
    assert!(empty.check_tangents(&m, path).is_ok());
    let iso = parse_materials(ISOTROPIC, "iso.toml").unwrap();
    let b = Batch::new(rows(10, |i| i % 2), 10, iso.len(), path).unwrap();
    assert!(b.check_tangents(&iso, path).is_ok());
}

#[test]
fn cli_eval_refuses_an_anisotropic_batch_without_tangents_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m.toml");
    std::fs::write(&m, MATERIALS).unwrap();
    let t = dir.path().join("plain.npy");
    write_npy_f32(&t, &rows(100, |i| i % 3), 10).unwrap();
    let out = dir.path().join("f.npy");
    let o = eval(&m, &t, &["--backend", "reference", "-o", path(&out)]);
    let msg = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{msg}");
    assert!(
        msg.contains("plain.npy") && msg.contains("row 1:") && msg.contains("`brushed`"),
        "{msg}"
    );
    assert!(!out.exists());
    // The same table, rows that do not use `brushed`: evaluated, nothing invalid.
    write_npy_f32(&t, &rows(100, |i| [0, 2][i % 2]), 10).unwrap();
    let o = eval(&m, &t, &["--backend", "reference", "-o", path(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains(" 0 invalid"), "{}", stderr(&o));
}

#[test]
fn generate_adds_tangents_when_a_material_needs_them() {
    let dir = tempfile::tempdir().unwrap();
    for (toml, columns) in [(MATERIALS, 13), (ISOTROPIC, 10)] {
        let m = dir.path().join("m.toml");
        std::fs::write(&m, toml).unwrap();
        let t = dir.path().join("t.npy");
        let o = generate(&m, 300, &t);
        assert!(o.status.success(), "{}", stderr(&o));
        let (_, shape) = read_npy_f32(&t).unwrap();
        assert_eq!(shape, vec![300, columns], "{}", stderr(&o));
        if columns == 13 {
            assert!(
                stderr(&o).contains("`brushed` is anisotropic"),
                "{}",
                stderr(&o)
            );
        }
        // The generated batch evaluates with no invalid tuple.
        let out = dir.path().join("f.npy");
        let o = eval(&m, &t, &["--backend", "reference", "-o", path(&out)]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(stderr(&o).contains(" 0 invalid"), "{}", stderr(&o));
    }
}

// ---------------------------------------------------------------------------------------
// MERL is isotropic.

#[test]
fn merl_export_of_an_anisotropic_material_warns_about_phi_h() {
    let m = materials();
    let dir = tempfile::tempdir().unwrap();
    let mut cpu = CpuReference::new();
    for (material, warns) in [(&m[1], true), (&m[2], false)] {
        let mut runner = Runner::new(&mut cpu);
        let path = dir.path().join(format!("{}.binary", material.name));
        merl::write(&mut runner, material, &path).unwrap();
        let warnings = runner.take_warnings();
        if warns {
            assert_eq!(warnings.len(), 1, "{warnings:?}");
            for f in ["`brushed`", "anisotropic", "isotropic", "φ_h = 0"] {
                assert!(warnings[0].contains(f), "{warnings:?} lacks `{f}`");
            }
        } else {
            assert!(warnings.is_empty(), "{warnings:?}");
        }
    }
}

#[test]
fn cli_table_merl_prints_the_warning() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m.toml");
    std::fs::write(&m, MATERIALS).unwrap();
    let out = dir.path().join("brushed.binary");
    let o = vkbrdf(&[
        "table",
        "merl",
        "--materials",
        m.to_str().unwrap(),
        "--material",
        "brushed",
        "--output",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("warning: material `brushed` is anisotropic")
            && stderr(&o).contains("φ_h = 0"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        std::fs::metadata(&out).unwrap().len(),
        merl::FILE_BYTES as u64
    );
}

// ---------------------------------------------------------------------------------------
// float16 overflow.

/// The float32 values of every channel of every layer of an EXR file, by `layer.channel`.
fn exr_values(path: &Path) -> Vec<(String, bool, Vec<f32>)> {
    let image = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
    image
        .layer_data
        .into_iter()
        .flat_map(|l| {
            let layer = l.attributes.layer_name.map(|n| n.to_string());
            l.channel_data.list.into_iter().map(move |c| {
                (
                    format!("{}.{}", layer.clone().unwrap_or_default(), c.name),
                    matches!(c.sample_data, FlatSamples::F16(_)),
                    c.sample_data.values_as_f32().collect(),
                )
            })
        })
        .collect()
}

/// Texels of `values` (`n × k` interleaved) with a component beyond float16's range.
fn over_half(values: &[f32], k: usize) -> usize {
    values
        .chunks(k)
        .filter(|t| t.iter().any(|x| x.abs() > HALF_MAX))
        .count()
}

/// `table slice --half` of `material` on the CPU reference: the file holds no inf, the
/// texels beyond float16 hold ±65504, and the warnings count them per layer.
/// `expect_*`: whether the layer overflows float16, `None` where the test does not care.
fn half_slice_clamps(
    material: &Material,
    grid: Grid,
    expect_brdf: Option<bool>,
    expect_terms: Option<bool>,
) {
    let dir = tempfile::tempdir().unwrap();
    let mut cpu = CpuReference::new();
    // The float32 values (the input of the clamping under test).
    let (brdf, terms) = slice::compute_from_tuples(
        &mut Runner::new(&mut cpu),
        material,
        grid,
        Spacing::Sqrt,
        true,
    )
    .unwrap();
    let terms = terms.unwrap();
    let (brdf_over, terms_over) = (over_half(&brdf, 3), over_half(&terms, 6));
    for (over, expect, what) in [
        (brdf_over, expect_brdf, "BRDF"),
        (terms_over, expect_terms, "term"),
    ] {
        if let Some(e) = expect {
            assert_eq!(over > 0, e, "{what} texels beyond float16: {over}");
        }
    }

    let job = SliceJob {
        material: material.clone(),
        grid,
        spacing: Spacing::Sqrt,
        terms: true,
        half: true,
        output: dir.path().join("slice.exr"),
    };
    let mut runner = Runner::new(&mut cpu);
    slice::write(&mut runner, &job).unwrap();
    let warnings = runner.take_warnings();
    for (layer, over) in [("brdf", brdf_over), ("terms", terms_over)] {
        let w: Vec<_> = warnings
            .iter()
            .filter(|w| w.contains(&format!("layer `{layer}`")))
            .collect();
        if over == 0 {
            assert!(w.is_empty(), "{warnings:?}");
        } else {
            assert_eq!(w.len(), 1, "{warnings:?}");
            assert!(
                w[0].contains(&format!(": {over} texel(s)")) && w[0].contains("65504"),
                "{w:?}, want {over} texels"
            );
        }
    }
    let channels = exr_values(&job.output);
    assert_eq!(channels.len(), 9);
    for (name, half, values) in &channels {
        assert!(half, "{name} is not float16");
        assert!(values.iter().all(|x| x.is_finite()), "{name} holds inf/NaN");
    }
    // The clamped texels read back as 65504 exactly where float32 exceeded it.
    let k_over = terms.chunks(6).filter(|t| t[5] > HALF_MAX).count();
    let k = &channels.iter().find(|c| c.0 == "terms.K").unwrap().2;
    assert_eq!(k.iter().filter(|&&x| x == HALF_MAX).count(), k_over);
}

#[test]
fn half_slice_clamps_k_beyond_float16_and_counts_the_texels() {
    let gold = vkbrdf::material::presets::preset("gold").unwrap().unwrap();
    // 2000 θ_d rows: the last is 0.0225° from grazing, K = 1/(4 cos_i cos_o) ≈ 1.6e6.
    half_slice_clamps(&gold, Grid::new(30, 2000).unwrap(), Some(false), Some(true));
}

#[test]
fn half_slice_clamps_the_brdf_layer_too() {
    let sharp = parse_materials(
        "[[material]]\nname = \"sharp\"\nmodel = \"phong\"\nexponent = 1e6\n",
        "sharp.toml",
    )
    .unwrap();
    // The peak (e + 2)/(2π) ≈ 1.6e5 lies in the first θ_h column.
    half_slice_clamps(&sharp[0], Grid::new(90, 90).unwrap(), Some(true), None);
}

#[test]
fn cli_table_slice_half_warns_with_the_count() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("gold.exr");
    let o = vkbrdf(&[
        "table",
        "slice",
        "--material",
        "gold",
        "--size",
        "30x2000",
        "--terms",
        "--half",
        "--backend",
        "reference",
        "--output",
        out.to_str().unwrap(),
    ]);
    let msg = stderr(&o);
    assert!(o.status.success(), "{msg}");
    assert!(
        msg.contains("warning: ") && msg.contains("of layer `terms` exceed float16"),
        "{msg}"
    );
    assert!(!msg.contains("layer `brdf`"), "{msg}");
    // Without --half nothing is clamped, nothing said.
    let o = vkbrdf(&[
        "table",
        "slice",
        "--material",
        "gold",
        "--size",
        "30x2000",
        "--terms",
        "--backend",
        "reference",
        "--output",
        out.to_str().unwrap(),
    ]);
    assert!(
        o.status.success() && !stderr(&o).contains("warning"),
        "{}",
        stderr(&o)
    );
}

// ---------------------------------------------------------------------------------------
// A MERL file that cannot be read says why.

#[test]
fn a_merl_file_that_is_missing_or_a_directory_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let toml =
        |file: &str| format!("[[material]]\nname = \"m\"\nmodel = \"merl\"\nfile = \"{file}\"\n");
    let err = |file: &str| {
        vkbrdf::material::parse_materials_in(&toml(file), "m.toml", dir.path())
            .unwrap_err()
            .to_string()
    };
    let e = err("nope.binary");
    assert!(
        e.contains("m.toml:4")
            && e.contains("key `file`")
            && e.contains("nope.binary")
            && e.contains("No such file or directory"),
        "{e}"
    );
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    let e = err("sub");
    assert!(e.contains("key `file`") && e.contains("a directory"), "{e}");
    let e = err("/dev/null");
    assert!(e.contains("not a regular file"), "{e}");
}
