//! Safe output: no command may destroy data it did not mean to replace.
//!
//! - [`check_outputs`] runs before any work: an output that is one of the inputs (same
//!   device and inode, after links), two outputs naming one file, a missing or unwritable
//!   directory, or a directory given as a file are errors then, not after a long run.
//! - [`stage`] writes an output's bytes; [`commit`] makes a set of staged outputs appear
//!   together. A regular file is written to a temporary file in its own directory and
//!   renamed over the target, so a failure (a full disk, a cancellation) leaves the previous
//!   file intact and no temporary file behind; a symlink is written *through* (the rename
//!   happens in the directory of the file it points to, and the link stays a link); several
//!   regular files commit all or none (an earlier rename is rolled back when a later one
//!   fails). A FIFO, a character or block device, or `-` (standard output) is never replaced
//!   by a regular file: its bytes are held until [`commit`] and then written directly, once
//!   the evaluation has succeeded — atomicity is a promise for regular files only.
//! - Writing checks a [`Cancel`] token between blocks.

mod disk;
mod file_kind;
mod writeback;

use crate::cancel::Cancel;
use crate::error::{Error, Result};
use disk::{set_final_mode, sync_dir};
use file_kind::{file_id, is_fifo, is_fifo_or_device, FileId, Identity};
use std::fs::File;
use std::io::{BufWriter, Cursor, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use writeback::Writeback;

/// The path that means standard output.
pub const STDOUT: &str = "-";

/// Where an output's bytes end up.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Destination {
    /// A regular file (existing or new) at `target`: the path given with every symlink
    /// resolved. Written atomically.
    Regular {
        /// The file the bytes replace (symlinks resolved).
        target: PathBuf,
    },
    /// An existing FIFO or device: written directly, never replaced.
    Special,
    /// Standard output (`-`).
    Stdout,
}

/// Classifies `path` as an output: resolves symlinks (dangling ones too, as `open` would
/// create their target) and refuses directories and sockets.
pub fn destination(path: &Path) -> Result<Destination> {
    if path.as_os_str() == STDOUT {
        return Ok(Destination::Stdout);
    }
    // What the path opens to, links followed by the kernel: `/dev/stdout` is a link to
    // `/proc/self/fd/1`, itself a "magic" link to a pipe or terminal that no path names,
    // so resolving it by hand finds nothing to write.
    if std::fs::metadata(path).is_ok_and(|m| is_fifo_or_device(&m)) {
        return Ok(Destination::Special);
    }
    let target = resolve_links(path).map_err(|source| io_error(path, source))?;
    match std::fs::metadata(&target) {
        Ok(m) if m.is_file() => Ok(Destination::Regular { target }),
        Ok(m) if m.is_dir() => Err(output_error(path, "is a directory; give a file name")),
        Ok(m) if is_fifo_or_device(&m) => Ok(Destination::Special),
        Ok(_) => Err(output_error(
            path,
            "is neither a regular file, a FIFO nor a device",
        )),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Destination::Regular { target }),
        Err(source) => Err(io_error(path, source)),
    }
}

/// Checks, before any work, that `outputs` can be written without harm: none is one of
/// `inputs` (same file after links), no two outputs are the same file, every output's
/// directory exists and accepts new files, and no output is a directory. `-` may appear
/// once, as standard output.
pub fn check_outputs(outputs: &[&Path], inputs: &[&Path]) -> Result<()> {
    let input_ids: Vec<(&Path, FileId)> = inputs
        .iter()
        .filter_map(|p| file_id(p).map(|id| (*p, id)))
        .collect();
    let mut seen: Vec<(&Path, Identity)> = Vec::new();
    for &out in outputs {
        let dest = destination(out)?;
        let identity = match &dest {
            Destination::Stdout => Identity::Stdout,
            Destination::Special => {
                Identity::File(file_id(out).ok_or_else(|| output_error(out, "cannot be examined"))?)
            }
            Destination::Regular { target } => {
                let dir = parent_dir(target);
                check_directory(out, dir)?;
                match file_id(target) {
                    Some(id) => Identity::File(id),
                    None => Identity::NewFile(
                        dir.canonicalize()
                            .map_err(|e| io_error(dir, e))?
                            .join(target.file_name().unwrap_or_default()),
                    ),
                }
            }
        };
        if let Identity::File(id) = &identity {
            if let Some((input, _)) = input_ids.iter().find(|(_, i)| i == id) {
                return Err(output_error(
                    out,
                    &format!(
                        "is the same file as the input `{}`; writing it would destroy the input",
                        input.display()
                    ),
                ));
            }
        }
        if let Some((other, _)) = seen.iter().find(|(_, i)| *i == identity) {
            return Err(output_error(
                out,
                &format!(
                    "names the same file as the output `{}`; one of them would be lost",
                    other.display()
                ),
            ));
        }
        if let Destination::Special = dest {
            // Opening checks permission; a FIFO is not opened here, since opening one for
            // writing blocks until a reader appears.
            if !is_fifo(out) {
                std::fs::OpenOptions::new()
                    .write(true)
                    .open(out)
                    .map_err(|e| io_error(out, e))?;
            }
        }
        seen.push((out, identity));
    }
    Ok(())
}

/// An advisory lock on one output while this process writes it: `flock` on
/// `.NAME.vkbrdf-lock` beside the target, taken when the output is staged and released
/// (the lock file removed) once the set is committed or abandoned. A second vkbrdf writing
/// the same file meanwhile is refused, so two runs never mix their output sets. (On NFS,
/// Linux emulates `flock` with byte-range locks through the lock manager: it holds across
/// clients where `lockd` runs, and not on mounts with `nolock`.)
#[derive(Debug)]
struct OutputLock {
    file: File,
    path: PathBuf,
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        // Removed while still held: a process that opened it meanwhile finds, after it
        // locks, that the path no longer names its file, and starts again.
        let _ = std::fs::remove_file(&self.path);
        let _ = self.file.unlock();
        LOCKS
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .retain(|p| p != &self.path);
    }
}

/// The lock files this process holds, for [`exit_cancelled`] to remove.
static LOCKS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Takes the lock of output `target` (`shown` as the user gave it, for the message).
fn lock_output(target: &Path, shown: &Path) -> Result<OutputLock> {
    use std::os::unix::fs::MetadataExt;
    let name = target.file_name().unwrap_or_default().to_string_lossy();
    let path = parent_dir(target).join(format!(".{name}.vkbrdf-lock"));
    loop {
        let file = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .map_err(|e| io_error(&path, e))?;
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                return Err(output_error(
                    shown,
                    &format!(
                        "another vkbrdf process is writing this output now (lock `{}`); wait for it to finish, or write elsewhere",
                        path.display()
                    ),
                ))
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(io_error(&path, e)),
        }
        let held = file.metadata().map_err(|e| io_error(&path, e))?;
        match std::fs::metadata(&path) {
            Ok(now) if now.dev() == held.dev() && now.ino() == held.ino() => {
                LOCKS
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .push(path.clone());
                return Ok(OutputLock { file, path });
            }
            _ => continue, // its holder removed it between our open and our lock
        }
    }
}

/// Serialises [`commit`] against [`exit_cancelled`].
static COMMIT: Mutex<()> = Mutex::new(());

/// The temporary files this process has staged and not yet renamed.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The prefix of this process's temporary files: `.vkbrdf-PID-`, so that a later run can
/// tell a dead process's leftovers (after SIGKILL or a power cut) from a live one's.
fn temp_prefix(pid: u32) -> String {
    format!(".vkbrdf-{pid}-")
}

/// A new temporary file in `dir` for a staged output, recorded for [`exit_cancelled`];
/// the first use of a directory removes the leftovers of dead vkbrdf processes there.
fn temp_file_in(dir: &Path) -> std::io::Result<tempfile::NamedTempFile> {
    remove_stale_temp_files(dir);
    let file = tempfile::Builder::new()
        .prefix(&temp_prefix(std::process::id()))
        .suffix(".partial")
        .tempfile_in(dir)?;
    LIVE.lock()
        .unwrap_or_else(|e| e.into_inner())
        .push(file.path().to_owned());
    Ok(file)
}

fn untrack(temp: &Path) {
    LIVE.lock()
        .unwrap_or_else(|e| e.into_inner())
        .retain(|p| p != temp);
}

/// Removes `.vkbrdf-PID-*.partial` files in `dir` whose process no longer runs (Linux:
/// no `/proc/PID`). A live process's files, and names of any other form (an older
/// vkbrdf's `.vkbrdf-XXXXXX.partial`, which `vkbrdf eval --help` says may be deleted),
/// are left alone. Each directory is swept once per process.
fn remove_stale_temp_files(dir: &Path) {
    static SWEPT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
    if !Path::new("/proc/self").exists() {
        return; // no way to tell a live pid here
    }
    {
        let mut swept = SWEPT.lock().unwrap_or_else(|e| e.into_inner());
        if swept.iter().any(|d| d == dir) {
            return;
        }
        swept.push(dir.to_owned());
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(name) = name.to_str() else { continue };
        let Some(rest) = name.strip_prefix(".vkbrdf-") else {
            continue;
        };
        if !name.ends_with(".partial") {
            continue;
        }
        let Some(pid) = rest.split('-').next().and_then(|p| p.parse::<u32>().ok()) else {
            continue;
        };
        if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// For a front end's signal handling: waits for a [`commit`] in progress to end, removes
/// every temporary file this process staged and exits with status 130. Used when an
/// operation does not reach its next cancellation check in time (a driver call, a read
/// from a FIFO without a writer): nothing is left half written.
pub fn exit_cancelled() -> ! {
    let _committing = COMMIT.lock().unwrap_or_else(|e| e.into_inner());
    for p in LIVE.lock().unwrap_or_else(|e| e.into_inner()).iter() {
        let _ = std::fs::remove_file(p);
    }
    for p in LOCKS.lock().unwrap_or_else(|e| e.into_inner()).iter() {
        let _ = std::fs::remove_file(p);
    }
    eprintln!("error: cancelled; nothing was written");
    std::process::exit(130)
}

/// A finished output that [`commit`] makes appear.
#[derive(Debug)]
pub struct Staged {
    path: PathBuf,
    bytes: Held,
}

#[derive(Debug)]
enum Held {
    /// Written, flushed and synced to a temporary file beside `target`.
    Temp {
        file: tempfile::NamedTempFile,
        target: PathBuf,
        lock: OutputLock,
    },
    /// For a FIFO, a device or standard output: written directly at commit.
    Memory { data: Vec<u8>, stdout: bool },
}

impl Staged {
    /// The temporary file holding the staged bytes (`None` for an output held in memory:
    /// a FIFO, a device or standard output).
    pub fn temp_path(&self) -> Option<&Path> {
        match &self.bytes {
            Held::Temp { file, .. } => Some(file.path()),
            Held::Memory { .. } => None,
        }
    }
}

/// The writer a [`stage`] body gets: buffered, seekable, and checking the cancellation
/// token on every block it passes on.
pub struct Sink<'a> {
    inner: SinkInner<'a>,
    cancel: &'a Cancel,
}

enum SinkInner<'a> {
    File(BufWriter<&'a mut File>),
    Memory(&'a mut Cursor<Vec<u8>>),
}

impl Write for Sink<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.cancel.is_cancelled() {
            return Err(std::io::Error::other("cancelled"));
        }
        match &mut self.inner {
            SinkInner::File(w) => w.write(buf),
            SinkInner::Memory(c) => c.write(buf),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match &mut self.inner {
            SinkInner::File(w) => w.flush(),
            SinkInner::Memory(c) => c.flush(),
        }
    }
}

impl Seek for Sink<'_> {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        match &mut self.inner {
            SinkInner::File(w) => w.seek(pos),
            SinkInner::Memory(c) => c.seek(pos),
        }
    }
}

/// Writes one output through `body` without making it visible yet: a regular file goes to
/// a synced temporary file in its target's directory; a FIFO, device or `-` is held in
/// memory. A failed or cancelled body leaves nothing behind.
pub fn stage(
    path: &Path,
    cancel: &Cancel,
    body: impl FnOnce(&mut Sink) -> std::io::Result<()>,
) -> Result<Staged> {
    let failed = |source| write_error(cancel, path, source);
    cancel.check()?;
    let bytes = match destination(path)? {
        Destination::Regular { target } => {
            let dir = parent_dir(&target);
            let lock = lock_output(&target, path)?;
            let mut file = temp_file_in(dir).map_err(|e| io_error(path, e))?;
            {
                let mut sink = Sink {
                    inner: SinkInner::File(BufWriter::with_capacity(1 << 20, file.as_file_mut())),
                    cancel,
                };
                body(&mut sink).map_err(failed)?;
                sink.flush().map_err(failed)?;
            }
            file.as_file().sync_all().map_err(failed)?;
            // tempfile creates 0600; give the result the mode a plain create would
            // (0666 & !umask), or keep the mode of the file it replaces.
            set_final_mode(file.as_file(), &target).map_err(failed)?;
            Held::Temp { file, target, lock }
        }
        dest => {
            let mut cursor = Cursor::new(Vec::new());
            {
                let mut sink = Sink {
                    inner: SinkInner::Memory(&mut cursor),
                    cancel,
                };
                body(&mut sink).map_err(failed)?;
            }
            Held::Memory {
                data: cursor.into_inner(),
                stdout: dest == Destination::Stdout,
            }
        }
    };
    Ok(Staged {
        path: path.to_owned(),
        bytes,
    })
}

/// An output written piece by piece — a stream whose parts are computed one after another
/// (`vkbrdf eval` writes each chunk as it is evaluated) — made visible by [`commit`] like a
/// [`stage`]d one: a regular file goes to a temporary file beside its target, anything else
/// is held in memory. Dropped without [`StagedWriter::finish`], it leaves nothing behind.
pub struct StagedWriter {
    path: PathBuf,
    inner: WriterInner,
    cancel: Cancel,
}

enum WriterInner {
    Temp {
        file: tempfile::NamedTempFile,
        out: BufWriter<File>,
        target: PathBuf,
        lock: OutputLock,
        writeback: Option<Writeback>,
    },
    Memory {
        cursor: Cursor<Vec<u8>>,
        stdout: bool,
    },
}

/// Starts a [`StagedWriter`] for `path`; every write checks `cancel`.
pub fn stage_writer(path: &Path, cancel: &Cancel) -> Result<StagedWriter> {
    cancel.check()?;
    let inner = match destination(path)? {
        Destination::Regular { target } => {
            let lock = lock_output(&target, path)?;
            let file = temp_file_in(parent_dir(&target)).map_err(|e| io_error(path, e))?;
            let out = file.as_file().try_clone().map_err(|e| io_error(path, e))?;
            WriterInner::Temp {
                writeback: Writeback::start(file.as_file()),
                file,
                out: BufWriter::with_capacity(1 << 20, out),
                target,
                lock,
            }
        }
        dest => WriterInner::Memory {
            cursor: Cursor::new(Vec::new()),
            stdout: dest == Destination::Stdout,
        },
    };
    Ok(StagedWriter {
        path: path.to_owned(),
        inner,
        cancel: cancel.clone(),
    })
}

impl Write for StagedWriter {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.cancel.is_cancelled() {
            return Err(std::io::Error::other("cancelled"));
        }
        match &mut self.inner {
            WriterInner::Temp { out, writeback, .. } => {
                let n = out.write(buf)?;
                if let Some(w) = writeback {
                    w.wrote(n as u64);
                }
                Ok(n)
            }
            WriterInner::Memory { cursor, .. } => cursor.write(buf),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match &mut self.inner {
            WriterInner::Temp { out, .. } => out.flush(),
            WriterInner::Memory { .. } => Ok(()),
        }
    }
}

impl StagedWriter {
    /// Whether [`StagedWriter::write_at`] can be used: the output is a regular file (a
    /// temporary one until its rename), not a FIFO, a device or standard output.
    pub fn is_positioned(&self) -> bool {
        matches!(self.inner, WriterInner::Temp { .. })
    }

    /// Writes `bytes` at `offset` of the staged file, past the buffer and from any thread
    /// (the pieces must not overlap): several workers then write the rows they evaluated
    /// where those rows go. Only for a regular file ([`StagedWriter::is_positioned`]);
    /// not to be mixed with buffered writes that are not flushed.
    pub fn write_at(&self, offset: u64, bytes: &[u8]) -> Result<()> {
        use std::os::unix::fs::FileExt;
        let failed = |source| write_error(&self.cancel, &self.path, source);
        if self.cancel.is_cancelled() {
            return Err(failed(std::io::Error::other("cancelled")));
        }
        let WriterInner::Temp {
            file, writeback, ..
        } = &self.inner
        else {
            return Err(failed(std::io::Error::other(
                "a positioned write to an output that is not a regular file",
            )));
        };
        file.as_file().write_all_at(bytes, offset).map_err(failed)?;
        if let Some(w) = writeback {
            w.wrote(bytes.len() as u64);
        }
        Ok(())
    }

    /// Reserves the staged file's `len` bytes on the disk before they are written, so that
    /// a disk without room says so before any work (`atomic/disk.rs` says why and where);
    /// nothing for an output written directly.
    pub fn preallocate(&self, len: u64) -> Result<()> {
        match &self.inner {
            WriterInner::Temp { file, .. } => disk::reserve(file.as_file(), len)
                .map_err(|e| write_error(&self.cancel, &self.path, e)),
            WriterInner::Memory { .. } => Ok(()),
        }
    }

    /// The error for a failed write to this output (or [`Error::Cancelled`]).
    pub fn error(&self, source: std::io::Error) -> Error {
        write_error(&self.cancel, &self.path, source)
    }

    /// Flushes and syncs the output: it is then ready for [`commit`].
    pub fn finish(self) -> Result<Staged> {
        let StagedWriter {
            path,
            inner,
            cancel,
        } = self;
        let failed = |source| write_error(&cancel, &path, source);
        let bytes = match inner {
            WriterInner::Temp {
                file,
                mut out,
                target,
                lock,
                writeback,
            } => {
                out.flush().map_err(failed)?;
                drop(out);
                if let Some(w) = writeback {
                    w.finish().map_err(failed)?;
                }
                file.as_file().sync_all().map_err(failed)?;
                set_final_mode(file.as_file(), &target).map_err(failed)?;
                Held::Temp { file, target, lock }
            }
            WriterInner::Memory { cursor, stdout } => Held::Memory {
                data: cursor.into_inner(),
                stdout,
            },
        };
        Ok(Staged { path, bytes })
    }
}

/// Makes every staged output appear: FIFOs, devices and standard output are written first
/// (a failure there leaves every regular file untouched), then each regular file is
/// renamed over its target; when a rename fails, those already made are rolled back (the
/// previous files restored from hard links, new ones removed), so the set appears whole or
/// not at all.
pub fn commit(staged: Vec<Staged>) -> Result<()> {
    // A forced exit on a signal (`exit_cancelled`) waits for a commit in progress, so a
    // set of outputs is never left half renamed.
    let _committing = COMMIT.lock().unwrap_or_else(|e| e.into_inner());
    let (direct, regular): (Vec<Staged>, Vec<Staged>) = staged
        .into_iter()
        .partition(|s| matches!(s.bytes, Held::Memory { .. }));
    for s in direct {
        if let Held::Memory { data, stdout } = s.bytes {
            write_direct(&s.path, &data, stdout).map_err(|e| io_error(&s.path, e))?;
        }
    }
    let keep_backups = regular.len() > 1;
    let mut done: Vec<(PathBuf, Option<PathBuf>)> = Vec::new();
    let mut locks: Vec<OutputLock> = Vec::new();
    let mut result = Ok(());
    for s in regular {
        let Held::Temp { file, target, lock } = s.bytes else {
            continue;
        };
        locks.push(lock); // released when the whole set is done
        let backup = if keep_backups {
            match backup_of(&target) {
                Ok(b) => b,
                Err(e) => {
                    result = Err(io_error(&s.path, e));
                    break;
                }
            }
        } else {
            None
        };
        let temp = file.path().to_owned();
        match file.persist(&target) {
            Ok(_) => {
                untrack(&temp);
                sync_dir(parent_dir(&target));
                done.push((target, backup));
            }
            Err(e) => {
                if let Some(b) = backup {
                    let _ = std::fs::remove_file(b);
                }
                result = Err(io_error(&s.path, e.error));
                break;
            }
        }
    }
    for (target, backup) in done {
        match (&result, backup) {
            (Ok(()), Some(b)) => {
                let _ = std::fs::remove_file(b);
            }
            (Ok(()), None) => {}
            (Err(_), Some(b)) => {
                let _ = std::fs::rename(b, &target);
            }
            (Err(_), None) => {
                let _ = std::fs::remove_file(&target);
            }
        }
    }
    result
}

/// Stages and commits one output (see the module docs).
pub fn write_cancellable(
    path: &Path,
    cancel: &Cancel,
    body: impl FnOnce(&mut Sink) -> std::io::Result<()>,
) -> Result<()> {
    commit(vec![stage(path, cancel, body)?])
}

/// [`write_cancellable`] without a cancellation token, for small outputs (reports).
pub fn write(path: &Path, body: impl FnOnce(&mut Sink) -> std::io::Result<()>) -> Result<()> {
    write_cancellable(path, &Cancel::new(), body)
}

/// Follows `path` through symlinks (at most 40, as the kernel does), also when the last
/// one dangles: the path whose directory entry a write would replace.
fn resolve_links(path: &Path) -> std::io::Result<PathBuf> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let link = std::fs::read_link(&p)?;
                p = if link.is_absolute() {
                    link
                } else {
                    parent_dir(&p).join(link)
                };
            }
            _ => return Ok(p),
        }
    }
    Err(std::io::Error::other("too many levels of symbolic links"))
}

/// The directory holding `path` (`.` for a bare file name).
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// The directory exists and a file can be created in it (the test `open` would make:
/// permissions, a read-only mount, a full inode table).
fn check_directory(out: &Path, dir: &Path) -> Result<()> {
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => {
            return Err(output_error(
                out,
                &format!("`{}` is not a directory", dir.display()),
            ))
        }
        Err(_) => {
            return Err(output_error(
                out,
                &format!("the directory `{}` does not exist", dir.display()),
            ))
        }
    }
    tempfile::Builder::new()
        .prefix(".vkbrdf-")
        .suffix(".probe")
        .tempfile_in(dir)
        .map(drop)
        .map_err(|e| {
            output_error(
                out,
                &format!("cannot create files in `{}`: {e}", dir.display()),
            )
        })
}

/// A hard link to `target` beside it, to restore it if a later rename of the set fails;
/// `None` when there is no previous file.
fn backup_of(target: &Path) -> std::io::Result<Option<PathBuf>> {
    if !target.exists() {
        return Ok(None);
    }
    let dir = parent_dir(target);
    for k in 0..100u32 {
        let name = dir.join(format!(".vkbrdf-{}-{k}.previous", std::process::id()));
        match std::fs::hard_link(target, &name) {
            Ok(()) => return Ok(Some(name)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
            Err(e) => return Err(e),
        }
    }
    Err(std::io::Error::other("no free name for a backup link"))
}

fn write_direct(path: &Path, data: &[u8], stdout: bool) -> std::io::Result<()> {
    if stdout {
        let mut out = std::io::stdout().lock();
        out.write_all(data)?;
        out.flush()
    } else {
        let mut f = std::fs::OpenOptions::new().write(true).open(path)?;
        f.write_all(data)?;
        f.flush()
    }
}

/// A failed write to `path`: [`Error::Cancelled`] when the token was the cause (the writer
/// refused the block), else the I/O error naming the path.
fn write_error(cancel: &Cancel, path: &Path, source: std::io::Error) -> Error {
    if cancel.is_cancelled() {
        Error::Cancelled
    } else {
        io_error(path, source)
    }
}

fn io_error(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_owned(),
        source,
    }
}

fn output_error(path: &Path, message: &str) -> Error {
    Error::Output {
        path: path.to_owned(),
        message: message.to_owned(),
    }
}
