//! `vkbrdf devices`: the Vulkan devices of this machine and which one vkbrdf uses.

use std::process::ExitCode;
use vkbrdf::gpu::{list_devices, DeviceSelector, INSTALL_HINT};

/// Arguments of `vkbrdf devices`.
#[derive(clap::Args, Debug, Clone)]
#[command(after_help = "\
Lists every Vulkan physical device with its type, driver, Vulkan version, subgroup size,
largest storage-buffer range, memory heaps and queue families, and the memory the
evaluator's input and output buffers take (where the kernel reads its rows and writes its
results: device-local and host-visible input memory means the kernel reads device memory
that the host writes in place). `(default)` marks the device vkbrdf picks
on its own: a discrete GPU, else an integrated one, else a virtual one, else a CPU
implementation such as lavapipe (llvmpipe). Choose another with `--device INDEX` or
`--device NAME` (any part of the name, case-insensitive) on the evaluating commands, or
with the environment variable VKBRDF_DEVICE. The last line says what `--backend auto`
(the default) runs and why: the Vulkan kernel when a device is named or a discrete or
integrated GPU exists, else the native CPU engine.

The first line names the CPU engine's instruction set (the best this CPU runs, or the
one VKBRDF_CPU_ISA=scalar|avx2+fma|avx512 forces) and the ones the CPU could run.

Exit status: 0 devices listed, 2 no Vulkan loader or no device, or a VKBRDF_CPU_ISA this
CPU cannot run.

Examples:
  vkbrdf devices
  vkbrdf eval --device llvmpipe ...
  VKBRDF_DEVICE=1 vkbrdf check")]
pub struct Args {}

/// Runs `vkbrdf devices`.
pub fn run(_args: &Args) -> anyhow::Result<ExitCode> {
    let isa = vkbrdf::cpu::Isa::from_env()?;
    let others: Vec<&str> = vkbrdf::cpu::Isa::available_all()
        .iter()
        .map(|i| i.name())
        .collect();
    let how = match std::env::var(vkbrdf::cpu::isa::ENV) {
        Ok(v) if !v.trim().is_empty() => format!("forced by {}", vkbrdf::cpu::isa::ENV),
        _ => "the best this CPU runs".to_string(),
    };
    outln!(
        "CPU engine: {} ({how}; this CPU runs {}; force one with {}=NAME)",
        isa.name(),
        others.join(", "),
        vkbrdf::cpu::isa::ENV
    );
    let devices = list_devices()?;
    if devices.is_empty() {
        anyhow::bail!("the Vulkan loader found no device; {INSTALL_HINT}");
    }
    for d in &devices {
        out!("{d}");
    }
    if let Ok(sel) = std::env::var("VKBRDF_DEVICE") {
        let matched = match sel.parse::<DeviceSelector>() {
            Ok(DeviceSelector::Index(i)) => devices.iter().any(|d| d.index == i),
            Ok(DeviceSelector::Name(n)) => devices
                .iter()
                .any(|d| d.name.to_lowercase().contains(&n.to_lowercase())),
            Err(_) => false,
        };
        if !matched {
            anyhow::bail!(
                "VKBRDF_DEVICE={sel:?} matches none of the devices listed above; give an index or part of a name, or unset it"
            );
        }
        outln!("VKBRDF_DEVICE={sel} is set: it overrides the default choice.");
    }
    let (vulkan, why) = super::backend_choice::auto_choice(&Default::default());
    let engine = if vulkan {
        "the Vulkan kernel".to_string()
    } else {
        format!("the native CPU engine ({})", vkbrdf::cpu::instruction_set())
    };
    outln!("--backend auto (the default) runs {engine}: {why}.");
    match vkbrdf::gpu::kernel_cache_dir() {
        Some(dir) => outln!(
            "Compiled kernels are kept in {} (VKBRDF_CACHE_DIR=DIR moves it, =off turns it off).",
            dir.display()
        ),
        None => {
            outln!("Compiled kernels are not kept across runs (VKBRDF_CACHE_DIR=DIR keeps them).")
        }
    }
    Ok(ExitCode::SUCCESS)
}
