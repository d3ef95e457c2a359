//! The first SIGINT or SIGTERM stops every long phase within about a second, exit 130,
//! nothing written (issue 30, item 6), and a later run removes a dead process's temporary
//! files (item 9).

mod common;

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn start(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start vkbrdf")
}

fn signal(child: &Child, sig: &str) {
    let ok = Command::new("kill")
        .args([&format!("-{sig}"), &child.id().to_string()])
        .status()
        .expect("kill")
        .success();
    assert!(ok);
}

/// Waits for `child` up to `limit`; its exit code and how long it took after the call.
fn wait(mut child: Child, limit: Duration) -> (Option<i32>, Duration) {
    let t = Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("wait") {
            return (status.code(), t.elapsed());
        }
        if t.elapsed() > limit {
            let _ = child.kill();
            panic!("still running {limit:?} after the signal");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn check_and_bench_stop_within_a_second_of_the_first_signal() {
    for (args, sig) in [
        (
            vec!["check", "--backend", "cpu", "--tuples", "20000"],
            "TERM",
        ),
        (vec!["check", "--backend", "reference"], "INT"),
        (vec!["bench", "--quick", "--no-peers"], "TERM"),
    ] {
        let child = start(&args);
        std::thread::sleep(Duration::from_millis(1500));
        signal(&child, sig);
        let (code, took) = wait(child, Duration::from_secs(5));
        assert_eq!(code, Some(130), "{args:?}");
        assert!(took < Duration::from_millis(2000), "{args:?}: {took:?}");
    }
}

#[test]
fn waiting_on_a_fifo_without_a_writer_stops_on_the_first_signal() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("m.toml");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let child = start(&["materials", "--file", common::path(&fifo)]);
    std::thread::sleep(Duration::from_millis(500));
    signal(&child, "INT");
    let (code, took) = wait(child, Duration::from_secs(5));
    assert_eq!(code, Some(130));
    assert!(took < Duration::from_millis(2000), "{took:?}");
}

#[test]
fn a_dead_processs_temporary_files_are_removed_by_the_next_run_and_a_live_ones_kept() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A pid that is not running (above the kernel's pid_max, or simply absent).
    let dead = (4_194_000u32..4_194_304)
        .find(|p| !std::path::Path::new(&format!("/proc/{p}")).exists())
        .expect("a free pid");
    let stale = d.join(format!(".vkbrdf-{dead}-AbC123.partial"));
    let live = d.join(format!(".vkbrdf-{}-XyZ789.partial", std::process::id()));
    let other = d.join("notes.partial");
    for f in [&stale, &live, &other] {
        std::fs::write(f, b"left over").unwrap();
    }
    let m = d.join("m.toml");
    std::fs::write(&m, "[[material]]\nname = \"g\"\npreset = \"gold\"\n").unwrap();
    let t = d.join("t.npy");
    assert!(common::generate(&m, 100, &t).status.success());
    assert!(!stale.exists(), "a dead process's temp file was kept");
    assert!(live.exists() && other.exists());
}
