//! Vulkan faults are typed: a lost device or exhausted memory during a batch is an
//! [`Error::Vulkan`] that keeps the `vk::Result`, names the chunk (index and rows) and says
//! what to try; the backend recovers and tears down cleanly; the CLI writes nothing.
//! The faults are injected (`VulkanOptions::inject_fault`, `VKBRDF_INJECT_VK_FAULT`): the
//! wait for chunk k reports the chosen result after the chunk really completed.

mod common;

use ash::vk;
use std::path::Path;
use std::process::Command;
use vkbrdf::backend::{Backend, Request};
use vkbrdf::batch::write_npy_f32;
use vkbrdf::gpu::{DeviceSelector, InjectedFault, VulkanBackend, VulkanOptions};
use vkbrdf::material::{parse_materials, Material};
use vkbrdf::reference::CpuReference;
use vkbrdf::Error;

const MATERIALS: &str = r#"
[[material]]
name = "matte"
model = "lambert"
diffuse = [0.8, 0.5, 0.2]

[[material]]
name = "gold"
preset = "gold"
"#;

/// A budget small enough that a 1000-tuple batch streams through many chunks.
const SMALL_BUDGET: u64 = 20 << 10;
const TUPLES: usize = 1000;

fn materials() -> Vec<Material> {
    parse_materials(MATERIALS, "faults.toml").unwrap()
}

/// A validating backend on the small budget with `fault` injected, or `None` (loudly, or a
/// panic under `VKBRDF_REQUIRE_VULKAN=1`) without a device.
fn faulty(fault: Option<InjectedFault>) -> Option<VulkanBackend> {
    common::vulkan()?;
    let options = VulkanOptions {
        max_gpu_memory: SMALL_BUDGET,
        validation: true,
        inject_fault: fault,
        ..VulkanOptions::default()
    };
    Some(VulkanBackend::new(DeviceSelector::from_env(), options).unwrap())
}

fn fault(result: vk::Result, chunk: usize) -> Option<InjectedFault> {
    Some(InjectedFault { result, chunk })
}

#[test]
fn a_fault_names_the_chunk_its_rows_and_what_to_try() {
    let materials = materials();
    let batch = vkbrdf::sample::sample_batch(TUPLES, materials.len(), 3, false);
    let cases = [
        (
            vk::Result::ERROR_DEVICE_LOST,
            &["ERROR_DEVICE_LOST", "device was lost", "driver", "retry"][..],
        ),
        (
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY,
            &[
                "ERROR_OUT_OF_DEVICE_MEMORY",
                "out of device memory",
                "smaller --max-gpu-memory",
                "now 20K",
            ][..],
        ),
        (
            vk::Result::ERROR_OUT_OF_HOST_MEMORY,
            &[
                "ERROR_OUT_OF_HOST_MEMORY",
                "out of host memory",
                "smaller --max-gpu-memory",
            ][..],
        ),
        (vk::Result::TIMEOUT, &["TIMEOUT", "hung device"][..]),
    ];
    let Some(probe) = faulty(None) else { return };
    let chunk = probe.chunk_tuples(materials.len()).unwrap();
    drop(probe);
    let chunks = TUPLES.div_ceil(chunk);
    assert!(
        chunks > 5,
        "want many chunks, got {chunks} of {chunk} tuples"
    );
    for (i, (result, advice)) in cases.into_iter().enumerate() {
        // Every code at a chunk in the ring's steady state; the first one too at the first
        // chunk and at the last (drained after the loop).
        let places: &[usize] = if i == 0 { &[2, 0, chunks - 1] } else { &[2] };
        for &k in places {
            let mut gpu = faulty(fault(result, k)).unwrap();
            let counter = gpu.validation_counter();
            let e = gpu
                .evaluate(&batch, &materials, &Request { terms: true })
                .expect_err("the injected fault must fail the batch");
            let Error::Vulkan {
                call,
                result: got,
                chunk: Some(failed),
            } = &e
            else {
                panic!("expected a Vulkan error naming its chunk, got {e:?}");
            };
            assert_eq!((*call, *got), ("vkWaitForFences", result));
            assert_eq!(e.vk_result(), Some(result));
            assert_eq!(failed.index, k as u64);
            assert_eq!(failed.count, chunks as u64);
            let rows = (k * chunk) as u64..TUPLES.min((k + 1) * chunk) as u64;
            assert_eq!(failed.rows, rows);
            assert_eq!(failed.max_gpu_memory, SMALL_BUDGET);
            let msg = e.to_string();
            let place = format!(
                "in chunk {k} of {chunks} (rows {}..{})",
                rows.start, rows.end
            );
            for f in advice.iter().copied().chain([place.as_str()]) {
                assert!(msg.contains(f), "`{msg}` lacks `{f}`");
            }
            // Recovered: the same backend evaluates a batch short of the faulty chunk.
            let short = vkbrdf::sample::sample_batch(k * chunk, materials.len(), 4, false);
            let got = gpu
                .evaluate(&short, &materials, &Request::default())
                .unwrap();
            let want = CpuReference::new()
                .evaluate(&short, &materials, &Request::default())
                .unwrap();
            assert_eq!(got.counts, want.counts);
            for (g, w) in got.brdf.iter().zip(&want.brdf) {
                assert!((g - w).abs() <= 1e-5 * w.abs().max(1e-3), "{g} vs {w}");
            }
            // Teardown after the fault: no panic in Drop, nothing left undestroyed.
            drop(gpu);
            assert_eq!(counter.count(), 0, "validation: {:?}", counter.messages());
        }
    }
}

#[test]
fn a_fault_past_the_last_chunk_never_fires() {
    let materials = materials();
    let batch = vkbrdf::sample::sample_batch(TUPLES, materials.len(), 5, false);
    let Some(mut gpu) = faulty(fault(vk::Result::ERROR_DEVICE_LOST, 1 << 20)) else {
        return;
    };
    let got = gpu
        .evaluate(&batch, &materials, &Request::default())
        .unwrap();
    assert_eq!(got.counts.tuples, TUPLES as u64);
}

#[test]
fn fault_specifications_parse_or_say_what_is_expected() {
    let ok = |s: &str| s.parse::<InjectedFault>().unwrap();
    assert_eq!(
        ok("device-lost@2"),
        InjectedFault {
            result: vk::Result::ERROR_DEVICE_LOST,
            chunk: 2
        }
    );
    assert_eq!(
        ok("out-of-device-memory@0").result,
        vk::Result::ERROR_OUT_OF_DEVICE_MEMORY
    );
    assert_eq!(
        ok("out-of-host-memory@7").result,
        vk::Result::ERROR_OUT_OF_HOST_MEMORY
    );
    for bad in [
        "device-lost",
        "lost@2",
        "device-lost@-1",
        "device-lost@x",
        "",
    ] {
        let e = bad.parse::<InjectedFault>().unwrap_err();
        assert!(e.contains("KIND@CHUNK") && e.contains("device-lost"), "{e}");
    }
}

/// Without a device there is nothing to inject into; the message of a typed error still
/// reads the same (no device needed to render it).
#[test]
fn errors_outside_a_batch_name_the_call_and_code_without_a_chunk() {
    let e = Error::Vulkan {
        call: "vkAllocateMemory",
        result: vk::Result::ERROR_OUT_OF_DEVICE_MEMORY,
        chunk: None,
    };
    let msg = e.to_string();
    assert!(
        msg.starts_with("Vulkan: vkAllocateMemory failed: ERROR_OUT_OF_DEVICE_MEMORY")
            && msg.contains("--max-gpu-memory")
            && !msg.contains("chunk"),
        "{msg}"
    );
    let other = Error::Vulkan {
        call: "vkCreateFence",
        result: vk::Result::ERROR_INITIALIZATION_FAILED,
        chunk: None,
    };
    assert_eq!(
        other.to_string(),
        format!(
            "Vulkan: vkCreateFence failed: ERROR_INITIALIZATION_FAILED ({})",
            vk::Result::ERROR_INITIALIZATION_FAILED
        )
    );
}

fn write_batch(dir: &Path, n: usize) -> (String, String) {
    let m = dir.join("m.toml");
    std::fs::write(&m, MATERIALS).unwrap();
    let batch = vkbrdf::sample::sample_batch(n, 2, 9, false);
    let t = dir.join("t.npy");
    write_npy_f32(&t, batch.as_slice(), batch.columns()).unwrap();
    (
        m.to_str().unwrap().to_string(),
        t.to_str().unwrap().to_string(),
    )
}

#[test]
fn cli_eval_reports_the_chunk_exits_2_and_writes_nothing() {
    if common::vulkan().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (m, t) = write_batch(dir.path(), TUPLES);
    let fresh = dir.path().join("fresh.npy");
    let kept = dir.path().join("kept.npy");
    let kept_terms = dir.path().join("kept-terms.npy");
    std::fs::write(&kept, b"precious").unwrap();
    std::fs::write(&kept_terms, b"precious terms").unwrap();
    for (fault, advice) in [
        ("device-lost@2", "device was lost"),
        ("out-of-device-memory@3", "smaller --max-gpu-memory"),
        ("out-of-host-memory@0", "smaller --max-gpu-memory"),
    ] {
        for (out, terms) in [(&fresh, None), (&kept, Some(&kept_terms))] {
            let mut args = vec![
                "eval",
                "--backend",
                "vulkan",
                "--max-gpu-memory",
                "20K",
                "-m",
                &m,
                "-i",
                &t,
                "-o",
                out.to_str().unwrap(),
            ];
            if let Some(terms) = terms {
                args.extend(["--terms", terms.to_str().unwrap()]);
            }
            let o = Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
                .args(&args)
                .env("VKBRDF_INJECT_VK_FAULT", fault)
                .output()
                .unwrap();
            let msg = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{fault}: {msg}");
            let chunk = fault.split('@').nth(1).unwrap();
            assert!(
                msg.contains(&format!("in chunk {chunk} of "))
                    && msg.contains("(rows ")
                    && msg.contains(advice),
                "{fault}: {msg}"
            );
            assert!(!msg.contains("panicked"), "{msg}");
            assert!(!fresh.exists(), "{fault}: an output was written");
            assert_eq!(std::fs::read(&kept).unwrap(), b"precious");
            assert_eq!(std::fs::read(&kept_terms).unwrap(), b"precious terms");
        }
    }
    let stray: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !["m.toml", "t.npy", "kept.npy", "kept-terms.npy"].contains(&n.as_str()))
        .collect();
    assert!(stray.is_empty(), "stray files: {stray:?}");
    // Without the fault the same command succeeds (the budget alone is not the failure).
    let o = Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
        .args([
            "eval",
            "--backend",
            "vulkan",
            "--max-gpu-memory",
            "20K",
            "-m",
            &m,
            "-i",
            &t,
            "-o",
            fresh.to_str().unwrap(),
        ])
        .env_remove("VKBRDF_INJECT_VK_FAULT")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(fresh.exists());
}

#[test]
fn cli_refuses_a_malformed_fault_specification() {
    if common::vulkan().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (m, t) = write_batch(dir.path(), 10);
    let out = dir.path().join("f.npy");
    let o = Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
        .args(["eval", "--backend", "vulkan", "-m", &m, "-i", &t, "-o"])
        .arg(&out)
        .env("VKBRDF_INJECT_VK_FAULT", "melted@1")
        .output()
        .unwrap();
    let msg = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{msg}");
    assert!(msg.contains("VKBRDF_INJECT_VK_FAULT=`melted@1`"), "{msg}");
    assert!(!out.exists());
}
