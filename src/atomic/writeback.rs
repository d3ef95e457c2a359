//! Early writeback for a staged output written piece by piece: a thread beside the writer
//! syncs the file's data every [`WRITEBACK_EVERY`] bytes, so the disk writes the first
//! chunks while later ones are still being computed, and the fsync that makes the output
//! durable before its rename waits only for the last stretch. Without it, `vkbrdf eval`
//! sat idle at its end for the whole file's writeback (a fifth of a 10^7-tuple run here).

use std::fs::File;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{sync_channel, SyncSender, TrySendError};
use std::thread::JoinHandle;

/// Bytes written between two early syncs: large enough that a sync's fixed cost is noise,
/// small enough that the final one waits for little — and that an output of a few MiB
/// (2^20 tuples' BRDF is 12 MiB) is synced while it is computed: at 32 MiB its whole
/// writeback came after the last chunk (docs/STREAMING.md).
pub(crate) const WRITEBACK_EVERY: u64 = 4 << 20;

/// The syncing thread of one file; see the module docs.
pub(crate) struct Writeback {
    request: Option<SyncSender<()>>,
    thread: Option<JoinHandle<std::io::Result<()>>>,
    since_last: AtomicU64,
}

impl Writeback {
    /// Starts the thread on a handle of `file`'s own. `None` when the system refuses a
    /// handle or a thread: the output is then made durable by its final fsync alone, as
    /// before (slower, never less safe).
    pub(crate) fn start(file: &File) -> Option<Writeback> {
        let handle = file.try_clone().ok()?;
        let (request, requests) = sync_channel::<()>(1);
        let thread = std::thread::Builder::new()
            .name("vkbrdf-writeback".into())
            .spawn(move || {
                for () in requests {
                    handle.sync_data()?;
                }
                Ok(())
            })
            .ok()?;
        Some(Writeback {
            request: Some(request),
            thread: Some(thread),
            since_last: AtomicU64::new(0),
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
        if let Some(r) = &self.request {
            match r.try_send(()) {
                Ok(()) | Err(TrySendError::Full(())) => {
                    self.since_last.fetch_sub(since, Ordering::Relaxed);
                }
                // The thread stopped on an error, which `finish` reports.
                Err(TrySendError::Disconnected(())) => {}
            }
        }
    }

    /// Stops the thread after its last sync; the first error a sync met (the output's
    /// final fsync must not hide it: after a failed sync the kernel may have dropped the
    /// pages and cleared the error).
    pub(crate) fn finish(mut self) -> std::io::Result<()> {
        self.request = None;
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(result)) => result,
            Some(Err(_)) => Err(std::io::Error::other("the writeback thread panicked")),
            None => Ok(()),
        }
    }
}

impl Drop for Writeback {
    /// An abandoned output (an error, a cancel): the thread ends after the sync it may be
    /// in, on its own handle; nothing waits for it, and the file it syncs is being removed.
    fn drop(&mut self) {
        self.request = None;
    }
}
