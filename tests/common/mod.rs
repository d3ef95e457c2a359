//! Shared test helpers: every backend, so one test body runs on each.
#![allow(dead_code)]

pub mod combinations;
pub mod mixed;
pub mod npy;
pub mod quadrature;
pub mod rule;
pub mod steepest;
pub mod strategies;

use std::process::{Command, Output};
use vkbrdf::backend::Backend;
use vkbrdf::gpu::{DeviceSelector, VulkanBackend, VulkanOptions};
use vkbrdf::material::{parse_materials, Material};
use vkbrdf::reference::CpuReference;

/// The materials of a test's TOML text (which must parse).
pub fn materials(toml: &str) -> Vec<Material> {
    parse_materials(toml, "test").expect("test materials parse")
}

/// The Vulkan backend with validation on, or `None` (with a loud message) when no device
/// exists. With `VKBRDF_REQUIRE_VULKAN=1` (CI) a missing device panics: Vulkan tests never
/// pass silently.
pub fn vulkan() -> Option<VulkanBackend> {
    vulkan_with(VulkanOptions {
        validation: true,
        ..VulkanOptions::default()
    })
}

/// [`vulkan`] with the given options.
pub fn vulkan_with(options: VulkanOptions) -> Option<VulkanBackend> {
    match VulkanBackend::new(DeviceSelector::from_env(), options) {
        Ok(b) => Some(b),
        Err(e) if std::env::var("VKBRDF_REQUIRE_VULKAN").as_deref() == Ok("1") => {
            panic!("VKBRDF_REQUIRE_VULKAN=1 but no Vulkan device: {e}")
        }
        Err(e) => {
            eprintln!("!!! SKIPPING the Vulkan half of this test: no Vulkan device ({e}). Set VKBRDF_REQUIRE_VULKAN=1 to fail instead.");
            None
        }
    }
}

/// The CPU reference, the native CPU engine and, when a Vulkan device exists, the Vulkan
/// backend.
pub fn backends() -> Vec<Box<dyn Backend>> {
    let mut v: Vec<Box<dyn Backend>> = vec![
        Box::new(CpuReference::new()),
        Box::new(vkbrdf::cpu::CpuEngine::new()),
    ];
    if let Some(b) = vulkan() {
        v.push(Box::new(b));
    }
    v
}

/// Runs the `vkbrdf` binary of this build with `args`, capturing its output.
pub fn vkbrdf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
        .args(args)
        .output()
        .expect("run vkbrdf")
}

/// A command's standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `vkbrdf generate -m M -n N -o OUT` (N tuples for the materials file M).
pub fn generate(m: &std::path::Path, n: usize, out: &std::path::Path) -> Output {
    let n = n.to_string();
    vkbrdf(&["generate", "-m", path(m), "-n", &n, "-o", path(out)])
}

/// `vkbrdf eval -m M -i T EXTRA…` (outputs and options in `extra`).
pub fn eval(m: &std::path::Path, t: &std::path::Path, extra: &[&str]) -> Output {
    let mut args = vec!["eval", "-m", path(m), "-i", path(t)];
    args.extend_from_slice(extra);
    vkbrdf(&args)
}

/// A path as a command-line argument (test paths are UTF-8).
pub fn path(p: &std::path::Path) -> &str {
    p.to_str().expect("UTF-8 test path")
}
