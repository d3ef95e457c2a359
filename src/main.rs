//! The `vkbrdf` command line: a thin layer over the library. Exit codes: 0 success,
//! 1 a check failed (`check`, `eval --strict`), 2 an error (bad input, no device, I/O),
//! 130 cancelled (SIGINT or SIGTERM; nothing was written).

mod cli;

use clap::Parser;
use std::process::ExitCode;

/// How long the running operation gets after the first signal to stop at its own
/// cancellation check (and clean up) before the watchdog exits for it.
const CANCEL_GRACE: std::time::Duration = std::time::Duration::from_millis(800);

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    let cancel = vkbrdf::cancel::Cancel::new();
    // The first SIGINT or SIGTERM sets the token: the running operation stops at its next
    // check and removes its temporary files. A second SIGINT exits at once (an escape
    // hatch should a check never come).
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        let _ = signal_hook::flag::register_conditional_shutdown(signal, 130, cancel.flag());
        let _ = signal_hook::flag::register(signal, cancel.flag());
    }
    // Every phase stops within about a second of the first signal: the running operation
    // at its next check, or else — parsing, a FIFO without a writer, a driver call, a
    // phase without checks — this watchdog, which removes the staged temporary files
    // and exits 130 itself.
    let watched = cancel.clone();
    std::thread::spawn(move || loop {
        std::thread::sleep(std::time::Duration::from_millis(50));
        if watched.is_cancelled() && !cli::owns_cancellation() {
            std::thread::sleep(CANCEL_GRACE);
            if !cli::owns_cancellation() {
                vkbrdf::atomic::exit_cancelled();
            }
        }
    });
    // The CPU engine's streamed runs read the input's rows in place (mapped), with a
    // truncated input reported as an error rather than a SIGBUS that ends the process.
    vkbrdf::batch::enable_mapped_reads();
    match cli::run(args, cancel) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            if matches!(e.downcast_ref(), Some(vkbrdf::Error::Cancelled)) {
                ExitCode::from(130)
            } else {
                ExitCode::from(2)
            }
        }
    }
}
