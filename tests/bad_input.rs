//! Bad input gets a clear error naming what and where, never a panic: every material error
//! of the materials format and every `.npy` error.

mod common;

use common::npy::write_npy;
use std::path::Path;
use vkbrdf::batch::Batch;
use vkbrdf::material::parse_materials;

/// Parses `toml` and returns the error text, failing the test if it parsed.
fn material_error(toml: &str) -> String {
    match parse_materials(toml, "m.toml") {
        Ok(m) => panic!("expected an error for\n{toml}\ngot {m:?}"),
        Err(e) => e.to_string(),
    }
}

/// Asserts the error for `toml` mentions every fragment.
fn assert_material_error(toml: &str, fragments: &[&str]) {
    let msg = material_error(toml);
    for f in fragments {
        assert!(
            msg.contains(f),
            "error for\n{toml}\nis `{msg}`, which lacks `{f}`"
        );
    }
}

const CT: &str =
    "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 0.3\ngeometry = \"smith\"\n";

#[test]
fn unknown_key_names_material_key_and_line() {
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"lambert\"\ncolour = [1, 0, 0]\n",
        &["m.toml:4", "material `a`", "key `colour`", "unknown key"],
    );
}

#[test]
fn unknown_values_are_rejected() {
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"oren-nayar\"\n",
        &["m.toml:3", "key `model`", "oren-nayar", "lambert"],
    );
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 0.3\ngeometry = \"smith\"\nfresnel = \"magic\"\n",
        &["m.toml:7", "key `fresnel`", "magic"],
    );
    assert_material_error(
        &format!("[[material]]\nname = \"a\"\n{CT}fresnel = \"none\"\nconvention = \"old\"\n"),
        &["key `convention`", "old"],
    );
    assert_material_error(
        "[[material]]\nname = \"a\"\npreset = \"unobtainium\"\n",
        &["key `preset`", "unobtainium", "gold"],
    );
}

#[test]
fn wrong_types_are_rejected() {
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = 3\n",
        &["key `model`", "expected a string"],
    );
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"phong\"\nexponent = \"high\"\n",
        &["key `exponent`", "expected a number"],
    );
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"lambert\"\ndiffuse = [1, 2]\n",
        &["key `diffuse`", "array of 2"],
    );
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"phong\"\nexponent = [1, 2]\n",
        &["key `exponent`", "array"],
    );
    assert_material_error(
        "[[material]]\nname = 5\nmodel = \"lambert\"\n",
        &["key `name`"],
    );
    assert_material_error(
        "[[material]]\nmodel = \"lambert\"\n",
        &["key `name`", "needs a `name`"],
    );
}

#[test]
fn malformed_toml_names_the_line() {
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"lambert\n",
        &["m.toml:3"],
    );
    assert_material_error("[[materials]]\nname = \"a\"\n", &["m.toml:1", "materials"]);
    assert_material_error("", &["no [[material]]"]);
}

#[test]
fn roughness_must_be_positive_and_finite() {
    for bad in [
        "0",
        "-0.1",
        "nan",
        "inf",
        "[0.1, 0]",
        "[0.1, -1]",
        "[0.1, 0.2, 0.3]",
    ] {
        assert_material_error(
            &format!("[[material]]\nname = \"a\"\nmodel = \"ward\"\nroughness = {bad}\n"),
            &["m.toml:4", "material `a`", "key `roughness`"],
        );
    }
}

#[test]
fn smith_needs_a_lambda() {
    for (dist, param) in [("gaussian", "roughness = 0.3"), ("blinn", "exponent = 20")] {
        for g in ["smith", "smith-correlated", "smith-fast"] {
            assert_material_error(
                &format!("[[material]]\nname = \"a\"\nmodel = \"cook-torrance\"\ndistribution = \"{dist}\"\n{param}\ngeometry = \"{g}\"\nfresnel = \"none\"\n"),
                &["key `geometry`", dist],
            );
        }
    }
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 0.3\ngeometry = \"smith-fast\"\nfresnel = \"none\"\n",
        &["key `geometry`", "Beckmann only"],
    );
}

#[test]
fn cloth_and_schlick_smith_rules() {
    let ct = |d: &str, param: &str, g: &str| {
        format!("[[material]]\nname = \"a\"\nmodel = \"cook-torrance\"\ndistribution = \"{d}\"\n{param}\ngeometry = \"{g}\"\nfresnel = \"none\"\n")
    };
    // No Λ (or k) to guess: every Smith form and schlick-smith with charlie, and
    // schlick-smith with gaussian and blinn.
    for g in ["smith", "smith-correlated", "smith-fast", "schlick-smith"] {
        assert_material_error(
            &ct("charlie", "roughness = 0.3", g),
            &[
                "m.toml:6",
                "key `geometry`",
                "`charlie` has none",
                "neubelt",
            ],
        );
    }
    for (d, param) in [("gaussian", "roughness = 0.3"), ("blinn", "exponent = 20")] {
        assert_material_error(
            &ct(d, param, "schlick-smith"),
            &["key `geometry`", "schlick-smith", d],
        );
    }
    // Isotropic only: schlick-smith, and charlie itself.
    for d in ["beckmann", "ggx"] {
        assert_material_error(
            &ct(d, "roughness = [0.1, 0.3]", "schlick-smith"),
            &["key `geometry`", "isotropic roughness only"],
        );
    }
    assert_material_error(
        &ct("charlie", "roughness = [0.1, 0.3]", "neubelt"),
        &["key `roughness`", "`charlie` is isotropic only"],
    );
    // 0 < m ≤ 1 (the paper's α = r²); the general roughness range still applies below.
    assert_material_error(
        &ct("charlie", "roughness = 1.5", "neubelt"),
        &["m.toml:5", "key `roughness`", "1.5", "0 < m ≤ 1"],
    );
    assert_material_error(
        &ct("charlie", "roughness = 0", "neubelt"),
        &["key `roughness`", "> 0"],
    );
    // And what is legal parses: neubelt with every distribution, schlick-smith with both.
    for (d, param) in [
        ("gaussian", "roughness = 0.3"),
        ("beckmann", "roughness = [0.1, 0.3]"),
        ("ggx", "roughness = 1e4"),
        ("blinn", "exponent = 20"),
        ("charlie", "roughness = 1.0"),
    ] {
        parse_materials(&ct(d, param, "neubelt"), "m.toml")
            .expect("neubelt is legal with every distribution");
    }
    for d in ["beckmann", "ggx"] {
        parse_materials(&ct(d, "roughness = 1e4", "schlick-smith"), "m.toml").expect("legal");
    }
}

#[test]
fn conductor_needs_extinction_and_dielectric_refuses_it() {
    assert_material_error(
        &format!("[[material]]\nname = \"a\"\n{CT}fresnel = \"conductor\"\nior = 0.2\n"),
        &["key `extinction`", "conductor"],
    );
    assert_material_error(
        &format!(
            "[[material]]\nname = \"a\"\n{CT}fresnel = \"conductor\"\nextinction = [3, 3, 3]\n"
        ),
        &["key `ior`"],
    );
    assert_material_error(
        &format!(
            "[[material]]\nname = \"a\"\n{CT}fresnel = \"dielectric\"\nior = 1.5\nextinction = 1\n"
        ),
        &["key `extinction`", "conductor"],
    );
    assert_material_error(
        &format!("[[material]]\nname = \"a\"\n{CT}fresnel = \"dielectric\"\n"),
        &["key `ior`", "missing"],
    );
    assert_material_error(
        &format!("[[material]]\nname = \"a\"\n{CT}fresnel = \"schlick\"\n"),
        &["key `f0`", "missing"],
    );
    assert_material_error(
        &format!("[[material]]\nname = \"a\"\n{CT}fresnel = \"schlick\"\nf0 = 0.04\nior = 1.5\n"),
        &["key `f0`", "not both"],
    );
    assert_material_error(
        &format!("[[material]]\nname = \"a\"\n{CT}fresnel = \"schlick\"\nf0 = 1.5\n"),
        &["key `f0`", "[0, 1]"],
    );
    assert_material_error(
        &format!("[[material]]\nname = \"a\"\n{CT}fresnel = \"dielectric\"\nior = 0\n"),
        &["key `ior`", "> 0"],
    );
}

#[test]
fn anisotropy_only_where_it_exists() {
    // Not in the seed or cook-torrance-1982 conventions.
    for conv in ["seed", "cook-torrance-1982"] {
        assert_material_error(
            &format!("[[material]]\nname = \"a\"\nmodel = \"cook-torrance\"\nconvention = \"{conv}\"\ndistribution = \"beckmann\"\nroughness = [0.1, 0.3]\ngeometry = \"smith\"\nfresnel = \"none\"\n"),
            &["key `roughness`", "modern"],
        );
    }
    // Not for the Gaussian distribution.
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"cook-torrance\"\ndistribution = \"gaussian\"\nroughness = [0.1, 0.3]\ngeometry = \"none\"\nfresnel = \"none\"\n",
        &["key `roughness`", "isotropic"],
    );
    // Not on a model that has no roughness at all.
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"phong\"\nexponent = 10\nroughness = [0.1, 0.3]\n",
        &["key `roughness`", "does not apply"],
    );
}

#[test]
fn negative_colours_and_weights_are_rejected() {
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"lambert\"\ndiffuse = [0.5, -0.1, 0.5]\n",
        &["key `diffuse`", "≥ 0", "-0.1"],
    );
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"phong\"\nexponent = 10\nspecular = -1\n",
        &["key `specular`"],
    );
    assert_material_error(
        &format!("[[material]]\nname = \"a\"\n{CT}fresnel = \"none\"\nspecular_weight = -0.5\n"),
        &["key `specular_weight`"],
    );
    assert_material_error(
        &format!("[[material]]\nname = \"a\"\n{CT}fresnel = \"none\"\ndiffuse_weight = -0.5\n"),
        &["key `diffuse_weight`"],
    );
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"phong\"\nexponent = -1\n",
        &["key `exponent`"],
    );
}

#[test]
fn missing_required_keys_and_duplicates() {
    assert_material_error("[[material]]\nname = \"a\"\n", &["key `model`", "missing"]);
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"cook-torrance\"\n",
        &["key `distribution`", "missing"],
    );
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"phong\"\n",
        &["key `exponent`", "missing"],
    );
    assert_material_error(
        "[[material]]\nname = \"a\"\nmodel = \"lambert\"\n[[material]]\nname = \"a\"\nmodel = \"lambert\"\n",
        &["m.toml:4", "duplicate"],
    );
}

#[test]
fn presets_take_overrides_and_drop_keys_the_override_makes_moot() {
    let m = parse_materials(
        "[[material]]\nname = \"rough-gold\"\npreset = \"gold\"\nroughness = 0.6\n",
        "m.toml",
    )
    .unwrap();
    let ct = m[0].cook_torrance().expect("gold is cook-torrance");
    assert_eq!(
        ct.distribution,
        vkbrdf::material::Distribution::Ggx(vkbrdf::material::Roughness::Isotropic(0.6))
    );
    // Switching gold to a Blinn distribution: the preset's roughness is dropped, not an error.
    let m = parse_materials(
        "[[material]]\nname = \"g\"\npreset = \"gold\"\ndistribution = \"blinn\"\nexponent = 80\ngeometry = \"cook-torrance\"\n",
        "m.toml",
    )
    .unwrap();
    assert_eq!(
        m[0].cook_torrance().unwrap().distribution,
        vkbrdf::material::Distribution::Blinn { exponent: 80.0 }
    );
}

// ---- .npy errors -------------------------------------------------------------------------

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn row(material: f32) -> Vec<f32> {
    vec![0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, material]
}

fn npy_error(
    descr: &str,
    fortran: bool,
    shape: &[usize],
    data: &[u8],
    material_count: usize,
) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tuples.npy");
    write_npy(&path, descr, fortran, shape, data);
    match Batch::read_npy(&path, material_count) {
        Ok(_) => panic!("expected an error for descr {descr} shape {shape:?}"),
        Err(e) => {
            let msg = e.to_string();
            assert!(
                msg.contains("tuples.npy"),
                "error `{msg}` does not name the file"
            );
            msg
        }
    }
}

#[test]
fn npy_good_files_read_in_both_float_widths() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ok.npy");
    let rows: Vec<f32> = [row(0.0), row(1.0)].concat();
    write_npy(&path, "<f4", false, &[2, 10], &f32_bytes(&rows));
    let b = Batch::read_npy(&path, 2).unwrap();
    assert_eq!(b.len(), 2);
    assert_eq!(b.material(1), 1);
    let wide: Vec<u8> = rows
        .iter()
        .flat_map(|&x| (x as f64).to_le_bytes())
        .collect();
    write_npy(&path, "<f8", false, &[2, 10], &wide);
    assert_eq!(Batch::read_npy(&path, 2).unwrap().as_slice(), &rows[..]);
}

#[test]
fn npy_wrong_dtype() {
    let msg = npy_error("<i4", false, &[1, 10], &[0u8; 40], 1);
    assert!(msg.contains("<i4") && msg.contains("float32"), "{msg}");
    let msg = npy_error(">f4", false, &[1, 10], &[0u8; 40], 1);
    assert!(msg.contains(">f4"), "{msg}");
}

#[test]
fn npy_wrong_rank_or_columns() {
    let msg = npy_error("<f4", false, &[10], &f32_bytes(&row(0.0)), 1);
    assert!(msg.contains("2-D"), "{msg}");
    let msg = npy_error("<f4", false, &[1, 1, 10], &f32_bytes(&row(0.0)), 1);
    assert!(msg.contains("2-D"), "{msg}");
    let msg = npy_error("<f4", false, &[1, 9], &f32_bytes(&row(0.0)[..9]), 1);
    assert!(msg.contains("found 9"), "{msg}");
}

/// A Fortran-order file (NumPy's `order='F'`, column after column) reads as the same rows;
/// a rank above 2 in Fortran order is refused, naming the order.
#[test]
fn npy_fortran_order_reads_as_rows() {
    let dir = tempfile::tempdir().unwrap();
    let rows: Vec<f32> = [row(0.0), row(1.0), row(1.0)]
        .concat()
        .iter()
        .enumerate()
        .map(|(i, &x)| if i % 10 == 9 { x } else { x + i as f32 / 64.0 })
        .collect();
    let columns: Vec<f32> = (0..10)
        .flat_map(|j| (0..3).map(move |i| (i, j)))
        .map(|(i, j)| rows[i * 10 + j])
        .collect();
    let path = dir.path().join("f.npy");
    write_npy(&path, "<f4", true, &[3, 10], &f32_bytes(&columns));
    let b = Batch::read_npy(&path, 2).unwrap();
    assert_eq!(b.as_slice(), rows.as_slice());
    let msg = npy_error("<f4", true, &[1, 1, 10], &f32_bytes(&row(0.0)), 1);
    assert!(msg.contains("Fortran"), "{msg}");
}

#[test]
fn npy_truncated() {
    let rows: Vec<f32> = [row(0.0), row(0.0)].concat();
    let bytes = f32_bytes(&rows);
    let msg = npy_error("<f4", false, &[2, 10], &bytes[..bytes.len() - 7], 1);
    assert!(msg.contains("truncated"), "{msg}");
    // Not even a header.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tuples.npy");
    std::fs::write(&path, b"\x93NUMPY\x01").unwrap();
    let msg = Batch::read_npy(&path, 1).unwrap_err().to_string();
    assert!(
        msg.contains("tuples.npy") && msg.contains("not a valid .npy"),
        "{msg}"
    );
}

#[test]
fn npy_bad_material_values_name_the_first_bad_row() {
    for (bad, why) in [(1.5f32, "1.5"), (3.0, "3"), (-1.0, "-1"), (f32::NAN, "NaN")] {
        let rows: Vec<f32> = [row(0.0), row(1.0), row(bad), row(bad)].concat();
        let msg = npy_error("<f4", false, &[4, 10], &f32_bytes(&rows), 3);
        assert!(
            msg.contains("row 2") && msg.contains(why) && msg.contains("0..3"),
            "material {bad}: {msg}"
        );
    }
}

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let e = Batch::read_npy(Path::new("/nonexistent/dir/t.npy"), 1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("/nonexistent/dir/t.npy"), "{e}");
    let e = vkbrdf::material::load_materials(Path::new("/nonexistent/m.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("/nonexistent/m.toml"), "{e}");
}

#[test]
fn measured_material_needs_a_readable_merl_file() {
    assert_material_error(
        "[[material]]\nname = \"m\"\nmodel = \"merl\"\n",
        &["material `m`", "key `file`", "missing"],
    );
    assert_material_error(
        "[[material]]\nname = \"m\"\nmodel = \"merl\"\nfile = \"/nonexistent/x.binary\"\n",
        &["m.toml:4", "key `file`", "/nonexistent/x.binary"],
    );
    assert_material_error(
        "[[material]]\nname = \"m\"\nmodel = \"merl\"\nfile = \"x\"\ndiffuse = 1\n",
        &["key `file`"],
    );
    // A file that is not a MERL binary.
    let dir = tempfile::tempdir().unwrap();
    let bogus = dir.path().join("bogus.binary");
    std::fs::write(&bogus, b"not a merl file").unwrap();
    let text = format!(
        "[[material]]\nname = \"m\"\nmodel = \"merl\"\nfile = \"{}\"\n",
        bogus.display()
    );
    assert_material_error(&text, &["key `file`", "bogus.binary"]);
}

#[test]
fn a_measured_material_has_no_fast_variant() {
    assert_material_error(
        "[[material]]\nname = \"m\"\nmodel = \"merl\"\nfile = \"x.binary\"\nprecision = \"fast\"\n",
        &[
            "m.toml:5",
            "material `m`",
            "key `precision`",
            "no fast variant",
        ],
    );
}

#[test]
fn htsg_parameters_are_checked() {
    let m = |body: &str| format!("[[material]]\nname = \"h\"\nmodel = \"htsg\"\n{body}\n");
    // FORMULAS.md §8's ranges, each naming its key.
    assert_material_error(
        &m("tau = 1\nior = 1.5"),
        &["`sigma0`", "missing", "m.toml:1:"],
    );
    assert_material_error(&m("sigma0 = 0.1\nior = 1.5"), &["`tau`", "missing"]);
    assert_material_error(&m("sigma0 = 0.1\ntau = 1"), &["`ior`", "missing"]);
    assert_material_error(
        &m("sigma0 = 0\ntau = 1\nior = 1.5"),
        &["`sigma0`", "[1e-4, 10]"],
    );
    assert_material_error(
        &m("sigma0 = 0.1\ntau = 1e3\nior = 1.5"),
        &["`tau`", "[1e-3, 100]"],
    );
    assert_material_error(
        &m("sigma0 = 5\ntau = 0.1\nior = 1.5"),
        &["`sigma0`", "sigma0 / tau", "5e1"],
    );
    assert_material_error(
        &m("sigma0 = 0.1\ntau = 1\nior = 1.5\nwavelengths = [100, 500, 600]"),
        &["`wavelengths`", "[200, 5000]", "m.toml:7:"],
    );
    assert_material_error(
        &m("sigma0 = 0.1\ntau = 1\nior = 1.5\nextinction = -1"),
        &["`extinction`"],
    );
    // Keys the model never reads, and the fast variant it does not have.
    assert_material_error(
        &m("sigma0 = 0.1\ntau = 1\nior = 1.5\nspecular = 1"),
        &["`specular`", "does not apply"],
    );
    assert_material_error(
        &m("sigma0 = 0.1\ntau = 1\nior = 1.5\nroughness = 0.1"),
        &["`roughness`", "does not apply"],
    );
    assert_material_error(
        &m("sigma0 = 0.1\ntau = 1\nior = 1.5\nprecision = \"fast\""),
        &["`precision`", "exact"],
    );
    // A dielectric (no extinction) is legal.
    assert!(parse_materials(&m("sigma0 = 0.1\ntau = 1\nior = 1.5"), "m.toml").is_ok());
}
