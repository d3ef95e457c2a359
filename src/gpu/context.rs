//! The Vulkan instance (with the validation layer and a message counter when asked for),
//! the physical-device choice, and the logical device with its one compute queue.
//!
//! Ownership: [`Device`] holds an `Arc<Instance>`, and every child object in this module
//! tree holds an `Arc<Device>`, so a parent can never be destroyed before its children
//! (vulkano's scheme; ash leaves `Drop` to its users).

use super::vk_error::vk_error;
use crate::error::{Error, Result};
use ash::vk;
use std::ffi::{c_void, CStr};
use std::fmt;
use std::io::Write;
use std::str::FromStr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

/// What to tell a user whose machine has no usable Vulkan driver.
pub const INSTALL_HINT: &str = "install a Vulkan driver and loader (on Debian/Ubuntu: \
`apt-get install mesa-vulkan-drivers libvulkan1`, which includes lavapipe, a CPU \
implementation); the commands that take `--backend` (eval, demo, stress, table, check) \
run on the native CPU engine with `--backend cpu` (what the default `auto` picks without \
a GPU) or on the f64 reference with `--backend reference`";

/// The name of the Khronos validation layer.
const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Which physical device to use, from `--device` or the `VKBRDF_DEVICE` environment
/// variable: an index into the list `vkbrdf devices` prints, or a case-insensitive
/// substring of the device name (e.g. `llvmpipe`, `nvidia`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DeviceSelector {
    /// The device at this index of the enumeration order.
    Index(usize),
    /// The best-ranked device whose name contains this text (case-insensitive).
    Name(String),
}

impl DeviceSelector {
    /// The selector in the `VKBRDF_DEVICE` environment variable, if set and non-empty.
    pub fn from_env() -> Option<DeviceSelector> {
        let s = std::env::var("VKBRDF_DEVICE").ok()?;
        s.parse().ok()
    }
}

impl FromStr for DeviceSelector {
    type Err = String;
    /// All digits: an index; anything else: a name substring. Empty is an error.
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let s = s.trim();
        if s.is_empty() {
            return Err("empty device selector; give an index or part of a device name".into());
        }
        Ok(match s.parse::<usize>() {
            Ok(i) => DeviceSelector::Index(i),
            Err(_) => DeviceSelector::Name(s.to_string()),
        })
    }
}

impl fmt::Display for DeviceSelector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DeviceSelector::Index(i) => write!(f, "index {i}"),
            DeviceSelector::Name(n) => write!(f, "name containing `{n}`"),
        }
    }
}

/// Validation-layer messages of severity warning or error: counted, echoed to stderr, and
/// the first few kept for reports.
#[derive(Debug, Default)]
pub(crate) struct MessageLog {
    count: AtomicU64,
    first: Mutex<Vec<String>>,
}

impl MessageLog {
    const KEEP: usize = 32;

    fn record(&self, severity: vk::DebugUtilsMessageSeverityFlagsEXT, message: &str) {
        self.count.fetch_add(1, Ordering::Relaxed);
        let line = format!("vulkan validation ({severity:?}): {message}");
        let _ = writeln!(std::io::stderr(), "{line}");
        let mut first = self.first.lock().unwrap_or_else(|e| e.into_inner());
        if first.len() < Self::KEEP {
            first.push(line);
        }
    }

    /// Warnings + errors so far.
    pub(crate) fn count(&self) -> u64 {
        self.count.load(Ordering::Relaxed)
    }

    /// The first messages (at most 32).
    pub(crate) fn messages(&self) -> Vec<String> {
        self.first.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

/// A handle on a backend's validation-message counter that stays readable after the
/// backend (and its instance) are gone, so messages emitted while destroying objects
/// ("… not destroyed") are counted too.
#[derive(Debug, Clone)]
pub struct ValidationCounter {
    log: Arc<MessageLog>,
}

impl ValidationCounter {
    /// Warnings + errors reported so far.
    pub fn count(&self) -> u64 {
        self.log.count()
    }

    /// The first (at most 32) messages.
    pub fn messages(&self) -> Vec<String> {
        self.log.messages()
    }
}

/// Called by the validation layer (through `VK_EXT_debug_utils`) for every message of the
/// severities we subscribe to (warning, error).
unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    if user_data.is_null() {
        return vk::FALSE;
    }
    // SAFETY: user_data is the address of the MessageLog inside the Arc that Instance owns;
    // Instance destroys the messenger (and the instance, whose creation chain also points
    // here) before that Arc is released, so the pointer is live for every call.
    let log = unsafe { &*(user_data as *const MessageLog) };
    // SAFETY: the layer passes a valid callback-data struct (or null) whose message string
    // is valid for the duration of the call (VK_EXT_debug_utils spec).
    let message = unsafe { data.as_ref().and_then(|d| d.message_as_c_str()) }
        .map(|m| m.to_string_lossy().into_owned())
        .unwrap_or_default();
    log.record(severity, &message);
    vk::FALSE
}

/// The messenger settings used both at instance creation (to catch messages from
/// `vkCreateInstance`/`vkDestroyInstance`) and for the persistent messenger.
fn messenger_info(log: &MessageLog) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(debug_callback))
        .user_data(log as *const MessageLog as *mut c_void)
}

/// A Vulkan instance, with the validation messenger when validation is on.
pub(crate) struct Instance {
    /// The loaded loader library; must outlive `raw`.
    pub entry: ash::Entry,
    /// The instance.
    pub raw: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// The message counter the messenger writes into (outlives the messenger).
    pub log: Arc<MessageLog>,
    /// The API version the instance was created with.
    pub api_version: u32,
}

impl Instance {
    /// Loads the Vulkan loader and creates an instance; with `validation`, enables
    /// `VK_LAYER_KHRONOS_validation` and a `VK_EXT_debug_utils` messenger when installed
    /// (see [`Instance::validation_enabled`]).
    pub fn new(validation: bool) -> Result<Arc<Instance>> {
        // SAFETY: loading libvulkan runs its initialisers; the loader is a well-behaved
        // system library, and the Entry keeps it loaded for as long as any handle lives.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| {
            Error::NoDevice(format!(
                "cannot load the Vulkan loader (libvulkan.so.1): {e}; {INSTALL_HINT}"
            ))
        })?;
        // SAFETY: a global command (no handle) through the entry's function pointers, which
        // the loaded `entry` keeps valid; ash passes a pointer to its own local for the result.
        let loader_version = unsafe { entry.try_enumerate_instance_version() }
            .map_err(vk_error("vkEnumerateInstanceVersion"))?
            .unwrap_or(vk::API_VERSION_1_0);
        let api_version = loader_version.min(vk::API_VERSION_1_3);
        let (layer_ok, debug_ok) = if validation {
            // SAFETY: a global command (no handle) through the loaded entry; ash runs the
            // count-then-fill idiom into a vector it sizes from the count.
            let layers = unsafe { entry.enumerate_instance_layer_properties() }
                .map_err(vk_error("vkEnumerateInstanceLayerProperties"))?;
            let layer_ok = layers
                .iter()
                .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER));
            // SAFETY: as for the layers; `None` asks for the loader's and implicit layers'
            // extensions, so no layer-name pointer has to outlive the call.
            let exts = unsafe { entry.enumerate_instance_extension_properties(None) }
                .map_err(vk_error("vkEnumerateInstanceExtensionProperties"))?;
            let debug_ok = exts
                .iter()
                .any(|e| e.extension_name_as_c_str() == Ok(ash::ext::debug_utils::NAME));
            if !layer_ok {
                let _ = writeln!(
                    std::io::stderr(),
                    "vkbrdf: validation requested but {VALIDATION_LAYER:?} is not installed \
                     (apt-get install vulkan-validationlayers); running without it"
                );
            }
            (layer_ok, layer_ok && debug_ok)
        } else {
            (false, false)
        };
        let log = Arc::new(MessageLog::default());
        let app = vk::ApplicationInfo::default()
            .application_name(c"vkbrdf")
            .engine_name(c"vkbrdf")
            .api_version(api_version);
        let layers = if layer_ok {
            vec![VALIDATION_LAYER.as_ptr()]
        } else {
            vec![]
        };
        let extensions = if debug_ok {
            vec![ash::ext::debug_utils::NAME.as_ptr()]
        } else {
            vec![]
        };
        let mut creation_messenger = messenger_info(&log);
        let mut info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if debug_ok {
            info = info.push_next(&mut creation_messenger);
        }
        // SAFETY: `info` and everything it points to (names, app info, messenger info whose
        // user data is the MessageLog kept alive in `log`) live until the call returns.
        let raw = unsafe { entry.create_instance(&info, None) }.map_err(|r| match r {
            vk::Result::ERROR_INCOMPATIBLE_DRIVER | vk::Result::ERROR_INITIALIZATION_FAILED => {
                Error::NoDevice(format!(
                    "no Vulkan driver could create an instance ({r:?}); {INSTALL_HINT}"
                ))
            }
            r => vk_error("vkCreateInstance")(r),
        })?;
        let mut instance = Instance {
            entry,
            raw,
            debug: None,
            log,
            api_version,
        };
        if debug_ok {
            let loader = ash::ext::debug_utils::Instance::new(&instance.entry, &instance.raw);
            // SAFETY: the instance was created with VK_EXT_debug_utils enabled; the user data
            // (MessageLog) outlives the messenger (Drop destroys the messenger first).
            let messenger = unsafe {
                loader.create_debug_utils_messenger(&messenger_info(&instance.log), None)
            }
            .map_err(vk_error("vkCreateDebugUtilsMessengerEXT"))?;
            instance.debug = Some((loader, messenger));
        }
        Ok(Arc::new(instance))
    }

    /// Whether the validation layer and its messenger are active.
    pub fn validation_enabled(&self) -> bool {
        self.debug.is_some()
    }

    /// A counter handle that outlives the instance.
    pub fn counter(&self) -> ValidationCounter {
        ValidationCounter {
            log: Arc::clone(&self.log),
        }
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        if let Some((loader, messenger)) = self.debug.take() {
            // SAFETY: the messenger belongs to this instance and is destroyed exactly once.
            unsafe { loader.destroy_debug_utils_messenger(messenger, None) };
        }
        // SAFETY: every child (devices hold an Arc<Instance>) is gone, so nothing uses the
        // instance any more; destroyed exactly once.
        unsafe { self.raw.destroy_instance(None) };
    }
}

/// What we know about one physical device.
#[derive(Clone)]
pub(crate) struct PhysicalInfo {
    /// The handle.
    pub raw: vk::PhysicalDevice,
    /// Position in the enumeration order (what `--device N` selects).
    pub index: usize,
    /// Core properties (name, type, limits, API version).
    pub properties: vk::PhysicalDeviceProperties,
    /// Memory types and heaps.
    pub memory: vk::PhysicalDeviceMemoryProperties,
    /// A queue family with compute support, if any.
    pub compute_family: Option<u32>,
    /// Valid bits of that family's timestamps (0: it has none; kernel timing then uses
    /// fences around a whole submission).
    pub timestamp_bits: u32,
    /// Subgroup size (Vulkan 1.1+).
    pub subgroup_size: Option<u32>,
    /// Whether compute shaders can use subgroup arithmetic (subgroupAdd, subgroupMin).
    pub subgroup_arithmetic: bool,
    /// Whether the kernel uses f64 (`shaderFloat64`, unless `VKBRDF_DISABLE_FLOAT64=1`): it
    /// then computes the frame in f64 (see `make_frame` in glsl/frame.glsl), else in f32.
    pub shader_float64: bool,
    /// Whether the device has `shaderFloat64` (even where `VKBRDF_DISABLE_FLOAT64` turns
    /// its use off).
    pub device_float64: bool,
    /// Driver name and info (Vulkan 1.2+).
    pub driver: Option<(String, String)>,
    /// Each queue family's capabilities and queue count.
    pub queue_families: Vec<(vk::QueueFlags, u32)>,
}

impl PhysicalInfo {
    /// The device name.
    pub fn name(&self) -> String {
        self.properties
            .device_name_as_c_str()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    }

    /// Preference order: discrete GPU, integrated, virtual, CPU (lavapipe), other.
    pub fn rank(&self) -> u8 {
        match self.properties.device_type {
            vk::PhysicalDeviceType::DISCRETE_GPU => 0,
            vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
            vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
            vk::PhysicalDeviceType::CPU => 3,
            _ => 4,
        }
    }
}

/// Every physical device of `instance`, with the properties vkbrdf uses.
/// `VKBRDF_DISABLE_FLOAT64`: `1` makes the kernel run its f32 frame as on a device without
/// `shaderFloat64` (the reference and other engines are not affected); unset, empty or `0`
/// leaves f64 on where the device has it.
pub fn float64_disabled() -> Result<bool> {
    match std::env::var("VKBRDF_DISABLE_FLOAT64").as_deref() {
        Err(_) | Ok("") | Ok("0") => Ok(false),
        Ok("1") => Ok(true),
        Ok(other) => Err(Error::Unsupported(format!(
            "VKBRDF_DISABLE_FLOAT64={other:?}: expected 1 (use the f32 frame) or 0"
        ))),
    }
}

pub(crate) fn enumerate(instance: &Instance) -> Result<Vec<PhysicalInfo>> {
    let disable_float64 = float64_disabled()?;
    // SAFETY: `instance` is borrowed, so its `Drop` (which destroys the VkInstance) cannot
    // run during the call; ash sizes the output vector from the count query.
    let devices = unsafe { instance.raw.enumerate_physical_devices() }
        .map_err(vk_error("vkEnumeratePhysicalDevices"))?;
    let mut out = Vec::with_capacity(devices.len());
    for (index, raw) in devices.into_iter().enumerate() {
        // SAFETY: `raw` was just enumerated from this instance.
        let (properties, memory, families) = unsafe {
            (
                instance.raw.get_physical_device_properties(raw),
                instance.raw.get_physical_device_memory_properties(raw),
                instance
                    .raw
                    .get_physical_device_queue_family_properties(raw),
            )
        };
        let compute_family = families
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
            .map(|i| i as u32);
        let timestamp_bits =
            compute_family.map_or(0, |i| families[i as usize].timestamp_valid_bits);
        let mut info = PhysicalInfo {
            raw,
            index,
            timestamp_bits,
            properties,
            memory,
            compute_family,
            subgroup_size: None,
            subgroup_arithmetic: false,
            shader_float64: false,
            // SAFETY: `raw` was just enumerated from this instance.
            device_float64: unsafe { instance.raw.get_physical_device_features(raw) }
                .shader_float64
                == vk::TRUE,
            driver: None,
            queue_families: families
                .iter()
                .map(|f| (f.queue_flags, f.queue_count))
                .collect(),
        };
        info.shader_float64 = info.device_float64 && !disable_float64;
        let version = properties.api_version.min(instance.api_version);
        if version >= vk::API_VERSION_1_1 {
            let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
            let mut driver = vk::PhysicalDeviceDriverProperties::default();
            {
                let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
                if version >= vk::API_VERSION_1_2 {
                    props2 = props2.push_next(&mut driver);
                }
                // SAFETY: instance and device both support Vulkan 1.1; the chained structs
                // are the 1.1/1.2 core ones the version check allows.
                unsafe {
                    instance
                        .raw
                        .get_physical_device_properties2(raw, &mut props2)
                };
            }
            info.subgroup_size = Some(subgroup.subgroup_size);
            info.subgroup_arithmetic = subgroup
                .supported_stages
                .contains(vk::ShaderStageFlags::COMPUTE)
                && subgroup.supported_operations.contains(
                    vk::SubgroupFeatureFlags::BASIC | vk::SubgroupFeatureFlags::ARITHMETIC,
                );
            if version >= vk::API_VERSION_1_2 {
                let s = |r: std::result::Result<&CStr, _>| {
                    r.map(|c: &CStr| c.to_string_lossy().into_owned())
                        .unwrap_or_default()
                };
                info.driver = Some((
                    s(driver.driver_name_as_c_str()),
                    s(driver.driver_info_as_c_str()),
                ));
            }
        }
        out.push(info);
    }
    Ok(out)
}

/// The device `selector` names, or the best-ranked one with a compute queue.
pub(crate) fn choose(devices: &[PhysicalInfo], selector: Option<&DeviceSelector>) -> Result<usize> {
    let names = || {
        devices
            .iter()
            .map(|d| format!("  {}: {}", d.index, d.name()))
            .collect::<Vec<_>>()
            .join("\n")
    };
    let usable = |d: &&PhysicalInfo| d.compute_family.is_some();
    let pick = match selector {
        None => devices.iter().filter(usable).min_by_key(|d| d.rank()),
        Some(DeviceSelector::Index(i)) => devices.get(*i).filter(usable),
        Some(DeviceSelector::Name(n)) => {
            let n = n.to_lowercase();
            devices
                .iter()
                .filter(usable)
                .filter(|d| d.name().to_lowercase().contains(&n))
                .min_by_key(|d| d.rank())
        }
    };
    match (pick, selector) {
        (Some(d), _) => Ok(d.index),
        (None, None) if devices.is_empty() => {
            Err(Error::NoDevice(format!("the Vulkan loader found no physical device; {INSTALL_HINT}")))
        }
        (None, None) => Err(Error::NoDevice(format!("no Vulkan device has a compute queue:\n{}", names()))),
        (None, Some(s)) => Err(Error::NoDevice(format!(
            "no Vulkan device with a compute queue matches --device / VKBRDF_DEVICE ({s}); the devices are:\n{}",
            names()
        ))),
    }
}

/// The logical device with its one compute queue.
pub(crate) struct Device {
    /// The device.
    pub raw: ash::Device,
    /// The queue every submission goes to.
    pub queue: vk::Queue,
    /// Its family.
    pub queue_family: u32,
    /// The physical device it was created on.
    pub physical: PhysicalInfo,
    /// The parent instance (declared last: dropped after `raw` is destroyed in `drop`).
    pub instance: Arc<Instance>,
}

impl Device {
    /// Creates an instance (validation per `validation`) and a device on the chosen
    /// physical device: `selector`, else `VKBRDF_DEVICE`, else the best-ranked one.
    pub fn new(selector: Option<&DeviceSelector>, validation: bool) -> Result<Arc<Device>> {
        let instance = Instance::new(validation)?;
        let devices = enumerate(&instance)?;
        let env = DeviceSelector::from_env();
        let chosen = choose(&devices, selector.or(env.as_ref()))?;
        let physical = devices[chosen].clone();
        let queue_family = physical
            .compute_family
            .expect("choose() only returns devices with a compute queue");
        let priorities = [1.0f32];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        let features =
            vk::PhysicalDeviceFeatures::default().shader_float64(physical.shader_float64);
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_features(&features);
        // SAFETY: `physical.raw` belongs to `instance`; `info` points to locals that live
        // until the call returns.
        let raw = unsafe { instance.raw.create_device(physical.raw, &info, None) }
            .map_err(vk_error("vkCreateDevice"))?;
        // SAFETY: the family and index 0 were requested in `info`.
        let queue = unsafe { raw.get_device_queue(queue_family, 0) };
        Ok(Arc::new(Device {
            raw,
            queue,
            queue_family,
            physical,
            instance,
        }))
    }

    /// Waits until the device has finished all work (used before destroying objects).
    pub fn wait_idle(&self) {
        // SAFETY: the device is live; an error here (device lost) leaves nothing to wait for.
        let _ = unsafe { self.raw.device_wait_idle() };
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        self.wait_idle();
        // SAFETY: every child object holds an Arc<Device>, so none is left; the device is
        // idle and destroyed exactly once, before its instance (dropped after this).
        unsafe { self.raw.destroy_device(None) };
    }
}
