//! Small RAII owners for the per-evaluator Vulkan objects: the command pool (and its
//! command buffers), the descriptor pool (and its sets), and fences.

use super::context::Device;
use super::layout::descriptor_type;
use super::vk_error::vk_error;
use crate::error::Result;
use ash::vk;
use std::sync::Arc;

/// How long one wait for a chunk may take before it is reported as an error (a hung or
/// lost device), in nanoseconds: 10 minutes.
const FENCE_TIMEOUT_NS: u64 = 600_000_000_000;

/// A fence, created unsignalled.
pub(crate) struct Fence {
    raw: vk::Fence,
    device: Arc<Device>,
}

impl Fence {
    pub fn new(device: &Arc<Device>) -> Result<Fence> {
        // SAFETY: `device` is an `Arc<Device>`, so the VkDevice is live for the call (and,
        // through the clone the fence keeps, until the fence is destroyed); the create info is
        // the default one (unsignalled, no extension chain).
        let raw = unsafe {
            device
                .raw
                .create_fence(&vk::FenceCreateInfo::default(), None)
        }
        .map_err(vk_error("vkCreateFence"))?;
        Ok(Fence {
            raw,
            device: Arc::clone(device),
        })
    }

    pub fn raw(&self) -> vk::Fence {
        self.raw
    }

    /// Waits until the fence is signalled, then resets it.
    pub fn wait_and_reset(&self) -> Result<()> {
        let fences = [self.raw];
        // A `TIMEOUT` comes back as an error too; its message says what it means.
        // SAFETY: the fence belongs to this device; waiting has no other precondition.
        unsafe {
            self.device
                .raw
                .wait_for_fences(&fences, true, FENCE_TIMEOUT_NS)
        }
        .map_err(vk_error("vkWaitForFences"))?;
        // SAFETY: the fence is signalled, so no queue operation still refers to it.
        unsafe { self.device.raw.reset_fences(&fences) }.map_err(vk_error("vkResetFences"))
    }

    /// Resets the fence after the device was waited idle (error recovery).
    pub fn reset(&self) {
        // SAFETY: called only after vkDeviceWaitIdle, so no pending submission uses it.
        let _ = unsafe { self.device.raw.reset_fences(&[self.raw]) };
    }
}

impl Drop for Fence {
    fn drop(&mut self) {
        // SAFETY: owners drop fences only after waiting for them (or the device idle).
        unsafe { self.device.raw.destroy_fence(self.raw, None) };
    }
}

/// A command pool whose buffers can be re-recorded one by one, with `count` primary
/// command buffers allocated from it (freed with the pool).
pub(crate) struct CommandPool {
    raw: vk::CommandPool,
    pub buffers: Vec<vk::CommandBuffer>,
    device: Arc<Device>,
}

impl CommandPool {
    pub fn new(device: &Arc<Device>, count: u32) -> Result<CommandPool> {
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(device.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: the device is live (`Arc<Device>`, also kept by the pool) and
        // `queue_family` is the family its one queue was created from.
        let raw = unsafe { device.raw.create_command_pool(&info, None) }
            .map_err(vk_error("vkCreateCommandPool"))?;
        let mut pool = CommandPool {
            raw,
            buffers: vec![],
            device: Arc::clone(device),
        };
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(raw)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(count);
        // SAFETY: the pool is live; on error `pool` is dropped and destroys it.
        pool.buffers = unsafe { device.raw.allocate_command_buffers(&alloc) }
            .map_err(vk_error("vkAllocateCommandBuffers"))?;
        Ok(pool)
    }
}

impl Drop for CommandPool {
    fn drop(&mut self) {
        // SAFETY: no command buffer of the pool is pending (owners wait idle first);
        // destroying the pool frees its command buffers.
        unsafe { self.device.raw.destroy_command_pool(self.raw, None) };
    }
}

/// A descriptor pool with `count` sets of `layout` allocated from it (freed with the pool).
pub(crate) struct DescriptorPool {
    raw: vk::DescriptorPool,
    pub sets: Vec<vk::DescriptorSet>,
    device: Arc<Device>,
}

impl DescriptorPool {
    pub fn new(
        device: &Arc<Device>,
        layout: vk::DescriptorSetLayout,
        bindings: u32,
        count: u32,
    ) -> Result<DescriptorPool> {
        let of_type = |ty: vk::DescriptorType| vk::DescriptorPoolSize {
            ty,
            descriptor_count: (0..bindings).filter(|&b| descriptor_type(b) == ty).count() as u32
                * count,
        };
        let sizes = [
            of_type(vk::DescriptorType::STORAGE_BUFFER),
            of_type(vk::DescriptorType::UNIFORM_TEXEL_BUFFER),
        ];
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(count)
            .pool_sizes(&sizes);
        // SAFETY: the device is live (`Arc<Device>`, also kept by the pool); `info` points
        // to `sizes`, a local that outlives the call.
        let raw = unsafe { device.raw.create_descriptor_pool(&info, None) }
            .map_err(vk_error("vkCreateDescriptorPool"))?;
        let mut pool = DescriptorPool {
            raw,
            sets: vec![],
            device: Arc::clone(device),
        };
        let layouts = vec![layout; count as usize];
        let alloc = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(raw)
            .set_layouts(&layouts);
        // SAFETY: the pool has room for exactly these sets; on error `pool` is dropped.
        pool.sets = unsafe { device.raw.allocate_descriptor_sets(&alloc) }
            .map_err(vk_error("vkAllocateDescriptorSets"))?;
        Ok(pool)
    }
}

impl Drop for DescriptorPool {
    fn drop(&mut self) {
        // SAFETY: no pending work uses the sets (owners wait idle first); destroying the
        // pool frees them.
        unsafe { self.device.raw.destroy_descriptor_pool(self.raw, None) };
    }
}

/// A pool of `count` timestamp queries (destroyed on drop).
pub(crate) struct TimestampPool {
    raw: vk::QueryPool,
    count: u32,
    device: Arc<Device>,
}

impl TimestampPool {
    pub fn new(device: &Arc<Device>, count: u32) -> Result<TimestampPool> {
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(count);
        // SAFETY: the device is live (`Arc<Device>`, also kept by the pool); `info` has no
        // extension chain.
        let raw = unsafe { device.raw.create_query_pool(&info, None) }
            .map_err(vk_error("vkCreateQueryPool"))?;
        Ok(TimestampPool {
            raw,
            count,
            device: Arc::clone(device),
        })
    }

    pub fn raw(&self) -> vk::QueryPool {
        self.raw
    }

    /// The pool's `count` raw timestamps, waiting until every one is available.
    /// Precondition: a submission that wrote all of them has completed (fence waited).
    pub fn results(&self) -> Result<Vec<u64>> {
        let mut data = vec![0u64; self.count as usize];
        // SAFETY: the pool belongs to this device; `data` holds `count` u64s, the layout the
        // TYPE_64 flag asks for; WAIT returns once the (completed) writes are available.
        unsafe {
            self.device.raw.get_query_pool_results(
                self.raw,
                0,
                &mut data,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .map_err(vk_error("vkGetQueryPoolResults"))?;
        Ok(data)
    }
}

impl Drop for TimestampPool {
    fn drop(&mut self) {
        // SAFETY: owners drop the pool only after waiting for the submissions using it.
        unsafe { self.device.raw.destroy_query_pool(self.raw, None) };
    }
}
