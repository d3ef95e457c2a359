//! Kernel-only timing for `vkbrdf bench`: the tuples are copied once into device-local
//! memory (VRAM on a discrete GPU), as an application whose data already lives on the GPU
//! would have them, and the dispatches are timed on the device with timestamp queries
//! (fences around the whole submission where the queue has no timestamps). A fence per small
//! dispatch would time the driver's round trip, not the kernel: a data-centre GPU evaluates
//! millions of tuples in the time one fence wait takes.
//!
//! The same machinery times a copy kernel that reads the bytes a tuple row holds and writes
//! three floats: the device's ceiling for the bytes the BRDF kernel moves.

use super::grouping::{bucket_order, gather_rows};
use super::state::{write_set, VulkanBackend};
use crate::backend::{Request, TERM_COLUMNS};
use crate::batch::Batch;
use crate::error::{Error, Result};
use crate::features::FeatureSet;
use crate::gpu::kernel::{workgroups, WORKGROUP_SIZE};
use crate::gpu::layout::{gpu_materials, GpuCounts, PushConstants, BINDING_COUNT};
use crate::gpu::memory::{Buffer, MemoryUse, TexelView};
use crate::gpu::sync::TimestampPool;
use crate::gpu::vk_error::vk_error;
use crate::material::Material;
use ash::vk;
use std::sync::Arc;
use std::time::Instant;

/// How a [`KernelTiming`] was clocked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum KernelClock {
    /// Device timestamps written before the first and after the last dispatch.
    Timestamps,
    /// Host wall time from submission to the fence (the queue has no timestamps).
    Fence,
}

/// What one kernel-only timing measured.
#[derive(Debug, Clone)]
pub struct KernelTiming {
    /// Median seconds for the requested number of tuples.
    pub seconds: f64,
    /// Tuples resident on the device: one dispatch covers them, and more tuples are timed
    /// as repeated dispatches over the same rows.
    pub resident_tuples: usize,
    /// Dispatches per timed run.
    pub dispatches: usize,
    /// Bytes each tuple reads (its row) and writes (RGB, plus the terms when asked for).
    pub bytes_per_tuple: usize,
    /// How the time was measured.
    pub clock: KernelClock,
    /// The BRDF of the resident tuples, `resident_tuples × 3`, from the last timed run
    /// (empty for the copy kernel): what the resident path computed, for comparison with
    /// [`Backend::evaluate`](crate::backend::Backend::evaluate).
    pub brdf: Vec<f32>,
}

/// The copy kernel: each invocation reads its row of `COLUMNS` floats from the storage
/// binding and writes three floats that depend on every one of them (so nothing is
/// optimised away): the same bytes in and out as the BRDF kernel, no arithmetic to speak of.
const COPY_KERNEL: &str = r#"#version 450
#include "layout.glsl"
layout(local_size_x_id = 0) in;
layout(std430, set = 0, binding = BINDING_TUPLES) readonly buffer In { float rows[]; };
layout(std430, set = 0, binding = BINDING_BRDF) writeonly buffer Out { float outp[]; };
layout(push_constant) uniform P { uint count; } p;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= p.count) { return; }
    vec3 s = vec3(0.0);
    for (uint k = 0u; k < COLUMNS; k++) {
        s[k % 3u] += rows[i * COLUMNS + k];
    }
    outp[3u * i] = s.x;
    outp[3u * i + 1u] = s.y;
    outp[3u * i + 2u] = s.z;
}
"#;

/// Untimed warm-up before a kernel timing: this long (see `time_resident`) …
const WARM_UP_SECONDS: f64 = 0.1;
/// … but no more runs than this (a slow device reaches the time in a few).
const MAX_WARM_UPS: usize = 50;

impl VulkanBackend {
    /// The kernel features for `batch` and `request`, widened by `forced` (the tangent
    /// layout and the terms output always follow the batch and the request).
    pub(super) fn features_with(
        batch: &Batch,
        materials: &[Material],
        request: &Request,
        forced: FeatureSet,
    ) -> FeatureSet {
        FeatureSet::of_batch(batch, materials, request).with_forced(forced)
    }

    /// Median seconds to evaluate `batch` with its tuples resident in device memory (kernel
    /// only), over `repeats` timed runs after a warm-up. See [`kernel_timing`](Self::kernel_timing).
    pub fn kernel_seconds(
        &mut self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
        repeats: usize,
    ) -> Result<f64> {
        self.kernel_seconds_with_features(batch, materials, request, repeats, FeatureSet::EMPTY)
    }

    /// [`kernel_seconds`](Self::kernel_seconds) with the kernel for `forced` ∪ what the
    /// batch needs (e.g. `FeatureSet::all()` for the all-features baseline).
    pub fn kernel_seconds_with_features(
        &mut self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
        repeats: usize,
        forced: FeatureSet,
    ) -> Result<f64> {
        let t = self.kernel_timing(batch, materials, request, batch.len(), repeats, forced)?;
        Ok(t.seconds)
    }

    /// The most tuples of `columns` floats one resident dispatch may cover: the storage
    /// range, the texel-buffer size and the dispatch size limits (no memory budget: the
    /// resident buffers are the bench's own, freed when it returns).
    pub fn resident_capacity(&self, columns: usize) -> usize {
        let limits = &self.device.physical.properties.limits;
        let by_range = u64::from(limits.max_storage_buffer_range) / (4 * columns as u64);
        let by_texels =
            (u64::from(limits.max_texel_buffer_elements).saturating_sub(1) * 4) / columns as u64;
        let by_dispatch =
            u64::from(limits.max_compute_work_group_count[0]) * u64::from(WORKGROUP_SIZE);
        // u32 push constants count the rows of a dispatch.
        by_range
            .min(by_texels)
            .min(by_dispatch)
            .min(u64::from(u32::MAX))
            .max(1) as usize
    }

    /// Times the kernel `batch` needs (∪ `forced`) on `total` tuples: the batch's first
    /// [`resident_capacity`](Self::resident_capacity) tuples are copied into device-local
    /// memory once, and `total` is covered by repeated dispatches over them, recorded in one
    /// command buffer. Median of `repeats` timed runs after a warm-up.
    pub fn kernel_timing(
        &mut self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
        total: usize,
        repeats: usize,
        forced: FeatureSet,
    ) -> Result<KernelTiming> {
        let cols = batch.columns();
        let n = batch.len().min(self.resident_capacity(cols));
        if n == 0 {
            return Err(Error::Unsupported(
                "kernel timing needs a non-empty batch".into(),
            ));
        }
        let features = self.grouping(Self::features_with(batch, materials, request, forced));
        let gpu = gpu_materials(materials);
        let pipeline = self.pipeline_for(features, (&gpu, materials), total)?;
        let per_invocation = self.rows_per_invocation();
        self.upload_materials(&gpu)?;
        let rows = &batch.as_slice()[..n * cols];
        // Grouping by material is host work done once here (the end-to-end timing has it).
        let order = features
            .contains(FeatureSet::BUCKETED)
            .then(|| bucket_order(rows, cols, materials.len()));
        let grouped = order.as_ref().map(|o| gather_rows(rows, cols, o));
        let terms = features.contains(FeatureSet::TERMS);
        let run = Resident {
            rows: grouped.as_deref().unwrap_or(rows),
            columns: cols,
            order: order.as_deref(),
            terms,
            material_count: materials.len(),
            per_invocation,
        };
        let mut timing = self.time_resident(pipeline, &run, total, repeats, true)?;
        timing.bytes_per_tuple = 4 * (cols + 3 + if terms { TERM_COLUMNS } else { 0 });
        Ok(timing)
    }

    /// Times the copy kernel (rows of `columns` floats in, three floats out) on `total`
    /// tuples, `resident` of them in device-local memory, as
    /// [`kernel_timing`](Self::kernel_timing) does: the device's bandwidth ceiling for the
    /// bytes the BRDF kernel moves.
    pub fn copy_timing(
        &mut self,
        columns: usize,
        resident: usize,
        total: usize,
        repeats: usize,
    ) -> Result<KernelTiming> {
        let n = resident.min(self.resident_capacity(columns)).max(1);
        let source = COPY_KERNEL.replace(
            "layout(local_size_x_id = 0) in;",
            &format!("layout(local_size_x_id = 0) in;\nconst uint COLUMNS = {columns}u;"),
        );
        let pipeline = self.kernels.probe(&source)?.raw();
        self.upload_materials(&[bytemuck::Zeroable::zeroed()])?;
        let rows: Vec<f32> = (0..n * columns).map(|i| (i % 7) as f32).collect();
        let run = Resident {
            rows: &rows,
            columns,
            order: None,
            terms: false,
            material_count: 1,
            per_invocation: 1,
        };
        let mut timing = self.time_resident(pipeline, &run, total, repeats, false)?;
        timing.bytes_per_tuple = 4 * (columns + 3);
        Ok(timing)
    }

    /// Copies `run` into device-local buffers, binds them to slot 0 and times `pipeline`
    /// over `total` tuples; reads the BRDF back when `read_back`.
    fn time_resident(
        &mut self,
        pipeline: vk::Pipeline,
        run: &Resident,
        total: usize,
        repeats: usize,
        read_back: bool,
    ) -> Result<KernelTiming> {
        let n = run.rows.len() / run.columns;
        let dev = Arc::clone(&self.device);
        // Declared before the work that uses them, so that on an error `recover` (which waits
        // for the device) runs before they are dropped.
        let input = Buffer::new(
            &dev,
            (4 * run.rows.len() as u64).div_ceil(16) * 16,
            MemoryUse::Resident,
        )?;
        let view = TexelView::new(&dev, &input)?;
        let brdf = Buffer::new(&dev, 12 * n as u64, MemoryUse::Resident)?;
        let terms = if run.terms {
            Some(Buffer::new(
                &dev,
                4 * (n * TERM_COLUMNS) as u64,
                MemoryUse::Resident,
            )?)
        } else {
            None
        };
        let order = match run.order {
            Some(o) => Some(Buffer::new(&dev, 4 * o.len() as u64, MemoryUse::Resident)?),
            None => None,
        };
        let mut staging = Buffer::new(&dev, input.size(), MemoryUse::Upload)?;
        let mut order_staging = match run.order {
            Some(o) => Some(Buffer::new(&dev, 4 * o.len() as u64, MemoryUse::Upload)?),
            None => None,
        };
        let pool = if dev.physical.timestamp_bits > 0 {
            Some(TimestampPool::new(&dev, 2)?)
        } else {
            None
        };
        let result = (|| {
            // SAFETY: fresh host-visible buffers that no submitted work uses yet.
            unsafe {
                staging.write(0, run.rows);
                if let (Some(b), Some(o)) = (order_staging.as_mut(), run.order) {
                    b.write(0, o);
                }
            }
            self.one_shot(|d, cmd| {
                // SAFETY: recording into slot 0's command buffer (begun by `one_shot`); the
                // regions lie inside both buffers (sizes made from the same lengths).
                unsafe {
                    d.cmd_copy_buffer(
                        cmd,
                        staging.raw(),
                        input.raw(),
                        &[vk::BufferCopy::default().size(input.size())],
                    );
                    if let (Some(src), Some(dst)) = (&order_staging, &order) {
                        let region = vk::BufferCopy::default().size(dst.size());
                        d.cmd_copy_buffer(cmd, src.raw(), dst.raw(), &[region]);
                    }
                }
            })?;
            let materials = self.materials.as_ref().expect("uploaded by the caller");
            let wanted: [&Buffer; BINDING_COUNT as usize] = [
                &input,
                materials,
                &brdf,
                terms.as_ref().unwrap_or(&self.dummy),
                &self.slots[0].counts,
                &input,
                order.as_ref().unwrap_or(&self.dummy),
                self.merl.as_ref().unwrap_or(&self.dummy),
            ];
            let ids = wanted.map(Buffer::id);
            // Slot 0 has no work in flight between calls, and `one_shot` waited for its own
            // submission: the set may be rewritten. Its `bound` ids make the next `prepare`
            // point it back at the slot's own buffers.
            write_set(&self.device, self.slots[0].set, &wanted, &view);
            self.slots[0].bound = ids;
            let dispatches = total.max(1).div_ceil(n);
            let push = PushConstants::rows(n as u32, run.material_count as u32, 0);
            let mut secs = Vec::with_capacity(repeats + 1);
            let mut clock = KernelClock::Fence;
            // Warm-up runs until WARM_UP_SECONDS have passed (at least one; at most
            // MAX_WARM_UPS): a GPU idles at a fraction of its clock and ramps up under load
            // (an H200 reads 345 MHz idle, 1980 MHz busy), and a few milliseconds of
            // timed work alone measured the ramp (copy-kernel rates of 1.2 to 3.9 TB/s for
            // the same kernel in one run).
            let warm_up = Instant::now();
            let mut runs = 0;
            loop {
                runs += 1;
                let warm = runs > MAX_WARM_UPS
                    || (runs > 1 && warm_up.elapsed().as_secs_f64() >= WARM_UP_SECONDS);
                if warm && secs.len() >= repeats.max(1) {
                    break;
                }
                // SAFETY: slot 0 is idle (the previous `one_shot` waited); the device does
                // not touch `counts` now.
                unsafe { self.slots[0].counts.write(0, &[GpuCounts::INITIAL]) };
                let start = Instant::now();
                let (layout, set) = (self.kernels.layout(), self.slots[0].set);
                self.one_shot(|d, cmd| {
                    record_dispatches(
                        d,
                        cmd,
                        layout,
                        pipeline,
                        set,
                        (push, run.per_invocation),
                        dispatches,
                        pool.as_ref(),
                    )
                })?;
                let wall = start.elapsed().as_secs_f64();
                let device_secs = match &pool {
                    Some(p) => {
                        let t = p.results()?;
                        let bits = dev.physical.timestamp_bits;
                        let mask = if bits >= 64 {
                            u64::MAX
                        } else {
                            (1u64 << bits) - 1
                        };
                        let ticks = t[1].wrapping_sub(t[0]) & mask;
                        let period = f64::from(dev.physical.properties.limits.timestamp_period);
                        Some(ticks as f64 * period * 1e-9)
                    }
                    None => None,
                };
                // A zero or absurd device interval (a driver that writes no real clock)
                // falls back to the wall time, which bounds it from above.
                let s = match device_secs {
                    Some(s) if s > 0.0 && s <= wall => {
                        clock = KernelClock::Timestamps;
                        s
                    }
                    _ => {
                        clock = KernelClock::Fence;
                        wall
                    }
                };
                if warm {
                    secs.push(s * total.max(1) as f64 / (dispatches * n) as f64);
                }
            }
            let mut out = Vec::new();
            if read_back {
                let grouped = self.read_resident(&brdf, 3 * n)?;
                out = match run.order {
                    // The kernel wrote row i of the grouped upload; it is the batch's order[i].
                    Some(order) => {
                        let mut placed = vec![0f32; 3 * n];
                        for (src, &dst) in grouped.chunks_exact(3).zip(order) {
                            placed[3 * dst as usize..3 * dst as usize + 3].copy_from_slice(src);
                        }
                        placed
                    }
                    None => grouped,
                };
            }
            Ok(KernelTiming {
                seconds: crate::stats::median(secs),
                resident_tuples: n,
                dispatches,
                bytes_per_tuple: 0,
                clock,
                brdf: out,
            })
        })();
        result.inspect_err(|_| self.recover())
    }

    /// `floats` floats from the start of device-local `buffer`, through a staging copy.
    fn read_resident(&mut self, buffer: &Buffer, floats: usize) -> Result<Vec<f32>> {
        let staging = Buffer::new(&self.device, 4 * floats as u64, MemoryUse::Readback)?;
        self.copy(buffer, &staging, 4 * floats as u64)?;
        let mut out = vec![0f32; floats];
        // SAFETY: `copy` waited for the copy, whose barrier made it visible to the host.
        unsafe { staging.read(0, &mut out) };
        Ok(out)
    }

    /// Records `record` into slot 0's command buffer, submits it and waits for it.
    /// Precondition: slot 0 has no work in flight.
    pub(super) fn one_shot(
        &self,
        record: impl FnOnce(&ash::Device, vk::CommandBuffer),
    ) -> Result<()> {
        let d = &self.device.raw;
        let slot = &self.slots[0];
        debug_assert!(slot.pending.is_none());
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the command buffer is not pending (precondition; every earlier one-shot
        // waited for its fence), and its pool allows per-buffer reset.
        unsafe { d.begin_command_buffer(slot.cmd, &begin) }
            .map_err(vk_error("vkBeginCommandBuffer"))?;
        record(d, slot.cmd);
        // SAFETY: recording began above.
        unsafe { d.end_command_buffer(slot.cmd) }.map_err(vk_error("vkEndCommandBuffer"))?;
        let cmds = [slot.cmd];
        let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
        // SAFETY: the command buffer is fully recorded; the fence is unsignalled and unused
        // (reset by its last wait); host writes to mapped buffers precede the submission.
        unsafe { d.queue_submit(self.device.queue, &submit, slot.fence.raw()) }
            .map_err(vk_error("vkQueueSubmit"))?;
        slot.fence.wait_and_reset()
    }
}

/// The rows of a resident timing run.
struct Resident<'a> {
    /// Row-major rows of `columns` floats (already grouped by material when `order` is set).
    rows: &'a [f32],
    columns: usize,
    /// The kernel's `order[]` (BUCKETED kernels).
    order: Option<&'a [u32]>,
    /// Whether the kernel writes the terms.
    terms: bool,
    material_count: usize,
    /// Rows an invocation takes (the evaluation kernel's `tuples_per_invocation`; the copy
    /// kernel 1).
    per_invocation: u32,
}

/// Records `dispatches` dispatches of `pipeline` over `push.tuple_count` rows
/// (`per_invocation` rows an invocation), bracketed by timestamps 0 and 1 of `pool` when
/// there is one.
#[allow(clippy::too_many_arguments)]
fn record_dispatches(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    set: vk::DescriptorSet,
    (push, per_invocation): (PushConstants, u32),
    dispatches: usize,
    pool: Option<&TimestampPool>,
) {
    let groups = workgroups(push.tuple_count, per_invocation);
    // Each dispatch rewrites the same outputs: order them (write → write), as a real
    // sequence of dependent batches would be, rather than let them overlap.
    let between = [vk::MemoryBarrier::default()
        .src_access_mask(vk::AccessFlags::SHADER_WRITE)
        .dst_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::SHADER_READ)];
    // SAFETY: recording into a begun command buffer; every handle is live for the
    // submission (owned by the backend or by `time_resident`'s locals, dropped after it).
    unsafe {
        d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipeline);
        d.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, layout, 0, &[set], &[]);
        d.cmd_push_constants(
            cmd,
            layout,
            vk::ShaderStageFlags::COMPUTE,
            0,
            bytemuck::bytes_of(&push),
        );
        if let Some(p) = pool {
            d.cmd_reset_query_pool(cmd, p.raw(), 0, 2);
            d.cmd_write_timestamp(cmd, vk::PipelineStageFlags::TOP_OF_PIPE, p.raw(), 0);
        }
        for i in 0..dispatches {
            if i > 0 {
                d.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::DependencyFlags::empty(),
                    &between,
                    &[],
                    &[],
                );
            }
            d.cmd_dispatch(cmd, groups, 1, 1);
        }
        if let Some(p) = pool {
            d.cmd_write_timestamp(cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, p.raw(), 1);
        }
    }
}
