//! What a staged output asks of the file system beyond its bytes: its blocks reserved
//! before they are written, its final mode, and a rename made durable.

use std::fs::File;
use std::path::Path;

/// Reserves `len` bytes of `file` on the disk (Linux; elsewhere nothing): the writes then
/// fill blocks already allocated, which costs ext4 less than allocating them piece by piece
/// as the early writeback reaches them (docs/STREAMING.md), and a disk without room says so
/// before any work instead of part-way. A file system without the call (EOPNOTSUPP, ENOSYS,
/// EINVAL) is written as before.
pub(super) fn reserve(file: &File, len: u64) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        use rustix::fs::{fallocate, FallocateFlags};
        use rustix::io::Errno;
        match fallocate(file, FallocateFlags::empty(), 0, len) {
            Ok(()) | Err(Errno::OPNOTSUPP | Errno::NOSYS | Errno::INVAL) => Ok(()),
            Err(e) => Err(e.into()),
        }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (file, len);
        Ok(())
    }
}

/// Makes a rename durable; a failure here loses nothing that the rename has not already
/// made visible, so it is not reported.
pub(super) fn sync_dir(dir: &Path) {
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
}

/// Gives the staged `file` the mode its target `path` has, or a new file's (0666 less the
/// umask): the temporary file was created 0600.
#[cfg(unix)]
pub(super) fn set_final_mode(file: &File, path: &Path) -> std::io::Result<()> {
    use std::os::unix::fs::PermissionsExt;
    let mode = match std::fs::metadata(path) {
        Ok(m) => m.permissions().mode() & 0o7777,
        Err(_) => 0o666 & !current_umask(),
    };
    file.set_permissions(std::fs::Permissions::from_mode(mode))
}

/// See the Unix form: no modes to carry here.
#[cfg(not(unix))]
pub(super) fn set_final_mode(_file: &File, _path: &Path) -> std::io::Result<()> {
    Ok(())
}

/// The process umask, read from /proc (no libc call, no unsafe); 022 when unreadable.
#[cfg(unix)]
fn current_umask() -> u32 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("Umask:").map(|v| v.trim().to_string()))
        })
        .and_then(|v| u32::from_str_radix(&v, 8).ok())
        .unwrap_or(0o022)
}
