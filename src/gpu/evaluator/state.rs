//! What the evaluator's files share: the [`VulkanBackend`] struct (its fields, in drop
//! order), its ring of [`FRAMES_IN_FLIGHT`] slots and their pending chunks, the host
//! stage sums, and the descriptor-set write. The methods live in `evaluator.rs` and its
//! other children, which use this file, never `evaluator.rs`.

use super::options::VulkanOptions;
use crate::features::FeatureSet;
use crate::gpu::context::Device;
use crate::gpu::host_copy::HostCopy;
use crate::gpu::kernel::Kernels;
use crate::gpu::layout::{descriptor_type, BINDING_COUNT, BINDING_TUPLE_TEXELS};
use crate::gpu::memory::{Buffer, TexelView};
use crate::gpu::sync::{CommandPool, DescriptorPool, Fence};
use ash::vk;
use std::ops::Range;
use std::sync::Arc;

/// Chunks in flight: one being filled by the host, one running, one being read back.
pub const FRAMES_IN_FLIGHT: usize = 3;

/// Host seconds of the streamed evaluation's stages, summed over the calls since the last
/// [`VulkanBackend::reset_host_stages`]: what `vkbrdf bench` reports as the upload, wait and
/// readback stages (the kernel's own time comes from device timestamps instead).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct HostStages {
    /// Grouping rows by material and copying them into the device-visible input buffers.
    pub upload_s: f64,
    /// Waiting on chunk fences: the device's kernel and transfers not hidden behind the
    /// host's own work.
    pub wait_s: f64,
    /// Copying results out of the device-visible output buffers (scattered back to row
    /// order when grouped).
    pub readback_s: f64,
    /// Chunks evaluated.
    pub chunks: u64,
}

/// Where a submitted chunk's results go when it is read back.
#[derive(Debug, Clone)]
pub(super) struct Pending {
    /// Float range of `Output::brdf` (the BRDF buffer's first `len` floats).
    pub(super) brdf: Range<usize>,
    /// Float range of `Output::terms`, when the chunk writes terms.
    pub(super) terms: Option<Range<usize>>,
    /// Batch row of the chunk's first tuple (turns chunk-relative rows into batch rows).
    pub(super) first_row: u64,
    /// The order the chunk's rows were uploaded in (`BUCKETED`): output row i belongs to
    /// chunk row `order[i]`.
    pub(super) order: Option<Vec<u32>>,
}

/// One frame in flight: its buffers, descriptor set, command buffer and fence.
pub(super) struct Slot {
    /// The RGBA32UI view of `input` (declared first: dropped before the buffer it views).
    pub(super) input_view: Option<TexelView>,
    pub(super) input: Option<Buffer>,
    /// The chunk's evaluation order (`BUCKETED` kernels only).
    pub(super) order: Option<Buffer>,
    pub(super) brdf: Option<Buffer>,
    pub(super) terms: Option<Buffer>,
    pub(super) counts: Buffer,
    pub(super) fence: Fence,
    pub(super) cmd: vk::CommandBuffer,
    pub(super) set: vk::DescriptorSet,
    /// The [`Buffer::id`]s the descriptor set points at now, by binding (ids, not handles:
    /// see [`Buffer::id`]).
    pub(super) bound: [u64; BINDING_COUNT as usize],
    pub(super) pending: Option<Pending>,
}

/// The Vulkan compute backend (see the [module docs](crate::gpu) for its design).
///
/// ```no_run
/// use vkbrdf::backend::{Backend, Request};
/// use vkbrdf::gpu::{VulkanBackend, VulkanOptions};
/// # fn main() -> vkbrdf::Result<()> {
/// let materials = vec![vkbrdf::material::presets::preset("gold").unwrap()?];
/// let batch = vkbrdf::sample::sample_batch(1000, materials.len(), 1, false);
/// let mut gpu = VulkanBackend::new(None, VulkanOptions::default())?;
/// let out = gpu.evaluate(&batch, &materials, &Request { terms: true })?;
/// assert_eq!(out.brdf.len(), 3000);
/// # Ok(()) }
/// ```
pub struct VulkanBackend {
    // Field order is drop order: buffers and fences, then the pools, the pipelines, and
    // last the device (Drop waits idle before any of them goes).
    pub(super) slots: Vec<Slot>,
    pub(super) materials: Option<Buffer>,
    /// The MERL tables of the last measured batch ([`BINDING_MERL`](crate::gpu::layout::BINDING_MERL)),
    /// uploaded once and kept while the next batch uses the same tables.
    pub(super) merl: Option<Buffer>,
    /// The tables `merl` holds, in order (kept alive, so a pointer match is a table match).
    pub(super) merl_tables: Vec<std::sync::Arc<crate::material::merl::MeasuredMerl>>,
    /// MERL tables uploaded so far ([`VulkanBackend::measured_uploads`]).
    pub(super) merl_uploads: u64,
    pub(super) dummy: Buffer,
    /// Owns the slots' descriptor sets (freed with the pool).
    pub(super) _descriptors: DescriptorPool,
    /// Owns the slots' command buffers (freed with the pool).
    pub(super) _commands: CommandPool,
    pub(super) kernels: Kernels,
    pub(super) last_features: Option<FeatureSet>,
    /// Whether the last evaluation's kernel had its material folded in.
    pub(super) last_folded: bool,
    /// The features [`crate::backend::Backend::share_kernels`] asked every kernel to include.
    pub(super) shared_features: FeatureSet,
    pub(super) options: VulkanOptions,
    /// Checked before each chunk is submitted.
    pub(super) cancel: crate::cancel::Cancel,
    /// Host time per stage, for the bench.
    pub(super) stages: HostStages,
    /// Rows an invocation of a folded kernel takes on this device
    /// ([`VulkanOptions::folded_tuples_per_invocation`]); the table kernels take one.
    pub(super) folded_per_invocation: u32,
    /// Copies into the input buffers and out of the output buffers, over a few threads on
    /// a GPU host ([`VulkanOptions::host_copy_threads`]).
    pub(super) host_copy: HostCopy,
    pub(super) device: Arc<Device>,
}

impl Drop for VulkanBackend {
    fn drop(&mut self) {
        // Then the fields drop in declaration order: buffers and fences, pools, pipelines
        // and layouts, and the device (when this was the last Arc).
        self.device.wait_idle();
    }
}

/// Points descriptor set `set` at `wanted` (one buffer per binding; the tuple-texel binding
/// takes `view`, a view of the input buffer). Precondition: no pending work uses the set.
pub(super) fn write_set(
    device: &Device,
    set: vk::DescriptorSet,
    wanted: &[&Buffer; BINDING_COUNT as usize],
    view: &TexelView,
) {
    let infos: Vec<[vk::DescriptorBufferInfo; 1]> = wanted
        .iter()
        .map(|b| {
            [vk::DescriptorBufferInfo {
                buffer: b.raw(),
                offset: 0,
                range: vk::WHOLE_SIZE,
            }]
        })
        .collect();
    let views = [view.raw()];
    let writes: Vec<vk::WriteDescriptorSet> = infos
        .iter()
        .enumerate()
        .map(|(binding, info)| {
            let binding = binding as u32;
            let write = vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(binding)
                .descriptor_type(descriptor_type(binding));
            if binding == BINDING_TUPLE_TEXELS {
                write.texel_buffer_view(&views)
            } else {
                write.buffer_info(info)
            }
        })
        .collect();
    // SAFETY: the set is not used by pending work (precondition) and every buffer and the
    // view are live.
    unsafe { device.raw.update_descriptor_sets(&writes, &[]) };
}
