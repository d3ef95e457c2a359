//! The driver's pipeline cache (`VkPipelineCache`) kept across runs: loaded from the disk
//! cache ([`super::disk_cache`]) when the kernels are set up, handed to every pipeline
//! creation, and written back when they are dropped, if a pipeline was created. The entry is
//! named by the device and driver (vendor, device, driver version and the driver's
//! `pipelineCacheUUID`), and its data is passed to the driver only when its header names
//! the same ones (Vulkan allows only data the same driver returned). Before writing, the
//! entry another process may have stored meanwhile is merged in, so concurrent runs add to
//! each other rather than replace.

use super::context::{Device, PhysicalInfo};
use super::disk_cache::{key_of, DiskCache};
use super::vk_error::vk_error;
use crate::error::Result;
use ash::vk;
use std::sync::Arc;

/// The disk cache's folder for pipeline caches.
const KIND: &str = "pipelines";

/// A `VkPipelineCache` and where it is kept.
pub(crate) struct PipelineCache {
    raw: vk::PipelineCache,
    disk: DiskCache,
    key: String,
    /// A pipeline was created with it since it was loaded (it then has something to add).
    grown: bool,
    device: Arc<Device>,
}

impl PipelineCache {
    /// The cache of `device`, started from the disk cache's entry for it when there is a
    /// usable one, else empty.
    pub fn new(device: &Arc<Device>, disk: DiskCache) -> Result<PipelineCache> {
        let key = device_key(&device.physical);
        let initial = load(&disk, &key, &device.physical).unwrap_or_default();
        let raw = match create(device, &initial) {
            Ok(raw) => raw,
            // A driver that refuses its own earlier data: start empty.
            Err(_) if !initial.is_empty() => create(device, &[])?,
            Err(e) => return Err(e),
        };
        Ok(PipelineCache {
            raw,
            disk,
            key,
            grown: false,
            device: Arc::clone(device),
        })
    }

    /// The handle, for a pipeline about to be created (which may add to it).
    pub fn for_creation(&mut self) -> vk::PipelineCache {
        self.grown = true;
        self.raw
    }

    /// Merges the disk's entry (another process's, perhaps) into this cache and stores the
    /// result. Failures leave the disk as it was.
    fn save(&self) {
        let d = &self.device.raw;
        if let Some(theirs) = load(&self.disk, &self.key, &self.device.physical) {
            if let Ok(other) = create(&self.device, &theirs) {
                // SAFETY: both caches are live on this device and not in use by another
                // thread (`&self` is the only handle to `raw`; `other` is local).
                let _ = unsafe { d.merge_pipeline_caches(self.raw, &[other]) };
                // SAFETY: `other` was created above and is used nowhere else.
                unsafe { d.destroy_pipeline_cache(other, None) };
            }
        }
        // SAFETY: `raw` is live; no pipeline is being created with it (we are dropping).
        if let Ok(data) = unsafe { d.get_pipeline_cache_data(self.raw) } {
            self.disk.store(KIND, &self.key, &data);
        }
    }
}

impl Drop for PipelineCache {
    fn drop(&mut self) {
        if self.grown {
            self.save();
        }
        // SAFETY: created on this device in `new`, destroyed exactly once; the owner
        // (`Kernels`) creates no pipeline with it any more.
        unsafe { self.device.raw.destroy_pipeline_cache(self.raw, None) };
    }
}

/// The disk's entry `key` if it is this device's and driver's data.
fn load(disk: &DiskCache, key: &str, p: &PhysicalInfo) -> Option<Vec<u8>> {
    disk.load(KIND, key).filter(|data| header_matches(data, p))
}

/// A pipeline cache on `device` holding `initial` (empty: an empty cache).
fn create(device: &Device, initial: &[u8]) -> Result<vk::PipelineCache> {
    let info = vk::PipelineCacheCreateInfo::default().initial_data(initial);
    // SAFETY: the device is live; `initial` is empty or data this device's driver returned
    // from vkGetPipelineCacheData (checked by `header_matches`, whole by the disk cache's
    // checksum), and outlives the call.
    unsafe { device.raw.create_pipeline_cache(&info, None) }
        .map_err(vk_error("vkCreatePipelineCache"))
}

/// The entry's name for this device and driver.
fn device_key(p: &PhysicalInfo) -> String {
    let props = &p.properties;
    key_of(&[
        &props.vendor_id.to_le_bytes(),
        &props.device_id.to_le_bytes(),
        &props.driver_version.to_le_bytes(),
        &props.pipeline_cache_uuid,
    ])
}

/// Whether `data` starts with a version-one pipeline cache header (Vulkan 1.0, §10.6:
/// header size, header version, vendor ID, device ID, pipelineCacheUUID) naming this device
/// and driver.
fn header_matches(data: &[u8], p: &PhysicalInfo) -> bool {
    let word = |i: usize| {
        data.get(i..i + 4)
            .map(|b| u32::from_le_bytes(b.try_into().unwrap()))
    };
    let props = &p.properties;
    data.len() >= 32
        && word(0).is_some_and(|size| size as usize >= 32 && size as usize <= data.len())
        && word(4) == Some(vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32)
        && word(8) == Some(props.vendor_id)
        && word(12) == Some(props.device_id)
        && data[16..32] == props.pipeline_cache_uuid
}
