//! Issue 30 item 10: quiet wrong answers and misleading messages, each refused or fixed.

mod common;

use common::{path, stderr, vkbrdf};
use std::path::{Path, PathBuf};

/// A one-material (gold) materials file and `n` tuples of it in `dir`.
fn gold_tuples(dir: &Path, n: usize) -> (PathBuf, PathBuf) {
    let m = dir.join("m.toml");
    std::fs::write(&m, "[[material]]\nname = \"g\"\npreset = \"gold\"\n").unwrap();
    let t = dir.join("t.npy");
    assert!(common::generate(&m, n, &t).status.success());
    (m, t)
}

#[test]
fn a_table_named_as_another_format_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    for (args, name) in [
        (
            vec!["table", "slice", "--material", "gold", "--size", "8"],
            "x.png",
        ),
        (vec!["table", "dfg", "--size", "4"], "d.npy"),
        (vec!["table", "albedo", "--size", "4"], "a.PNG"),
    ] {
        let out = dir.path().join(name);
        let mut a = args.clone();
        a.extend(["-o", path(&out)]);
        let o = vkbrdf(&a);
        assert_eq!(o.status.code(), Some(2), "{a:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("OpenEXR") && stderr(&o).contains(name),
            "{}",
            stderr(&o)
        );
        assert!(!out.exists());
    }
}

#[test]
fn bytes_after_an_npy_arrays_data_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (m, t) = gold_tuples(dir.path(), 10);
    let mut bytes = std::fs::read(&t).unwrap();
    bytes.extend([0u8; 400]);
    std::fs::write(&t, &bytes).unwrap();
    let out = dir.path().join("o.npy");
    let o = common::eval(&m, &t, &["--backend", "cpu", "-o", path(&out)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("400 bytes follow the data"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
}

#[test]
fn sizes_in_tib_are_understood_and_a_garbage_validation_setting_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let (m, t) = gold_tuples(dir.path(), 10);
    let out = dir.path().join("o.npy");
    let o = common::eval(
        &m,
        &t,
        &["--backend", "cpu", "--max-memory", "1TiB", "-o", path(&out)],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
        .args(["materials"])
        .env("VKBRDF_VALIDATION", "garbage")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("VKBRDF_VALIDATION"), "{}", stderr(&o));
}

#[test]
fn an_output_directory_that_is_a_file_is_named_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("plain");
    std::fs::write(&file, b"x").unwrap();
    for args in [
        vec!["demo", "--out-dir", path(&file)],
        vec!["bench", "--quick", "--no-peers", "--plot", path(&file)],
    ] {
        let t = std::time::Instant::now();
        let o = vkbrdf(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(stderr(&o).contains(path(&file)), "{}", stderr(&o));
        assert!(stderr(&o).contains("not a directory"), "{}", stderr(&o));
        // Refused before the work, not after it (the bench took 14 s to say so).
        assert!(t.elapsed() < std::time::Duration::from_secs(5));
    }
}

#[test]
fn at_help_points_to_a_command_that_exists_and_names_its_own_default() {
    let o = vkbrdf(&["at", "--help"]);
    let help = String::from_utf8_lossy(&o.stdout);
    assert!(!help.contains("materials --presets"), "{help}");
    assert!(help.contains("`vkbrdf materials` lists them"), "{help}");
    assert!(
        help.contains("runs the f64 reference unless --backend"),
        "{help}"
    );
}

#[test]
fn dev_stdout_is_written_directly_and_a_non_seekable_input_is_refused_by_name() {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let (m, t) = gold_tuples(dir.path(), 50);
    // -o /dev/stdout into a pipe: the .npy arrives on the pipe.
    let o = Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
        .args(["eval", "--backend", "cpu", "-m", path(&m), "-i", path(&t)])
        .args(["-o", "/dev/stdout"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(o.stdout.starts_with(b"\x93NUMPY"));
    assert_eq!(o.stdout.len(), 128 + 50 * 12);
    // stress --report /dev/stdout too.
    let o = vkbrdf(&[
        "stress",
        "--tuples",
        "1000",
        "--backend",
        "cpu",
        "--report",
        "/dev/stdout",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("stress tuples"));
    // Standard input, /dev/stdin and a FIFO as the input: refused with the reason.
    for input in ["-", "/dev/stdin"] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
            .args(["eval", "--backend", "cpu", "-m", path(&m), "-i", input])
            .args(["-o", path(&dir.path().join("o.npy"))])
            .stdin(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let _ = child
            .stdin
            .take()
            .unwrap()
            .write_all(&std::fs::read(&t).unwrap());
        let o = child.wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{input}");
        assert!(
            stderr(&o).contains("save them to a file first"),
            "{}",
            stderr(&o)
        );
    }
}

#[test]
fn long_commands_print_progress_lines_when_stderr_is_not_a_terminal() {
    // The interval is 10 s by default; VKBRDF_PROGRESS_INTERVAL shortens it here.
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
        .args([
            "check",
            "--backend",
            "cpu",
            "--tuples",
            "3000",
            "--filter",
            "ggx",
        ])
        .env("VKBRDF_PROGRESS_INTERVAL", "0.1")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("[vkbrdf check]"), "{e}");
    assert!(e.contains("combinations done"), "{e}");
}
