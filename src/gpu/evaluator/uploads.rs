//! What the kernels read besides the tuples, uploaded between calls: the material table
//! (rewritten in place each call) and the MERL tables of measured materials (kept in
//! device-local memory while consecutive batches use the same ones).

use super::state::VulkanBackend;
use crate::error::{Error, Result};
use crate::gpu::layout::{measured_tables, GpuMaterial};
use crate::gpu::memory::{Buffer, MemoryUse};
use crate::material::Material;
use ash::vk;

impl VulkanBackend {
    /// Copies the material table into its buffer (growing it when needed).
    /// Precondition: nothing is pending (true between and at the start of calls).
    pub(super) fn upload_materials(&mut self, table: &[GpuMaterial]) -> Result<()> {
        debug_assert!(self.slots.iter().all(|s| s.pending.is_none()));
        let bytes = std::mem::size_of_val(table) as u64;
        Buffer::ensure(&self.device, &mut self.materials, bytes, MemoryUse::Upload)?;
        // SAFETY: no submitted work is pending (precondition), so the device does not read
        // the table while it is rewritten.
        unsafe { self.materials.as_mut().expect("ensured").write(0, table) };
        Ok(())
    }

    /// Uploads the MERL tables of `materials` ([`measured_tables`]) unless the buffer holds
    /// exactly these already: a measured material costs one 17.5 MB upload per table, not
    /// one per batch. Precondition: nothing is pending.
    pub(super) fn upload_measured(&mut self, materials: &[Material]) -> Result<()> {
        debug_assert!(self.slots.iter().all(|s| s.pending.is_none()));
        let tables = measured_tables(materials);
        if !tables.is_empty() && !self.float64_frame() {
            return Err(Error::Unsupported(format!(
                "measured (MERL) materials need a device with 64-bit floats in shaders \
                 (shaderFloat64): the bin lookup takes the reference's angles in f64, and \
                 an f32 atan2 picks the neighbouring bin for about 1 tuple in 10^4; {} runs \
                 the f32 frame; use --backend cpu",
                self.device_name()
            )));
        }
        let same = tables.len() == self.merl_tables.len()
            && tables
                .iter()
                .zip(&self.merl_tables)
                .all(|(a, b)| std::sync::Arc::ptr_eq(a, b));
        if tables.is_empty() || same {
            return Ok(());
        }
        let per_table = 3 * crate::material::merl::SAMPLES;
        let bytes = (4 * per_table * tables.len()) as u64;
        // Device-local (VRAM on a discrete GPU), filled once through a staging buffer: every
        // lookup reads it, up to 24 reads per tuple with the linear lookup.
        self.merl = None;
        self.merl_tables.clear();
        let merl = Buffer::new(&self.device, bytes, MemoryUse::Resident)?;
        let mut staging = Buffer::new(&self.device, bytes, MemoryUse::Upload)?;
        for (t, table) in tables.iter().enumerate() {
            // SAFETY: a fresh host-visible buffer no submitted work uses.
            unsafe { staging.write((4 * per_table * t) as u64, &table.values_f32()) };
        }
        self.one_shot(|d, cmd| {
            let region = [vk::BufferCopy::default().size(bytes)];
            // The copy's writes made visible to the kernels' reads (later submissions).
            let barrier = [vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::SHADER_READ)];
            // SAFETY: recording into slot 0's command buffer (begun by `one_shot`); the
            // region lies inside both buffers (same size).
            unsafe {
                d.cmd_copy_buffer(cmd, staging.raw(), merl.raw(), &region);
                d.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::DependencyFlags::empty(),
                    &barrier,
                    &[],
                    &[],
                );
            }
        })?;
        self.merl = Some(merl);
        self.merl_uploads += tables.len() as u64;
        self.merl_tables = tables;
        Ok(())
    }
}
