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

/// Version of the sidecar's layout (2: the part's and its terms part's fingerprints).
pub const SIDECAR_SCHEMA: u32 = 2;

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
    /// The BRDF part's own fingerprint as written (`merge` verifies it).
    pub part: InputPrint,
    /// The terms part's fingerprint as written (`merge --terms` verifies it: shards that
    /// shared one terms file overwrote each other's rows).
    pub terms_part: Option<InputPrint>,
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
    parse_sidecar(&text, &path, what)
}

/// A sidecar's JSON `text` (read from `path`, named in errors) as `T`: an error, never a
/// panic, for anything that is not one (the sidecar fuzz target drives this).
pub fn parse_sidecar<T: serde::de::DeserializeOwned>(
    text: &str,
    path: &Path,
    what: &str,
) -> Result<T> {
    serde_json::from_str(text).map_err(|e| Error::Batch {
        path: path.to_owned(),
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
) -> Result<Merged> {
    let bad = |path: &Path, message: String| Error::Batch {
        path: path.to_owned(),
        message,
    };
    let (first, mut cars) = read_parts(parts, output, Sidecar::read)?;
    let terms_file = |(p, c): &(PathBuf, Sidecar)| {
        c.terms.as_ref().map(|rel| {
            if rel.is_absolute() {
                rel.clone()
            } else {
                p.parent().unwrap_or(Path::new("")).join(rel)
            }
        })
    };
    // The terms parts the sidecars name are inputs too.
    let terms_parts: Vec<PathBuf> = cars.iter().filter_map(terms_file).collect();
    let outputs: Vec<&Path> = std::iter::once(output).chain(terms).collect();
    check_merge_outputs(&outputs, parts, &terms_parts)?;
    for (p, c) in &cars {
        c.validate().map_err(|m| bad(&sidecar_path(p), m))?;
        let print = fingerprint(p)?;
        if print != c.part {
            return Err(bad(
                p,
                format!(
                    "its content is not what its sidecar recorded (size {} hash {} against {} {}): the part was changed or overwritten after eval wrote it",
                    print.size, print.hash, c.part.size, c.part.hash
                ),
            ));
        }
    }
    let base = cars[0].1.clone();
    for car in &cars {
        let (p, c) = car;
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
            return Err(differs(
                "the input (its fingerprint and row count)",
                &(&c.input, c.total_rows),
                &(&base.input, base.total_rows),
            ));
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
        if let (Some(_), Some(file)) = (terms, terms_file(car)) {
            let print = fingerprint(&file)?;
            if Some(&print) != c.terms_part.as_ref() {
                return Err(bad(
                    &file,
                    format!(
                        "the terms part of {} is not what its sidecar recorded (size {} hash {}): another shard or run wrote it since — give each shard its own --terms file",
                        p.display(),
                        print.size,
                        print.hash
                    ),
                ));
            }
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
    let (brdf, brdf_saturated) = join(
        &cars,
        |(p, _)| p.clone(),
        output,
        3,
        base.total_rows,
        cancel,
    )?;
    let mut staged = vec![brdf];
    let mut terms_saturated = vec![0; cars.len()];
    if let Some(t) = terms {
        let part_terms = |car: &(PathBuf, Sidecar)| terms_file(car).expect("checked above");
        let (joined, sat) = join(&cars, part_terms, t, TERM_COLUMNS, base.total_rows, cancel)?;
        staged.push(joined);
        terms_saturated = sat;
    }
    // The saturated count against the data: a saturated tuple has an output of f32::MAX,
    // so the rows holding one bound the count from below (and, with the terms, above).
    for (i, (p, c)) in cars.iter().enumerate() {
        let (b, t) = (brdf_saturated[i], terms_saturated[i]);
        let low = b.max(t);
        let high = if terms.is_some() {
            b + t
        } else {
            c.rows[1] - c.rows[0]
        };
        if c.saturated < low || c.saturated > high {
            return Err(bad(
                &sidecar_path(p),
                format!(
                    "records {} saturated tuples, but the part's data holds {b} rows with an output of f32::MAX{}",
                    c.saturated,
                    if terms.is_some() { format!(" ({t} in its terms)") } else { String::new() }
                ),
            ));
        }
    }
    atomic::commit(staged)?;
    Ok(Merged {
        counts,
        warnings: mixed_engines_warning(cars.iter().map(|(_, c)| c.engine.as_str()))
            .into_iter()
            .collect(),
    })
}

/// The output checks of a merge (see [`atomic::check_outputs`]): every file it reads is an
/// input — the parts, their sidecars, and `named`, the files the sidecars point at.
pub fn check_merge_outputs(outputs: &[&Path], parts: &[PathBuf], named: &[PathBuf]) -> Result<()> {
    let sidecars: Vec<PathBuf> = parts.iter().map(|p| sidecar_path(p)).collect();
    let inputs: Vec<&Path> = parts
        .iter()
        .chain(&sidecars)
        .chain(named)
        .map(PathBuf::as_path)
        .collect();
    atomic::check_outputs(outputs, &inputs)
}

/// The warning a merge with `--allow-mixed` gives when its parts came from several
/// engines (instruction sets, devices): their values may differ in the last bits.
pub fn mixed_engines_warning<'a>(engines: impl Iterator<Item = &'a str>) -> Option<String> {
    let mut seen: Vec<&str> = Vec::new();
    for e in engines {
        if !seen.contains(&e) {
            seen.push(e);
        }
    }
    (seen.len() > 1).then(|| {
        format!(
            "the parts came from different engines or instruction sets ({}); their values may differ in the last bits, each within FORMULAS.md §1's rule of the reference",
            seen.join("; ")
        )
    })
}

/// What [`merge`] joined: the counts, and the warnings to show.
#[derive(Debug, Clone)]
pub struct Merged {
    /// The joined counts.
    pub counts: Counts,
    /// Warnings (parts of several engines, with `allow_mixed`).
    pub warnings: Vec<String>,
}

impl Sidecar {
    /// The sidecar's numbers checked against each other: the row range is the shard's own
    /// of the total, the counts fit in it and the first invalid row lies in it exactly when
    /// a tuple is invalid. The message says which field is wrong.
    pub fn validate(&self) -> std::result::Result<(), String> {
        let Shard { k, n } = self.shard;
        if n == 0 || k == 0 || k > n {
            return Err(format!("shard {k}/{n} is not K/N with 1 <= K <= N"));
        }
        let want = self.shard.rows(self.total_rows);
        if self.rows != [want.start, want.end] {
            return Err(format!(
                "rows {:?} are not shard {k}/{n}'s rows of {} ({:?})",
                self.rows, self.total_rows, want
            ));
        }
        let rows = want.end - want.start;
        let counted =
            u128::from(self.invalid) + u128::from(self.below_horizon) + u128::from(self.saturated);
        if counted > u128::from(rows) {
            return Err(format!(
                "invalid {} + below_horizon {} + saturated {} exceed the part's {rows} rows",
                self.invalid, self.below_horizon, self.saturated
            ));
        }
        match self.first_invalid {
            Some(r) if self.invalid == 0 || !want.contains(&r) => Err(format!(
                "first_invalid {r} with {} invalid tuples in rows {:?}",
                self.invalid, want
            )),
            None if self.invalid > 0 => Err(format!(
                "{} invalid tuples but no first_invalid row",
                self.invalid
            )),
            _ => Ok(()),
        }
    }
}

/// Concatenates the parts' rows (each checked against its sidecar's row range) into a
/// staged `.npy` of `total × columns` float32.
///
/// Every value is checked on the way (an output is never inf or NaN: a part that holds one
/// was altered), and the rows holding f32::MAX (saturated) are counted per part.
fn join(
    cars: &[(PathBuf, Sidecar)],
    file_of: impl Fn(&(PathBuf, Sidecar)) -> PathBuf,
    output: &Path,
    columns: usize,
    total: u64,
    cancel: &Cancel,
) -> Result<(atomic::Staged, Vec<u64>)> {
    let mut saturated = Vec::with_capacity(cars.len());
    let mut w = atomic::stage_writer(output, cancel)?;
    w.write_all(&crate::batch::npy_header_f32(total, columns))
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
        let row_bytes = columns * 4;
        let want = rows * row_bytes as u64;
        let mut buf = vec![0u8; row_bytes * 16_384];
        let (mut copied, mut row, mut sat) = (0u64, car.1.rows[0], 0u64);
        let mut reader = reader.take(want);
        while copied < want {
            let take = buf.len().min((want - copied) as usize);
            let n = read_full(&mut reader, &mut buf[..take]).map_err(|source| Error::Io {
                path: file.clone(),
                source,
            })?;
            if n < take {
                return Err(Error::Batch {
                    path: file,
                    message: format!("truncated: {} of {want} data bytes", copied + n as u64),
                });
            }
            for r in buf[..n].chunks_exact(row_bytes) {
                let mut max = false;
                for v in r.chunks_exact(4) {
                    let x = f32::from_le_bytes([v[0], v[1], v[2], v[3]]);
                    if !x.is_finite() {
                        return Err(Error::Batch {
                            path: file,
                            message: format!(
                                "row {row} holds {x}: vkbrdf never writes inf or NaN, so the part was altered"
                            ),
                        });
                    }
                    max |= x == f32::MAX;
                }
                sat += u64::from(max);
                row += 1;
            }
            w.write_all(&buf[..n]).map_err(|e| w.error(e))?;
            copied += n as u64;
        }
        saturated.push(sat);
    }
    Ok((w.finish()?, saturated))
}

/// Reads until `buf` is full or the reader ends; returns the bytes read.
fn read_full(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
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
