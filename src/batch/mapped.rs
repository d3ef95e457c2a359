//! Windows of a float32 `.npy` input mapped read-only ([`Window`]), so that a streamed
//! `eval` reads its rows where the page cache holds them instead of copying them into a
//! buffer first: the CPU engine's workers evaluate them there, and the Vulkan engine's
//! one copy is the page cache's into its staging memory. That copy was the largest share
//! of a streamed `eval` left (docs/STREAMING.md, "Rows read in place").
//!
//! A mapped file that shrinks under the run (another process truncates it) or whose page
//! cannot be read (a disk's I/O error) raises SIGBUS at the access, which kills the process
//! where `pread` would have returned an error. [`enable`] installs a SIGBUS handler that,
//! for an address inside a live window, maps a page of zeros over the faulting page and
//! records the address; the reader asks its window afterwards ([`Window::fault`]) and
//! reports the error with the row, and the run's outputs, all temporary, go. Every other
//! SIGBUS goes to the action installed before (the default one ends the process as it
//! would have). EFL's `eina_mmap_safety` and Sapling's indexedlog recover the same way.
//!
//! Mapping is opt-in for the process ([`enable`], which the command line calls): a library
//! that takes over a signal's action unasked would surprise its host. Where it is not
//! enabled, or another handler has since replaced this one, or the system is not Linux,
//! rows are read by `pread` as before.

use std::fs::File;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Windows alive at once, at most (one a CPU worker; more wait for `pread`).
const SLOTS: usize = 64;

/// A live window's address range, as the SIGBUS handler reads it.
struct Slot {
    busy: AtomicBool,
    /// The range's first byte and one past its last (0, 0: none, so no address matches).
    start: AtomicUsize,
    end: AtomicUsize,
    /// The first address that faulted (0: none).
    fault: AtomicUsize,
}

#[allow(clippy::declare_interior_mutable_const)] // a template for the array's slots
const FREE: Slot = Slot {
    busy: AtomicBool::new(false),
    start: AtomicUsize::new(0),
    end: AtomicUsize::new(0),
    fault: AtomicUsize::new(0),
};

static LIVE: [Slot; SLOTS] = [FREE; SLOTS];

/// Lets streamed runs read a float32 input's rows where the page cache holds them
/// (read-only mappings of a chunk at a time) instead of copying them; returns whether
/// they can (Linux). It installs a SIGBUS handler for the process, once: a file truncated
/// under the run then fails the run with an error naming the row, as a read would,
/// instead of ending the process; a SIGBUS elsewhere goes to the action installed before.
/// Programs call it at start (`vkbrdf`'s `main` does); without it, or where another
/// handler later replaces this one, rows are read by `pread`.
pub fn enable() -> bool {
    guard::install()
}

/// Whether windows may be mapped now: [`enable`] ran and its handler is still the
/// process's SIGBUS action.
pub(crate) fn active() -> bool {
    guard::installed()
}

/// The page size the SIGBUS handler replaces faulting pages by (tests cut files on it).
#[cfg(test)]
pub(crate) fn page_size() -> usize {
    guard::page_size()
}

/// A read-only shared mapping of a byte range of a file, registered with the SIGBUS
/// handler for as long as it lives.
pub(crate) struct Window {
    // `slot` is released in `drop`, before the field `map` unmaps the pages.
    map: memmap2::Mmap,
    slot: &'static Slot,
}

impl Window {
    /// `len` bytes of `file` from `offset`, mapped with their page-table entries filled
    /// (one call instead of a fault every few pages); `None` where they cannot be mapped
    /// (mapping not [`active`], no slot free, the kernel refused): read them instead.
    pub(crate) fn new(file: &File, offset: u64, len: usize) -> Option<Window> {
        if len == 0 || !active() {
            return None;
        }
        let slot = LIVE.iter().find(|s| {
            s.busy
                .compare_exchange(false, true, Ordering::Acquire, Ordering::Relaxed)
                .is_ok()
        })?;
        match map(file, offset, len) {
            Some(map) => {
                let range = map.as_ptr() as usize..map.as_ptr() as usize + map.len();
                slot.fault.store(0, Ordering::Relaxed);
                slot.end.store(range.end, Ordering::Relaxed);
                // Published last: the handler matches an address only once `start` is set.
                slot.start.store(range.start, Ordering::Release);
                Some(Window { map, slot })
            }
            None => {
                slot.busy.store(false, Ordering::Release);
                None
            }
        }
    }

    /// The range's bytes. A page that faulted reads as zeros ([`Window::fault`] says so).
    pub(crate) fn bytes(&self) -> &[u8] {
        &self.map
    }

    /// The offset in [`Window::bytes`] of the first page that could not be read (the file
    /// shrank under the mapping, or its disk failed), if any did.
    pub(crate) fn fault(&self) -> Option<usize> {
        match self.slot.fault.load(Ordering::Acquire) {
            0 => None,
            at => Some(at.saturating_sub(self.map.as_ptr() as usize)),
        }
    }
}

impl Drop for Window {
    fn drop(&mut self) {
        // Unregistered before `map` unmaps: an address of a freed range never matches.
        self.slot.start.store(0, Ordering::Release);
        self.slot.end.store(0, Ordering::Release);
        self.slot.busy.store(false, Ordering::Release);
    }
}

/// `len` bytes of `file` from `offset`, mapped read-only and populated.
#[allow(unsafe_code)] // memmap2's map is unsafe: the mapped file may change under it
fn map(file: &File, offset: u64, len: usize) -> Option<memmap2::Mmap> {
    // SAFETY: the mapping is read-only and private to this process's reads. Another
    // process may still change or truncate the file: a change shows as different floats
    // (as it would to `pread`), and a truncation faults, which the SIGBUS handler turns
    // into a zero page and a recorded fault (`active` checked it is installed) that the
    // reader reports before it uses any value of the window.
    unsafe {
        memmap2::MmapOptions::new()
            .offset(offset)
            .len(len)
            .populate()
            .map(file)
    }
    .ok()
}

/// Elsewhere no handler: mapped reads stay off, rows are read by `pread`.
#[cfg(not(target_os = "linux"))]
mod guard {
    pub(super) fn install() -> bool {
        false
    }

    pub(super) fn installed() -> bool {
        false
    }

    pub(super) fn page_size() -> usize {
        4096
    }
}

/// The SIGBUS handler and its installation (Linux).
#[cfg(target_os = "linux")]
mod guard {
    use super::{Ordering, LIVE};
    use std::sync::OnceLock;

    /// The action before this module's: where a SIGBUS outside every window goes.
    static PREVIOUS: OnceLock<libc::sigaction> = OnceLock::new();
    /// The system's page size, read once at installation (the handler may not call
    /// `sysconf`).
    static PAGE: super::AtomicUsize = super::AtomicUsize::new(4096);
    static INSTALLED: OnceLock<bool> = OnceLock::new();

    pub(super) fn install() -> bool {
        *INSTALLED.get_or_init(|| {
            let Some(previous) = current() else {
                return false;
            };
            let _ = PREVIOUS.set(previous);
            PAGE.store(page_size(), Ordering::Relaxed);
            set(handler_action())
        })
    }

    pub(super) fn installed() -> bool {
        INSTALLED.get() == Some(&true)
            && current().is_some_and(|a| a.sa_sigaction == on_sigbus as *const () as usize)
    }

    #[allow(unsafe_code)] // no crate installs a handler that returns from a fault
    pub(super) fn page_size() -> usize {
        // SAFETY: sysconf reads a constant of the system; no memory of ours.
        let p = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
        usize::try_from(p)
            .ok()
            .filter(|p| p.is_power_of_two())
            .unwrap_or(4096)
    }

    /// The process's SIGBUS action now.
    #[allow(unsafe_code)]
    fn current() -> Option<libc::sigaction> {
        // SAFETY: a zeroed sigaction is a valid value of the plain C struct, and
        // sigaction with a null new action only writes the current one into `old`.
        unsafe {
            let mut old: libc::sigaction = std::mem::zeroed();
            (libc::sigaction(libc::SIGBUS, std::ptr::null(), &mut old) == 0).then_some(old)
        }
    }

    /// Makes `action` the process's SIGBUS action.
    #[allow(unsafe_code)]
    fn set(action: libc::sigaction) -> bool {
        // SAFETY: `action` is a fully initialised sigaction; the kernel copies it.
        unsafe { libc::sigaction(libc::SIGBUS, &action, std::ptr::null_mut()) == 0 }
    }

    #[allow(unsafe_code)]
    fn handler_action() -> libc::sigaction {
        // SAFETY: as in `current`; the mask is then emptied by sigemptyset on our value.
        unsafe {
            let mut a: libc::sigaction = std::mem::zeroed();
            a.sa_sigaction = on_sigbus as *const () as usize;
            a.sa_flags = libc::SA_SIGINFO;
            libc::sigemptyset(&mut a.sa_mask);
            a
        }
    }

    /// The handler: a fault inside a live window gets a page of zeros over the faulting
    /// page and is recorded; the instruction then runs again and reads the zeros. Only
    /// async-signal-safe work: atomics and the `mmap` and `sigaction` system calls.
    #[allow(unsafe_code)]
    extern "C" fn on_sigbus(
        signal: libc::c_int,
        info: *mut libc::siginfo_t,
        context: *mut libc::c_void,
    ) {
        // SAFETY: an SA_SIGINFO handler gets a valid siginfo_t from the kernel; for
        // SIGBUS its address field is the faulting address.
        let (address, code) = unsafe { ((*info).si_addr() as usize, (*info).si_code) };
        let window = LIVE.iter().find(|s| {
            let start = s.start.load(Ordering::Acquire);
            start != 0 && start <= address && address < s.end.load(Ordering::Acquire)
        });
        // A fault the kernel raised (si_code > 0), not a SIGBUS another process sent.
        if let Some(slot) = window.filter(|_| code > 0) {
            let page = PAGE.load(Ordering::Relaxed);
            let at = address & !(page - 1);
            // SAFETY: the page lies in a window this process mapped and still holds (a
            // window leaves `LIVE` before it is unmapped), so replacing it with a private
            // zero page changes only what that window's reader sees, which it is told.
            let zero = unsafe {
                libc::mmap(
                    at as *mut libc::c_void,
                    page,
                    libc::PROT_READ,
                    libc::MAP_PRIVATE | libc::MAP_ANONYMOUS | libc::MAP_FIXED,
                    -1,
                    0,
                )
            };
            if zero as usize == at {
                let _ =
                    slot.fault
                        .compare_exchange(0, address, Ordering::Release, Ordering::Relaxed);
                return;
            }
        }
        chain(signal, info, context);
    }

    /// Hands the signal to the action installed before this module's.
    #[allow(unsafe_code)]
    fn chain(signal: libc::c_int, info: *mut libc::siginfo_t, context: *mut libc::c_void) {
        let Some(previous) = PREVIOUS.get() else {
            return default(signal, info);
        };
        match previous.sa_sigaction {
            libc::SIG_DFL | libc::SIG_IGN => default(signal, info),
            f if previous.sa_flags & libc::SA_SIGINFO != 0 => {
                type Action = extern "C" fn(libc::c_int, *mut libc::siginfo_t, *mut libc::c_void);
                // SAFETY: with SA_SIGINFO the previous action's address is a
                // three-argument handler, which the kernel would have called so.
                let f: Action = unsafe { std::mem::transmute::<usize, Action>(f) };
                f(signal, info, context)
            }
            f => {
                type Handler = extern "C" fn(libc::c_int);
                // SAFETY: without SA_SIGINFO it is a one-argument handler.
                let f: Handler = unsafe { std::mem::transmute::<usize, Handler>(f) };
                f(signal)
            }
        }
    }

    /// The default action, as if no handler had been installed: for a fault, returning
    /// runs the instruction again, which faults again and ends the process; a SIGBUS sent
    /// by another process is raised again.
    #[allow(unsafe_code)]
    fn default(signal: libc::c_int, info: *mut libc::siginfo_t) {
        // SAFETY: a zeroed sigaction is SIG_DFL with an empty mask and no flags.
        let dfl: libc::sigaction = unsafe { std::mem::zeroed() };
        set(dfl);
        // SAFETY: as in `on_sigbus`.
        if unsafe { (*info).si_code } <= 0 {
            // SAFETY: raise takes an integer and sends the signal to this thread.
            unsafe { libc::raise(signal) };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::hint::black_box;

    /// Bytes that differ from their neighbours and from zero, so a page read from the
    /// wrong place or zero-filled cannot match by chance.
    fn pattern(len: usize) -> Vec<u8> {
        (0..len as u64)
            .map(|i| ((i.wrapping_mul(2_654_435_761) >> 13) as u8) | 1)
            .collect()
    }

    #[test]
    #[cfg(target_os = "linux")]
    fn a_window_reads_the_file_in_place_and_a_truncated_page_reads_zeros_and_is_reported() {
        assert!(enable(), "the SIGBUS handler installs on Linux");
        let page = guard_page();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rows.bin");
        let bytes = pattern(3 * page + 100);
        std::fs::write(&path, &bytes).unwrap();
        let file = File::open(&path).unwrap();
        // From an offset inside the first page to the end: three pages touched.
        let w = Window::new(&file, 100, 3 * page).expect("a window maps");
        assert!(w.bytes() == &bytes[100..100 + 3 * page]);
        assert_eq!(w.fault(), None);
        // Another process's truncation: the file now ends 10 bytes into its second page,
        // so its third and fourth pages are gone (an access there raises SIGBUS) while the
        // rest of the second reads as zeros without a fault.
        std::fs::OpenOptions::new()
            .write(true)
            .open(&path)
            .unwrap()
            .set_len(page as u64 + 10)
            .unwrap();
        let read: Vec<u8> = w.bytes().iter().map(|b| black_box(*b)).collect();
        let gone = 2 * page - 100; // the window's offset of the file's third page
        assert!(
            read[..page - 100] == bytes[100..page],
            "the first page is kept"
        );
        assert!(
            read[gone..].iter().all(|&b| b == 0),
            "lost pages read as zeros"
        );
        let fault = w.fault().expect("the lost page's access is reported");
        assert!(
            (gone..3 * page).contains(&fault),
            "fault at {fault}, the lost pages start at {gone}"
        );
        // A fresh window over what is left reads it and reports nothing.
        drop(w);
        let w = Window::new(&file, 0, page).expect("a window maps");
        assert!(w.bytes() == &bytes[..page]);
        assert_eq!(w.fault(), None);
    }

    /// A SIGBUS outside every window still ends the process: the test runs itself in a
    /// child process that faults on a mapping of its own, and the child must die of it.
    #[test]
    #[cfg(target_os = "linux")]
    fn a_sigbus_outside_every_window_still_ends_the_process() {
        const CHILD: &str = "VKBRDF_SIGBUS_CHILD";
        if let Some(dir) = std::env::var_os(CHILD) {
            assert!(enable());
            let path = std::path::Path::new(&dir).join("other.bin");
            std::fs::write(&path, pattern(2 * guard_page())).unwrap();
            let file = File::open(&path).unwrap();
            // SAFETY: the test truncates the file under this mapping on purpose, to
            // raise the SIGBUS it checks.
            #[allow(unsafe_code)]
            let other = unsafe { memmap2::Mmap::map(&file).unwrap() };
            file.set_len(0).ok();
            std::fs::OpenOptions::new()
                .write(true)
                .open(&path)
                .unwrap()
                .set_len(0)
                .unwrap();
            black_box(other[guard_page()]);
            std::process::exit(0); // reached only if the fault was swallowed
        }
        let dir = tempfile::tempdir().unwrap();
        let status = std::process::Command::new(std::env::current_exe().unwrap())
            .args([
                "batch::mapped::tests::a_sigbus_outside_every_window_still_ends_the_process",
                "--exact",
                "--test-threads=1",
            ])
            .env(CHILD, dir.path())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status()
            .unwrap();
        use std::os::unix::process::ExitStatusExt;
        assert_eq!(status.signal(), Some(libc::SIGBUS), "{status:?}");
    }

    fn guard_page() -> usize {
        page_size()
    }
}
