//! [`VulkanBackend`]: the [`Backend`] that runs the GLSL kernel, streaming a batch through
//! a ring of [`FRAMES_IN_FLIGHT`] slots so host copies overlap device work.
//!
//! Per chunk: wait for the slot's previous chunk (fence), copy its results out, copy the
//! next rows in, record one dispatch, submit with the slot's fence. While the device works
//! on chunk `c`, the host is copying chunk `c + 1` in and chunk `c − 2` out.
//!
//! The struct, its slots and what the methods here and in the children share are in
//! `state`, the settings in `options`: the children use those, never this file.

mod folding;
mod generated;
mod grouping;
mod link;
mod options;
mod overlapped;
mod row_source;
mod state;
mod timing;
mod uploads;
pub use link::LinkRates;
pub use options::{validation_from_env, InjectedFault, VulkanOptions, FOLD_MATERIAL_MIN_TUPLES};
pub use state::{HostStages, VulkanBackend, FRAMES_IN_FLIGHT};
pub use timing::{KernelClock, KernelTiming};

use super::context::{Device, DeviceSelector, ValidationCounter};
use super::emulate_ftz::flush_to_zero_scope;
use super::host_copy::{self, HostCopy};
use super::kernel::{workgroups, Kernels, WORKGROUP_SIZE};
use super::layout::{gpu_materials, GpuCounts, GpuMaterial, PushConstants, BINDING_COUNT};
use super::memory::{Buffer, MemoryUse, TexelView};
use super::sync::{CommandPool, DescriptorPool, Fence};
use super::vk_error::vk_error;
use crate::backend::{Backend, Counts, Output, OverlappedStream, Request, TERM_COLUMNS};
use crate::batch::columns::ColumnBatch;
use crate::batch::{Batch, COLUMNS_TANGENT};
use crate::error::{Error, FailedChunk, Result};
use crate::features::FeatureSet;
use crate::material::Material;
use ash::vk;
use grouping::{bucket_order, gather_rows, read_in_place};
use row_source::RowSource;
use state::{write_set, Pending, Slot};

/// Upper bound on tuples per chunk (about 22 MiB of buffers per slot at the widest layout):
/// small enough that a million-tuple batch already streams in several overlapped chunks,
/// large enough that the per-dispatch cost (tens of µs) is noise.
pub const MAX_CHUNK_TUPLES: usize = 1 << 18;

/// Bytes one tuple can occupy in a slot at the widest layout: 13 input floats (tangents),
/// its place in the evaluation order (a u32), 3 BRDF floats, 6 term floats. Chunks are sized for it, so the slot buffers never exceed
/// the memory budget whatever mix of batches the backend sees.
const WORST_CASE_BYTES_PER_TUPLE: u64 = 4 * (COLUMNS_TANGENT + 1 + 3 + TERM_COLUMNS) as u64;

/// Bytes held by the backend's persistent buffers, per purpose (all slots together).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BufferBytes {
    /// Tuple input buffers.
    pub input: u64,
    /// BRDF output buffers.
    pub brdf: u64,
    /// Term output buffers (0 until some evaluation asks for terms).
    pub terms: u64,
    /// The material table.
    pub materials: u64,
}

impl BufferBytes {
    /// The sum.
    pub fn total(&self) -> u64 {
        self.input + self.brdf + self.terms + self.materials
    }
}

impl VulkanBackend {
    /// Opens a device — `selector`, else the `VKBRDF_DEVICE` environment variable, else the
    /// best one (discrete > integrated > virtual > CPU) — and creates the backend's
    /// persistent objects. Fails with [`Error::NoDevice`] when Vulkan is not installed or no
    /// device matches.
    pub fn new(
        selector: Option<DeviceSelector>,
        mut options: VulkanOptions,
    ) -> Result<VulkanBackend> {
        if options.inject_fault.is_none() {
            options.inject_fault = InjectedFault::from_env()?;
        }
        let device = flush_to_zero_scope(|| Device::new(selector.as_ref(), options.validation))?;
        let mut kernels = Kernels::new(&device, options.extra_defines.clone())?;
        let folded_per_invocation = options
            .folded_tuples_per_invocation
            .unwrap_or(1)
            .clamp(1, 4);
        kernels.folded_per_invocation = folded_per_invocation;
        let copy_threads = options.host_copy_threads.unwrap_or_else(|| {
            host_copy::default_threads(
                device.physical.properties.device_type == vk::PhysicalDeviceType::CPU,
            )
        });
        let commands = CommandPool::new(&device, FRAMES_IN_FLIGHT as u32)?;
        let descriptors = DescriptorPool::new(
            &device,
            kernels.set_layout(),
            BINDING_COUNT,
            FRAMES_IN_FLIGHT as u32,
        )?;
        let dummy = Buffer::new(&device, 16, MemoryUse::Readback)?;
        let mut slots = Vec::with_capacity(FRAMES_IN_FLIGHT);
        for i in 0..FRAMES_IN_FLIGHT {
            slots.push(Slot {
                input_view: None,
                input: None,
                order: None,
                brdf: None,
                terms: None,
                counts: Buffer::new(
                    &device,
                    std::mem::size_of::<GpuCounts>() as u64,
                    MemoryUse::Readback,
                )?,
                fence: Fence::new(&device)?,
                cmd: commands.buffers[i],
                set: descriptors.sets[i],
                bound: [0; BINDING_COUNT as usize],
                pending: None,
            });
        }
        Ok(VulkanBackend {
            slots,
            materials: None,
            merl: None,
            merl_tables: Vec::new(),
            merl_uploads: 0,
            dummy,
            _descriptors: descriptors,
            _commands: commands,
            kernels,
            last_features: None,
            last_folded: false,
            options,
            cancel: crate::cancel::Cancel::new(),
            shared_features: FeatureSet::EMPTY,
            stages: HostStages::default(),
            folded_per_invocation,
            host_copy: HostCopy::new(copy_threads),
            device,
        })
    }

    /// Host seconds per stage since the last [`reset_host_stages`](Self::reset_host_stages).
    pub fn host_stages(&self) -> HostStages {
        self.stages
    }

    /// Starts the [`HostStages`] sums again from zero.
    pub fn reset_host_stages(&mut self) {
        self.stages = HostStages::default();
    }

    /// How many MERL tables this backend has uploaded: each once while consecutive batches
    /// use the same tables.
    pub fn measured_uploads(&self) -> u64 {
        self.merl_uploads
    }

    /// The device's name (e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`).
    pub fn device_name(&self) -> String {
        self.device.physical.name()
    }

    /// Whether the device is a CPU implementation (lavapipe, SwiftShader).
    pub fn is_cpu_device(&self) -> bool {
        self.device.physical.properties.device_type == vk::PhysicalDeviceType::CPU
    }

    /// Whether the kernel computes its frame in f64 on this device (see
    /// `VKBRDF_DISABLE_FLOAT64`).
    pub fn float64_frame(&self) -> bool {
        self.device.physical.shader_float64
    }

    /// Whether the validation layer is active (asked for and installed).
    pub fn validation_enabled(&self) -> bool {
        self.device.instance.validation_enabled()
    }

    /// Validation-layer warnings and errors reported since the backend was created.
    pub fn validation_message_count(&self) -> u64 {
        self.device.instance.log.count()
    }

    /// The first (at most 32) validation messages, for reports.
    pub fn validation_messages(&self) -> Vec<String> {
        self.device.instance.log.messages()
    }

    /// A handle on the validation counter that stays valid after the backend is dropped,
    /// so messages emitted during destruction (leaked objects) can be checked too.
    pub fn validation_counter(&self) -> ValidationCounter {
        self.device.instance.counter()
    }

    /// The FeatureSet (and so the pipeline) the last evaluation ran with.
    pub fn last_features(&self) -> Option<FeatureSet> {
        self.last_features
    }

    /// How many pipelines this backend has created (each a kernel compile, unless a cache
    /// held it): a prepared `check` ([`Backend::prepare_kernels`]) creates none while it runs.
    pub fn pipelines_created(&self) -> u64 {
        self.kernels.created()
    }

    /// The SPIR-V of the kernel for `features` (compiled and cached on first use).
    pub fn spirv(&mut self, features: FeatureSet) -> Result<Vec<u32>> {
        self.kernels.spirv(features)
    }

    /// Bytes held by the persistent buffers now.
    pub fn buffer_bytes(&self) -> BufferBytes {
        let size = |b: &Option<Buffer>| b.as_ref().map_or(0, Buffer::size);
        let mut bytes = BufferBytes {
            materials: size(&self.materials),
            ..BufferBytes::default()
        };
        for s in &self.slots {
            bytes.input += size(&s.input);
            bytes.brdf += size(&s.brdf);
            bytes.terms += size(&s.terms);
        }
        bytes
    }

    /// Tuples per chunk for a material table of `material_count` rows: the memory budget
    /// over [`FRAMES_IN_FLIGHT`] slots at the widest tuple layout, capped by
    /// `maxStorageBufferRange` (one input buffer), the dispatch size limit and
    /// [`MAX_CHUNK_TUPLES`]; a multiple of the workgroup size when above it.
    pub fn chunk_tuples(&self, material_count: usize) -> Result<usize> {
        let limits = &self.device.physical.properties.limits;
        let table = (material_count * std::mem::size_of::<GpuMaterial>()) as u64;
        if table > u64::from(limits.max_storage_buffer_range) {
            return Err(Error::Unsupported(format!(
                "{material_count} materials need {table} bytes, over the device's maxStorageBufferRange of {} bytes",
                limits.max_storage_buffer_range
            )));
        }
        let fixed = table + 16 * (FRAMES_IN_FLIGHT as u64 + 1);
        let per_chunk_tuple = FRAMES_IN_FLIGHT as u64 * WORST_CASE_BYTES_PER_TUPLE;
        let by_memory = self.options.max_gpu_memory.saturating_sub(fixed) / per_chunk_tuple;
        let by_range = u64::from(limits.max_storage_buffer_range) / (4 * COLUMNS_TANGENT as u64);
        // The input is also viewed as RGBA32UI texels (4 words each, one spare at the end).
        let by_texels = (u64::from(limits.max_texel_buffer_elements).saturating_sub(1) * 4)
            / COLUMNS_TANGENT as u64;
        let by_dispatch =
            u64::from(limits.max_compute_work_group_count[0]) * u64::from(WORKGROUP_SIZE);
        let chunk = by_memory
            .min(by_range)
            .min(by_texels)
            .min(by_dispatch)
            .min(MAX_CHUNK_TUPLES as u64) as usize;
        if chunk == 0 {
            return Err(Error::Unsupported(format!(
                "max_gpu_memory = {} bytes cannot hold one tuple in each of the {FRAMES_IN_FLIGHT} frames in flight; allow at least {} bytes",
                self.options.max_gpu_memory,
                fixed + per_chunk_tuple
            )));
        }
        let wg = WORKGROUP_SIZE as usize;
        Ok(if chunk >= wg { chunk / wg * wg } else { chunk })
    }

    /// Evaluates with the kernel for `forced` ∪ what the batch needs (the tangent layout and
    /// the terms output still follow the batch and `request`): e.g. `FeatureSet::all()` runs
    /// the all-features kernel, the baseline of the specialisation measurement.
    pub fn evaluate_with_features(
        &mut self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
        forced: FeatureSet,
    ) -> Result<Output> {
        let features = self.grouping(Self::features_with(batch, materials, request, forced));
        self.run(RowSource::Rows(batch), materials, features)
    }

    /// Runs a probe shader — GLSL with `main()` that may `#include` the embedded files
    /// (`layout.glsl`, `math.glsl`, …) and use the kernel's bindings: `BINDING_TUPLES` holds
    /// `input` as `float[]`, `BINDING_MATERIALS` holds `materials`, and `BINDING_BRDF`
    /// receives `outputs` floats, which are returned. Push constant `tuple_count` is
    /// `outputs`; the workgroup size is specialization constant 0 and the dispatch covers
    /// `outputs` invocations. A testing aid: the layout round trip and the accuracy of the
    /// math helpers are measured with it.
    pub fn run_probe(
        &mut self,
        source: &str,
        materials: &[GpuMaterial],
        input: &[f32],
        outputs: usize,
    ) -> Result<Vec<f32>> {
        let pipeline = self.kernels.probe(source)?.raw();
        self.upload_materials(materials)?;
        let groups = outputs.div_ceil(WORKGROUP_SIZE as usize);
        if groups
            > self
                .device
                .physical
                .properties
                .limits
                .max_compute_work_group_count[0] as usize
        {
            return Err(Error::Unsupported(format!(
                "a probe of {outputs} outputs exceeds the dispatch limit"
            )));
        }
        let mut out = Output {
            brdf: vec![0.0; outputs],
            ..Output::default()
        };
        let result = (|| {
            self.prepare(0, input.len(), outputs, 0)?;
            let slot = &mut self.slots[0];
            // SAFETY: slot 0 has no pending work (nothing is pending between calls).
            unsafe {
                slot.input.as_mut().expect("prepared").write(0, input);
                slot.counts.write(0, &[GpuCounts::INITIAL]);
            }
            let pending = Pending {
                brdf: 0..outputs,
                terms: None,
                order: None,
                first_row: 0,
            };
            let push = PushConstants::rows(outputs as u32, materials.len() as u32, 0);
            self.submit(0, pipeline, push, pending, 1)?;
            self.finish(0, &mut out)
        })();
        result.inspect_err(|_| self.recover())?;
        Ok(out.brdf)
    }

    /// The features a call on `batch` gets: what it uses (with the shared ones, when
    /// [`Backend::share_kernels`] gave some), without `BUCKETED` when the options turn the
    /// grouping off. A call and a stream's chunk (`overlapped.rs`) take the same.
    fn batch_features(
        &self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
    ) -> FeatureSet {
        let features = if self.shared_features == FeatureSet::EMPTY {
            FeatureSet::of_batch(batch, materials, request)
        } else {
            Self::features_with(batch, materials, request, self.shared_features)
        };
        self.grouping(features)
    }

    /// `features` without `BUCKETED` when the options turn the grouping off.
    fn grouping(&self, features: FeatureSet) -> FeatureSet {
        if self.options.group_by_material {
            features
        } else {
            features.without(FeatureSet::BUCKETED)
        }
    }

    /// Evaluates `batch` with the pipeline for exactly `features`.
    fn run(
        &mut self,
        batch: RowSource,
        materials: &[Material],
        features: FeatureSet,
    ) -> Result<Output> {
        let n = batch.len();
        let terms = features.contains(FeatureSet::TERMS);
        let mut out = Output::zeroed(n, terms);
        self.last_features = Some(features);
        if n == 0 {
            return Ok(out);
        }
        let chunk = self.chunk_tuples(materials.len())?;
        // Before the pipeline: a device without f64 refuses measured materials here.
        self.upload_measured(materials)?;
        let gpu = gpu_materials(materials);
        let pipeline = (
            self.pipeline_for(features, (&gpu, materials), n)?,
            self.rows_per_invocation(),
        );
        self.upload_materials(&gpu)?;
        let bucketed = features.contains(FeatureSet::BUCKETED);
        self.stream(
            batch,
            materials.len() as u32,
            pipeline,
            (chunk, bucketed),
            terms,
            &mut out,
        )
        .inspect_err(|_| self.recover())?;
        Ok(out)
    }

    /// The chunk loop (see the module docs): `pipeline` and the rows an invocation of it
    /// takes.
    fn stream(
        &mut self,
        batch: RowSource,
        material_count: u32,
        (pipeline, per_invocation): (vk::Pipeline, u32),
        (chunk, bucketed): (usize, bool),
        terms: bool,
        out: &mut Output,
    ) -> Result<()> {
        let (n, cols) = (batch.len(), batch.columns());
        let mut scratch = Vec::new();
        let chunks = n.div_ceil(chunk);
        // A failure names the chunk it happened in (index, rows) and the memory budget.
        let max_gpu_memory = self.options.max_gpu_memory;
        let failed = |c: usize| FailedChunk {
            index: c as u64,
            count: chunks as u64,
            rows: (c * chunk) as u64..n.min((c + 1) * chunk) as u64,
            max_gpu_memory,
        };
        for c in 0..chunks {
            self.cancel.check()?;
            let s = c % FRAMES_IN_FLIGHT;
            // Slot `s` holds chunk `c − S`, if any.
            if let Some(done) = c.checked_sub(FRAMES_IN_FLIGHT) {
                self.finish_chunk(s, done, out)
                    .map_err(|e| e.in_chunk(failed(done)))?;
            }
            let (start, len) = (c * chunk, chunk.min(n - c * chunk));
            let rows = batch.rows(start..start + len, &mut scratch);
            let pending = self
                .load_chunk(s, rows, cols, material_count as usize, bucketed, terms)
                .map(|order| Pending {
                    brdf: start * 3..(start + len) * 3,
                    terms: terms.then(|| start * TERM_COLUMNS..(start + len) * TERM_COLUMNS),
                    first_row: start as u64,
                    order,
                })
                .map_err(|e| e.in_chunk(failed(c)))?;
            let push = PushConstants::rows(len as u32, material_count, start as u32);
            self.submit(s, pipeline, push, pending, per_invocation)
                .map_err(|e| e.in_chunk(failed(c)))?;
        }
        // Drain in submission order: the oldest pending chunk sits in slot `chunks % S`.
        for done in chunks.saturating_sub(FRAMES_IN_FLIGHT)..chunks {
            self.finish_chunk(done % FRAMES_IN_FLIGHT, done, out)
                .map_err(|e| e.in_chunk(failed(done)))?;
        }
        Ok(())
    }

    /// [`finish`](Self::finish) of slot `s`, which holds chunk `c` of a batch; then the
    /// [`InjectedFault`] for chunk `c`, if one is set.
    fn finish_chunk(&mut self, s: usize, c: usize, out: &mut Output) -> Result<()> {
        self.finish(s, out)?;
        match self.options.inject_fault {
            Some(fault) if fault.chunk == c => Err(vk_error("vkWaitForFences")(fault.result)),
            _ => Ok(()),
        }
    }

    /// Loads `rows` (`cols` floats each) into slot `s` — grouped by material when
    /// `bucketed`, with its order — sizes the outputs (terms too when `terms`) and resets
    /// the counts. Returns the order the rows went in, if grouped. Precondition: slot `s`
    /// is not pending.
    fn load_chunk(
        &mut self,
        s: usize,
        rows: &[f32],
        cols: usize,
        material_count: usize,
        bucketed: bool,
        terms: bool,
    ) -> Result<Option<Vec<u32>>> {
        let started = std::time::Instant::now();
        let len = rows.len() / cols;
        let order = bucketed.then(|| bucket_order(rows, cols, material_count));
        let grouped = order.as_ref().map(|o| gather_rows(rows, cols, o));
        self.prepare_with_order(
            s,
            rows.len(),
            len * 3,
            if terms { len * TERM_COLUMNS } else { 0 },
            order.as_ref().map_or(0, Vec::len),
        )?;
        let slot = &mut self.slots[s];
        // SAFETY: slot `s` is not pending (precondition), so the device neither reads nor
        // writes its buffers.
        unsafe {
            let input: &[u8] = bytemuck::cast_slice(grouped.as_deref().unwrap_or(rows));
            let mapped = slot
                .input
                .as_mut()
                .expect("prepared")
                .mapped_mut(input.len());
            self.host_copy.copy(mapped, input);
            if let Some(order) = &order {
                slot.order.as_mut().expect("prepared").write(0, order);
            }
            slot.counts.write(0, &[GpuCounts::INITIAL]);
        }
        self.stages.upload_s += started.elapsed().as_secs_f64();
        Ok(order)
    }

    /// Grows slot `s`'s buffers to the given float counts and points its descriptor set at
    /// the current buffers. Precondition: slot `s` is not pending.
    fn prepare(
        &mut self,
        s: usize,
        input_floats: usize,
        brdf_floats: usize,
        terms_floats: usize,
    ) -> Result<()> {
        self.prepare_with_order(s, input_floats, brdf_floats, terms_floats, 0)
    }

    /// [`prepare`](Self::prepare) with an order buffer of `order_len` u32s (0: none).
    fn prepare_with_order(
        &mut self,
        s: usize,
        input_floats: usize,
        brdf_floats: usize,
        terms_floats: usize,
        order_len: usize,
    ) -> Result<()> {
        let slot = &mut self.slots[s];
        debug_assert!(slot.pending.is_none());
        // Whole RGBA32UI texels, so the texel view covers every input float.
        let input_bytes = (4 * input_floats as u64).div_ceil(16) * 16;
        if slot.input.as_ref().is_none_or(|b| b.size() < input_bytes) {
            slot.input_view = None; // the view goes before the buffer it views
        }
        Buffer::ensure(
            &self.device,
            &mut slot.input,
            input_bytes,
            MemoryUse::Upload,
        )?;
        let input = slot.input.as_ref().expect("ensured");
        if slot.input_view.as_ref().map(TexelView::buffer_id) != Some(input.id()) {
            slot.input_view = None;
            slot.input_view = Some(TexelView::new(&self.device, input)?);
        }
        Buffer::ensure(
            &self.device,
            &mut slot.brdf,
            4 * brdf_floats as u64,
            MemoryUse::Readback,
        )?;
        if terms_floats > 0 {
            Buffer::ensure(
                &self.device,
                &mut slot.terms,
                4 * terms_floats as u64,
                MemoryUse::Readback,
            )?;
        }
        if order_len > 0 {
            Buffer::ensure(
                &self.device,
                &mut slot.order,
                4 * order_len as u64,
                MemoryUse::Upload,
            )?;
        }
        let materials = self
            .materials
            .as_ref()
            .expect("materials are uploaded before any slot is prepared");
        let wanted: [&Buffer; BINDING_COUNT as usize] = [
            slot.input.as_ref().expect("ensured"),
            materials,
            slot.brdf.as_ref().expect("ensured"),
            slot.terms.as_ref().unwrap_or(&self.dummy),
            &slot.counts,
            // BINDING_TUPLE_TEXELS: the input again, through its view (written below).
            slot.input.as_ref().expect("ensured"),
            slot.order.as_ref().unwrap_or(&self.dummy),
            self.merl.as_ref().unwrap_or(&self.dummy),
        ];
        let ids = wanted.map(Buffer::id);
        if ids != slot.bound {
            let view = slot.input_view.as_ref().expect("created above");
            // Precondition of this function: the set is not used by pending work.
            write_set(&self.device, slot.set, &wanted, view);
            slot.bound = ids;
        }
        Ok(())
    }

    /// Records and submits one dispatch over `push.tuple_count` rows on slot `s`,
    /// `per_invocation` rows an invocation (the evaluation kernel's
    /// [`VulkanOptions::folded_tuples_per_invocation`] for a folded kernel; 1 for the others).
    fn submit(
        &mut self,
        s: usize,
        pipeline: vk::Pipeline,
        push: PushConstants,
        pending: Pending,
        per_invocation: u32,
    ) -> Result<()> {
        let (d, layout) = (&self.device.raw, self.kernels.layout());
        let slot = &mut self.slots[s];
        let cmd = slot.cmd;
        let groups = workgroups(push.tuple_count, per_invocation);
        // Results must be visible to host reads after the fence: compute writes → host reads.
        let barrier = [vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::SHADER_WRITE)
            .dst_access_mask(vk::AccessFlags::HOST_READ)];
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the command buffer is not pending (the slot's fence was waited), its pool
        // allows per-buffer reset (begin resets it), and every handle recorded is live.
        unsafe {
            d.begin_command_buffer(cmd, &begin)
                .map_err(vk_error("vkBeginCommandBuffer"))?;
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipeline);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                layout,
                0,
                &[slot.set],
                &[],
            );
            d.cmd_push_constants(
                cmd,
                layout,
                vk::ShaderStageFlags::COMPUTE,
                0,
                bytemuck::bytes_of(&push),
            );
            d.cmd_dispatch(cmd, groups, 1, 1);
            d.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &barrier,
                &[],
                &[],
            );
            d.end_command_buffer(cmd)
                .map_err(vk_error("vkEndCommandBuffer"))?;
        }
        let cmds = [cmd];
        let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
        // SAFETY: the command buffer is fully recorded, the fence is unsignalled and unused
        // (reset after its last wait), and the host writes to the slot's mapped buffers
        // happen-before this call (submission makes them visible to the device).
        unsafe { d.queue_submit(self.device.queue, &submit, slot.fence.raw()) }
            .map_err(vk_error("vkQueueSubmit"))?;
        slot.pending = Some(pending);
        Ok(())
    }

    /// If slot `s` has a chunk in flight: waits for it and copies its results into `out`.
    fn finish(&mut self, s: usize, out: &mut Output) -> Result<()> {
        let Some(p) = self.slots[s].pending.take() else {
            return Ok(());
        };
        let slot = &self.slots[s];
        let started = std::time::Instant::now();
        slot.fence.wait_and_reset()?;
        let waited = started.elapsed();
        let mut counts = [GpuCounts::INITIAL];
        // SAFETY: the fence is signalled, so the dispatch and its compute→host barrier have
        // completed: the buffers hold final, host-visible results and nothing writes them.
        unsafe {
            let brdf = slot.brdf.as_ref().expect("prepared");
            let (order, copy) = (p.order.as_deref(), &self.host_copy);
            read_in_place(brdf, &mut out.brdf[p.brdf.clone()], 3, order, copy);
            if let (Some(range), Some(terms)) = (p.terms.clone(), out.terms.as_mut()) {
                let buffer = slot.terms.as_ref().expect("prepared with terms");
                read_in_place(buffer, &mut terms[range], TERM_COLUMNS, order, copy);
            }
            slot.counts.read(0, &mut counts);
        }
        self.stages.wait_s += waited.as_secs_f64();
        self.stages.readback_s += (started.elapsed() - waited).as_secs_f64();
        self.stages.chunks += 1;
        let c = counts[0];
        out.counts.absorb(&Counts {
            tuples: 0,
            invalid: u64::from(c.invalid),
            below_horizon: u64::from(c.below_horizon),
            saturated: u64::from(c.saturated),
            // u32::MAX: no invalid tuple in this chunk (GpuCounts::INITIAL).
            first_invalid: (c.first_invalid != u32::MAX)
                .then(|| p.first_row + u64::from(c.first_invalid)),
        });
        Ok(())
    }

    /// After an error mid-stream: waits for the device, then forgets pending chunks and
    /// resets fences and command buffers, so the next call starts clean.
    fn recover(&mut self) {
        self.device.wait_idle();
        for slot in &mut self.slots {
            slot.pending = None;
            slot.fence.reset();
            // SAFETY: the device is idle, so the command buffer is not pending.
            let _ = unsafe {
                self.device
                    .raw
                    .reset_command_buffer(slot.cmd, vk::CommandBufferResetFlags::empty())
            };
        }
    }
}

impl Backend for VulkanBackend {
    fn name(&self) -> String {
        format!("vulkan: {}", self.device_name())
    }

    fn set_cancel(&mut self, cancel: crate::cancel::Cancel) {
        self.cancel = cancel;
    }

    fn evaluate(
        &mut self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
    ) -> Result<Output> {
        let features = self.batch_features(batch, materials, request);
        self.run(RowSource::Rows(batch), materials, features)
    }

    fn evaluate_columns_into(
        &mut self,
        batch: &ColumnBatch,
        materials: &[Material],
        request: &Request,
        out: &mut Output,
    ) -> Result<()> {
        let features = FeatureSet::of_columns(batch, materials, request);
        let features = self.grouping(features.with_forced(self.shared_features));
        *out = self.run(RowSource::Columns(batch), materials, features)?;
        Ok(())
    }

    fn overlapped<'a>(
        &'a mut self,
        materials: &'a [Material],
        request: Request,
        total_rows: u64,
    ) -> Result<Box<dyn OverlappedStream + 'a>> {
        let stream = overlapped::VulkanStream::new(self, materials, request, total_rows)?;
        Ok(Box::new(stream))
    }

    fn share_kernels(&mut self, materials: &[Material]) {
        self.shared_features = FeatureSet::of_materials(materials);
    }

    fn prepare_kernels(&mut self, plans: &[crate::backend::KernelPlan<'_>]) -> Result<()> {
        // The feature sets `evaluate` will pick for these batches (`FeatureSet::of_batch`,
        // the shared features, the grouping).
        let sets: Vec<FeatureSet> = plans
            .iter()
            .map(|p| {
                let used = FeatureSet::of_used_all(p.materials, p.tangents, &p.request);
                self.grouping(used.with_forced(FeatureSet::of_materials(p.shared)))
            })
            .collect();
        self.kernels.prepare(&sets)
    }

    fn generated_directions(&mut self) -> Option<&mut dyn crate::backend::GeneratedDirections> {
        Some(self)
    }
}
