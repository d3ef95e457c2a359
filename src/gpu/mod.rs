//! The Vulkan compute backend — the only module of the crate with `unsafe` code. Every
//! `unsafe` block carries a `// SAFETY:` line naming the invariant it relies on.
//!
//! # Pieces
//! - [`context`](DeviceSelector): loads the Vulkan loader (a missing `libvulkan` is an
//!   [`Error::NoDevice`](crate::error::Error::NoDevice) that says what to install), creates
//!   the instance — with `VK_LAYER_KHRONOS_validation` and a `VK_EXT_debug_utils` messenger
//!   that counts warnings and errors when [`VulkanOptions::validation`] asks for it — picks
//!   the physical device (discrete GPU > integrated > virtual > CPU, overridden by a
//!   [`DeviceSelector`] from `--device` or `VKBRDF_DEVICE`) and creates the logical device
//!   with one compute queue.
//! - `memory`: storage buffers, persistently mapped, freed on drop.
//! - [`kernel`]: the GLSL in `glsl/`, embedded with `include_str!` and compiled by shaderc
//!   at run time (`#include` resolved against the embedded files, errors naming file and
//!   line), one pipeline per [`FeatureSet`](crate::features::FeatureSet), cached.
//! - [`VulkanBackend`] (`evaluator`): chunking and streaming, the [`Backend`](crate::backend::Backend).
//! - [`layout`]: the `#[repr(C)]` GPU structs and the codes the GLSL reads.
//! - [`devices`]: `vkbrdf devices`.
//! - `vk_error`: a failed call's `vk::Result` as an
//!   [`Error::Vulkan`](crate::error::Error::Vulkan), for every file here.
//!
//! # Decisions
//! Memory types, synchronisation, one queue, counts, input, RAII and errors, each with its
//! reason and measurement: `docs/ARCHITECTURE.md`, "Decisions".
#![allow(unsafe_code)]

mod context;
pub mod devices;
mod disk_cache;
mod emulate_ftz;
mod evaluator;
mod fold;
mod host_copy;
pub mod kernel;
pub mod layout;
mod memory;
mod pipeline_cache;
mod sync;
mod vk_error;

pub use context::{DeviceSelector, ValidationCounter, INSTALL_HINT};
pub use devices::{list_devices, DeviceInfo, HeapInfo};
pub use evaluator::{
    validation_from_env, BufferBytes, HostStages, InjectedFault, KernelClock, KernelTiming,
    LinkRates, VulkanBackend, VulkanOptions, FOLD_MATERIAL_MIN_TUPLES, FRAMES_IN_FLIGHT,
    MAX_CHUNK_TUPLES,
};
pub use kernel::FOLDED_MATERIALS_MAX;

/// The directory where compiled kernels are kept across runs (`VKBRDF_CACHE_DIR`, else the
/// user's cache directory), or `None` when the cache is off or no home is known.
pub fn kernel_cache_dir() -> Option<std::path::PathBuf> {
    disk_cache::DiskCache::from_env()
        .dir()
        .map(std::path::Path::to_path_buf)
}
