//! `vkbrdf devices`: what Vulkan devices this machine has, and which one vkbrdf would pick.

use super::context::{choose, enumerate, Instance, PhysicalInfo};
use super::memory::MemoryUse;
use crate::error::Result;
use ash::vk;
use std::fmt;

/// One memory heap of a device.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HeapInfo {
    /// Size in bytes.
    pub size: u64,
    /// Whether the heap is device-local (VRAM on a discrete GPU).
    pub device_local: bool,
}

/// What `vkbrdf devices` reports about one physical device.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceInfo {
    /// Index in the enumeration order (what `--device N` selects).
    pub index: usize,
    /// Device name, e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`.
    pub name: String,
    /// `discrete GPU`, `integrated GPU`, `virtual GPU`, `CPU` or `other`.
    pub device_type: String,
    /// Driver name (Vulkan 1.2+ drivers), e.g. `llvmpipe`.
    pub driver_name: Option<String>,
    /// Driver info (Vulkan 1.2+ drivers), e.g. `Mesa 25.0.7 (LLVM 15.0.6)`.
    pub driver_info: Option<String>,
    /// Vulkan API version the device supports, `major.minor.patch`.
    pub api_version: String,
    /// Memory heaps.
    pub heaps: Vec<HeapInfo>,
    /// Subgroup size (Vulkan 1.1+).
    pub subgroup_size: Option<u32>,
    /// Largest storage-buffer range one descriptor may cover, in bytes.
    pub max_storage_buffer_range: u32,
    /// The frame the kernel computes on this device: `float64` (the device has
    /// `shaderFloat64`), or `f32` (it has not, or `VKBRDF_DISABLE_FLOAT64=1`).
    pub frame: String,
    /// Whether the device has a compute queue (vkbrdf can use it).
    pub compute: bool,
    /// Each queue family: its capabilities (`graphics compute transfer`, …) and queues.
    pub queue_families: Vec<(String, u32)>,
    /// The memory the evaluator's input buffers take (written by the host, read by the
    /// kernel): type index, heap and flags, e.g. `type 1, heap 0: device-local
    /// host-visible host-coherent` (resizable BAR: the kernel reads device memory).
    pub upload_memory: Option<String>,
    /// The memory the evaluator's output buffers take (written by the kernel, read by the
    /// host), as `upload_memory`.
    pub readback_memory: Option<String>,
    /// Whether vkbrdf picks this device when no `--device` / `VKBRDF_DEVICE` is given.
    pub default_choice: bool,
}

fn type_name(t: vk::PhysicalDeviceType) -> &'static str {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
        vk::PhysicalDeviceType::CPU => "CPU",
        _ => "other",
    }
}

/// `graphics compute transfer …`: the capabilities vkbrdf cares about, in words.
fn queue_words(flags: vk::QueueFlags) -> String {
    let words: Vec<&str> = [
        (vk::QueueFlags::GRAPHICS, "graphics"),
        (vk::QueueFlags::COMPUTE, "compute"),
        (vk::QueueFlags::TRANSFER, "transfer"),
    ]
    .into_iter()
    .filter(|(f, _)| flags.contains(*f))
    .map(|(_, w)| w)
    .collect();
    if words.is_empty() {
        "other".to_string()
    } else {
        words.join(" ")
    }
}

/// `type N, heap H: device-local host-visible …` for the memory type `usage` takes.
fn memory_words(p: &PhysicalInfo, usage: MemoryUse) -> Option<String> {
    let t = usage.chosen_type(&p.memory)?;
    let ty = p.memory.memory_types[t as usize];
    let words: Vec<&str> = [
        (vk::MemoryPropertyFlags::DEVICE_LOCAL, "device-local"),
        (vk::MemoryPropertyFlags::HOST_VISIBLE, "host-visible"),
        (vk::MemoryPropertyFlags::HOST_COHERENT, "host-coherent"),
        (vk::MemoryPropertyFlags::HOST_CACHED, "host-cached"),
    ]
    .into_iter()
    .filter(|(f, _)| ty.property_flags.contains(*f))
    .map(|(_, w)| w)
    .collect();
    Some(format!(
        "type {t}, heap {}: {}",
        ty.heap_index,
        words.join(" ")
    ))
}

fn info(p: &PhysicalInfo, default_choice: bool) -> DeviceInfo {
    let v = p.properties.api_version;
    let heaps = p.memory.memory_heaps[..p.memory.memory_heap_count as usize]
        .iter()
        .map(|h| HeapInfo {
            size: h.size,
            device_local: h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL),
        })
        .collect();
    DeviceInfo {
        index: p.index,
        name: p.name(),
        device_type: type_name(p.properties.device_type).to_string(),
        driver_name: p.driver.as_ref().map(|d| d.0.clone()),
        driver_info: p.driver.as_ref().map(|d| d.1.clone()),
        api_version: format!(
            "{}.{}.{}",
            vk::api_version_major(v),
            vk::api_version_minor(v),
            vk::api_version_patch(v)
        ),
        heaps,
        subgroup_size: p.subgroup_size,
        max_storage_buffer_range: p.properties.limits.max_storage_buffer_range,
        frame: match (p.shader_float64, p.device_float64) {
            (true, _) => "float64 (shaderFloat64)".to_string(),
            (false, true) => {
                "f32 (shaderFloat64 turned off by VKBRDF_DISABLE_FLOAT64=1)".to_string()
            }
            (false, false) => "f32 (the device has no shaderFloat64)".to_string(),
        },
        compute: p.compute_family.is_some(),
        queue_families: p
            .queue_families
            .iter()
            .map(|&(flags, count)| (queue_words(flags), count))
            .collect(),
        upload_memory: memory_words(p, MemoryUse::Upload),
        readback_memory: memory_words(p, MemoryUse::Readback),
        default_choice,
    }
}

/// Every Vulkan physical device, in enumeration order, marking the one vkbrdf would pick
/// by default (ignoring `VKBRDF_DEVICE`). Fails with [`crate::Error::NoDevice`] when the
/// Vulkan loader is missing.
pub fn list_devices() -> Result<Vec<DeviceInfo>> {
    let instance = Instance::new(false)?;
    let devices = enumerate(&instance)?;
    let default = choose(&devices, None).ok();
    Ok(devices
        .iter()
        .map(|p| info(p, Some(p.index) == default))
        .collect())
}

fn mib(bytes: u64) -> String {
    format!("{:.0} MiB", bytes as f64 / (1024.0 * 1024.0))
}

impl fmt::Display for DeviceInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mark = if self.default_choice {
            "  (default)"
        } else {
            ""
        };
        writeln!(
            f,
            "{}: {} [{}]{mark}",
            self.index, self.name, self.device_type
        )?;
        if let (Some(n), Some(i)) = (&self.driver_name, &self.driver_info) {
            writeln!(f, "   driver:          {n} ({i})")?;
        }
        writeln!(f, "   Vulkan:          {}", self.api_version)?;
        if let Some(s) = self.subgroup_size {
            writeln!(f, "   subgroup size:   {s}")?;
        }
        writeln!(f, "   kernel frame:    {}", self.frame)?;
        writeln!(
            f,
            "   max storage buffer range: {}",
            mib(u64::from(self.max_storage_buffer_range))
        )?;
        for (i, h) in self.heaps.iter().enumerate() {
            let local = if h.device_local {
                "device-local"
            } else {
                "host"
            };
            writeln!(f, "   heap {i}:          {} ({local})", mib(h.size))?;
        }
        for (i, (words, count)) in self.queue_families.iter().enumerate() {
            writeln!(f, "   queue family {i}:  {words} ({count} queue(s))")?;
        }
        if let Some(m) = &self.upload_memory {
            writeln!(f, "   input buffers:   {m}")?;
        }
        if let Some(m) = &self.readback_memory {
            writeln!(f, "   output buffers:  {m}")?;
        }
        if !self.compute {
            writeln!(f, "   (no compute queue: not usable by vkbrdf)")?;
        }
        Ok(())
    }
}
