//! Cancellation: a token that long library operations check between units of work
//! (chunks of a batch, blocks of an output file) and stop at, cleanly.
//!
//! The library never installs a signal handler of its own: whoever drives it (the CLI's
//! SIGINT/SIGTERM handler, a Python binding's Ctrl-C check) sets the token, and every
//! operation that holds a clone of it returns [`Error::Cancelled`] at its next check,
//! leaving no partial output behind.

use crate::error::{Error, Result};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A shared cancellation flag. Clones share the flag; the default token is never set
/// unless someone calls [`Cancel::cancel`] on it or a clone.
#[derive(Debug, Clone, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A fresh, unset token.
    pub fn new() -> Cancel {
        Cancel::default()
    }

    /// Asks every operation holding this token (or a clone) to stop.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Whether [`Cancel::cancel`] has been called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// `Err(Error::Cancelled)` once the token is set: the check long operations make.
    pub fn check(&self) -> Result<()> {
        if self.is_cancelled() {
            Err(Error::Cancelled)
        } else {
            Ok(())
        }
    }

    /// The underlying flag, for a signal handler to set (e.g. `signal_hook::flag::register`,
    /// which only stores `true` into it: async-signal-safe).
    pub fn flag(&self) -> Arc<AtomicBool> {
        Arc::clone(&self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clones_share_the_flag() {
        let a = Cancel::new();
        let b = a.clone();
        assert!(a.check().is_ok());
        b.cancel();
        assert!(a.is_cancelled());
        assert!(matches!(a.check(), Err(Error::Cancelled)));
        assert!(!Cancel::new().is_cancelled());
    }
}
