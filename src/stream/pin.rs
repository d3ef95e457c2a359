//! The CPU engine's workers held to a core each, where the run has the cores to itself.
//!
//! Without it, two workers sometimes shared one core for a whole scheduler tick (4 ms at
//! 250 Hz) while the other core idled: a worker woken from a lock it waited on (the
//! file's, the address space's) is placed beside the worker that woke it, and the load
//! balancer moves it back only at the next tick. A 2^20-tuple run (10 ms) lost a tick one
//! to three times (docs/STREAMING.md, "Workers stacked on one core"). Held to distinct
//! cores, they cannot stack; a worker whose core another program also uses only takes
//! fewer slices, as slices go to whichever worker asks next.
//!
//! Only when the process may run on exactly as many cores as there are workers (the
//! default: one worker a core it may use): with more allowed cores than workers (a
//! container's CPU quota on a larger machine) the scheduler's choice of an idle core is
//! worth more than the tick, and the workers are left free.

/// Cores to hold the workers to, one each, or `None` (see the module docs).
pub(super) fn cores_for(workers: usize) -> Option<Vec<usize>> {
    #[cfg(target_os = "linux")]
    {
        use rustix::thread::{sched_getaffinity, CpuSet};
        let allowed = sched_getaffinity(None).ok()?;
        let cores: Vec<usize> = (0..CpuSet::MAX_CPU)
            .filter(|&c| allowed.is_set(c))
            .collect();
        (workers > 1 && cores.len() == workers).then_some(cores)
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = workers;
        None
    }
}

/// The calling thread held to `core` until this is dropped, when it may again run where it
/// could before.
pub(super) struct Held {
    #[cfg(target_os = "linux")]
    before: Option<rustix::thread::CpuSet>,
}

impl Held {
    /// Holds the calling thread to `core` (nothing, where the system refuses).
    pub(super) fn to(core: usize) -> Held {
        #[cfg(target_os = "linux")]
        {
            use rustix::thread::{sched_getaffinity, sched_setaffinity, CpuSet};
            let before = sched_getaffinity(None).ok();
            let mut only = CpuSet::new();
            only.set(core);
            let held = before.is_some() && sched_setaffinity(None, &only).is_ok();
            Held {
                before: before.filter(|_| held),
            }
        }
        #[cfg(not(target_os = "linux"))]
        {
            let _ = core;
            Held {}
        }
    }
}

impl Drop for Held {
    fn drop(&mut self) {
        #[cfg(target_os = "linux")]
        if let Some(before) = &self.before {
            let _ = rustix::thread::sched_setaffinity(None, before);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A held thread runs only on its core, and is free again afterwards.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_held_thread_runs_on_its_core_and_is_released() {
        use rustix::thread::sched_getaffinity;
        std::thread::spawn(|| {
            let before = sched_getaffinity(None).unwrap();
            let core = (0..rustix::thread::CpuSet::MAX_CPU)
                .find(|&c| before.is_set(c))
                .unwrap();
            {
                let _held = Held::to(core);
                let now = sched_getaffinity(None).unwrap();
                assert_eq!(now.count(), 1);
                assert!(now.is_set(core));
                assert_eq!(rustix::thread::sched_getcpu(), core);
            }
            assert!(sched_getaffinity(None).unwrap() == before);
        })
        .join()
        .unwrap();
        // One worker is never held; as many as the allowed cores are, one core each.
        assert_eq!(cores_for(1), None);
        let allowed = sched_getaffinity(None).unwrap().count() as usize;
        if allowed > 1 {
            let cores = cores_for(allowed).expect("the process's own cores");
            assert_eq!(cores.len(), allowed);
            assert_eq!(cores_for(allowed - 1), None);
        }
    }
}
