//! The `vkbrdf` command line: a thin layer over the library. Exit codes: 0 success,
//! 1 a check failed (`check`, `eval --strict`), 2 an error (bad input, no device, I/O).

mod cli;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
