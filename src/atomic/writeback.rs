//! Early writeback for a staged output written piece by piece: a thread beside the writer
//! starts the disk's write of the file's data every [`WRITEBACK_EVERY`] bytes, so the disk
//! writes the first chunks while later ones are still being computed, and the fsync that
//! makes the output durable before its rename waits only for the last stretch. Without it,
//! `vkbrdf eval` sat idle at its end for the whole file's writeback (a fifth of a
//! 10^7-tuple run here).
//!
//! On Linux the thread only starts the write (`sync_file_range(SYNC_FILE_RANGE_WRITE)`):
//! it neither waits for the disk nor commits the file system's journal, which `fdatasync`
//! does at every call for a file that grows (its size and blocks are metadata). The final
//! fsync is what makes the output durable, on every system; an error of the early writes
//! reaches it (the kernel records writeback errors for the file's next fsync), and the
//! thread's own errors are reported too. Elsewhere the thread calls `fdatasync`.
//!
//! When every core is busy (the CPU engine's workers take them all), the thread, woken,
//! may not run for milliseconds: the scheduler lets the running workers finish their
//! slices first, and a 2^20-tuple run's whole output then waited for its final fsync
//! (1–4 ms of a 10 ms run, against 0.4–0.9 with the writes started on time). So a writer
//! that finds the last request still untaken, with the thread not inside a call, starts
//! the write itself; a thread inside a call means the disk is what is slow, and the writer
//! goes on (docs/STREAMING.md, "The writeback thread starved").

use std::fs::File;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{sync_channel, SyncSender, TrySendError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

/// Bytes written between two early writebacks: large enough that a call's fixed cost is
/// noise, small enough that the final fsync waits for little — and that an output of a few
/// MiB (2^20 tuples' BRDF is 12 MiB) reaches the disk while it is computed: at 32 MiB its
/// whole writeback came after the last chunk (docs/STREAMING.md).
#[cfg(target_os = "linux")]
pub(crate) const WRITEBACK_EVERY: u64 = 1 << 20;
/// See the Linux constant: `fdatasync` commits the journal at each call, so it is called
/// less often.
#[cfg(not(target_os = "linux"))]
pub(crate) const WRITEBACK_EVERY: u64 = 4 << 20;

/// The syncing thread of one file; see the module docs.
pub(crate) struct Writeback {
    request: Option<SyncSender<()>>,
    thread: Option<JoinHandle<std::io::Result<()>>>,
    since_last: AtomicU64,
    shared: Arc<Shared>,
}

/// What the thread and the writers share.
struct Shared {
    /// A handle of the file's own (the writers' calls use it).
    file: File,
    /// The thread is inside a call.
    calling: AtomicBool,
    /// The first error of a writer's own call (the thread returns its own).
    error: Mutex<Option<std::io::Error>>,
}

impl Writeback {
    /// Starts the thread on a handle of `file`'s own. `None` when the system refuses a
    /// handle or a thread: the output is then made durable by its final fsync alone, as
    /// before (slower, never less safe).
    pub(crate) fn start(file: &File) -> Option<Writeback> {
        let shared = Arc::new(Shared {
            file: file.try_clone().ok()?,
            calling: AtomicBool::new(false),
            error: Mutex::new(None),
        });
        let theirs = Arc::clone(&shared);
        let (request, requests) = sync_channel::<()>(1);
        let thread = std::thread::Builder::new()
            .name("vkbrdf-writeback".into())
            .spawn(move || {
                for () in requests {
                    theirs.calling.store(true, Ordering::Relaxed);
                    let started = start_writeback(&theirs.file);
                    theirs.calling.store(false, Ordering::Relaxed);
                    started?;
                }
                Ok(())
            })
            .ok()?;
        Some(Writeback {
            request: Some(request),
            thread: Some(thread),
            since_last: AtomicU64::new(0),
            shared,
        })
    }

    /// `bytes` more reached the file: asks for a sync once [`WRITEBACK_EVERY`] have since
    /// the last request (never waits: a sync still running takes the new bytes next time).
    /// Writers on several threads may call it at once.
    pub(crate) fn wrote(&self, bytes: u64) {
        let since = self.since_last.fetch_add(bytes, Ordering::Relaxed) + bytes;
        if since < WRITEBACK_EVERY {
            return;
        }
        let Some(r) = &self.request else {
            return;
        };
        let sent = r.try_send(());
        // Disconnected: the thread stopped on an error, which `finish` reports.
        if matches!(sent, Err(TrySendError::Disconnected(()))) {
            return;
        }
        self.since_last.fetch_sub(since, Ordering::Relaxed);
        // Full: the last request is still untaken; a thread outside any call has not run
        // since (starved, see the module docs), so the write is started here.
        let starved = sent.is_err() && !self.shared.calling.load(Ordering::Relaxed);
        if starved {
            if let Err(e) = start_writeback(&self.shared.file) {
                let mut first = self.shared.error.lock().unwrap_or_else(|p| p.into_inner());
                first.get_or_insert(e);
            }
        }
    }

    /// Stops the thread after its last sync; the first error a sync met (the output's
    /// final fsync must not hide it: after a failed sync the kernel may have dropped the
    /// pages and cleared the error).
    pub(crate) fn finish(mut self) -> std::io::Result<()> {
        self.request = None;
        let thread = match self.thread.take().map(JoinHandle::join) {
            Some(Ok(result)) => result,
            Some(Err(_)) => Err(std::io::Error::other("the writeback thread panicked")),
            None => Ok(()),
        };
        let mine = self
            .shared
            .error
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take();
        thread.and(mine.map_or(Ok(()), Err))
    }
}

/// Starts the disk's write of `file`'s dirty pages without waiting for it (Linux), see the
/// module docs.
#[cfg(target_os = "linux")]
#[allow(unsafe_code)] // no safe wrapper of sync_file_range in rustix or std
fn start_writeback(file: &File) -> std::io::Result<()> {
    use std::os::fd::AsRawFd;
    // Offset 0 and length 0: the whole file, as far as it reaches when the call runs.
    // SAFETY: `file` is an open file the caller holds a handle of for the whole call, and
    // sync_file_range reads no memory of ours: its arguments are integers.
    let r = unsafe { libc::sync_file_range(file.as_raw_fd(), 0, 0, libc::SYNC_FILE_RANGE_WRITE) };
    if r == 0 {
        return Ok(());
    }
    let e = std::io::Error::last_os_error();
    match e.raw_os_error() {
        // A kernel or file system that does not take the call (a sandbox's ENOSYS, a
        // file system's EINVAL or EOPNOTSUPP) gets the sync it had before; any other
        // error is the output's.
        Some(libc::ENOSYS | libc::EINVAL | libc::EOPNOTSUPP) => file.sync_data(),
        _ => Err(e),
    }
}

/// The data synced (systems without `sync_file_range`).
#[cfg(not(target_os = "linux"))]
fn start_writeback(file: &File) -> std::io::Result<()> {
    file.sync_data()
}

impl Drop for Writeback {
    /// An abandoned output (an error, a cancel): the thread ends after the sync it may be
    /// in, on its own handle; nothing waits for it, and the file it syncs is being removed.
    fn drop(&mut self) {
        self.request = None;
    }
}
