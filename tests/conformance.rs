//! Conformance of the Vulkan backend against the f64 reference, with the validation layer
//! on: every legal material combination within tolerance, the GPU structs' layout, the
//! kernel's math helpers, specialisation, counts, the terms switch and streaming, and zero
//! validation warnings or errors in every test (counted after the backend is dropped, so
//! leaks count too).
//!
//! Without a Vulkan device these tests print a loud notice and return, unless
//! `VKBRDF_REQUIRE_VULKAN=1` (CI), where they fail.

use vkbrdf::backend::{Backend, Request};
use vkbrdf::check::{self, CheckOptions, CombinationReport};
use vkbrdf::gpu::{ValidationCounter, VulkanBackend, VulkanOptions};
use vkbrdf::Error;

/// Tuples per combination in the full conformance test (198 combinations).
const TUPLES_PER_COMBINATION: usize = 1000;

/// A validating Vulkan backend, or `None` (after a loud notice) when the machine has no
/// Vulkan device and `VKBRDF_REQUIRE_VULKAN` is not `1`.
fn vulkan(max_gpu_memory: Option<u64>) -> Option<VulkanBackend> {
    let mut options = VulkanOptions {
        validation: true,
        ..VulkanOptions::default()
    };
    if let Some(m) = max_gpu_memory {
        options.max_gpu_memory = m;
    }
    match VulkanBackend::new(None, options) {
        Ok(b) => {
            assert!(b.validation_enabled(), "the validation layer is not installed (apt-get install vulkan-validationlayers): these tests need it");
            Some(b)
        }
        Err(Error::NoDevice(msg)) => {
            if std::env::var("VKBRDF_REQUIRE_VULKAN").as_deref() == Ok("1") {
                panic!("VKBRDF_REQUIRE_VULKAN=1 but no Vulkan device: {msg}");
            }
            eprintln!("\n!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!");
            eprintln!(
                "!!! SKIPPED: no Vulkan device, the Vulkan conformance test did NOT run: {msg}"
            );
            eprintln!("!!! (set VKBRDF_REQUIRE_VULKAN=1 to make this a failure)");
            eprintln!("!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!\n");
            None
        }
        Err(e) => panic!("cannot create the Vulkan backend: {e}"),
    }
}

/// Drops the backend, then asserts that validation reported nothing, destruction included.
fn finish(backend: VulkanBackend) {
    let counter: ValidationCounter = backend.validation_counter();
    drop(backend);
    assert_eq!(
        counter.count(),
        0,
        "validation messages:\n{}",
        counter.messages().join("\n")
    );
}

#[test]
fn every_combination_matches_the_reference() {
    let Some(mut gpu) = vulkan(None) else { return };
    let options = CheckOptions {
        tuples: TUPLES_PER_COMBINATION,
        seed: 1,
    };
    eprintln!("{}", CombinationReport::header());
    let reports =
        check::run(&mut gpu, &options, &mut |r| eprintln!("{}", r.row())).expect("check run");
    let failures: Vec<String> = reports
        .iter()
        .filter(|r| !r.pass())
        .map(|r| {
            format!(
                "{}\n{}",
                r.row(),
                r.worst.as_ref().map(|w| w.to_string()).unwrap_or_default()
            )
        })
        .collect();
    let worst = reports
        .iter()
        .max_by(|a, b| a.max_rel.total_cmp(&b.max_rel))
        .expect("some combinations");
    let mut columns = [0f64; 9];
    for r in &reports {
        for (c, m) in columns.iter_mut().zip(r.column_max) {
            *c = c.max(m);
        }
    }
    eprintln!("worst combination: {}", worst.row());
    eprintln!(
        "max per column: {:?}",
        check::COLUMNS.iter().zip(columns).collect::<Vec<_>>()
    );
    assert!(
        failures.is_empty(),
        "{} of {} combinations fail:\n{}",
        failures.len(),
        reports.len(),
        failures.join("\n")
    );
    finish(gpu);
}
