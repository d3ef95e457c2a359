//! Every numeric option of every subcommand, driven with 0, 1, just past its stated
//! maximum, a negative value and garbage: the exit status is 0, 1 or 2 — never 101 (a
//! panic) — a refusal names the option and its range, and a negative value reaches the
//! range check instead of being read as an unknown flag.

mod common;
use common::vkbrdf;

use std::path::Path;
use std::process::Command;

/// One numeric option: the command line around it, the option, and the value just past
/// its maximum.
struct Case {
    command: Vec<String>,
    option: &'static str,
    past_max: &'static str,
}

fn cases(dir: &Path) -> Vec<Case> {
    let p = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let m = p("m.toml");
    let t = p("t.npy");
    let s = |v: &[&str]| v.iter().map(|x| (*x).to_string()).collect::<Vec<_>>();
    let with = |base: Vec<String>, extra: &[&str]| {
        let mut b = base;
        b.extend(extra.iter().map(|x| (*x).to_string()));
        b
    };
    let eval = s(&["eval", "-m", &m, "-i", &t, "-o", &p("o.npy")]);
    let generate = s(&["generate", "-m", &m, "-o", &p("g.npy")]);
    let demo = s(&["demo", "--out-dir", &p("demo")]);
    let stress = s(&["stress", "--backend", "reference"]);
    let bench = s(&["bench", "--quick", "--no-peers", "--scenario", "lambert"]);
    let check = s(&["check", "--filter", "lambert"]);
    let slice = s(&[
        "table",
        "slice",
        "--material",
        "gold",
        "--backend",
        "reference",
    ]);
    let albedo = s(&["table", "albedo", "--backend", "reference", "--size", "2"]);
    let dfg = s(&["table", "dfg", "--backend", "reference", "--size", "2"]);
    let preview = s(&[
        "table",
        "preview",
        "--material",
        "gold",
        "--backend",
        "reference",
    ]);
    let case = |command: Vec<String>, option, past_max| Case {
        command,
        option,
        past_max,
    };
    vec![
        case(eval.clone(), "--max-gpu-memory", "1025G"),
        case(eval.clone(), "--max-memory", "2048GiB"),
        case(
            with(generate.clone(), &["-n", "10"]),
            "--seed",
            "18446744073709551616",
        ),
        case(generate, "--tuples", "100000001"),
        case(
            with(demo.clone(), &["--check", "10"]),
            "--tuples",
            "100000001",
        ),
        case(with(demo, &["--tuples", "100"]), "--check", "10000001"),
        case(
            with(stress.clone(), &["--seed", "1"]),
            "--tuples",
            "10000000001",
        ),
        case(
            with(stress.clone(), &["--tuples", "10"]),
            "--seed",
            "18446744073709551616",
        ),
        case(
            with(stress.clone(), &["--tuples", "10"]),
            "--target",
            "1.0000001",
        ),
        case(with(stress, &["--tuples", "10"]), "--chunk", "67108865"),
        case(bench, "--repeats", "1001"),
        case(
            with(check.clone(), &["--seed", "1"]),
            "--tuples",
            "10000001",
        ),
        case(
            with(check, &["--tuples", "10"]),
            "--seed",
            "18446744073709551616",
        ),
        case(with(slice, &["-o", &p("s.exr")]), "--size", "1073741824"),
        case(
            with(albedo.clone(), &["-o", &p("a.exr"), "--samples", "16"]),
            "--size",
            "1073741824",
        ),
        case(with(albedo, &["-o", &p("a.exr")]), "--samples", "67108865"),
        case(
            with(dfg.clone(), &["-o", &p("d.exr")]),
            "--samples",
            "67108865",
        ),
        case(
            with(dfg, &["-o", &p("d.exr"), "--samples", "16"]),
            "--size",
            "1073741824",
        ),
        case(
            with(preview.clone(), &["--sphere", &p("s.png")]),
            "--size",
            "16385",
        ),
        case(
            with(preview.clone(), &["--polar", &p("p.png")]),
            "--incidence",
            "90",
        ),
        case(
            with(preview, &["--sphere", &p("s.png")]),
            "--exposure",
            "1000001",
        ),
    ]
}

#[test]
fn every_numeric_option_is_range_checked_and_nothing_panics() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("m.toml"),
        "[[material]]\nname = \"gold\"\npreset = \"gold\"\n",
    )
    .unwrap();
    let o = vkbrdf(&[
        "generate",
        "-m",
        dir.path().join("m.toml").to_str().unwrap(),
        "-n",
        "100",
        "-o",
        dir.path().join("t.npy").to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let mut refused = 0;
    for case in cases(dir.path()) {
        for value in ["0", "1", case.past_max, "-1", "-10", "12abc", ""] {
            let mut args: Vec<&str> = case.command.iter().map(String::as_str).collect();
            args.push(case.option);
            args.push(value);
            let o = vkbrdf(&args);
            let code = o.status.code();
            let err = String::from_utf8_lossy(&o.stderr);
            let line = args.join(" ");
            assert!(
                matches!(code, Some(0..=2)),
                "`vkbrdf {line}` exited {code:?}:\n{err}"
            );
            assert!(
                !err.contains("panicked"),
                "`vkbrdf {line}` panicked:\n{err}"
            );
            if code != Some(0) {
                assert!(!err.trim().is_empty(), "`vkbrdf {line}` failed silently");
            }
            if value.starts_with('-') {
                assert!(
                    !err.contains("unexpected argument"),
                    "`vkbrdf {line}`: the negative value did not reach the range check:\n{err}"
                );
            }
            if value == case.past_max || value == "-1" || value == "12abc" {
                assert_eq!(code, Some(2), "`vkbrdf {line}` accepted {value}:\n{err}");
                assert!(
                    err.contains(case.option),
                    "`vkbrdf {line}`: the message does not name the option:\n{err}"
                );
                refused += 1;
            }
        }
    }
    assert!(refused >= 60, "only {refused} refusals checked");
}

/// The panic the issue found: `bench --quick --repeats 0` indexed an empty list.
#[test]
fn bench_with_zero_repeats_is_refused_not_a_panic() {
    let o = vkbrdf(&[
        "bench",
        "--quick",
        "--repeats",
        "0",
        "--no-peers",
        "--scenario",
        "lambert",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("1..=1000"));
}

/// A check of nothing does not pass.
#[test]
fn checks_of_nothing_are_refused() {
    for args in [
        &["check", "--tuples", "0"][..],
        &["demo", "--check", "0"][..],
        &["check", "--filter", "no-such-combination"][..],
    ] {
        let o = vkbrdf(args);
        assert_eq!(o.status.code(), Some(2), "{args:?} passed");
    }
}

/// `VKBRDF_DEVICE` naming no device is an error that lists the devices, not a silent
/// switch to the CPU (nor, in `devices`, a silent success).
#[test]
fn a_device_selector_matching_nothing_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m.toml");
    std::fs::write(&m, "[[material]]\nname = \"g\"\npreset = \"gold\"\n").unwrap();
    let t = dir.path().join("t.npy");
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
            .args(args)
            .env("VKBRDF_DEVICE", "no-such-device-anywhere")
            .output()
            .unwrap()
    };
    let g = run(&[
        "generate",
        "-m",
        m.to_str().unwrap(),
        "-n",
        "10",
        "-o",
        t.to_str().unwrap(),
    ]);
    assert!(g.status.success());
    let o = run(&[
        "eval",
        "-m",
        m.to_str().unwrap(),
        "-i",
        t.to_str().unwrap(),
        "-o",
        dir.path().join("o.npy").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!dir.path().join("o.npy").exists());
    let o = run(&["devices"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no-such-device-anywhere"));
}

/// `stress` without `--backend` stresses every backend the machine has (its help says
/// Vulkan and the reference): with Vulkan required (CI), both appear in the report.
#[test]
fn stress_defaults_to_every_available_backend() {
    let o = vkbrdf(&["stress", "--tuples", "100"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("cpu-reference"), "{out}");
    if std::env::var("VKBRDF_REQUIRE_VULKAN").as_deref() == Ok("1") {
        assert!(out.contains("vulkan"), "{out}");
    }
}

/// Help texts that disagreed with behaviour.
#[test]
fn help_texts_match_behaviour() {
    let help = |args: &[&str]| {
        let o = vkbrdf(args);
        String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr)
    };
    // `table preview` with no picture asks for either, not for --sphere alone.
    let o = help(&["table", "preview", "--material", "gold"]);
    assert!(o.contains("--sphere") && o.contains("--polar"), "{o}");
    assert!(help(&["materials", "--help"]).contains("precision"));
    assert!(help(&["table", "albedo", "--help"]).contains("1/1024"));
    // The presets listed with the TOML spellings a materials file uses.
    let list = help(&["materials"]);
    assert!(list.contains("smith-correlated"), "{list}");
    assert!(!list.contains("SmithCorrelated"), "{list}");
    // Commands without --backend do not suggest it as if they had it (check has it now).
    let h = help(&["devices", "--help"]);
    assert!(!h.contains("--backend cpu"), "devices --help: {h}");
}

/// A closed standard output ends the process quietly (as `| head` does to other tools).
#[test]
fn a_closed_stdout_is_not_a_panic() {
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
        .arg("materials")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_ne!(o.status.code(), Some(101));
}

/// `devices` says where the kernel's buffers live and which queues a device has (what a
/// GPU run needs to tell whether the kernel reads device memory the host writes in place):
/// the evaluator's input and output buffers are host-visible on every device (it writes
/// and reads them in place), and the device vkbrdf uses has a compute queue.
#[test]
fn devices_report_queue_families_and_the_buffers_memory() {
    let o = vkbrdf(&["devices"]);
    if !o.status.success() {
        assert_ne!(
            std::env::var("VKBRDF_REQUIRE_VULKAN").as_deref(),
            Ok("1"),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        return; // no Vulkan here
    }
    let out = String::from_utf8_lossy(&o.stdout);
    let line = |label: &str| {
        out.lines()
            .find(|l| l.trim_start().starts_with(label))
            .unwrap_or_else(|| panic!("no {label:?} line: {out}"))
            .to_string()
    };
    assert!(line("queue family 0:").contains("queue(s)"), "{out}");
    assert!(
        out.lines()
            .any(|l| l.trim_start().starts_with("queue family") && l.contains("compute")),
        "{out}"
    );
    for label in ["input buffers:", "output buffers:"] {
        let l = line(label);
        assert!(l.contains("host-visible") && l.contains("heap "), "{l}");
    }
}
