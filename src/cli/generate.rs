//! `vkbrdf generate`: a seeded sample batch for a materials file.

use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `vkbrdf generate`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Row i uses material i mod (number of materials). L and V are uniform over the hemisphere
of a random normal N, with random lengths in [0.5, 2); --tangents adds random Tx Ty Tz
columns, which are added anyway when a material of the file is anisotropic (roughness
[mx, my]) and needs them.

Example:
  vkbrdf generate --materials m.toml --tuples 1000000 --tangents --output t.npy")]
pub struct Args {
    /// Materials file whose table the material column indexes.
    #[arg(long, short = 'm', value_name = "M.toml")]
    pub materials: PathBuf,
    /// Number of tuples, 1 to 100,000,000 (the batch is built in memory).
    #[arg(long, short = 'n', default_value_t = 1_000_000, allow_negative_numbers = true,
          value_parser = super::ranges::integer::<usize>(1, super::ranges::MAX_IN_MEMORY_TUPLES))]
    pub tuples: usize,
    /// Append tangent columns (13 columns instead of 10); implied when a material is
    /// anisotropic.
    #[arg(long)]
    pub tangents: bool,
    /// Random seed, 0 to 2^64 − 1 (same seed, same file).
    #[arg(long, default_value_t = 1, allow_negative_numbers = true,
          value_parser = super::ranges::integer::<u64>(0, u64::MAX))]
    pub seed: u64,
    /// Output .npy file (float32).
    #[arg(long, short = 'o', value_name = "T.npy")]
    pub output: PathBuf,
}

/// Runs `vkbrdf generate`.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let materials = vkbrdf::material::load_materials(&args.materials)?;
    vkbrdf::atomic::check_outputs(&[args.output.as_path()], &[args.materials.as_path()])?;
    let anisotropic = materials.iter().find(|m| m.is_anisotropic());
    if let (Some(m), false) = (anisotropic, args.tangents) {
        eprintln!(
            "note: adding tangent columns: material `{}` is anisotropic and needs them",
            m.name
        );
    }
    let tangents = args.tangents || anisotropic.is_some();
    let batch = vkbrdf::sample::sample_batch(args.tuples, materials.len(), args.seed, tangents);
    let cancel = super::common::cancel();
    let staged =
        vkbrdf::batch::stage_npy_f32(&args.output, batch.as_slice(), batch.columns(), &cancel)?;
    vkbrdf::atomic::commit(vec![staged])?;
    eprintln!(
        "wrote {} tuples × {} columns to {}",
        batch.len(),
        batch.columns(),
        args.output.display()
    );
    Ok(ExitCode::SUCCESS)
}
