//! Storage buffers with RAII: host-visible ones persistently mapped, device-local ones not.
//!
//! Two host-visible preferences: [`MemoryUse::Upload`] (tuples, materials) prefers memory
//! that is also `DEVICE_LOCAL` (resizable BAR / unified memory), [`MemoryUse::Readback`]
//! (results, counters) prefers `HOST_CACHED`, so host reads of results are cached reads. Both
//! require `HOST_VISIBLE | HOST_COHERENT`, which the spec guarantees to exist, so no flush or
//! invalidate calls are needed. [`MemoryUse::Resident`] is `DEVICE_LOCAL` only (VRAM on a
//! discrete GPU), filled and read by transfer commands: the bench's kernel-only timing keeps
//! its tuples there, as an application whose data already lives on the GPU would. On
//! lavapipe every type is ordinary RAM.

use super::context::Device;
use super::vk_error::vk_error;
use crate::error::{Error, Result};
use ash::vk;
use bytemuck::Pod;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// What a buffer is for: decides the preferred memory type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MemoryUse {
    /// Written by the host, read by the device.
    Upload,
    /// Written by the device, read by the host.
    Readback,
    /// Device-local, not mapped: reached by the host only through transfer commands.
    Resident,
}

impl MemoryUse {
    /// The memory properties a buffer for this use requires, and those it prefers.
    fn flags(self) -> (vk::MemoryPropertyFlags, vk::MemoryPropertyFlags) {
        let host = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        match self {
            MemoryUse::Upload => (host, vk::MemoryPropertyFlags::DEVICE_LOCAL),
            MemoryUse::Readback => (host, vk::MemoryPropertyFlags::HOST_CACHED),
            MemoryUse::Resident => (
                vk::MemoryPropertyFlags::DEVICE_LOCAL,
                vk::MemoryPropertyFlags::empty(),
            ),
        }
    }

    /// The memory type a buffer for this use takes on a device with `props`, where the
    /// buffer allows every type (storage buffers do on the drivers seen so far; `vkbrdf
    /// devices` reports it so that a GPU run says where the kernel reads and writes).
    pub fn chosen_type(self, props: &vk::PhysicalDeviceMemoryProperties) -> Option<u32> {
        let (required, preferred) = self.flags();
        memory_type(props, u32::MAX, required, preferred)
    }
}

/// Source of [`Buffer::id`]s.
static NEXT_ID: AtomicU64 = AtomicU64::new(1);

/// A storage buffer with its own memory, mapped for its whole life.
pub(crate) struct Buffer {
    id: u64,
    raw: vk::Buffer,
    memory: vk::DeviceMemory,
    size: u64,
    mapped: *mut u8,
    device: Arc<Device>,
}

/// The index of a memory type allowed by `bits` with `required` flags, preferring one that
/// also has `preferred`.
fn memory_type(
    props: &vk::PhysicalDeviceMemoryProperties,
    bits: u32,
    required: vk::MemoryPropertyFlags,
    preferred: vk::MemoryPropertyFlags,
) -> Option<u32> {
    let types = &props.memory_types[..props.memory_type_count as usize];
    let fits = |i: usize, flags: vk::MemoryPropertyFlags| {
        bits & (1 << i) != 0 && types[i].property_flags.contains(flags)
    };
    (0..types.len())
        .find(|&i| fits(i, required | preferred))
        .or_else(|| (0..types.len()).find(|&i| fits(i, required)))
        .map(|i| i as u32)
}

impl Buffer {
    /// Makes `buffer` at least `bytes` large (replacing a smaller one; the old one is freed
    /// first, so the budget holds one of them at a time).
    pub fn ensure(
        device: &Arc<Device>,
        buffer: &mut Option<Buffer>,
        bytes: u64,
        usage: MemoryUse,
    ) -> Result<()> {
        if buffer.as_ref().is_none_or(|b| b.size() < bytes) {
            *buffer = None;
            *buffer = Some(Buffer::new(device, bytes, usage)?);
        }
        Ok(())
    }

    /// A mapped storage buffer of at least `size` bytes (0 is rounded up to 16).
    pub fn new(device: &Arc<Device>, size: u64, usage: MemoryUse) -> Result<Buffer> {
        let size = size.max(16);
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(match usage {
                // Uploads are also read as a uniform texel buffer (BINDING_TUPLE_TEXELS).
                MemoryUse::Upload => {
                    vk::BufferUsageFlags::STORAGE_BUFFER
                        | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER
                        | vk::BufferUsageFlags::TRANSFER_SRC
                }
                MemoryUse::Readback => {
                    vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST
                }
                MemoryUse::Resident => {
                    vk::BufferUsageFlags::STORAGE_BUFFER
                        | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER
                        | vk::BufferUsageFlags::TRANSFER_SRC
                        | vk::BufferUsageFlags::TRANSFER_DST
                }
            })
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        let d = &device.raw;
        // SAFETY: the device is live (`Arc<Device>`, also kept by the buffer); `info` has a
        // nonzero size, exclusive sharing and no extension chain.
        let raw = unsafe { d.create_buffer(&info, None) }.map_err(vk_error("vkCreateBuffer"))?;
        // Owns `raw` until the memory is bound, so every error path below frees it.
        struct Guard<'a>(&'a ash::Device, vk::Buffer, vk::DeviceMemory);
        impl Drop for Guard<'_> {
            fn drop(&mut self) {
                // SAFETY: the handles were created above from this device, are not in use by
                // any submitted work, and are destroyed only here (on an error path).
                unsafe {
                    self.0.destroy_buffer(self.1, None);
                    self.0.free_memory(self.2, None);
                }
            }
        }
        let mut guard = Guard(d, raw, vk::DeviceMemory::null());
        // SAFETY: `raw` is a live buffer of this device.
        let req = unsafe { d.get_buffer_memory_requirements(raw) };
        let (required, preferred) = usage.flags();
        let type_index = memory_type(
            &device.physical.memory,
            req.memory_type_bits,
            required,
            preferred,
        )
        .ok_or_else(|| {
            Error::Unsupported(format!(
                "the device has no {required:?} memory type for storage buffers"
            ))
        })?;
        let alloc = vk::MemoryAllocateInfo::default()
            .allocation_size(req.size)
            .memory_type_index(type_index);
        // SAFETY: the device is live; the size is the buffer's requirement and the type
        // index one of the types its `memory_type_bits` allow.
        let memory =
            unsafe { d.allocate_memory(&alloc, None) }.map_err(vk_error("vkAllocateMemory"))?;
        guard.2 = memory;
        // SAFETY: fresh buffer and memory of a compatible type and sufficient size, offset 0.
        unsafe { d.bind_buffer_memory(raw, memory, 0) }.map_err(vk_error("vkBindBufferMemory"))?;
        let mapped = if usage == MemoryUse::Resident {
            std::ptr::null_mut()
        } else {
            // SAFETY: the memory is host visible (required above) and not mapped yet; the
            // whole range is mapped.
            unsafe { d.map_memory(memory, 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty()) }
                .map_err(vk_error("vkMapMemory"))?
        };
        std::mem::forget(guard);
        Ok(Buffer {
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            raw,
            memory,
            size,
            mapped: mapped.cast(),
            device: Arc::clone(device),
        })
    }

    /// A process-unique identity. Not the handle: a driver may give a new buffer the handle
    /// of one just destroyed (lavapipe's handles are pointers), and a descriptor set that
    /// compared handles would keep pointing at the freed memory.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// The buffer handle.
    pub fn raw(&self) -> vk::Buffer {
        self.raw
    }

    /// Size in bytes.
    pub fn size(&self) -> u64 {
        self.size
    }

    /// Copies `data` into the buffer at byte `offset`.
    ///
    /// # Panics
    /// If the data does not fit, or the buffer is [`MemoryUse::Resident`] (caller bugs:
    /// buffers are sized before use, and resident ones are filled by transfers).
    ///
    /// # Safety
    /// No submitted, unfinished GPU work may read or write this buffer (the caller has
    /// waited on the fence of the last submission that used it).
    pub unsafe fn write<T: Pod>(&mut self, offset: u64, data: &[T]) {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        assert!(!self.mapped.is_null(), "a resident buffer is not mapped");
        assert!(
            offset + bytes.len() as u64 <= self.size,
            "buffer write out of range"
        );
        // SAFETY: the range is inside the mapping (checked above); the caller guarantees no
        // concurrent device access; the source is a distinct host allocation.
        unsafe {
            std::ptr::copy_nonoverlapping(
                bytes.as_ptr(),
                self.mapped.add(offset as usize),
                bytes.len(),
            )
        };
    }

    /// The mapping's first `len` bytes, for a copy split over threads
    /// (`gpu::host_copy`).
    ///
    /// # Panics
    /// If `len` exceeds the buffer, or the buffer is [`MemoryUse::Resident`].
    ///
    /// # Safety
    /// As for [`Buffer::write`], for as long as the slice lives.
    pub unsafe fn mapped_mut(&mut self, len: usize) -> &mut [u8] {
        assert!(!self.mapped.is_null(), "a resident buffer is not mapped");
        assert!(len as u64 <= self.size, "mapped range out of range");
        // SAFETY: `len` bytes from the mapping's start lie inside it (checked above); the
        // `&mut self` borrow keeps every other host access out while the slice lives, and
        // the caller keeps the device out.
        unsafe { std::slice::from_raw_parts_mut(self.mapped, len) }
    }

    /// The mapping's first `len` bytes, for a copy split over threads.
    ///
    /// # Panics
    /// If `len` exceeds the buffer, or the buffer is [`MemoryUse::Resident`].
    ///
    /// # Safety
    /// As for [`Buffer::read`], for as long as the slice lives.
    pub unsafe fn mapped(&self, len: usize) -> &[u8] {
        assert!(!self.mapped.is_null(), "a resident buffer is not mapped");
        assert!(len as u64 <= self.size, "mapped range out of range");
        // SAFETY: inside the mapping (checked above); no host writer while `&self` is
        // borrowed (writes take `&mut self`), no device writer (the caller).
        unsafe { std::slice::from_raw_parts(self.mapped, len) }
    }

    /// Copies `out.len()` elements from byte `offset` of the buffer into `out`.
    ///
    /// # Panics
    /// If the range is outside the buffer, or the buffer is [`MemoryUse::Resident`].
    ///
    /// # Safety
    /// As for [`Buffer::write`]: the device must have finished writing the buffer (fence
    /// waited, and the command buffer's barrier made the writes host-visible).
    pub unsafe fn read<T: Pod>(&self, offset: u64, out: &mut [T]) {
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(out);
        assert!(!self.mapped.is_null(), "a resident buffer is not mapped");
        assert!(
            offset + bytes.len() as u64 <= self.size,
            "buffer read out of range"
        );
        // SAFETY: the range is inside the mapping; no concurrent device access (caller).
        unsafe {
            std::ptr::copy_nonoverlapping(
                self.mapped.add(offset as usize),
                bytes.as_mut_ptr(),
                bytes.len(),
            )
        };
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: owners drop buffers only when no submitted work uses them (the evaluator
        // waits for its fences, and waits idle in its own Drop); freeing the memory unmaps it.
        unsafe {
            self.device.raw.destroy_buffer(self.raw, None);
            self.device.raw.free_memory(self.memory, None);
        }
    }
}

// SAFETY: the only non-Send member is the mapping pointer, which is plain process memory
// owned by this buffer; moving the owner to another thread moves that ownership with it.
unsafe impl Send for Buffer {}

/// An RGBA32UI view of a whole [`Buffer`] (created with [`MemoryUse::Upload`] or
/// [`MemoryUse::Resident`], whose size is a
/// multiple of 16 bytes), for binding it as a uniform texel buffer. Destroyed on drop; the
/// owner drops it before the buffer it views.
pub(crate) struct TexelView {
    raw: vk::BufferView,
    /// The [`Buffer::id`] of the viewed buffer.
    buffer: u64,
    device: Arc<Device>,
}

impl TexelView {
    /// A view of all of `buffer` as RGBA32UI texels: the kernel reads the inputs' bits
    /// (a float format's texel fetch could flush subnormals; glsl/input.glsl, `input_vector`).
    pub fn new(device: &Arc<Device>, buffer: &Buffer) -> Result<TexelView> {
        debug_assert_eq!(buffer.size() % 16, 0, "a texel view covers whole texels");
        let info = vk::BufferViewCreateInfo::default()
            .buffer(buffer.raw())
            .format(vk::Format::R32G32B32A32_UINT)
            .offset(0)
            .range(buffer.size() / 16 * 16);
        // SAFETY: the buffer is live, was created with UNIFORM_TEXEL_BUFFER usage, and the
        // range is whole texels within it.
        let raw = unsafe { device.raw.create_buffer_view(&info, None) }
            .map_err(vk_error("vkCreateBufferView"))?;
        Ok(TexelView {
            raw,
            buffer: buffer.id(),
            device: Arc::clone(device),
        })
    }

    /// The view handle.
    pub fn raw(&self) -> vk::BufferView {
        self.raw
    }

    /// The [`Buffer::id`] of the buffer it views.
    pub fn buffer_id(&self) -> u64 {
        self.buffer
    }
}

impl Drop for TexelView {
    fn drop(&mut self) {
        // SAFETY: owners drop the view only when no pending work uses it (their slot was
        // waited on, or the device is idle), before the buffer it views; destroyed once.
        unsafe { self.device.raw.destroy_buffer_view(self.raw, None) };
    }
}
