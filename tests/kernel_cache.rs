//! The compiled kernels kept across runs (`VKBRDF_CACHE_DIR`; src/gpu/disk_cache.rs and
//! src/gpu/pipeline_cache.rs): a run stores the SPIR-V and the driver's pipeline cache, a
//! later run computes the same bytes with them, a damaged entry is ignored and rewritten,
//! `off` writes nothing, a directory that cannot be created is not an error, and runs at
//! the same time leave only whole entries.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const MATERIALS: &str = r#"
[[material]]
name = "gold"
preset = "gold"

[[material]]
name = "matte"
model = "lambert"
diffuse = [0.8, 0.5, 0.2]
"#;

/// A materials file and 1,000 tuples for it in `dir`.
fn batch(dir: &Path) -> (PathBuf, PathBuf) {
    let m = dir.join("m.toml");
    std::fs::write(&m, MATERIALS).unwrap();
    let t = dir.join("t.npy");
    let g = common::generate(&m, 1000, &t);
    assert!(g.status.success(), "{}", common::stderr(&g));
    (m, t)
}

/// `vkbrdf eval` on Vulkan with `VKBRDF_CACHE_DIR=cache`, writing `out`.
fn eval(cache: &str, m: &Path, t: &Path, out: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
        .env("VKBRDF_CACHE_DIR", cache)
        .args(["eval", "--backend", "vulkan", "-m", common::path(m), "-i"])
        .args([common::path(t), "-o", common::path(out)])
        .output()
        .expect("run vkbrdf")
}

/// The entries under `dir/kind`, as (name, bytes).
fn entries(dir: &Path, kind: &str) -> Vec<(String, Vec<u8>)> {
    let Ok(read) = std::fs::read_dir(dir.join(kind)) else {
        return Vec::new();
    };
    let mut v: Vec<(String, Vec<u8>)> = read
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

/// Whether `bytes` is a whole entry: the magic, and a length that matches the file.
fn whole(bytes: &[u8]) -> bool {
    bytes.len() >= 24
        && &bytes[..8] == b"VKBRDFC1"
        && u64::from_le_bytes(bytes[8..16].try_into().unwrap()) as usize == bytes.len() - 24
}

/// Another run with the cache `c` writes the bytes of `first`, leaving the SPIR-V entries
/// `spirv`.
fn same_again(c: &str, m: &Path, t: &Path, first: &Path, spirv: &[(String, Vec<u8>)], why: &str) {
    let again = first.with_file_name("again.npy");
    let o = eval(c, m, t, &again);
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert_eq!(
        std::fs::read(first).unwrap(),
        std::fs::read(&again).unwrap()
    );
    assert_eq!(entries(Path::new(c), "spirv"), spirv, "{why}");
}

#[test]
fn a_second_run_computes_the_same_from_the_cache_and_a_damaged_entry_is_rewritten() {
    if common::vulkan().is_none() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let (m, t) = batch(tmp.path());
    let cache = tmp.path().join("cache");
    let c = common::path(&cache);
    let first = tmp.path().join("first.npy");
    let o = eval(c, &m, &t, &first);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let spirv = entries(&cache, "spirv");
    let pipelines = entries(&cache, "pipelines");
    assert!(!spirv.is_empty(), "no SPIR-V stored");
    assert_eq!(pipelines.len(), 1, "one pipeline cache for the one device");
    assert!(spirv
        .iter()
        .chain(&pipelines)
        .all(|(n, b)| n.ends_with(".bin") && whole(b)));

    // Read, not compiled again: a kernel compiled is always stored, by renaming a new file
    // into place, so an unchanged inode means the entry served the run.
    let inodes = || {
        let mut v: Vec<u64> = std::fs::read_dir(cache.join("spirv"))
            .unwrap()
            .map(|e| std::os::unix::fs::MetadataExt::ino(&e.unwrap().metadata().unwrap()))
            .collect();
        v.sort();
        v
    };
    let before = inodes();
    same_again(c, &m, &t, &first, &spirv, "the SPIR-V was stored once");
    assert_eq!(
        inodes(),
        before,
        "the second run compiled its kernels again"
    );

    // Damaged entries: one cut short, one not an entry at all.
    let (name, bytes) = &spirv[0];
    std::fs::write(cache.join("spirv").join(name), &bytes[..bytes.len() / 2]).unwrap();
    std::fs::write(
        cache.join("pipelines").join(&pipelines[0].0),
        b"not a cache",
    )
    .unwrap();
    same_again(
        c,
        &m,
        &t,
        &first,
        &spirv,
        "the damaged SPIR-V was rewritten",
    );
    assert!(entries(&cache, "pipelines").iter().all(|(_, b)| whole(b)));
}

#[test]
fn off_writes_nothing_and_a_directory_that_cannot_be_made_is_no_error() {
    if common::vulkan().is_none() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let (m, t) = batch(tmp.path());
    let reference = tmp.path().join("reference.npy");
    let o = eval("off", &m, &t, &reference);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let listing = |d: &Path| {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    assert_eq!(listing(tmp.path()), ["m.toml", "reference.npy", "t.npy"]);
    // Below a regular file no directory can be made, as with a read-only home.
    let blocked = tmp.path().join("m.toml").join("cache");
    let out = tmp.path().join("out.npy");
    let o = eval(common::path(&blocked), &m, &t, &out);
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert!(
        !common::stderr(&o).contains("cache"),
        "{}",
        common::stderr(&o)
    );
    assert_eq!(
        std::fs::read(&reference).unwrap(),
        std::fs::read(&out).unwrap()
    );
}

#[test]
fn runs_at_the_same_time_leave_whole_entries() {
    if common::vulkan().is_none() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let (m, t) = batch(tmp.path());
    let cache = tmp.path().join("cache");
    let children: Vec<_> = (0..4)
        .map(|i| {
            Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
                .env("VKBRDF_CACHE_DIR", &cache)
                .args(["eval", "--backend", "vulkan", "-m", common::path(&m), "-i"])
                .arg(&t)
                .arg("-o")
                .arg(tmp.path().join(format!("out{i}.npy")))
                .spawn()
                .unwrap()
        })
        .collect();
    for mut child in children {
        assert!(child.wait().unwrap().success());
    }
    let first = std::fs::read(tmp.path().join("out0.npy")).unwrap();
    for i in 1..4 {
        assert_eq!(
            std::fs::read(tmp.path().join(format!("out{i}.npy"))).unwrap(),
            first
        );
    }
    for kind in ["spirv", "pipelines"] {
        let e = entries(&cache, kind);
        assert!(!e.is_empty(), "{kind}: nothing stored");
        for (name, bytes) in e {
            assert!(name.ends_with(".bin") && whole(&bytes), "{kind}/{name}");
        }
    }
}
