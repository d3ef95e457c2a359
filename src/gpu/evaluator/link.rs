//! The host↔device copy rates: the ceilings of the streamed path's upload and readback
//! stages (`vkbrdf bench`'s stage table, issue 31). Two figures each way: the host's own
//! copy into (out of) the mapped buffers the evaluator fills (what its upload and readback
//! stages do), and a transfer command between a mapped buffer and a device-local one (the
//! link: PCIe on a discrete GPU, a `memcpy` on a CPU device).

use super::state::VulkanBackend;
use crate::error::Result;
use crate::gpu::memory::{Buffer, MemoryUse};
use crate::stats::median;
use ash::vk;
use std::time::Instant;

/// Copy rates in bytes per second (medians of the repeats).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct LinkRates {
    /// The host writing a mapped upload buffer (`memcpy` into the mapping).
    pub host_to_mapped: f64,
    /// The host reading a mapped readback buffer (`memcpy` out of the mapping).
    pub mapped_to_host: f64,
    /// A transfer command from a mapped buffer into device-local memory.
    pub host_to_device: f64,
    /// A transfer command from device-local memory into a mapped buffer.
    pub device_to_host: f64,
    /// Threads the host's copies are split over, as the evaluator splits them
    /// ([`VulkanOptions::host_copy_threads`](crate::gpu::VulkanOptions::host_copy_threads)).
    pub copy_threads: usize,
}

impl VulkanBackend {
    /// Measures [`LinkRates`] on `bytes` bytes (at most the backend's memory budget's
    /// quarter), each copy `repeats` times.
    pub fn link_rates(&mut self, bytes: u64, repeats: usize) -> Result<LinkRates> {
        let bytes = bytes.min(self.options.max_gpu_memory / 4).max(1 << 16) & !15;
        let mut upload = Buffer::new(&self.device, bytes, MemoryUse::Upload)?;
        let readback = Buffer::new(&self.device, bytes, MemoryUse::Readback)?;
        let resident = Buffer::new(&self.device, bytes, MemoryUse::Resident)?;
        let host: Vec<u32> = (0..bytes / 4).map(|i| i as u32).collect();
        let mut back = vec![0u32; host.len()];
        let mut times = [Vec::new(), Vec::new(), Vec::new(), Vec::new()];
        // One untimed round first: the pages of every buffer faulted in.
        for round in 0..=repeats.max(1) {
            let t = Instant::now();
            // The host's copies split over threads as the evaluator's stages split them.
            let (bytes_in, len) = (bytemuck::cast_slice(&host), 4 * host.len());
            // SAFETY: no submitted work uses `upload` (every one-shot below waited).
            let mapped = unsafe { upload.mapped_mut(len) };
            self.host_copy.copy(mapped, bytes_in);
            let host_to_mapped = t.elapsed().as_secs_f64();
            let t = Instant::now();
            self.copy(&upload, &resident, bytes)?;
            let host_to_device = t.elapsed().as_secs_f64();
            let t = Instant::now();
            self.copy(&resident, &readback, bytes)?;
            let device_to_host = t.elapsed().as_secs_f64();
            let t = Instant::now();
            // SAFETY: the copy above was waited for, and its barrier made it host-visible.
            let mapped = unsafe { readback.mapped(len) };
            self.host_copy
                .copy(bytemuck::cast_slice_mut(&mut back), mapped);
            let mapped_to_host = t.elapsed().as_secs_f64();
            if round > 0 {
                for (v, s) in times.iter_mut().zip([
                    host_to_mapped,
                    mapped_to_host,
                    host_to_device,
                    device_to_host,
                ]) {
                    v.push(s);
                }
            }
        }
        if back != host {
            return Err(crate::error::Error::Unsupported(
                "the link measurement's round trip changed the bytes (a driver fault)".into(),
            ));
        }
        let [a, b, c, d] = times.map(|s| bytes as f64 / median(s).max(1e-12));
        Ok(LinkRates {
            host_to_mapped: a,
            mapped_to_host: b,
            host_to_device: c,
            device_to_host: d,
            copy_threads: self.host_copy.threads(),
        })
    }

    /// Copies `bytes` bytes from `from` to `to` with a transfer command and waits for it:
    /// after the host's, earlier transfers' or the kernels' writes to `from`, and before
    /// the host's or a later transfer's reads of `to`.
    pub(super) fn copy(&self, from: &Buffer, to: &Buffer, bytes: u64) -> Result<()> {
        self.one_shot(|d, cmd| {
            // Host writes, earlier transfers and kernels → this copy; this copy → host reads
            // and later transfers.
            let before = [vk::MemoryBarrier::default()
                .src_access_mask(
                    vk::AccessFlags::HOST_WRITE
                        | vk::AccessFlags::TRANSFER_WRITE
                        | vk::AccessFlags::SHADER_WRITE,
                )
                .dst_access_mask(vk::AccessFlags::TRANSFER_READ)];
            let after = [vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::HOST_READ | vk::AccessFlags::TRANSFER_READ)];
            // SAFETY: recording into slot 0's begun command buffer; both buffers are live,
            // at least `bytes` long, and distinct.
            unsafe {
                d.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::HOST
                        | vk::PipelineStageFlags::TRANSFER
                        | vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::DependencyFlags::empty(),
                    &before,
                    &[],
                    &[],
                );
                d.cmd_copy_buffer(
                    cmd,
                    from.raw(),
                    to.raw(),
                    &[vk::BufferCopy::default().size(bytes)],
                );
                d.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::PipelineStageFlags::HOST | vk::PipelineStageFlags::TRANSFER,
                    vk::DependencyFlags::empty(),
                    &after,
                    &[],
                    &[],
                );
            }
        })
    }
}
