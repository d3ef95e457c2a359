//! The Vulkan compute backend — the only module of the crate with `unsafe` code. Every
//! `unsafe` block carries a `// SAFETY:` line naming the invariant it relies on.
//!
//! # Pieces
//! - [`context`](DeviceSelector): loads the Vulkan loader (a missing `libvulkan` is an
//!   [`Error::NoDevice`] that says what to install), creates the instance — with
//!   `VK_LAYER_KHRONOS_validation` and a `VK_EXT_debug_utils` messenger that counts warnings
//!   and errors when [`VulkanOptions::validation`] asks for it — picks the physical device
//!   (discrete GPU > integrated > virtual > CPU, overridden by a [`DeviceSelector`] from
//!   `--device` or `VKBRDF_DEVICE`) and creates the logical device with one compute queue.
//! - `memory`: storage buffers, persistently mapped, freed on drop.
//! - [`kernel`]: the GLSL in `glsl/`, embedded with `include_str!` and compiled by shaderc
//!   at run time (`#include` resolved against the embedded files, errors naming file and
//!   line), one pipeline per [`FeatureSet`](crate::features::FeatureSet), cached.
//! - [`VulkanBackend`] (`evaluator`): chunking and streaming, the [`Backend`](crate::backend::Backend).
//! - [`layout`]: the `#[repr(C)]` GPU structs and the codes the GLSL reads.
//! - [`devices`]: `vkbrdf devices`.
//!
//! # Decisions
//! - **Memory types.** Every buffer is `HOST_VISIBLE | HOST_COHERENT` and mapped for its
//!   whole life: the host writes tuples straight into the buffer the kernel reads and reads
//!   results straight from the buffer it writes, with no staging copy and no flush or
//!   invalidate. Uploads prefer memory that is also `DEVICE_LOCAL`, readbacks prefer
//!   `HOST_CACHED` (uncached reads of results are several times slower). On lavapipe,
//!   integrated GPUs and discrete GPUs with resizable BAR this is the fastest path; it is
//!   what the project's machines (lavapipe) run. On a discrete GPU without resizable BAR
//!   the kernel would read tuples across PCIe instead; there the better design is a
//!   `DEVICE_LOCAL` buffer per slot plus host-visible staging buffers, with
//!   `vkCmdCopyBuffer` in → dispatch → `vkCmdCopyBuffer` out recorded in the same command
//!   buffer (barriers transfer→compute→transfer→host). The slot structure below already
//!   has the place for it: only `memory.rs` and the recording in `submit` would change.
//! - **Memory bound.** Slot buffers are sized for chunks such that all
//!   [`FRAMES_IN_FLIGHT`] slots at the widest tuple layout (13 input + 3 + 6 output floats)
//!   fit in [`VulkanOptions::max_gpu_memory`], and one input buffer fits in
//!   `maxStorageBufferRange` (128 MiB on lavapipe) and one dispatch in
//!   `maxComputeWorkGroupCount[0]`. Buffers persist between calls and only grow (the old
//!   one is freed before the new one is allocated).
//! - **Synchronisation.** One fence per slot and nothing else: each submission is one
//!   command buffer (dispatch, then a compute-write → host-read memory barrier) signalling
//!   its slot's fence; the host waits on that fence before it reads the results or reuses
//!   the slot's buffers, command buffer or descriptor set. Host writes before
//!   `vkQueueSubmit` are visible to the device by the submission's implicit host
//!   synchronisation. No semaphores: chunks are independent, and results go to the host.
//! - **One queue.** The work is a stream of independent dispatches whose only consumer is
//!   the host; one compute queue executes them in order and the ring of fences gives all
//!   the overlap there is to get (host copies vs device work). A second queue (e.g. a
//!   transfer queue for staging copies on a discrete GPU) would add cross-queue semaphores
//!   and ownership transfers for no gain on the devices this runs on.
//! - **Counts.** Invalid and below-horizon tuples are reduced per subgroup
//!   (`subgroupAdd`/`subgroupMin` where the device supports subgroup arithmetic in compute
//!   shaders), then one global atomic per subgroup that has something to count, and none
//!   otherwise; per-invocation atomics on devices without subgroup arithmetic. Not a
//!   workgroup reduction in shared memory: that needs `barrier()`, and llvmpipe runs any
//!   shader with a barrier through coroutines, which made the whole kernel 2.7× slower on
//!   lavapipe (4M tuples of a load-and-store kernel: 280 ms with the barrier, 103 without).
//! - **Input.** The kernel reads tuple rows through a uniform texel buffer (RGBA32F view,
//!   `BINDING_TUPLE_TEXELS`) over the same mapped bytes as the storage binding: 3 `texelFetch`
//!   per 10-float row (4 with tangents) and a per-lane shift by `row * COLUMNS mod 4`, so the
//!   host layout and copies are unchanged. On lavapipe each storage-buffer load is a per-lane
//!   bounds-checked gather; side by side (lavapipe, Mesa 25, 1M tuples, kernel-only, noisy
//!   shared machine) a load-and-store kernel went from 65–103 to 106–161 M tuples/s and
//!   Lambert from 32–59 to 57–80 M/s. Tried and dropped: loading the material once per
//!   subgroup (`subgroupAllEqual` + `subgroupBroadcastFirst`): Lambert 57–69 vs 77–80 M/s
//!   without; workgroup size 256 or 1024 instead of 64: no difference above the noise.
//! - **Accuracy.** The kernel is f32. Where f32 inputs determine a value well it agrees
//!   with the f64 reference to 1e-5 relative (measured ≤ 7e-6); near grazing mirror
//!   geometry with sharp lobes no f32 evaluation can, and [`crate::check`] holds it to a
//!   multiple of the value's f32 sensitivity instead. Three reformulations keep the kernel
//!   at that limit (each found by the conformance check, each commented in the GLSL):
//!   `c = v·h` is computed as `|l + v|/2` (the dot product loses ~u/(2c²) at grazing
//!   angles); the tangent frame is built from cross products, not Gram–Schmidt (which
//!   tilts t out of the tangent plane by ~u/|n × T|); and `exp`, `log`, `log1p`, `atan2`
//!   and `erfc` are the kernel's own (glsl/math.glsl, errors measured by
//!   `tests/conformance.rs`), since lavapipe's `exp` is off by 65 ulp and the Vulkan spec
//!   allows far more.
//! - **Subnormal inputs.** lavapipe keeps f32 subnormals, so a vector whose components are
//!   all subnormal is normalised like any other, as the reference does. A driver that
//!   flushes subnormals to zero would see a zero vector there and count the tuple invalid.
//! - **RAII.** Child objects hold an `Arc` of their `Device` (in `context`), which
//!   holds an `Arc` of the instance: parents outlive children. [`VulkanBackend`]'s `Drop`
//!   waits for the device to go idle; its fields then drop in reverse creation order.
//! - **Errors.** Every `vk::Result` is mapped at its call site to
//!   [`Error::Vulkan`]` { call: "vkCreateBuffer", result, .. }`, which keeps the
//!   `vk::Result` itself; nothing unwraps a driver result. A failure while a batch streams
//!   also names its chunk ([`FailedChunk`](crate::error::FailedChunk): index, rows, memory
//!   budget), and the message says what to try for `ERROR_DEVICE_LOST`, the out-of-memory
//!   codes and `TIMEOUT`. After any error the backend waits for the device and forgets the
//!   pending chunks (`recover`), so it stays usable and drops cleanly. The error path is
//!   tested by fault injection: `VKBRDF_INJECT_VK_FAULT=device-lost@2` (or the hidden
//!   `VulkanOptions::inject_fault`) makes the wait for chunk 2 of every batch report
//!   `ERROR_DEVICE_LOST` (also `out-of-device-memory`, `out-of-host-memory`, `timeout`).
#![allow(unsafe_code)]

mod context;
pub mod devices;
mod evaluator;
pub mod kernel;
pub mod layout;
mod memory;
mod sync;

pub use context::{DeviceSelector, ValidationCounter, INSTALL_HINT};
pub use devices::{list_devices, DeviceInfo, HeapInfo};
pub use evaluator::{
    validation_from_env, BufferBytes, InjectedFault, VulkanBackend, VulkanOptions,
    FRAMES_IN_FLIGHT, MAX_CHUNK_TUPLES,
};

use crate::error::Error;
use ash::vk;

/// Maps a failed `vk::Result` of `call` to [`Error::Vulkan`].
pub(crate) fn vk_error(call: &'static str) -> impl Fn(vk::Result) -> Error {
    move |result| Error::Vulkan {
        call,
        result,
        chunk: None,
    }
}
