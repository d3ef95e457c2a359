//! Which engine evaluates: the names `auto`, `vulkan`, `cpu` and `reference` that the CLI's
//! `--backend` and the Python package's `backend=` accept, and the rule `auto` follows.

use crate::backend::Backend;
use crate::cpu::CpuEngine;
use crate::error::{Error, Result};
use crate::gpu::{DeviceSelector, VulkanBackend, VulkanOptions};
use crate::reference::CpuReference;

/// The engines by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// The Vulkan kernel when a device is named or a discrete or integrated GPU exists,
    /// else the native CPU engine.
    Auto,
    /// Vulkan compute (the GLSL kernel) on the chosen device (lavapipe without a GPU).
    Vulkan,
    /// The native CPU engine (f32 SIMD lanes on every core).
    Cpu,
    /// The f64 CPU reference (exact; the judge).
    Reference,
}

impl Kind {
    /// Every kind, in the order the documentation lists them.
    pub const ALL: [Kind; 4] = [Kind::Auto, Kind::Vulkan, Kind::Cpu, Kind::Reference];

    /// The name `--backend` and `backend=` take.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Auto => "auto",
            Kind::Vulkan => "vulkan",
            Kind::Cpu => "cpu",
            Kind::Reference => "reference",
        }
    }
}

impl std::str::FromStr for Kind {
    type Err = Error;
    /// One of `auto`, `vulkan`, `cpu`, `reference`; anything else is an
    /// [`Error::Unsupported`] listing them.
    fn from_str(s: &str) -> Result<Kind> {
        Kind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                Error::Unsupported(format!(
                    "unknown backend `{s}`; expected one of: auto, vulkan, cpu, reference"
                ))
            })
    }
}

/// What [`Kind::Auto`] picks on this machine, and why: `(true, why)` for the Vulkan
/// kernel, `(false, why)` for the native CPU engine. `device` is the device the caller
/// named (`--device`), if any.
pub fn auto_choice(device: Option<&DeviceSelector>) -> (bool, String) {
    if device.is_some() {
        return (true, "--device names a Vulkan device".into());
    }
    if DeviceSelector::from_env().is_some() {
        return (true, "VKBRDF_DEVICE names a Vulkan device".into());
    }
    match crate::gpu::list_devices() {
        Ok(list) => match list
            .iter()
            .find(|d| d.device_type == "discrete GPU" || d.device_type == "integrated GPU")
        {
            Some(d) => (true, format!("{} is a {}", d.name, d.device_type)),
            None => (
                false,
                "no discrete or integrated GPU (a CPU Vulkan device such as lavapipe is slower than the native engine; --backend vulkan uses it)".into(),
            ),
        },
        Err(e) => (false, format!("no Vulkan driver ({e})")),
    }
}

/// Opens the Vulkan backend on `device`, else the `VKBRDF_DEVICE` environment variable's
/// device, else the best one.
pub fn open_vulkan(
    device: Option<DeviceSelector>,
    options: VulkanOptions,
) -> Result<VulkanBackend> {
    VulkanBackend::new(device.or_else(DeviceSelector::from_env), options)
}

/// Opens the engine `kind` (no cancellation token set: see [`Backend::set_cancel`]).
pub fn open(
    kind: Kind,
    device: Option<DeviceSelector>,
    options: VulkanOptions,
) -> Result<Box<dyn Backend>> {
    Ok(match kind {
        Kind::Reference => Box::new(CpuReference::new()),
        Kind::Cpu => Box::new(cpu_engine()?),
        Kind::Vulkan => Box::new(open_vulkan(device, options)?),
        Kind::Auto => {
            if auto_choice(device.as_ref()).0 {
                Box::new(open_vulkan(device, options)?)
            } else {
                Box::new(cpu_engine()?)
            }
        }
    })
}

/// The CPU engine on every core, on the instruction set `VKBRDF_CPU_ISA` names (an error
/// for a bad name or one this CPU lacks), else the best.
pub fn cpu_engine() -> Result<CpuEngine> {
    let isa = crate::cpu::Isa::from_env()?;
    Ok(CpuEngine::with_isa(
        std::thread::available_parallelism().map_or(1, |n| n.get()),
        isa,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_an_unknown_name_lists_the_known_ones() {
        for k in Kind::ALL {
            assert_eq!(k.name().parse::<Kind>().unwrap(), k);
        }
        let e = "gpu".parse::<Kind>().unwrap_err().to_string();
        assert_eq!(
            e,
            "unknown backend `gpu`; expected one of: auto, vulkan, cpu, reference"
        );
        assert!("Vulkan".parse::<Kind>().is_err());
    }
}
