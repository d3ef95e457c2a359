//! `vkbrdf table slice|albedo|dfg|merl --shard K/N` and `vkbrdf merge` of table parts: the
//! merged file equals the unsharded run byte for byte (N = 1, 3, 7 and N larger than the
//! table's rows, whose extra parts are empty), and parts that do not belong together are
//! refused with exit 2, naming the part and what differs, with nothing written.

mod common;

use common::{path, stderr, vkbrdf};
use std::path::{Path, PathBuf};

/// Runs `vkbrdf table ARGS -o OUT [--shard K/N]`, asserting success.
fn table(args: &[&str], out: &Path, shard: Option<String>) {
    let mut a: Vec<&str> = vec!["table"];
    a.extend_from_slice(args);
    a.extend_from_slice(&["-o", path(out)]);
    if let Some(s) = &shard {
        a.extend_from_slice(&["--shard", s]);
    }
    let r = vkbrdf(&a);
    assert!(r.status.success(), "{a:?}: {}", stderr(&r));
}

/// The backends the CLI tests run on: the reference and the CPU engine, and Vulkan when a
/// device exists (required under `VKBRDF_REQUIRE_VULKAN=1`).
fn backends() -> Vec<&'static str> {
    let mut v = vec!["reference", "cpu"];
    if common::vulkan().is_some() {
        v.push("vulkan");
    }
    v
}

/// Runs the table `args` (output named `name.EXT`) whole and as N parts for each N of
/// `ns`, merges each set (parts given in reverse order: order does not matter) and checks
/// the merge equals the whole run byte for byte. `extra` names a second output option
/// (`--average`) whose parts are merged and compared too.
fn check_sharded(dir: &Path, args: &[&str], ext: &str, ns: &[u64], extra: Option<&str>) {
    let whole = dir.join(format!("whole.{ext}"));
    let whole_extra = dir.join(format!("whole-extra.{ext}"));
    let mut a = args.to_vec();
    if let Some(opt) = extra {
        a.extend_from_slice(&[opt, path(&whole_extra)]);
    }
    table(&a, &whole, None);
    // A part of an EXR table is a .npy band; a MERL part is a MERL binary of its band.
    let part_ext = if ext == "exr" { "npy" } else { ext };
    for &n in ns {
        let mut parts = Vec::new();
        let mut extras = Vec::new();
        for k in 1..=n {
            let p = dir.join(format!("p{k}-of-{n}.{part_ext}"));
            let q = dir.join(format!("q{k}-of-{n}.{part_ext}"));
            let mut a = args.to_vec();
            if let Some(opt) = extra {
                a.extend_from_slice(&[opt, path(&q)]);
                extras.push(q.clone());
            }
            table(&a, &p, Some(format!("{k}/{n}")));
            assert!(vkbrdf::stream::shard::sidecar_path(&p).exists());
            parts.push(p);
        }
        for (set, want) in [(&parts, &whole), (&extras, &whole_extra)] {
            if set.is_empty() {
                continue;
            }
            let merged = dir.join(format!("merged-{n}.{ext}"));
            let mut m = vec!["merge", "-o", path(&merged)];
            m.extend(set.iter().rev().map(|p| path(p)));
            let r = vkbrdf(&m);
            assert!(r.status.success(), "{args:?} N = {n}: {}", stderr(&r));
            assert!(
                std::fs::read(want).unwrap() == std::fs::read(&merged).unwrap(),
                "{args:?}: the merge of {n} parts differs from the whole run"
            );
            std::fs::remove_file(&merged).unwrap();
        }
        for p in parts.iter().chain(&extras) {
            std::fs::remove_file(p).unwrap();
            std::fs::remove_file(vkbrdf::stream::shard::sidecar_path(p)).unwrap();
        }
    }
}

#[test]
fn merged_slice_shards_equal_the_unsharded_slice() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m.toml");
    std::fs::write(
        &m,
        "[[material]]\nname = \"brushed\"\nmodel = \"cook-torrance\"\nconvention = \"modern\"\n\
         distribution = \"ggx\"\nroughness = [0.1, 0.4]\ngeometry = \"smith-correlated\"\n\
         fresnel = \"schlick\"\nf0 = [0.9, 0.8, 0.6]\n",
    )
    .unwrap();
    for backend in backends() {
        // 5 θ_d rows: N = 7 has two empty parts.
        check_sharded(
            dir.path(),
            &[
                "slice",
                "--material",
                "gold",
                "--size",
                "9x5",
                "--terms",
                "--backend",
                backend,
            ],
            "exr",
            &[1, 3, 7],
            None,
        );
        // An anisotropic material (tangents), float16, linear spacing.
        check_sharded(
            dir.path(),
            &[
                "slice",
                "-m",
                path(&m),
                "--material",
                "brushed",
                "--size",
                "6x4",
                "--linear",
                "--half",
                "--backend",
                backend,
            ],
            "exr",
            &[3, 6],
            None,
        );
    }
}

#[test]
fn merged_albedo_and_average_shards_equal_the_unsharded_tables() {
    let dir = tempfile::tempdir().unwrap();
    for backend in backends() {
        check_sharded(
            dir.path(),
            &[
                "albedo",
                "--size",
                "6x5",
                "--samples",
                "300",
                "--backend",
                backend,
            ],
            "exr",
            &[1, 3, 7],
            Some("--average"),
        );
    }
    check_sharded(
        dir.path(),
        &[
            "albedo",
            "--distribution",
            "beckmann",
            "--geometry",
            "smith",
            "--roughness-axis",
            "perceptual",
            "--sampling",
            "endpoints",
            "--size",
            "5x4",
            "--samples",
            "64",
            "--backend",
            "cpu",
        ],
        "exr",
        &[3],
        Some("--average"),
    );
}

#[test]
fn merged_dfg_shards_equal_the_unsharded_table() {
    let dir = tempfile::tempdir().unwrap();
    for backend in backends() {
        check_sharded(
            dir.path(),
            &[
                "dfg",
                "--size",
                "7x6",
                "--samples",
                "300",
                "--backend",
                backend,
            ],
            "exr",
            &[1, 3, 7],
            None,
        );
    }
    for style in ["filament", "ue4"] {
        check_sharded(
            dir.path(),
            &[
                "dfg",
                "--lut-style",
                style,
                "--size",
                "8x6",
                "--samples",
                "128",
                "--half",
                "--backend",
                "cpu",
            ],
            "exr",
            &[4, 9],
            None,
        );
    }
}

#[test]
fn merged_merl_shards_equal_the_unsharded_file() {
    let dir = tempfile::tempdir().unwrap();
    // 90 θ_h bins: N = 91 has an empty part.
    check_sharded(
        dir.path(),
        &["merl", "--material", "gold", "--backend", "cpu"],
        "binary",
        &[1, 3, 7, 91],
        None,
    );
    check_sharded(
        dir.path(),
        &["merl", "--material", "gold", "--backend", "reference"],
        "binary",
        &[7],
        None,
    );
}

/// The same table written twice is the same bytes: the `exr` crate keeps custom header
/// attributes in a randomly seeded `HashMap`, and the provenance attributes came out in a
/// different order on every run (one header per layer: the slice with terms has two).
#[test]
fn a_table_written_twice_is_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    for args in [
        &["slice", "--material", "gold", "--size", "4x3", "--terms"][..],
        &["dfg", "--size", "4x3", "--samples", "16"][..],
    ] {
        let files: Vec<Vec<u8>> = (0..3)
            .map(|i| {
                let out = dir.path().join(format!("t{i}.exr"));
                let mut a = args.to_vec();
                a.extend_from_slice(&["--backend", "reference"]);
                table(&a, &out, None);
                std::fs::read(&out).unwrap()
            })
            .collect();
        assert!(files[0] == files[1] && files[1] == files[2], "{args:?}");
        // Still a readable EXR with every provenance attribute.
        let image =
            exr::prelude::read_all_flat_layers_from_file(dir.path().join("t0.exr")).unwrap();
        for layer in &image.layer_data {
            let names: Vec<String> = layer
                .attributes
                .other
                .keys()
                .map(|k| k.to_string())
                .collect();
            for key in ["vkbrdf.table", "vkbrdf.backend", "vkbrdf.version"] {
                assert!(names.iter().any(|n| n == key), "{key} missing: {names:?}");
            }
        }
    }
}

/// Writes the dfg parts `k/n` of `args` as `name-k.npy` and returns their paths.
fn dfg_parts(dir: &Path, name: &str, args: &[&str], n: u64) -> Vec<PathBuf> {
    (1..=n)
        .map(|k| {
            let p = dir.join(format!("{name}-{k}.npy"));
            table(args, &p, Some(format!("{k}/{n}")));
            p
        })
        .collect()
}

/// `vkbrdf merge -o OUT PARTS…` must fail with exit 2, naming `names` and saying `what`,
/// and write nothing.
fn refused(dir: &Path, extra: &[&str], parts: &[&PathBuf], names: &Path, what: &str) {
    let out = dir.join("refused.exr");
    let mut a = vec!["merge", "-o", path(&out)];
    a.extend_from_slice(extra);
    a.extend(parts.iter().map(|p| path(p)));
    let r = vkbrdf(&a);
    let e = stderr(&r);
    assert_eq!(r.status.code(), Some(2), "{a:?}: {e}");
    assert!(
        e.contains(path(names)) && e.contains(what),
        "{a:?}: wanted {} and {what:?} in: {e}",
        names.display()
    );
    assert!(!out.exists(), "{a:?} wrote {}", out.display());
}

#[test]
fn merge_refuses_table_parts_that_do_not_belong_together() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let base = [
        "dfg",
        "--size",
        "4x3",
        "--samples",
        "16",
        "--backend",
        "cpu",
    ];
    let a = dfg_parts(d, "a", &base, 3);
    let samples = dfg_parts(
        d,
        "s",
        &[
            "dfg",
            "--size",
            "4x3",
            "--samples",
            "32",
            "--backend",
            "cpu",
        ],
        3,
    );
    let size = dfg_parts(
        d,
        "z",
        &[
            "dfg",
            "--size",
            "4x4",
            "--samples",
            "16",
            "--backend",
            "cpu",
        ],
        3,
    );
    let half = dfg_parts(
        d,
        "h",
        &[
            "dfg",
            "--size",
            "4x3",
            "--samples",
            "16",
            "--half",
            "--backend",
            "cpu",
        ],
        3,
    );
    let reference = dfg_parts(
        d,
        "r",
        &[
            "dfg",
            "--size",
            "4x3",
            "--samples",
            "16",
            "--backend",
            "reference",
        ],
        3,
    );
    let four = dfg_parts(d, "f", &base, 4);
    let albedo = d.join("albedo-2.npy");
    table(
        &[
            "albedo",
            "--size",
            "4x3",
            "--samples",
            "16",
            "--backend",
            "cpu",
        ],
        &albedo,
        Some("2/3".into()),
    );
    let slice_a = d.join("slice-a.npy");
    let slice_b = d.join("slice-b.npy");
    std::fs::write(
        d.join("m1.toml"),
        "[[material]]\nname = \"x\"\nmodel = \"lambert\"\ndiffuse = 0.5\n",
    )
    .unwrap();
    std::fs::write(
        d.join("m2.toml"),
        "[[material]]\nname = \"x\"\nmodel = \"lambert\"\ndiffuse = 0.25\n",
    )
    .unwrap();
    for (m, p, k) in [("m1.toml", &slice_a, "1/2"), ("m2.toml", &slice_b, "2/2")] {
        let m = d.join(m);
        table(
            &[
                "slice",
                "-m",
                path(&m),
                "--material",
                "x",
                "--size",
                "3x2",
                "--backend",
                "cpu",
            ],
            p,
            Some(k.into()),
        );
    }

    // Different options, kinds, N, engines.
    refused(
        d,
        &[],
        &[&a[0], &samples[1], &a[2]],
        &samples[1],
        "option samples",
    );
    refused(d, &[], &[&a[0], &a[1], &size[2]], &size[2], "option size");
    refused(d, &[], &[&a[0], &half[1], &a[2]], &half[1], "option half");
    refused(d, &[], &[&a[0], &albedo, &a[2]], &albedo, "table kind");
    refused(
        d,
        &[],
        &[&a[0], &a[1], &four[2]],
        &four[2],
        "number of shards",
    );
    refused(
        d,
        &[],
        &[&a[0], &reference[1], &a[2]],
        &reference[1],
        "engine",
    );
    refused(d, &[], &[&slice_a, &slice_b], &slice_b, "option materials");
    // Missing and repeated parts.
    refused(
        d,
        &[],
        &[&a[0], &a[2]],
        &d.join("refused.exr"),
        "shards [2] of 3",
    );
    let copy = d.join("copy.npy");
    std::fs::copy(&a[1], &copy).unwrap();
    std::fs::copy(
        vkbrdf::stream::shard::sidecar_path(&a[1]),
        vkbrdf::stream::shard::sidecar_path(&copy),
    )
    .unwrap();
    refused(d, &[], &[&a[0], &a[1], &copy, &a[2]], &copy, "given twice");
    // A batch part among table parts.
    let mt = d.join("mt.toml");
    std::fs::write(
        &mt,
        "[[material]]\nname = \"l\"\nmodel = \"lambert\"\ndiffuse = 0.5\n",
    )
    .unwrap();
    let t = d.join("t.npy");
    assert!(common::generate(&mt, 20, &t).status.success());
    let batch = d.join("batch-2.npy");
    let r = common::eval(
        &mt,
        &t,
        &["-o", path(&batch), "--backend", "cpu", "--shard", "2/3"],
    );
    assert!(r.status.success(), "{}", stderr(&r));
    refused(d, &[], &[&a[0], &batch, &a[2]], &batch, "a part of a batch");
    refused(d, &[], &[&batch, &a[0]], &a[0], "a part of a table");
    // --terms belongs to batch parts.
    refused(
        d,
        &["--terms", "x.npy"],
        &[&a[0], &a[1], &a[2]],
        Path::new("x.npy"),
        "drop --terms",
    );
    // A part without its sidecar; a part whose data does not match its sidecar.
    let lone = d.join("lone.npy");
    std::fs::copy(&a[1], &lone).unwrap();
    refused(
        d,
        &[],
        &[&a[0], &lone, &a[2]],
        &vkbrdf::stream::shard::sidecar_path(&lone),
        "",
    );
    std::fs::write(&a[1], b"\x93NUMPY garbage").unwrap();
    refused(d, &[], &[&a[0], &a[1], &a[2]], &a[1], "not a valid .npy");
    let wrong_shape = dfg_parts(
        d,
        "w",
        &[
            "dfg",
            "--size",
            "5x3",
            "--samples",
            "16",
            "--backend",
            "cpu",
        ],
        3,
    );
    std::fs::copy(&wrong_shape[1], &a[1]).unwrap();
    refused(
        d,
        &[],
        &[&a[0], &a[1], &a[2]],
        &a[1],
        "but its sidecar says float32",
    );
    // A sidecar whose table size was edited.
    let car = vkbrdf::stream::shard::sidecar_path(&a[2]);
    let text = std::fs::read_to_string(&car).unwrap();
    std::fs::write(
        &car,
        text.replacen("\"total_rows\": 3", "\"total_rows\": 4", 1),
    )
    .unwrap();
    refused(
        d,
        &[],
        &[&a[2], &a[0]],
        &a[2],
        "its sidecar says rows [2, 3], but shard 3/3 of 4 rows",
    );

    // With --allow-mixed the engines may differ; the provenance names both.
    let out = d.join("mixed.exr");
    let r = vkbrdf(&[
        "merge",
        "-o",
        path(&out),
        "--allow-mixed",
        path(&a[0]),
        path(&reference[1]),
        path(&reference[2]),
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    let image = exr::prelude::read_all_flat_layers_from_file(&out).unwrap();
    let backend = image.layer_data[0]
        .attributes
        .other
        .iter()
        .find(|(k, _)| *k == "vkbrdf.backend")
        .map(|(_, v)| format!("{v:?}"))
        .unwrap();
    assert!(
        backend.contains("cpu (") && backend.contains("cpu-reference"),
        "{backend}"
    );
}

#[test]
fn table_shard_options_are_checked_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let exr = d.join("part.exr");
    let npy = d.join("part.npy");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        // A part is a .npy band, whatever its name says.
        (
            vec!["dfg", "--size", "4x3", "-o", path(&exr), "--shard", "1/2"],
            "name the part PART.npy",
        ),
        (
            vec![
                "slice",
                "--material",
                "gold",
                "-o",
                path(&exr),
                "--shard",
                "1/2",
            ],
            "name the part PART.npy",
        ),
        (
            vec![
                "albedo",
                "-o",
                path(&npy),
                "--average",
                path(&exr),
                "--shard",
                "1/2",
            ],
            "name the part PART.npy",
        ),
        // K/N out of range or malformed.
        (
            vec!["dfg", "-o", path(&npy), "--shard", "0/3"],
            "1 <= K <= N",
        ),
        (
            vec!["dfg", "-o", path(&npy), "--shard", "4/3"],
            "1 <= K <= N",
        ),
        (
            vec![
                "merl",
                "--material",
                "gold",
                "-o",
                path(&npy),
                "--shard",
                "3",
            ],
            "1 <= K <= N",
        ),
        (
            vec!["albedo", "-o", path(&npy), "--shard", "1/0"],
            "1 <= K <= N",
        ),
        // A PNG of a band is not the slice's PNG.
        (
            vec![
                "slice",
                "--material",
                "gold",
                "-o",
                path(&npy),
                "--png",
                "s.png",
                "--shard",
                "1/2",
            ],
            "--png",
        ),
    ];
    for (args, what) in cases {
        let mut a = vec!["table"];
        a.extend_from_slice(&args);
        let r = vkbrdf(&a);
        assert_eq!(r.status.code(), Some(2), "{a:?}: {}", stderr(&r));
        assert!(stderr(&r).contains(what), "{a:?}: {}", stderr(&r));
        assert!(!exr.exists() && !npy.exists(), "{a:?} wrote a part");
    }
}

/// A table too large for memory is refused before any work with the figure it would need
/// (issue 13 item 5); a shard of it checks the memory of its own band only, so the work
/// can be split until each band fits.
#[test]
fn a_shard_needs_memory_for_its_band_only() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole.exr");
    let part = dir.path().join("part.npy");
    let size = [
        "--size",
        "200000x200000",
        "--samples",
        "1",
        "--backend",
        "cpu",
    ];
    let mut a = vec!["table", "dfg", "-o", path(&whole)];
    a.extend_from_slice(&size);
    let r = vkbrdf(&a);
    assert_eq!(r.status.code(), Some(2), "{}", stderr(&r));
    assert!(
        stderr(&r).contains("the DFG table would need 10132.8 GiB"),
        "{}",
        stderr(&r)
    );
    let mut a = vec!["table", "dfg", "-o", path(&part), "--shard", "1/2"];
    a.extend_from_slice(&size);
    let r = vkbrdf(&a);
    assert_eq!(r.status.code(), Some(2), "{}", stderr(&r));
    assert!(
        stderr(&r).contains("the DFG table's band would need 5066.4 GiB"),
        "{}",
        stderr(&r)
    );
    // 5 rows of 200000 texels.
    let mut a = vec!["table", "dfg", "-o", path(&part), "--shard", "1/40000"];
    a.extend_from_slice(&size);
    let r = vkbrdf(&a);
    assert!(r.status.success(), "{}", stderr(&r));
    let car = vkbrdf::table::shard::TableSidecar::read(&part).unwrap();
    assert_eq!((car.rows, car.total_rows), ([0, 5], 200000));
    assert_eq!(
        std::fs::metadata(&part).unwrap().len(),
        128 + 5 * 200000 * 2 * 4
    );
    assert!(!whole.exists());
}
