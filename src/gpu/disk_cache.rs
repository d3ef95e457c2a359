//! What the kernel compiles, kept across runs in the user's cache directory: the SPIR-V
//! shaderc made for each kernel (`spirv/`) and the driver's pipeline cache for each device
//! and driver (`pipelines/`, see [`super::pipeline_cache`]).
//!
//! The directory is `VKBRDF_CACHE_DIR` when set (`off` or empty: no cache), else
//! `$XDG_CACHE_HOME/vkbrdf`, else `$HOME/.cache/vkbrdf`. Each entry is one file written
//! whole under a temporary name and renamed into place, so processes sharing the directory
//! read either an old entry or a new one, never part of one; each carries its length and a
//! checksum, and an entry that does not match them is ignored as if absent. A directory that
//! cannot be created or written (a read-only home, a full disk) is no cache: the run
//! compiles as it would without one. Deleting the directory is always safe.

use std::ffi::OsString;
use std::io::{Read, Write};
use std::path::PathBuf;

/// The first bytes of every entry.
const MAGIC: &[u8; 8] = b"VKBRDFC1";
/// Magic, payload length (u64 LE) and the payload's CRC-32 (`crc32fast`, u64 LE).
const HEADER: usize = 24;
/// Entries larger than this are ignored (and replaced by the next store): a pipeline
/// cache merged run after run is bounded by it.
const MAX_ENTRY: usize = 128 << 20;
/// FNV-1a's offset basis; the entries' names also hash from a second basis.
const FNV_BASIS: u64 = 0xcbf2_9ce4_8422_2325;
/// Entries a folder keeps: past this many, a store removes the oldest half (a new build or
/// a new batch's kernel adds entries, and nothing else ever removes them).
const MAX_ENTRIES: usize = 2048;

/// The cache directory, or none.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct DiskCache {
    dir: Option<PathBuf>,
}

impl DiskCache {
    /// The directory the environment names (see the module documentation).
    pub fn from_env() -> DiskCache {
        DiskCache::from_vars(
            std::env::var_os("VKBRDF_CACHE_DIR"),
            std::env::var_os("XDG_CACHE_HOME"),
            std::env::var_os("HOME"),
        )
    }

    /// [`DiskCache::from_env`] given the three variables.
    fn from_vars(
        explicit: Option<OsString>,
        xdg: Option<OsString>,
        home: Option<OsString>,
    ) -> DiskCache {
        let non_empty = |v: Option<OsString>| v.filter(|v| !v.is_empty());
        let dir = match explicit {
            Some(v) if v.is_empty() || v == "off" => None,
            Some(v) => Some(PathBuf::from(v)),
            None => non_empty(xdg)
                .map(PathBuf::from)
                .or_else(|| non_empty(home).map(|h| PathBuf::from(h).join(".cache")))
                .map(|d| d.join("vkbrdf")),
        };
        DiskCache { dir }
    }

    /// The directory, if there is a cache.
    pub fn dir(&self) -> Option<&std::path::Path> {
        self.dir.as_deref()
    }

    /// The entry `kind/key`, if present and whole.
    pub fn load(&self, kind: &str, key: &str) -> Option<Vec<u8>> {
        let path = self.dir.as_ref()?.join(kind).join(format!("{key}.bin"));
        let file = std::fs::File::open(path).ok()?;
        // Not read at all when larger than any entry kept.
        if file.metadata().ok()?.len() > (HEADER + MAX_ENTRY) as u64 {
            return None;
        }
        let mut bytes = Vec::new();
        file.take((HEADER + MAX_ENTRY) as u64)
            .read_to_end(&mut bytes)
            .ok()?;
        let len = payload_len(&bytes)?;
        bytes.drain(..HEADER);
        (bytes.len() == len).then_some(bytes)
    }

    /// [`DiskCache::load`] of an entry [`DiskCache::store_words`] wrote.
    pub fn load_words(&self, kind: &str, key: &str) -> Option<Vec<u32>> {
        let bytes = self.load(kind, key)?;
        (!bytes.is_empty() && bytes.len() % 4 == 0).then(|| {
            bytes
                .chunks_exact(4)
                .map(|w| u32::from_le_bytes(w.try_into().unwrap()))
                .collect()
        })
    }

    /// [`DiskCache::store`] of 32-bit words (SPIR-V), little-endian.
    pub fn store_words(&self, kind: &str, key: &str, words: &[u32]) {
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        self.store(kind, key, &bytes);
    }

    /// Stores `payload` as `kind/key`, replacing any entry; failures are ignored (see the
    /// module documentation).
    pub fn store(&self, kind: &str, key: &str, payload: &[u8]) {
        let Some(dir) = &self.dir else {
            return;
        };
        let dir = dir.join(kind);
        let write = || -> std::io::Result<()> {
            std::fs::create_dir_all(&dir)?;
            let mut file = tempfile::NamedTempFile::new_in(&dir)?;
            file.write_all(&header(payload))?;
            file.write_all(payload)?;
            file.persist(dir.join(format!("{key}.bin")))?;
            Ok(())
        };
        if write().is_ok() {
            prune(&dir, MAX_ENTRIES);
        }
    }
}

/// Removes the least recently written entries of `dir` while it holds more than `max`,
/// down to half of `max`. Best effort: an entry another process removed or replaced
/// meanwhile is skipped.
fn prune(dir: &std::path::Path, max: usize) {
    let Ok(read) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<(std::time::SystemTime, PathBuf)> = read
        .filter_map(|e| {
            let e = e.ok()?;
            let modified = e.metadata().ok()?.modified().ok()?;
            Some((modified, e.path()))
        })
        .filter(|(_, p)| p.extension().is_some_and(|x| x == "bin"))
        .collect();
    if entries.len() <= max {
        return;
    }
    entries.sort();
    for (_, path) in &entries[..entries.len() - max / 2] {
        let _ = std::fs::remove_file(path);
    }
}

/// FNV-1a (64 bits) of `parts` in order, from `basis`.
fn fnv1a(basis: u64, parts: &[&[u8]]) -> u64 {
    let mut h = basis;
    for part in parts {
        // The length first, so that ("ab", "c") and ("a", "bc") differ.
        for b in (part.len() as u64).to_le_bytes().iter().chain(part.iter()) {
            h = (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// An entry's name for the value made from `parts`: two FNV-1a hashes of them from
/// different bases, 32 hex digits (a stale entry would need both to collide).
pub(crate) fn key_of(parts: &[&[u8]]) -> String {
    let a = fnv1a(FNV_BASIS, parts);
    let b = fnv1a(0x6c62_272e_07bb_0142, parts);
    format!("{a:016x}{b:016x}")
}

/// The header of an entry holding `payload`.
fn header(payload: &[u8]) -> [u8; HEADER] {
    let mut h = [0u8; HEADER];
    h[..8].copy_from_slice(MAGIC);
    h[8..16].copy_from_slice(&(payload.len() as u64).to_le_bytes());
    h[16..].copy_from_slice(&u64::from(crc32fast::hash(payload)).to_le_bytes());
    h
}

/// The payload length of a whole entry (header and payload); `None` for anything else
/// (another format, cut short, changed, too large).
fn payload_len(bytes: &[u8]) -> Option<usize> {
    if bytes.len() < HEADER || bytes.len() > HEADER + MAX_ENTRY {
        return None;
    }
    let payload = &bytes[HEADER..];
    (header(payload)[..] == bytes[..HEADER]).then_some(payload.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_directory_follows_the_environment() {
        let os = |s: &str| Some(OsString::from(s));
        let dir = |c: DiskCache| c.dir.map(|d| d.to_string_lossy().into_owned());
        assert_eq!(
            dir(DiskCache::from_vars(os("/c"), os("/x"), os("/h"))).as_deref(),
            Some("/c")
        );
        assert_eq!(
            dir(DiskCache::from_vars(os("off"), os("/x"), os("/h"))),
            None
        );
        assert_eq!(dir(DiskCache::from_vars(os(""), os("/x"), os("/h"))), None);
        assert_eq!(
            dir(DiskCache::from_vars(None, os("/x"), os("/h"))).as_deref(),
            Some("/x/vkbrdf")
        );
        assert_eq!(
            dir(DiskCache::from_vars(None, os(""), os("/h"))).as_deref(),
            Some("/h/.cache/vkbrdf")
        );
        assert_eq!(dir(DiskCache::from_vars(None, None, None)), None);
    }

    /// An entry's bytes.
    fn entry(payload: &[u8]) -> Vec<u8> {
        [&header(payload)[..], payload].concat()
    }

    /// The payload of a whole entry.
    fn unwrap_entry(bytes: &[u8]) -> Option<&[u8]> {
        payload_len(bytes).map(|_| &bytes[HEADER..])
    }

    #[test]
    fn an_entry_is_read_back_only_whole_and_unchanged() {
        let e = entry(b"kernel words");
        assert_eq!(unwrap_entry(&e), Some(&b"kernel words"[..]));
        assert_eq!(unwrap_entry(&e[..e.len() - 1]), None, "cut short");
        let mut changed = e.clone();
        *changed.last_mut().unwrap() ^= 1;
        assert_eq!(unwrap_entry(&changed), None, "a flipped bit");
        let mut longer = e.clone();
        longer.push(0);
        assert_eq!(unwrap_entry(&longer), None, "bytes appended");
        assert_eq!(unwrap_entry(b"VKBRDFC0 and more bytes than a header"), None);
        assert_eq!(unwrap_entry(&entry(b"")), Some(&b""[..]));
    }

    #[test]
    fn keys_differ_by_content_and_by_split() {
        assert_eq!(key_of(&[b"a", b"b"]), key_of(&[b"a", b"b"]));
        assert_ne!(key_of(&[b"ab", b"c"]), key_of(&[b"a", b"bc"]));
        assert_ne!(key_of(&[b"a"]), key_of(&[b"b"]));
        assert_eq!(key_of(&[b"a"]).len(), 32);
    }

    #[test]
    fn a_full_folder_keeps_its_newest_half() {
        let tmp = tempfile::tempdir().unwrap();
        let old = std::time::SystemTime::UNIX_EPOCH + std::time::Duration::from_secs(1_000_000);
        for i in 0..9u64 {
            let path = tmp.path().join(format!("{i}.bin"));
            std::fs::write(&path, b"x").unwrap();
            let file = std::fs::File::options().write(true).open(&path).unwrap();
            file.set_modified(old + std::time::Duration::from_secs(i))
                .unwrap();
        }
        std::fs::write(tmp.path().join("other.txt"), b"not an entry").unwrap();
        prune(tmp.path(), 10);
        assert_eq!(
            std::fs::read_dir(tmp.path()).unwrap().count(),
            10,
            "at the limit: kept"
        );
        prune(tmp.path(), 8);
        let mut left: Vec<String> = std::fs::read_dir(tmp.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(left, ["5.bin", "6.bin", "7.bin", "8.bin", "other.txt"]);
    }

    #[test]
    fn store_and_load_round_trip_and_an_unwritable_directory_is_no_cache() {
        let tmp = tempfile::tempdir().unwrap();
        let cache = DiskCache {
            dir: Some(tmp.path().join("c")),
        };
        assert_eq!(cache.load("spirv", "k"), None);
        cache.store("spirv", "k", b"words");
        assert_eq!(cache.load("spirv", "k").as_deref(), Some(&b"words"[..]));
        cache.store("spirv", "k", b"other words");
        assert_eq!(
            cache.load("spirv", "k").as_deref(),
            Some(&b"other words"[..])
        );
        // A directory below a regular file cannot exist: storing is silently nothing.
        std::fs::write(tmp.path().join("file"), b"x").unwrap();
        let blocked = DiskCache {
            dir: Some(tmp.path().join("file").join("c")),
        };
        blocked.store("spirv", "k", b"words");
        assert_eq!(blocked.load("spirv", "k"), None);
    }
}
