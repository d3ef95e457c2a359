//! What kind of file a path is, and which file: the identities that let `check_outputs`
//! see an output that is an input (through a link or another name), and the FIFOs and
//! devices that are written directly instead of staged.

use std::path::{Path, PathBuf};

/// A file's identity: device and inode (on Unix).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct FileId(u64, u64);

/// What an output or input path names: an existing file, a file not made yet, or
/// standard output.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum Identity {
    File(FileId),
    NewFile(PathBuf),
    Stdout,
}

#[cfg(unix)]
pub(super) fn file_id(path: &Path) -> Option<FileId> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(path)
        .ok()
        .map(|m| FileId(m.dev(), m.ino()))
}

#[cfg(not(unix))]
pub(super) fn file_id(path: &Path) -> Option<FileId> {
    // Without inodes, the canonical path stands in for the identity.
    use std::hash::{Hash, Hasher};
    let p = path.canonicalize().ok()?;
    let mut h = std::collections::hash_map::DefaultHasher::new();
    p.hash(&mut h);
    Some(FileId(0, h.finish()))
}

#[cfg(unix)]
pub(super) fn is_fifo_or_device(m: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::FileTypeExt;
    let t = m.file_type();
    t.is_fifo() || t.is_char_device() || t.is_block_device()
}

#[cfg(not(unix))]
pub(super) fn is_fifo_or_device(_m: &std::fs::Metadata) -> bool {
    false
}

#[cfg(unix)]
pub(super) fn is_fifo(path: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    std::fs::metadata(path).is_ok_and(|m| m.file_type().is_fifo())
}

#[cfg(not(unix))]
pub(super) fn is_fifo(_path: &Path) -> bool {
    false
}
