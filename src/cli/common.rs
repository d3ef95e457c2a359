//! What the commands share with the front end (`cli/mod.rs`): the process's cancellation
//! token, the writes to standard output and the output directory, and the status line of
//! the heartbeat. Below both, so that no command uses the module that dispatches to it.

use vkbrdf::cancel::Cancel;

/// Ends the process after a failed write to standard output: quietly with 141 (as a
/// shell reports a process ended by SIGPIPE) when the reader has gone, else with 2.
pub fn stdout_failed(e: std::io::Error) -> ! {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(141);
    }
    eprintln!("error: writing to standard output: {e}");
    std::process::exit(2)
}

/// The process's cancellation token, set by the signal handler in `main`.
pub(super) static CANCEL: std::sync::OnceLock<Cancel> = std::sync::OnceLock::new();

/// The token every command hands to its backend and its output writes.
pub fn cancel() -> Cancel {
    CANCEL.get().cloned().unwrap_or_default()
}

/// Set while a command handles a cancellation itself (`fit` writes its best result so
/// far): `main`'s watchdog then leaves the exit to it (a second signal still exits at once).
static OWNS_CANCEL: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Says whether the running command handles a cancellation itself ([`OWNS_CANCEL`]).
pub(crate) fn own_cancellation(own: bool) {
    OWNS_CANCEL.store(own, std::sync::atomic::Ordering::SeqCst);
}

/// Whether the running command handles a cancellation itself.
pub fn owns_cancellation() -> bool {
    OWNS_CANCEL.load(std::sync::atomic::Ordering::SeqCst)
}

/// Makes the output directory `dir` (with its parents), or says why not, naming it: called
/// before any work, so that a bad `--out-dir` or `--plot` is found at once.
pub(crate) fn output_dir(dir: &std::path::Path, option: &str) -> anyhow::Result<()> {
    if dir.exists() && !dir.is_dir() {
        anyhow::bail!(
            "{option} {}: exists and is not a directory; give a directory (it is created if missing)",
            dir.display()
        );
    }
    std::fs::create_dir_all(dir).map_err(|e| {
        anyhow::anyhow!(
            "{option} {}: cannot create the directory: {e}",
            dir.display()
        )
    })
}

/// What a long command is doing now, for [`start_heartbeat`]'s lines.
static STATUS: std::sync::Mutex<String> = std::sync::Mutex::new(String::new());

/// Sets the status line a long command reports (see [`start_heartbeat`]).
pub(crate) fn set_status(status: impl Into<String>) {
    *STATUS.lock().unwrap_or_else(|e| e.into_inner()) = status.into();
}

/// `bar.set_message(msg)`, and the same text as the heartbeat's status.
pub(crate) fn progress_message(bar: &indicatif::ProgressBar, msg: String) {
    set_status(msg.clone());
    bar.set_message(msg);
}

/// Where standard error is not a terminal (a pipe, a log, CI), the progress bars draw
/// nothing: a line every 10 s says the command is alive, how long it has run and what it
/// is doing, so that a person reading the log never waits minutes on silence.
pub(super) fn start_heartbeat(command: &'static str) {
    use std::io::IsTerminal;
    if std::io::stderr().is_terminal() {
        return;
    }
    // VKBRDF_PROGRESS_INTERVAL=SECONDS changes the interval (a log that wants fewer
    // lines, a test that wants them sooner).
    let every = std::env::var("VKBRDF_PROGRESS_INTERVAL")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s >= 0.05)
        .map_or(HEARTBEAT, std::time::Duration::from_secs_f64);
    let start = std::time::Instant::now();
    std::thread::spawn(move || loop {
        std::thread::sleep(every);
        let status = STATUS.lock().unwrap_or_else(|e| e.into_inner()).clone();
        let status = if status.is_empty() {
            "working".to_string()
        } else {
            status
        };
        eprintln!(
            "[vkbrdf {command}] {:.0} s: {status}",
            start.elapsed().as_secs_f64()
        );
    });
}

/// How often [`start_heartbeat`] prints by default.
const HEARTBEAT: std::time::Duration = std::time::Duration::from_secs(10);
