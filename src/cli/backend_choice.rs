//! `--backend`, `--device` and `--max-gpu-memory`: which evaluator a command runs on.

use vkbrdf::backend::Backend;
use vkbrdf::gpu::{DeviceSelector, VulkanBackend, VulkanOptions};
use vkbrdf::reference::CpuReference;

/// The evaluators a command can run on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BackendKind {
    /// Vulkan compute (the GLSL kernel) on the chosen device.
    Vulkan,
    /// The f64 CPU reference (exact; the judge).
    Cpu,
}

/// Backend options shared by the commands that evaluate.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct BackendArgs {
    /// Evaluator: `vulkan` (default; falls back to `cpu` with a message when no Vulkan
    /// driver is installed) or `cpu` (the f64 reference).
    #[arg(long, value_enum)]
    pub backend: Option<BackendKind>,
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// Vulkan device options.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct DeviceArgs {
    /// Vulkan device: an index or part of a name from `vkbrdf devices` (default: a GPU if
    /// present, else lavapipe; the environment variable VKBRDF_DEVICE does the same).
    #[arg(long, value_name = "NAME|INDEX")]
    pub device: Option<DeviceSelector>,
    /// Device memory budget for the tuple and output buffers, e.g. 256M or 2G, from 1K
    /// to 1024G; larger batches stream through in chunks.
    #[arg(long, value_name = "BYTES", value_parser = parse_bytes, default_value = "256M",
          allow_negative_numbers = true)]
    pub max_gpu_memory: u64,
}

/// Parses `123`, `64K`, `256M`, `2G` (binary multiples).
pub fn parse_bytes(s: &str) -> Result<u64, String> {
    let s = s.trim();
    let (num, mult) = match s.char_indices().last() {
        Some((i, 'k' | 'K')) => (&s[..i], 1u64 << 10),
        Some((i, 'm' | 'M')) => (&s[..i], 1 << 20),
        Some((i, 'g' | 'G')) => (&s[..i], 1 << 30),
        _ => (s, 1),
    };
    let n: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a size like 256M or 2G"))?;
    let bytes = n * mult as f64;
    if !(n.is_finite() && (1024.0..=(1u64 << 40) as f64).contains(&bytes)) {
        return Err(format!(
            "`{s}` is out of range; give a size from 1K to 1024G"
        ));
    }
    Ok(bytes as u64)
}

/// Opens the Vulkan backend on the selected device.
pub fn open_vulkan(args: &DeviceArgs) -> anyhow::Result<VulkanBackend> {
    let selector = args.device.clone().or_else(DeviceSelector::from_env);
    let options = VulkanOptions {
        max_gpu_memory: args.max_gpu_memory,
        ..VulkanOptions::default()
    };
    Ok(VulkanBackend::new(selector, options)?)
}

/// Opens the requested backend. Without `--backend`, Vulkan is tried first and the CPU
/// reference used (with a message saying how to get Vulkan) when no driver is found.
pub fn open(args: &BackendArgs) -> anyhow::Result<Box<dyn Backend>> {
    let mut backend = open_uncancellable(args)?;
    backend.set_cancel(super::cancel());
    Ok(backend)
}

fn open_uncancellable(args: &BackendArgs) -> anyhow::Result<Box<dyn Backend>> {
    match args.backend {
        Some(BackendKind::Cpu) => Ok(Box::new(CpuReference::new())),
        Some(BackendKind::Vulkan) => Ok(Box::new(open_vulkan(&args.device)?)),
        None => match open_vulkan(&args.device) {
            Ok(b) => Ok(Box::new(b)),
            // Only when nothing asked for a device: a selector (flag or VKBRDF_DEVICE)
            // that matches no device is the user's error, not a reason to switch engines.
            Err(e) if args.device.device.is_none() && DeviceSelector::from_env().is_none() => {
                eprintln!(
                    "note: no Vulkan device ({e:#});\n      falling back to the CPU reference (--backend cpu). For Vulkan on any machine, install lavapipe:\n      sudo apt-get install mesa-vulkan-drivers libvulkan1"
                );
                Ok(Box::new(CpuReference::new()))
            }
            Err(e) => Err(e),
        },
    }
}
