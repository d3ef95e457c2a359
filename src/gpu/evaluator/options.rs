//! The settings of a [`VulkanBackend`](crate::gpu::VulkanBackend): [`VulkanOptions`], the
//! testing aid [`InjectedFault`] and the environment variables they default from.

use crate::error::{Error, Result};
use ash::vk;

/// Settings of a [`VulkanBackend`](crate::gpu::VulkanBackend).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VulkanOptions {
    /// Upper bound on the device memory the backend's buffers use, in bytes (default
    /// 256 MiB). Batches larger than this stream through in chunks.
    pub max_gpu_memory: u64,
    /// Enable `VK_LAYER_KHRONOS_validation` and count its warnings and errors (default:
    /// on when the environment variable `VKBRDF_VALIDATION` is `1`).
    pub validation: bool,
    /// Extra preprocessor definitions (`NAME`, `VALUE`) for every kernel this backend
    /// compiles: for measuring kernel variants side by side in one process
    /// (`examples/kernel_time.rs`). Default: none.
    pub extra_defines: Vec<(String, String)>,
    /// Upload batches that mix materials grouped by material (the `BUCKETED` kernels;
    /// default on). Off only to measure what the grouping gains.
    pub group_by_material: bool,
    /// A batch of one material and at least this many tuples is evaluated by a kernel with
    /// the material folded in as specialization constants (default
    /// [`FOLD_MATERIAL_MIN_TUPLES`], or the environment variable `VKBRDF_FOLD_MIN_TUPLES`:
    /// a count, or `off`; `usize::MAX`: never). See docs/VULKAN.md, "Specialised kernels",
    /// for where a fold pays.
    pub fold_material_min_tuples: usize,
    /// Rows one invocation of a kernel with its material folded in evaluates, 1–4 (rows
    /// `stride` apart, so neighbouring invocations still read neighbouring rows). `None`
    /// (the default, unless the environment variable `VKBRDF_TUPLES_PER_INVOCATION` gives
    /// 1–4): one. On lavapipe 4 makes the kernel alone 1.09–1.14× faster, but each fold's
    /// pipeline creation costs +0.07 s warm and +0.45 s cold, which a 2^24-tuple `eval`
    /// (the fold threshold) does not earn back (~0.02 s): for repeated or far larger
    /// batches (docs/VULKAN.md). Unmeasured on a GPU. The table kernels always take one.
    pub folded_tuples_per_invocation: Option<u32>,
    /// Chunks of an `eval` stream left on the device while the host copies the next chunk
    /// in and an older one out (`Backend::overlapped`), 0 to
    /// [`FRAMES_IN_FLIGHT`](crate::gpu::FRAMES_IN_FLIGHT) − 1 (more is taken as that; the
    /// ring keeps one slot for the chunk being copied in). `None`
    /// (the default, unless the environment variable `VKBRDF_CHUNKS_IN_FLIGHT` gives a
    /// count): 0 on a CPU device
    /// (lavapipe computes on the host's own cores, so nothing overlaps: 1–3 measured no
    /// faster there, and each slot's buffers are one more first touch), 2 on a GPU.
    pub chunks_in_flight: Option<usize>,
    /// Threads the host's copies into and out of the device's mapped buffers are split
    /// over. `None` (the default, unless the environment variable
    /// `VKBRDF_HOST_COPY_THREADS` gives a count): 1 on a CPU device, whose kernel needs the
    /// host's cores, else a quarter of the host's cores, 1 to 4 (one thread's copy caps a
    /// stream near 200 M tuples/s; docs/STREAMING.md).
    pub host_copy_threads: Option<usize>,
    /// Testing aid: a fault to inject into batch evaluations (see [`InjectedFault`]).
    /// Default: none, or what the environment variable `VKBRDF_INJECT_VK_FAULT` says
    /// (read by [`VulkanBackend::new`](crate::gpu::VulkanBackend::new)).
    #[doc(hidden)]
    pub inject_fault: Option<InjectedFault>,
}

/// Testing aid: the wait for chunk `chunk` (0-based) of every batch evaluation
/// ([`Backend::evaluate`](crate::backend::Backend::evaluate)) reports `result` after the
/// chunk really completed, as a lost device or exhausted memory would, so the error path
/// (the message naming the chunk, the recovery, the teardown, the CLI writing nothing) can
/// be tested on any device.
/// Set by [`VulkanOptions::inject_fault`] or by the environment variable
/// `VKBRDF_INJECT_VK_FAULT=KIND@CHUNK`, KIND one of `device-lost`, `out-of-device-memory`,
/// `out-of-host-memory`, `timeout` (e.g. `device-lost@2`).
#[doc(hidden)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InjectedFault {
    /// What the wait returns.
    pub result: vk::Result,
    /// 0-based chunk index within a batch.
    pub chunk: usize,
}

/// The environment variable [`InjectedFault`] is read from.
const INJECT_FAULT_VAR: &str = "VKBRDF_INJECT_VK_FAULT";

impl std::str::FromStr for InjectedFault {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let usage = || {
            format!("`{s}`: expected KIND@CHUNK, KIND one of device-lost, out-of-device-memory, out-of-host-memory, timeout, CHUNK a 0-based chunk index (e.g. device-lost@2)")
        };
        let (kind, chunk) = s.split_once('@').ok_or_else(usage)?;
        let result = match kind.trim() {
            "device-lost" => vk::Result::ERROR_DEVICE_LOST,
            "out-of-device-memory" => vk::Result::ERROR_OUT_OF_DEVICE_MEMORY,
            "out-of-host-memory" => vk::Result::ERROR_OUT_OF_HOST_MEMORY,
            "timeout" => vk::Result::TIMEOUT,
            _ => return Err(usage()),
        };
        let chunk = chunk.trim().parse().map_err(|_| usage())?;
        Ok(InjectedFault { result, chunk })
    }
}

impl InjectedFault {
    /// The fault `VKBRDF_INJECT_VK_FAULT` asks for, if set (an unparsable value is an error).
    pub(super) fn from_env() -> Result<Option<InjectedFault>> {
        match std::env::var(INJECT_FAULT_VAR) {
            Ok(v) if !v.is_empty() => v
                .parse()
                .map(Some)
                .map_err(|e| Error::Unsupported(format!("{INJECT_FAULT_VAR}={e}"))),
            _ => Ok(None),
        }
    }
}

impl Default for VulkanOptions {
    fn default() -> Self {
        VulkanOptions {
            max_gpu_memory: 256 << 20,
            validation: validation_from_env(),
            extra_defines: Vec::new(),
            group_by_material: true,
            fold_material_min_tuples: fold_min_tuples_from_env(),
            folded_tuples_per_invocation: tuples_per_invocation_from_env(),
            chunks_in_flight: count_from_env("VKBRDF_CHUNKS_IN_FLIGHT"),
            host_copy_threads: count_from_env("VKBRDF_HOST_COPY_THREADS"),
            inject_fault: None,
        }
    }
}

/// The default of [`VulkanOptions::fold_material_min_tuples`].
pub const FOLD_MATERIAL_MIN_TUPLES: usize = 1 << 24;

/// `VKBRDF_FOLD_MIN_TUPLES`: a tuple count, or `off` (never fold); unset, empty or
/// unreadable, [`FOLD_MATERIAL_MIN_TUPLES`] (a setting for measurements, not worth an error).
fn fold_min_tuples_from_env() -> usize {
    match std::env::var("VKBRDF_FOLD_MIN_TUPLES").as_deref() {
        Ok("off") => usize::MAX,
        Ok(v) => v.trim().parse().unwrap_or(FOLD_MATERIAL_MIN_TUPLES),
        Err(_) => FOLD_MATERIAL_MIN_TUPLES,
    }
}

/// `VKBRDF_TUPLES_PER_INVOCATION`: 1–4; anything else, the device's default (a setting
/// for measurements).
fn tuples_per_invocation_from_env() -> Option<u32> {
    std::env::var("VKBRDF_TUPLES_PER_INVOCATION")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .filter(|k| (1..=4).contains(k))
}

/// A count from the environment variable `name`; unset or unreadable, `None` (the
/// device's default: these are settings for measurements, not worth an error).
fn count_from_env(name: &str) -> Option<usize> {
    std::env::var(name).ok().and_then(|v| v.trim().parse().ok())
}

/// Whether `VKBRDF_VALIDATION` asks for the validation layer (`1`, `true` or `yes`).
pub fn validation_from_env() -> bool {
    matches!(
        std::env::var("VKBRDF_VALIDATION").as_deref(),
        Ok("1" | "true" | "yes")
    )
}
