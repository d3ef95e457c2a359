//! `vkbrdf merge`: joins the parts of a sharded `eval` or `table` into one output.

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

Table parts (`vkbrdf table slice|albedo|dfg|merl --shard K/N`) are joined the same way:
the parts must be every K of one N of the same table (kind, size, options, material) by
the same engine, device and version (--allow-mixed accepts a mix); OUT is the EXR (or MERL
binary) the unsharded command writes, bit for bit, with the same channels and header.

Examples:
  seq 1 4 | xargs -P 4 -I K vkbrdf eval -m m.toml -i t.npy -o part-K.npy --terms terms-K.npy --shard K/4
  vkbrdf merge -o brdf.npy --terms terms.npy part-*.npy
  seq 1 4 | xargs -P 4 -I K vkbrdf table dfg --lut-style filament -o dfg-K.npy --shard K/4
  vkbrdf merge -o dfg.exr dfg-*.npy")]
pub struct Args {
    /// Where the joined BRDF goes (.npy, float32 (n, 3)); for table parts, the table
    /// (EXR or MERL binary).
    #[arg(long, short = 'o', value_name = "OUT")]
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
    let cancel = super::common::cancel();
    // Table parts or batch parts, never both.
    let mut kinds = Vec::with_capacity(args.parts.len());
    for p in &args.parts {
        kinds.push(vkbrdf::table::shard::is_table_part(p)?);
    }
    let what = |table: bool| {
        if table {
            "a part of a table (vkbrdf table … --shard)"
        } else {
            "a part of a batch (vkbrdf eval --shard)"
        }
    };
    if let Some(i) = kinds.iter().position(|&t| t != kinds[0]) {
        anyhow::bail!(vkbrdf::Error::Batch {
            path: args.parts[i].clone(),
            message: format!(
                "this is {}, but {} is {}: merge the parts of one run",
                what(kinds[i]),
                args.parts[0].display(),
                what(kinds[0])
            ),
        });
    }
    if kinds[0] {
        if let Some(t) = &args.terms {
            anyhow::bail!(
                "--terms {}: table parts carry their terms as a layer of the table (table slice --terms); drop --terms",
                t.display()
            );
        }
        let m = vkbrdf::table::shard::merge(&args.parts, &args.output, args.allow_mixed, &cancel)?;
        for w in &m.warnings {
            eprintln!("warning: {w}");
        }
        eprintln!(
            "merged {} parts of a {} table ({} rows) into {}",
            args.parts.len(),
            m.table,
            m.rows,
            args.output.display()
        );
        return Ok(ExitCode::SUCCESS);
    }
    let m = vkbrdf::stream::shard::merge(
        &args.parts,
        &args.output,
        args.terms.as_deref(),
        args.allow_mixed,
        &cancel,
    )?;
    for w in &m.warnings {
        eprintln!("warning: {w}");
    }
    let c = m.counts;
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
