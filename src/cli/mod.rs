//! Subcommands. Each module parses its own arguments (clap derive) and returns an exit code.

mod backend_choice;
mod bench;
mod check;
mod demo;
mod devices;
mod eval;
mod generate;
mod materials;
mod stress;
mod table;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Evaluate BRDFs in bulk on Vulkan compute, checked against an f64 CPU reference.
///
/// Values are BRDFs f in 1/sr, without the cosine factor. Directions are any length and
/// are normalised; see FORMULAS in the README for every model, term and convention.
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
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Eval(a) => eval::run(&a),
        Command::Materials(a) => materials::run(&a),
        Command::Generate(a) => generate::run(&a),
        Command::Demo(a) => demo::run(&a),
        Command::Stress(a) => stress::run(&a),
        Command::Bench(a) => bench::run(&a),
        Command::Check(a) => check::run(&a),
        Command::Devices(a) => devices::run(&a),
        Command::Table(a) => table::run(&a),
    }
}
