//! Outputs never destroy data (docs/RELIABILITY.md): an output that is an input or named
//! twice is refused before any work; symlinks are written through; FIFOs, devices and `-`
//! are written directly, never replaced; a full disk, a failed write or a cancellation
//! leaves the previous file intact and no temporary file; `eval --terms` writes both files
//! or neither. The CLI runs on the CPU reference so the tests need no device; the full
//! disk also on the CPU engine, whose workers write their rows at offsets.

mod common;
use common::{generate, stderr, vkbrdf};

use std::fs;
use std::os::unix::fs::{symlink, FileTypeExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use vkbrdf::cancel::Cancel;

const MATERIALS: &str = r#"
[[material]]
name = "gold"
preset = "gold"
"#;

/// A directory with `m.toml` and a 1000-tuple batch `t.npy`.
fn setup() -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m.toml");
    fs::write(&m, MATERIALS).unwrap();
    let t = dir.path().join("t.npy");
    let o = generate(&m, 1000, &t);
    assert!(o.status.success(), "{}", stderr(&o));
    (dir, m, t)
}

/// `vkbrdf eval` on the CPU reference (no device needed).
fn eval(m: &Path, t: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["--backend", "reference"];
    args.extend_from_slice(extra);
    common::eval(m, t, &args)
}

/// Names of the temporary files vkbrdf leaves in `dir` (there must be none).
fn strays(dir: &Path) -> Vec<String> {
    fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".vkbrdf-"))
        .collect()
}

/// A 1000 × 3 float32 `.npy`: the BRDF output of the batch.
fn is_brdf_npy(bytes: &[u8]) -> bool {
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("copy.npy");
    fs::write(&copy, bytes).unwrap();
    let (data, shape) = vkbrdf::batch::read_npy_f32(&copy).unwrap();
    shape == [1000, 3] && data.iter().any(|&x| x > 0.0)
}

#[test]
fn an_output_that_is_the_input_is_refused_before_any_work() {
    let (dir, m, t) = setup();
    let before = fs::read(&t).unwrap();
    for out in [t.clone(), m.clone()] {
        let o = eval(&m, &t, &["-o", out.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("same file as the input"),
            "{}",
            stderr(&o)
        );
        assert!(
            !stderr(&o).contains("tuples on"),
            "evaluated before refusing"
        );
    }
    // Through a symlink, and through a hard link: the same inode.
    let link = dir.path().join("link.npy");
    symlink(&t, &link).unwrap();
    let hard = dir.path().join("hard.npy");
    fs::hard_link(&t, &hard).unwrap();
    for out in [&link, &hard] {
        let o = eval(&m, &t, &["-o", out.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    }
    assert_eq!(fs::read(&t).unwrap(), before);
    assert!(strays(dir.path()).is_empty());
}

#[test]
fn two_outputs_naming_one_file_are_refused() {
    let (dir, m, t) = setup();
    let a = dir.path().join("a.npy");
    let o = eval(
        &m,
        &t,
        &["-o", a.to_str().unwrap(), "--terms", a.to_str().unwrap()],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("same file as the output"),
        "{}",
        stderr(&o)
    );
    assert!(!a.exists());
    // `dir/./a.npy` and `a.npy` are one file too, before it exists.
    let dotted = dir.path().join(".").join("a.npy");
    let o = eval(
        &m,
        &t,
        &[
            "-o",
            a.to_str().unwrap(),
            "--terms",
            dotted.to_str().unwrap(),
        ],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    // Table outputs: --average = --output.
    let e = dir.path().join("e.exr");
    let o = vkbrdf(&[
        "table",
        "albedo",
        "--backend",
        "reference",
        "--size",
        "2",
        "--samples",
        "16",
        "-o",
        e.to_str().unwrap(),
        "--average",
        e.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(!e.exists());
}

#[test]
fn a_missing_or_unusable_directory_is_found_before_any_work() {
    let (dir, m, t) = setup();
    let missing = dir.path().join("nope").join("x.npy");
    let o = eval(&m, &t, &["-o", missing.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("does not exist"), "{}", stderr(&o));
    assert!(!stderr(&o).contains("tuples on"));
    // An output that is a directory.
    let o = eval(&m, &t, &["-o", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("is a directory"), "{}", stderr(&o));
    // A parent that is a file.
    let o = eval(&m, &t, &["-o", t.join("x.npy").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn a_symlink_is_written_through_and_stays_a_link() {
    let (dir, m, t) = setup();
    let target = dir.path().join("real.npy");
    fs::write(&target, b"old").unwrap();
    let link = dir.path().join("link.npy");
    symlink("real.npy", &link).unwrap();
    let o = eval(&m, &t, &["-o", link.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(is_brdf_npy(&fs::read(&target).unwrap()));
    // A dangling link: its target is created, the link kept.
    let dangling = dir.path().join("dangling.npy");
    symlink("new.npy", &dangling).unwrap();
    let o = eval(&m, &t, &["-o", dangling.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(fs::symlink_metadata(&dangling)
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(is_brdf_npy(&fs::read(dir.path().join("new.npy")).unwrap()));
    assert!(strays(dir.path()).is_empty());
}

#[test]
fn a_fifo_is_written_directly_not_replaced() {
    let (dir, m, t) = setup();
    let fifo = dir.path().join("fifo");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || fs::read(fifo).unwrap())
    };
    let o = eval(&m, &t, &["-o", fifo.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(is_brdf_npy(&reader.join().unwrap()));
    assert!(fs::metadata(&fifo).unwrap().file_type().is_fifo());
}

#[test]
fn standard_output_takes_the_npy() {
    let (_dir, m, t) = setup();
    let o = eval(&m, &t, &["-o", "-"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(is_brdf_npy(&o.stdout));
    // `-` twice is two outputs on one stream.
    let o = eval(&m, &t, &["-o", "-", "--terms", "-"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn a_full_device_is_an_error_and_stays_a_device() {
    let (_dir, m, t) = setup();
    let o = eval(&m, &t, &["-o", "/dev/full"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("No space left"), "{}", stderr(&o));
    assert!(fs::metadata("/dev/full")
        .unwrap()
        .file_type()
        .is_char_device());
}

/// A full disk: a 64 KiB tmpfs (mounted directly as root, else in a user and mount
/// namespace) holding yesterday's
/// outputs (BRDF 32 KiB, terms 4 KiB; 28 KiB free). The new BRDF (12 KiB) and terms
/// (24 KiB) each fit alone but not together: both previous files must survive unchanged
/// and no temporary file may remain. (Written one after the other, terms first, the terms
/// would be replaced and the BRDF not: one file of the pair lost.)
#[test]
fn a_full_disk_leaves_the_previous_files_and_no_temporary_file() {
    // The reference writes in order (the pipeline), the CPU engine's workers at offsets.
    for backend in ["reference", "cpu"] {
        full_disk_keeps_the_previous_files(backend);
    }
}

fn full_disk_keeps_the_previous_files(backend: &str) {
    let (dir, m, t) = setup();
    let bin = env!("CARGO_BIN_EXE_vkbrdf");
    let script = format!(
        r#"set -e
mnt={dir}/mnt; mkdir -p $mnt
mount -t tmpfs -o size=64k tmpfs $mnt
trap 'umount $mnt' EXIT
head -c 32768 /dev/zero | tr '\0' 'b' > $mnt/brdf.npy
head -c 4096 /dev/zero | tr '\0' 't' > $mnt/terms.npy
set +e
{bin} eval --backend {backend} -m {m} -i {t} -o $mnt/brdf.npy --terms $mnt/terms.npy
echo "exit=$?"
set -e
echo "brdf=$(tr -d 'b' < $mnt/brdf.npy | wc -c) $(wc -c < $mnt/brdf.npy)"
echo "terms=$(tr -d 't' < $mnt/terms.npy | wc -c) $(wc -c < $mnt/terms.npy)"
echo "strays=$(ls -A $mnt | grep -c '^\.vkbrdf-' || true)"
"#,
        dir = dir.path().display(),
        m = m.display(),
        t = t.display()
    );
    let root = fs::read_to_string("/proc/self/status")
        .unwrap()
        .lines()
        .any(|l| l.starts_with("Uid:") && l.split_whitespace().nth(1) == Some("0"));
    // As root (CI, a chroot) the tmpfs is mounted directly and unmounted by the script's
    // trap; `unshare -m` would need `/` to be a mount point, which it is not in a chroot.
    // Otherwise a user namespace (`unshare -r -m`) grants the mount.
    let o = if root {
        Command::new("sh").args(["-c", &script]).output().unwrap()
    } else {
        Command::new("unshare")
            .args(["-r", "-m", "sh", "-c", &script])
            .output()
            .unwrap()
    };
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "the tmpfs script failed (needs unshare and mount):\n{out}\n{}",
        stderr(&o)
    );
    assert!(out.contains("exit=2"), "{backend}: {out}\n{}", stderr(&o));
    assert!(
        stderr(&o).contains("No space left"),
        "{backend}: {}",
        stderr(&o)
    );
    // Every byte of both previous files is still the old one.
    assert!(out.contains("brdf=0 32768"), "{backend}: {out}");
    assert!(out.contains("terms=0 4096"), "{backend}: {out}");
    assert!(out.contains("strays=0"), "{backend}: {out}");
}

/// A cancellation in the middle of a write (the token set by the body after its first
/// megabyte, as a signal handler would) leaves the previous file and no temporary file.
#[test]
fn cancelling_mid_write_keeps_the_previous_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.bin");
    fs::write(&path, b"previous").unwrap();
    let cancel = Cancel::new();
    let result = vkbrdf::atomic::write_cancellable(&path, &cancel, |w| {
        use std::io::Write;
        let block = vec![7u8; 1 << 20];
        w.write_all(&block)?;
        cancel.cancel();
        for _ in 0..64 {
            w.write_all(&block)?;
        }
        Ok(())
    });
    assert!(
        matches!(result, Err(vkbrdf::Error::Cancelled)),
        "{result:?}"
    );
    assert_eq!(fs::read(&path).unwrap(), b"previous");
    assert!(strays(dir.path()).is_empty());
}

/// Two staged files where the second cannot be renamed into place (its target became a
/// non-empty directory after staging): the first rename is rolled back, so neither file
/// changes.
#[test]
fn a_set_of_files_appears_whole_or_not_at_all() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.bin");
    let b = dir.path().join("b.bin");
    fs::write(&a, b"old a").unwrap();
    let cancel = Cancel::new();
    let write = |p: &Path, bytes: &'static [u8]| {
        vkbrdf::atomic::stage(p, &cancel, |w| std::io::Write::write_all(w, bytes)).unwrap()
    };
    let staged = vec![write(&a, b"new a"), write(&b, b"new b")];
    fs::create_dir(&b).unwrap();
    fs::write(b.join("keep"), b"x").unwrap();
    assert!(vkbrdf::atomic::commit(staged).is_err());
    assert_eq!(fs::read(&a).unwrap(), b"old a");
    assert!(b.join("keep").exists());
    assert!(strays(dir.path()).is_empty(), "{:?}", strays(dir.path()));
}

/// SIGINT while the reference evaluates a large batch: exit 130, the previous output
/// intact, no temporary file. The signal is sent once the process has installed its
/// handler (read from /proc, no sleeping on a guess).
#[test]
fn sigint_during_a_run_keeps_the_previous_output() {
    let (dir, m, _) = setup();
    let big = dir.path().join("big.npy");
    let o = generate(&m, 2_000_000, &big);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = dir.path().join("out.npy");
    fs::write(&out, b"previous").unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
        .args(["eval", "--backend", "reference", "-m"])
        .arg(&m)
        .arg("-i")
        .arg(&big)
        .arg("-o")
        .arg(&out)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let status = format!("/proc/{}/status", child.id());
    // SigCgt is a hex mask; SIGINT (2) is bit 1.
    let handles_sigint = || {
        fs::read_to_string(&status).ok().is_some_and(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("SigCgt:"))
                .and_then(|m| u64::from_str_radix(m.trim(), 16).ok())
                .is_some_and(|mask| mask & 0b10 != 0)
        })
    };
    while !handles_sigint() {
        std::thread::yield_now();
    }
    // The shell's built-in kill: a minimal Debian has no kill binary (procps).
    let killed = Command::new("sh")
        .args(["-c", "kill -INT \"$1\"", "sh", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    assert!(stderr(&o).contains("cancelled"), "{}", stderr(&o));
    assert_eq!(fs::read(&out).unwrap(), b"previous");
    assert!(strays(dir.path()).is_empty());
}
