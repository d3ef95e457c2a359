//! `--backend` and `--device`: which evaluator a command runs on.

use vkbrdf::backend::Backend;
use vkbrdf::reference::CpuReference;

/// The evaluators a command can run on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BackendKind {
    /// The f64 CPU reference (exact; slower).
    Cpu,
}

/// Backend options shared by the commands that evaluate.
#[derive(clap::Args, Debug, Clone)]
pub struct BackendArgs {
    /// Evaluator to run on.
    #[arg(long, value_enum, default_value = "cpu")]
    pub backend: BackendKind,
}

/// Opens the requested backend.
pub fn open(args: &BackendArgs) -> anyhow::Result<Box<dyn Backend>> {
    match args.backend {
        BackendKind::Cpu => Ok(Box::new(CpuReference::new())),
    }
}
