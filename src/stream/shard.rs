//! Shards: `eval --shard K/N` evaluates one contiguous part of a batch and writes it as a
//! plain `.npy` part with a JSON sidecar (`PART.shard.json`); [`merge`] checks that parts
//! belong together and joins them, bit-identical to the unsharded run. No scheduler: N
//! shards run under whatever runs N commands (xargs -P, GNU parallel, a Slurm array, a
//! Kubernetes indexed Job; docs/STREAMING.md).

use crate::atomic;
use crate::backend::{Counts, TERM_COLUMNS};
use crate::batch::{npy_head, open_sized};
use crate::cancel::Cancel;
use crate::error::{Error, Result};
use std::io::{Read, Seek, SeekFrom, Write};

use std::path::{Path, PathBuf};

/// Version of the sidecar's layout.
pub const SIDECAR_SCHEMA: u32 = 1;

/// Part `k` of `n` (1-based, as Jest and Playwright spell it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    /// 1 ..= n.
    pub k: u64,
    /// Number of parts, >= 1.
    pub n: u64,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Shard, String> {
        let bad = || format!("{s:?} is not K/N with 1 <= K <= N (e.g. 2/8)");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let k: u64 = k.trim().parse().map_err(|_| bad())?;
        let n: u64 = n.trim().parse().map_err(|_| bad())?;
        if k == 0 || n == 0 || k > n {
            return Err(bad());
        }
        Ok(Shard { k, n })
    }
}

impl Shard {
    /// The rows of a batch of `total` rows this shard evaluates: `[(k−1)·total/n,
    /// k·total/n)`, so the parts tile the batch whatever n (empty when n > total).
    pub fn rows(&self, total: u64) -> std::ops::Range<u64> {
        let at = |i: u64| (u128::from(i) * u128::from(total) / u128::from(self.n)) as u64;
        at(self.k - 1)..at(self.k)
    }
}

/// What a part's sidecar records.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sidecar {
    /// [`SIDECAR_SCHEMA`].
    pub schema: u32,
    /// This part.
    pub shard: Shard,
    /// The batch rows it holds, `[start, end)`.
    pub rows: [u64; 2],
    /// Rows in the whole batch.
    pub total_rows: u64,
    /// The input's fingerprint: see [`fingerprint`].
    pub input: InputPrint,
    /// The materials file's fingerprint (whole file).
    pub materials: InputPrint,
    /// Engine and device that evaluated it.
    pub engine: String,
    /// vkbrdf's version.
    pub version: String,
    /// Whether a terms part (`TERMS.npy` of the same rows) was written.
    pub terms: Option<PathBuf>,
    /// The part's counts (first invalid row counted from the batch's start).
    pub invalid: u64,
    /// See `invalid`.
    pub below_horizon: u64,
    /// See `invalid`.
    pub saturated: u64,
    /// See `invalid`.
    pub first_invalid: Option<u64>,
}

/// A file's size and a 64-bit FNV-1a hash of its first MiB and 62 evenly spaced 64 KiB
/// blocks: every shard of an 8 GiB input computes it without reading the whole file, and
/// two different batches of the same size almost surely differ in it.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct InputPrint {
    /// Bytes.
    pub size: u64,
    /// Hex FNV-1a 64 of the sampled bytes.
    pub hash: String,
}

/// The [`InputPrint`] of `path`.
pub fn fingerprint(path: &Path) -> Result<InputPrint> {
    let io = |source| Error::Io {
        path: path.to_owned(),
        source,
    };
    let mut f = std::fs::File::open(path).map_err(io)?;
    let size = f.metadata().map_err(io)?.len();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    let mut buf = vec![0u8; 1 << 20];
    let n = read_up_to(&mut f, &mut buf).map_err(io)?;
    eat(&buf[..n]);
    buf.truncate(64 << 10);
    for i in 1..=62u64 {
        let at = size / 63 * i;
        f.seek(SeekFrom::Start(at)).map_err(io)?;
        let n = read_up_to(&mut f, &mut buf).map_err(io)?;
        eat(&buf[..n]);
    }
    Ok(InputPrint {
        size,
        hash: format!("{h:016x}"),
    })
}

fn read_up_to(f: &mut std::fs::File, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match f.read(&mut buf[n..])? {
            0 => break,
            k => n += k,
        }
    }
    Ok(n)
}

/// The sidecar path of part `part`: `PART.shard.json`.
pub fn sidecar_path(part: &Path) -> PathBuf {
    let mut s = part.as_os_str().to_owned();
    s.push(".shard.json");
    PathBuf::from(s)
}

impl Sidecar {
    /// The counts it records.
    pub fn counts(&self) -> Counts {
        Counts {
            tuples: self.rows[1] - self.rows[0],
            invalid: self.invalid,
            below_horizon: self.below_horizon,
            saturated: self.saturated,
            first_invalid: self.first_invalid,
        }
    }

    /// Reads the sidecar of part `part`.
    pub fn read(part: &Path) -> Result<Sidecar> {
        read_sidecar(part, "shard sidecar")
    }

    /// The sidecar as it is written (pretty JSON).
    pub fn to_json(&self) -> String {
        sidecar_json(self)
    }
}

/// Reads the sidecar of part `part` (a batch's or a table's): an I/O error names the
/// file, a parse error says it is not a vkbrdf `what`.
pub fn read_sidecar<T: serde::de::DeserializeOwned>(part: &Path, what: &str) -> Result<T> {
    let path = sidecar_path(part);
    let text = std::fs::read_to_string(&path).map_err(|source| Error::Io {
        path: path.clone(),
        source,
    })?;
    serde_json::from_str(&text).map_err(|e| Error::Batch {
        path,
        message: format!("not a vkbrdf {what}: {e}"),
    })
}

/// A sidecar as it is written: pretty JSON and a newline.
pub fn sidecar_json<T: serde::Serialize>(sidecar: &T) -> String {
    serde_json::to_string_pretty(sidecar).expect("a sidecar serialises") + "\n"
}

/// Joins the parts `parts` (BRDF `.npy` parts with their sidecars) into `output` (and their
/// terms parts into `terms`, when given): every part of one N, each once, of the same input
/// and materials, by the same engine and version unless `allow_mixed`. Streams the data in
/// blocks; both outputs appear together or neither. Returns the joined counts.
pub fn merge(
    parts: &[PathBuf],
    output: &Path,
    terms: Option<&Path>,
    allow_mixed: bool,
    cancel: &Cancel,
) -> Result<Counts> {
    let bad = |path: &Path, message: String| Error::Batch {
        path: path.to_owned(),
        message,
    };
    let (first, mut cars) = read_parts(parts, output, Sidecar::read)?;
    let base = cars[0].1.clone();
    for (p, c) in &cars {
        let differs = |what: &str, a: &dyn std::fmt::Debug, b: &dyn std::fmt::Debug| {
            part_differs(p, first, what, a, b)
        };
        if c.schema != SIDECAR_SCHEMA {
            return Err(bad(
                p,
                format!(
                    "sidecar schema {} (this vkbrdf reads {SIDECAR_SCHEMA})",
                    c.schema
                ),
            ));
        }
        if c.shard.n != base.shard.n {
            return Err(differs("the number of shards", &c.shard.n, &base.shard.n));
        }
        if c.input != base.input || c.total_rows != base.total_rows {
            return Err(differs("the input", &c.input, &base.input));
        }
        if c.materials != base.materials {
            return Err(differs("the materials file", &c.materials, &base.materials));
        }
        if !allow_mixed && (c.engine != base.engine || c.version != base.version) {
            return Err(differs(
                "the engine or version (--allow-mixed accepts that)",
                &(&c.engine, &c.version),
                &(&base.engine, &base.version),
            ));
        }
        if terms.is_some() && c.terms.is_none() {
            return Err(bad(p, "this part has no terms part (eval --terms)".into()));
        }
    }
    check_complete(&mut cars, |c| c.shard, base.shard.n, output, "")?;
    let mut counts = Counts {
        tuples: base.total_rows,
        ..Counts::default()
    };
    for (_, c) in &cars {
        counts.absorb(&c.counts());
    }
    let mut staged = vec![join(
        &cars,
        |(p, _)| p.clone(),
        output,
        3,
        base.total_rows,
        cancel,
    )?];
    if let Some(t) = terms {
        let part_terms = |(p, c): &(PathBuf, Sidecar)| {
            let rel = c.terms.clone().expect("checked above");
            if rel.is_absolute() {
                rel
            } else {
                p.parent().unwrap_or(Path::new("")).join(rel)
            }
        };
        staged.push(join(
            &cars,
            part_terms,
            t,
            TERM_COLUMNS,
            base.total_rows,
            cancel,
        )?);
    }
    atomic::commit(staged)?;
    Ok(counts)
}

/// Concatenates the parts' rows (each checked against its sidecar's row range) into a
/// staged `.npy` of `total × columns` float32.
fn join(
    cars: &[(PathBuf, Sidecar)],
    file_of: impl Fn(&(PathBuf, Sidecar)) -> PathBuf,
    output: &Path,
    columns: usize,
    total: u64,
    cancel: &Cancel,
) -> Result<atomic::Staged> {
    let mut w = atomic::stage_writer(output, cancel)?;
    w.write_all(&super::npy_header_f32(total, columns))
        .map_err(|e| w.error(e))?;
    for car in cars {
        let file = file_of(car);
        let rows = car.1.rows[1] - car.1.rows[0];
        let (mut reader, len) = open_sized(&file)?;
        let head = npy_head(&mut reader, len, &file)?;
        let npy = npyz::NpyFile::new(std::io::Cursor::new(head)).map_err(|e| Error::Batch {
            path: file.clone(),
            message: format!("not a valid .npy file: {e}"),
        })?;
        let dtype = npy.dtype().descr();
        if npy.shape() != [rows, columns as u64]
            || npy.order() != npyz::Order::C
            || !dtype.contains("<f4")
        {
            return Err(Error::Batch {
                path: file,
                message: format!(
                    "shape {:?} dtype {dtype}, but its sidecar says {rows} float32 rows of {columns}",
                    npy.shape()
                ),
            });
        }
        let want = rows * columns as u64 * 4;
        let copied = std::io::copy(&mut reader.take(want), &mut w).map_err(|e| w.error(e))?;
        if copied != want {
            return Err(Error::Batch {
                path: file,
                message: format!("truncated: {copied} of {want} data bytes"),
            });
        }
    }
    w.finish()
}

/// The error of part `part` whose `what` differs from the first part's (`a` against `b`).
pub fn part_differs(
    part: &Path,
    first: &Path,
    what: &str,
    a: &dyn std::fmt::Debug,
    b: &dyn std::fmt::Debug,
) -> Error {
    Error::Batch {
        path: part.to_owned(),
        message: format!(
            "{what} differs from {}'s: {a:?} against {b:?}",
            first.display()
        ),
    }
}

/// Sorts `parts` by K and checks that each K of 1..=n is there exactly once: a part given
/// twice is named with its twin, missing ones against `output` (`whole` names what they
/// are parts of in that message, e.g. " of the dfg table"; "" for a batch).
pub fn check_complete<T>(
    parts: &mut [(PathBuf, T)],
    shard: impl Fn(&T) -> Shard,
    n: u64,
    output: &Path,
    whole: &str,
) -> Result<()> {
    parts.sort_by_key(|(_, c)| shard(c).k);
    for w in parts.windows(2) {
        let k = shard(&w[1].1).k;
        if shard(&w[0].1).k == k {
            return Err(Error::Batch {
                path: w[1].0.clone(),
                message: format!("shard {k}/{n} given twice (also {})", w[0].0.display()),
            });
        }
    }
    let missing: Vec<u64> = (1..=n)
        .filter(|k| !parts.iter().any(|(_, c)| shard(c).k == *k))
        .collect();
    if !missing.is_empty() {
        return Err(Error::Batch {
            path: output.to_owned(),
            message: format!("shards {missing:?} of {n}{whole} are missing"),
        });
    }
    Ok(())
}

/// Each part with its sidecar (`read`), and the first part's path; an error when there is
/// no part.
pub fn read_parts<'a, T>(
    parts: &'a [PathBuf],
    output: &Path,
    read: impl Fn(&Path) -> Result<T>,
) -> Result<(&'a Path, Vec<(PathBuf, T)>)> {
    let Some(first) = parts.first() else {
        return Err(Error::Batch {
            path: output.to_owned(),
            message: "no parts to merge".into(),
        });
    };
    let cars = parts
        .iter()
        .map(|p| Ok((p.clone(), read(p)?)))
        .collect::<Result<_>>()?;
    Ok((first, cars))
}
