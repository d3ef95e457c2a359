//! `vkbrdf merge`: joins the parts of a sharded `eval` into one output.

use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `vkbrdf merge`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Each PART is the BRDF output of `vkbrdf eval --shard K/N`, with its sidecar PART.shard.json
beside it. The parts must be every K of one N, once each, of the same input and materials
file, evaluated by the same engine, device and version (--allow-mixed accepts a mix); the
result is bit-identical to the unsharded run and is written atomically (with --terms, both
files or neither). The joined counts are printed.

Example:
  seq 1 4 | xargs -P 4 -I K vkbrdf eval -m m.toml -i t.npy -o part-K.npy --terms terms-K.npy --shard K/4
  vkbrdf merge -o brdf.npy --terms terms.npy part-*.npy")]
pub struct Args {
    /// Where the joined BRDF goes (.npy, float32 (n, 3)).
    #[arg(long, short = 'o', value_name = "BRDF.npy")]
    pub output: PathBuf,
    /// Also join the parts' terms (each sidecar names its terms part) into this file.
    #[arg(long, value_name = "TERMS.npy")]
    pub terms: Option<PathBuf>,
    /// Accept parts evaluated by different engines, devices or versions.
    #[arg(long)]
    pub allow_mixed: bool,
    /// The BRDF parts.
    #[arg(required = true, value_name = "PART")]
    pub parts: Vec<PathBuf>,
}

/// Runs `vkbrdf merge`.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let cancel = super::cancel();
    let mut inputs: Vec<&std::path::Path> = args.parts.iter().map(PathBuf::as_path).collect();
    let sidecars: Vec<PathBuf> = args
        .parts
        .iter()
        .map(|p| vkbrdf::stream::shard::sidecar_path(p))
        .collect();
    inputs.extend(sidecars.iter().map(PathBuf::as_path));
    let outputs: Vec<&std::path::Path> = std::iter::once(args.output.as_path())
        .chain(args.terms.as_deref())
        .collect();
    vkbrdf::atomic::check_outputs(&outputs, &inputs)?;
    let c = vkbrdf::stream::shard::merge(
        &args.parts,
        &args.output,
        args.terms.as_deref(),
        args.allow_mixed,
        &cancel,
    )?;
    eprintln!(
        "merged {} parts: {} tuples, {} evaluated, {} invalid{}, {} below the horizon, {} saturated",
        args.parts.len(),
        c.tuples,
        c.tuples - c.invalid - c.below_horizon,
        c.invalid,
        c.first_invalid
            .map_or(String::new(), |r| format!(" (first at row {r})")),
        c.below_horizon,
        c.saturated
    );
    Ok(ExitCode::SUCCESS)
}
