//! `vkbrdf merge` never destroys an input and never joins what does not belong together
//! (issue 30, items 2–4): the terms parts a sidecar names are inputs too; each part and
//! terms part is identified by content (shards sharing one `--terms` file are refused);
//! sidecar numbers are validated, and counts the data can show are recomputed.

mod common;

use common::{eval, generate, path, stderr, vkbrdf};
use std::path::{Path, PathBuf};

const MATERIALS: &str = "[[material]]\nname = \"g\"\npreset = \"gold\"\n";

/// A materials file, 1,000 tuples and the two shards of them, shard K's terms part at
/// `terms_of(K)`.
fn sharded_with(dir: &Path, terms_of: impl Fn(u32) -> PathBuf) -> (PathBuf, PathBuf) {
    let m = dir.join("m.toml");
    std::fs::write(&m, MATERIALS).unwrap();
    let t = dir.join("t.npy");
    assert!(generate(&m, 1000, &t).status.success());
    for k in 1..=2 {
        let part = dir.join(format!("part-{k}.npy"));
        let terms = terms_of(k);
        let shard = format!("{k}/2");
        let args = [
            "--backend",
            "cpu",
            "-o",
            path(&part),
            "--terms",
            path(&terms),
        ];
        let o = eval(&m, &t, &[&args[..], &["--shard", &shard]].concat());
        assert!(o.status.success(), "{}", stderr(&o));
    }
    (m, t)
}

/// [`sharded_with`] each shard's own terms part, `terms-K.npy`.
fn sharded(dir: &Path) -> (PathBuf, PathBuf) {
    sharded_with(dir, |k| dir.join(format!("terms-{k}.npy")))
}

fn parts(dir: &Path) -> Vec<String> {
    (1..=2)
        .map(|k| path(&dir.join(format!("part-{k}.npy"))).to_string())
        .collect()
}

fn merge(args: &[&str], dir: &Path) -> std::process::Output {
    let mut a = vec!["merge"];
    a.extend_from_slice(args);
    let p = parts(dir);
    a.extend(p.iter().map(String::as_str));
    vkbrdf(&a)
}

#[test]
fn a_terms_part_named_by_a_sidecar_is_an_input_and_is_never_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    sharded(dir.path());
    let terms2 = dir.path().join("terms-2.npy");
    let before = std::fs::read(&terms2).unwrap();
    let out = dir.path().join("o.npy");
    for args in [
        vec!["-o", path(&out), "--terms", path(&terms2)],
        vec!["-o", path(&terms2)],
    ] {
        let o = merge(&args, dir.path());
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains("terms-2.npy"), "{}", stderr(&o));
        assert!(stderr(&o).contains("input"), "{}", stderr(&o));
        assert_eq!(std::fs::read(&terms2).unwrap(), before, "{args:?}");
    }
    // The right call still works.
    let terms = dir.path().join("terms.npy");
    let o = merge(&["-o", path(&out), "--terms", path(&terms)], dir.path());
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn shards_that_shared_one_terms_file_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    sharded_with(d, |_| d.join("terms.npy"));
    let out = d.join("o.npy");
    let all = d.join("all-terms.npy");
    let o = merge(&["-o", path(&out), "--terms", path(&all)], d);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("own --terms"), "{}", stderr(&o));
    assert!(!out.exists() && !all.exists());
}

/// Rewrites part `k`'s sidecar through `edit` (on its JSON value).
fn edit_sidecar(dir: &Path, k: u32, edit: impl Fn(&mut serde_json::Value)) {
    let p = dir.join(format!("part-{k}.npy.shard.json"));
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
    edit(&mut v);
    std::fs::write(&p, serde_json::to_string_pretty(&v).unwrap()).unwrap();
}

#[test]
fn sidecar_numbers_are_validated_and_altered_data_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    sharded(d);
    let out = d.join("o.npy");
    let keep = std::fs::read(d.join("part-1.npy.shard.json")).unwrap();
    for (field, value, says) in [
        ("invalid", serde_json::json!(99_999_999u64), "exceed"),
        ("rows", serde_json::json!([0, 900]), "rows"),
        ("first_invalid", serde_json::json!(7), "first_invalid"),
        ("saturated", serde_json::json!(3), "saturated"),
    ] {
        edit_sidecar(d, 1, |v| v[field] = value.clone());
        // With the terms joined, the data bounds the saturated count from both sides.
        let terms = d.join("terms.npy");
        let o = merge(&["-o", path(&out), "--terms", path(&terms)], d);
        assert_eq!(o.status.code(), Some(2), "{field}: {}", stderr(&o));
        assert!(stderr(&o).contains(says), "{field}: {}", stderr(&o));
        assert!(!stderr(&o).contains("18446744073"), "{}", stderr(&o));
        assert!(!out.exists());
        std::fs::write(d.join("part-1.npy.shard.json"), &keep).unwrap();
    }
    // A part whose data was altered (an inf written over a value) is refused by content.
    let p2 = d.join("part-2.npy");
    let mut bytes = std::fs::read(&p2).unwrap();
    let at = bytes.len() - 4;
    bytes[at..].copy_from_slice(&f32::INFINITY.to_le_bytes());
    std::fs::write(&p2, &bytes).unwrap();
    let o = merge(&["-o", path(&out)], d);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("part-2.npy"), "{}", stderr(&o));
    assert!(!out.exists());
}

#[test]
fn materials_files_refuse_far_duplicates_control_characters_and_a_model_that_drops_its_preset() {
    use vkbrdf::material::parse_materials;
    // A duplicate 40,000 materials apart is still found (by a hash set, in linear time).
    let mut text = String::new();
    for i in 0..40_000 {
        text.push_str(&format!(
            "[[material]]\nname = \"m{i}\"\nmodel = \"lambert\"\ndiffuse = 0.5\n"
        ));
    }
    assert_eq!(parse_materials(&text, "big").unwrap().len(), 40_000);
    text.push_str("[[material]]\nname = \"m0\"\nmodel = \"lambert\"\ndiffuse = 0.5\n");
    let e = parse_materials(&text, "big").unwrap_err().to_string();
    assert!(e.contains("duplicate") && e.contains("m0"), "{e}");
    for name in ["a\\nb", "a\\u0000b", "tab\\there"] {
        let t = format!("[[material]]\nname = \"{name}\"\nmodel = \"lambert\"\ndiffuse = 0.5\n");
        let e = parse_materials(&t, "names").unwrap_err().to_string();
        assert!(e.contains("control character"), "{name}: {e}");
    }
    let e = parse_materials(
        "[[material]]\nname = \"x\"\npreset = \"gold\"\nmodel = \"lambert\"\n",
        "preset",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("preset `gold`") && e.contains("model"), "{e}");
    // The preset's own model, restated, is fine.
    assert!(parse_materials(
        "[[material]]\nname = \"x\"\npreset = \"gold\"\nmodel = \"cook-torrance\"\n",
        "preset"
    )
    .is_ok());
    assert_eq!(vkbrdf::material::MAX_MATERIALS, 1 << 24);
}

#[test]
fn a_second_writer_of_an_output_set_is_refused_and_sets_never_mix() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (ma, mb) = (d.join("a.toml"), d.join("b.toml"));
    std::fs::write(&ma, "[[material]]\nname = \"g\"\npreset = \"gold\"\n").unwrap();
    std::fs::write(&mb, "[[material]]\nname = \"s\"\npreset = \"silver\"\n").unwrap();
    let t = d.join("t.npy");
    assert!(generate(&ma, 200_000, &t).status.success());
    let (x, xt) = (d.join("X.npy"), d.join("Xt.npy"));
    // A lock held by "another process" (this test) refuses the writer, naming the file.
    let lock_path = d.join(".X.npy.vkbrdf-lock");
    let held = std::fs::File::create(&lock_path).unwrap();
    held.try_lock().unwrap();
    let o = eval(
        &ma,
        &t,
        &["--backend", "cpu", "-o", path(&x), "--terms", path(&xt)],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("another vkbrdf process") && stderr(&o).contains("X.npy"));
    assert!(!x.exists() && !xt.exists());
    held.unlock().unwrap();
    drop(held);
    std::fs::remove_file(&lock_path).unwrap();
    // The expected sets of each run alone.
    let expect = |m: &Path, tag: &str| {
        let (b, tt) = (d.join(format!("{tag}.npy")), d.join(format!("{tag}t.npy")));
        let o = eval(
            m,
            &t,
            &["--backend", "cpu", "-o", path(&b), "--terms", path(&tt)],
        );
        assert!(o.status.success(), "{}", stderr(&o));
        (std::fs::read(b).unwrap(), std::fs::read(tt).unwrap())
    };
    let (a, b) = (expect(&ma, "A"), expect(&mb, "B"));
    for round in 0..6 {
        let spawn = |m: &Path| {
            std::process::Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
                .args(["eval", "--backend", "cpu", "-m", path(m), "-i", path(&t)])
                .args(["-o", path(&x), "--terms", path(&xt)])
                .output()
        };
        let (ra, rb) = std::thread::scope(|s| {
            let ha = s.spawn(|| spawn(&ma).unwrap());
            let hb = s.spawn(|| spawn(&mb).unwrap());
            (ha.join().unwrap(), hb.join().unwrap())
        });
        for r in [&ra, &rb] {
            assert!(matches!(r.status.code(), Some(0 | 2)), "{}", stderr(r));
        }
        let got = (std::fs::read(&x).unwrap(), std::fs::read(&xt).unwrap());
        assert!(
            got == a || got == b,
            "round {round}: the outputs mix two runs"
        );
    }
    // No lock file is left behind.
    assert!(!lock_path.exists());
}

#[test]
fn parts_from_different_instruction_sets_are_refused_or_named_with_allow_mixed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let m = d.join("m.toml");
    std::fs::write(&m, MATERIALS).unwrap();
    let t = d.join("t.npy");
    assert!(generate(&m, 1000, &t).status.success());
    for (k, isa) in [(1, "scalar"), (2, vkbrdf::cpu::Isa::best().name())] {
        let part = d.join(format!("part-{k}.npy"));
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
            .args(["eval", "--backend", "cpu", "-m", path(&m), "-i", path(&t)])
            .args(["-o", path(&part), "--shard", &format!("{k}/2")])
            .env("VKBRDF_CPU_ISA", isa)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
    }
    if vkbrdf::cpu::Isa::best() == vkbrdf::cpu::Isa::Scalar {
        return; // one variant only on this machine
    }
    let out = d.join("o.npy");
    let o = merge(&["-o", path(&out)], d);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--allow-mixed"), "{}", stderr(&o));
    let o = merge(&["-o", path(&out), "--allow-mixed"], d);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("scalar") && stderr(&o).contains("different engines"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn table_parts_from_different_instruction_sets_are_named_with_allow_mixed() {
    if vkbrdf::cpu::Isa::best() == vkbrdf::cpu::Isa::Scalar {
        return; // one variant only on this machine
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut parts = Vec::new();
    for (k, isa) in [(1, "scalar"), (2, vkbrdf::cpu::Isa::best().name())] {
        let part = d.join(format!("dfg-{k}.npy"));
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
            .args(["table", "dfg", "--size", "4", "--backend", "cpu"])
            .args(["-o", path(&part), "--shard", &format!("{k}/2")])
            .env("VKBRDF_CPU_ISA", isa)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        parts.push(path(&part).to_string());
    }
    let out = d.join("dfg.exr");
    let mut args = vec!["merge", "-o", path(&out)];
    args.extend(parts.iter().map(String::as_str));
    let o = vkbrdf(&args);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    args.push("--allow-mixed");
    let o = vkbrdf(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("different engines"), "{}", stderr(&o));
}
