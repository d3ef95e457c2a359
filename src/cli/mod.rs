//! Subcommands. Each module parses its own arguments (clap derive) and returns an exit code.

/// `println!` for a command's results: a standard output closed early (`vkbrdf materials |
/// head`) ends the process quietly, as it does other Unix tools, instead of panicking.
macro_rules! outln {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = writeln!(std::io::stdout(), $($t)*) {
            $crate::cli::common::stdout_failed(e)
        }
    }};
}

/// `print!` with [`outln!`]'s handling of a closed standard output.
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = write!(std::io::stdout(), $($t)*) {
            $crate::cli::common::stdout_failed(e)
        }
    }};
}

mod at;
mod backend_choice;
mod bandwidth;
mod bench;
mod check;
mod common;
mod demo;
mod devices;
mod eval;
mod fit;
mod generate;
mod materials;
mod merge;
mod ranges;
mod stress;
mod table;

use clap::{Parser, Subcommand};
pub use common::owns_cancellation;
use common::{start_heartbeat, CANCEL};
use std::process::ExitCode;
use vkbrdf::cancel::Cancel;

/// Evaluate BRDFs in bulk on Vulkan compute, checked against an f64 CPU reference.
///
/// Values are BRDFs f in 1/sr, without the cosine factor. Directions are any length and
/// are normalised; see docs/FORMULAS.md for every model, term and convention.
#[derive(Parser)]
#[command(
    name = "vkbrdf",
    version,
    propagate_version = true,
    after_help = "\
Examples:
  vkbrdf demo                                   # every preset on sample directions
  vkbrdf materials                              # list the presets
  vkbrdf generate --materials m.toml --tuples 1000000 --output t.npy
  vkbrdf eval --materials m.toml --input t.npy --output brdf.npy --terms terms.npy"
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Evaluate a batch of tuples from a .npy file and write BRDF (and term) arrays.
    Eval(eval::Args),
    /// Join the parts of a sharded `eval --shard K/N` into one output.
    Merge(merge::Args),
    /// One material at a few directions given as angles: f and D, G, F, K.
    At(at::Args),
    /// List the built-in material presets, or validate and list a materials file.
    Materials(materials::Args),
    /// Write a seeded sample batch of tuples (.npy) for a materials file.
    Generate(generate::Args),
    /// The built-in default job: every preset on sample directions, checked against the
    /// reference, with a summary table.
    Demo(demo::Args),
    /// Evaluate an adversarial corpus and judge it against the f64 reference: non-finite
    /// outputs, invalid counts, and relative error per term, model and regime.
    Stress(stress::Args),
    /// Throughput against batch size, error and the peers (Mitsuba 3, NumPy, memcpy):
    /// table, JSON and SVG plots.
    Bench(bench::Args),
    /// Conformance: every legal combination on a Vulkan device against the f64 reference;
    /// exit 0 only when all pass — the command to trust a new GPU or driver.
    Check(check::Args),
    /// List the Vulkan devices and the one vkbrdf picks.
    Devices(devices::Args),
    /// Generate tables to EXR (slice, albedo, dfg), MERL binaries and preview pictures.
    Table(table::Args),
    /// Fit an analytic material to measured data (a MERL binary or tuples with values):
    /// its parameters, every published metric, a report and a residual slice.
    Fit(Box<fit::Args>),
}

/// Runs the parsed command line; `cancel` is set when the user asks the process to stop.
pub fn run(cli: Cli, cancel: Cancel) -> anyhow::Result<ExitCode> {
    let _ = CANCEL.set(cancel);
    check_environment()?;
    let long = match &cli.command {
        Command::Check(_) => Some("check"),
        Command::Bench(_) => Some("bench"),
        Command::Stress(_) => Some("stress"),
        Command::Table(_) => Some("table"),
        Command::Eval(_) => Some("eval"),
        Command::Demo(_) => Some("demo"),
        Command::Merge(_) => Some("merge"),
        Command::Fit(_) => Some("fit"),
        _ => None,
    };
    if let Some(name) = long {
        start_heartbeat(name);
    }
    match cli.command {
        Command::Eval(a) => eval::run(&a),
        Command::Merge(a) => merge::run(&a),
        Command::At(a) => at::run(&a),
        Command::Materials(a) => materials::run(&a),
        Command::Generate(a) => generate::run(&a),
        Command::Demo(a) => demo::run(&a),
        Command::Stress(a) => stress::run(&a),
        Command::Bench(a) => bench::run(&a),
        Command::Check(a) => check::run(&a),
        Command::Devices(a) => devices::run(&a),
        Command::Table(a) => table::run(&a),
        Command::Fit(a) => fit::run(&a),
    }
}

/// The environment variables vkbrdf reads whose values are not free text, checked before
/// any work: a misspelt value is an error, never silently the default.
fn check_environment() -> anyhow::Result<()> {
    vkbrdf::cpu::Isa::from_env()?;
    if let Ok(v) = std::env::var("VKBRDF_VALIDATION") {
        if !matches!(v.as_str(), "" | "0" | "1" | "true" | "false" | "yes" | "no") {
            anyhow::bail!(
                "VKBRDF_VALIDATION={v:?}: use 1, true or yes to turn the Vulkan validation layer on, 0, false or no (or unset it) for off"
            );
        }
    }
    Ok(())
}
