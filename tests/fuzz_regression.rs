//! Replays the fuzzers' minimised corpora (`tests/fuzz_corpus/<target>/`, from `cargo fuzz
//! cmin`; see docs/fuzzing.md) through the same entry points and checks as the fuzz
//! targets in `fuzz/fuzz_targets/`, on stable: every file gives Ok or a clean error that
//! names its source, never a panic. Below them, the inputs the fuzzers (and the review of
//! what they found) turned up, each pinned by its own test.

use std::io::Read;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use vkbrdf::batch::{read_npy_f32_from, Batch};
use vkbrdf::material::parse_materials_in;
use vkbrdf::table::merl;

/// The corpus files of one target, sorted; at least `min` of them, so that an emptied or
/// moved corpus fails instead of passing vacuously.
fn corpus(target: &str, min: usize) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz_corpus")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(
        files.len() >= min,
        "{}: {} files, expected at least {min}",
        dir.display(),
        files.len()
    );
    files
}

/// Runs `check` on every file's bytes, naming the file when it panics.
fn replay(target: &str, min: usize, check: impl Fn(&[u8])) {
    let mut failures = Vec::new();
    for file in corpus(target, min) {
        let data = std::fs::read(&file).unwrap();
        if catch_unwind(AssertUnwindSafe(|| check(&data))).is_err() {
            failures.push(file.display().to_string());
        }
    }
    assert!(failures.is_empty(), "panicked on: {failures:#?}");
}

fn check_materials(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match parse_materials_in(text, "fuzz.toml", Path::new("/nonexistent/vkbrdf-fuzz")) {
        Ok(materials) => assert!(!materials.is_empty()),
        Err(e) => assert!(e.to_string().contains("fuzz.toml"), "{e}"),
    }
}

fn check_npy(data: &[u8]) {
    let source = Path::new("fuzz.npy");
    let known = read_npy_f32_from(data, Some(data.len() as u64), source);
    let unknown = read_npy_f32_from(data, None, source);
    match (&known, &unknown) {
        (Ok(a), Ok(b)) => {
            assert_eq!(a.1, b.1);
            assert!(a
                .0
                .iter()
                .zip(&b.0)
                .all(|(x, y)| x.to_bits() == y.to_bits()));
            assert_eq!(a.0.len(), b.0.len());
        }
        (Ok(_), Err(e)) => {
            panic!("the length-aware read accepted what the stream read rejects: {e}")
        }
        (Err(e), _) => assert!(e.to_string().contains("fuzz.npy"), "{e}"),
    }
    if let Ok(batch) = Batch::read_npy_from(data, Some(data.len() as u64), 3, source) {
        for i in 0..batch.len() {
            assert!(batch.tuple(i).material < 3);
        }
    }
}

fn check_merl(data: &[u8]) {
    if let Err(e) = merl::read_from(data, Path::new("fuzz.binary")) {
        assert!(e.to_string().contains("fuzz.binary"), "{e}");
    }
}

/// The `merl_lookup` target's table: every sign, the invalid marker and zeros.
fn lookup_table() -> merl::MeasuredMerl {
    let mut bytes: Vec<u8> = [90i32, 90, 180]
        .iter()
        .flat_map(|d| d.to_le_bytes())
        .collect();
    for s in 0..3 * merl::SAMPLES {
        let x = match s % 7 {
            0 => merl::INVALID,
            1 => 0.0,
            k => (s % 1000) as f64 * k as f64 * 0.01,
        };
        bytes.extend(x.to_le_bytes());
    }
    merl::read_from(&bytes[..], Path::new("table.binary")).unwrap()
}

fn check_merl_lookup(table: &merl::MeasuredMerl, data: &[u8]) {
    let x: Vec<f64> = data
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
        .collect();
    let good = |f: [f64; 3]| f.iter().all(|v| v.is_finite() && *v >= 0.0);
    if x.len() >= 9 {
        let f = table.lookup([x[0], x[1], x[2]], [x[3], x[4], x[5]], [x[6], x[7], x[8]]);
        assert!(good(f), "{f:?} at {x:?}");
    }
    if x.len() >= 3 {
        let f = table.lookup_half_diff(x[0], x[1], x[2]);
        assert!(good(f), "{f:?} at {x:?}");
    }
}

#[test]
fn materials_corpus_replays_without_panic() {
    replay("materials", 20, check_materials);
}

#[test]
fn npy_corpus_replays_without_panic() {
    replay("npy", 10, check_npy);
}

#[test]
fn merl_corpus_replays_without_panic() {
    replay("merl", 3, check_merl);
}

#[test]
fn merl_lookup_corpus_replays_without_panic() {
    let table = lookup_table();
    replay("merl_lookup", 3, |data| check_merl_lookup(&table, data));
}

// ---- what the fuzzers found ------------------------------------------------------------

/// A `.npy` preamble (magic, version, little-endian header length) and header text.
fn npy(version: u8, header_len: Option<u32>, header: &str, data: &[u8]) -> Vec<u8> {
    let mut out = b"\x93NUMPY".to_vec();
    out.extend([version, 0]);
    let len = header_len.unwrap_or(header.len() as u32);
    match version {
        1 => out.extend((len as u16).to_le_bytes()),
        _ => out.extend(len.to_le_bytes()),
    }
    out.extend(header.as_bytes());
    out.extend(data);
    out
}

fn npy_error(bytes: &[u8], len: Option<u64>) -> String {
    read_npy_f32_from(bytes, len, Path::new("t.npy"))
        .unwrap_err()
        .to_string()
}

#[test]
fn npy_header_length_beyond_the_file_is_refused_before_allocating_it() {
    // A version-2 preamble stating a 4 GiB header, and nothing after it: npyz allocated
    // the 4 GiB before finding the stream empty.
    let bytes = npy(2, Some(u32::MAX), "", b"");
    for len in [Some(bytes.len() as u64), None] {
        let msg = npy_error(&bytes, len);
        assert!(
            msg.contains("t.npy")
                && msg.contains("4294967295 bytes long")
                && msg.contains("truncated"),
            "{msg}"
        );
    }
}

#[test]
fn npy_shape_whose_element_count_overflows_is_an_error() {
    // (2^63 + 2) x 10 wraps to 20 in 64 bits: 20 values made a 2-row batch of a file
    // claiming 9.2e18 rows (and a panic where overflow checks are on).
    let header = "{'descr': '<f4', 'fortran_order': False, 'shape': (9223372036854775810, 10), }\n";
    let rows: Vec<u8> = (0..20).flat_map(|_| 0f32.to_le_bytes()).collect();
    let bytes = npy(1, None, header, &rows);
    for len in [Some(bytes.len() as u64), None] {
        let msg = npy_error(&bytes, len);
        assert!(
            msg.contains("t.npy") && msg.contains("more than 2^64 values"),
            "{msg}"
        );
    }
    assert!(Batch::read_npy_from(&bytes[..], None, 1, Path::new("t.npy")).is_err());
    // A zero does not excuse the rest: the strides multiply the other dimensions (numpy
    // refuses such shapes too), while a plain empty batch reads fine.
    let header =
        "{'descr': '<f4', 'fortran_order': False, 'shape': (0, 9223372036854775807, 4), }\n";
    let msg = npy_error(&npy(1, None, header, b""), None);
    assert!(msg.contains("more than 2^64 values"), "{msg}");
    let header = "{'descr': '<f4', 'fortran_order': False, 'shape': (0, 10), }\n";
    let batch = Batch::read_npy_from(&npy(1, None, header, b"")[..], None, 1, Path::new("t.npy"));
    assert!(batch.unwrap().is_empty());
}

#[test]
fn npy_shape_beyond_the_file_length_is_refused_before_reading_data() {
    let header = "{'descr': '<f8', 'fortran_order': False, 'shape': (1000000000000, 10), }\n";
    let bytes = npy(1, None, header, &[0u8; 80]);
    let msg = npy_error(&bytes, Some(bytes.len() as u64));
    assert!(
        msg.contains("truncated")
            && msg.contains("needs 80000000000000 bytes of data, the file holds 80"),
        "{msg}"
    );
    // From a stream of unknown length the same file fails when the data runs out.
    assert!(npy_error(&bytes, None).contains("truncated"));
}

#[test]
fn merl_reader_stops_at_one_table_on_an_endless_stream() {
    // Valid dimensions followed by zeros forever: the old reader (read the whole file,
    // then check its size) never returned.
    let header: Vec<u8> = [90i32, 90, 180]
        .iter()
        .flat_map(|d| d.to_le_bytes())
        .collect();
    let endless = header.as_slice().chain(std::io::repeat(0));
    let msg = merl::read_from(endless, Path::new("endless.binary"))
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("endless.binary")
            && msg.contains(&format!("more than {} bytes", merl::FILE_BYTES))
            && msg.contains("padded"),
        "{msg}"
    );
    // A device that never ends: refused before reading (not a regular file), not an
    // exhausted memory; through `read_from` its stream ends at the header's dimensions.
    let msg = merl::read(Path::new("/dev/zero")).unwrap_err().to_string();
    assert!(
        msg.contains("/dev/zero") && msg.contains("not a regular file"),
        "{msg}"
    );
    let zero = std::fs::File::open("/dev/zero").unwrap();
    let msg = merl::read_from(zero, Path::new("/dev/zero"))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("dimensions 0x0x0"), "{msg}");
}

#[test]
fn merl_reader_from_bytes_matches_the_file_reader() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.binary");
    let values: Vec<f64> = (0..3 * merl::SAMPLES)
        .map(|i| (i % 97) as f64 - 1.0)
        .collect();
    merl::write_values(&path, &values).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let a = merl::read(&path).unwrap();
    let b = merl::read_from(&bytes[..], &path).unwrap();
    assert_eq!(a, b);
    assert_eq!(b.stored(2, 89, 89, 179), values[3 * merl::SAMPLES - 1]);
    // One byte short and one byte long.
    for bad in [
        &bytes[..bytes.len() - 1],
        &[bytes.as_slice(), &[0]].concat()[..],
    ] {
        let msg = merl::read_from(bad, Path::new("x.binary"))
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("x.binary") && msg.contains("truncated or padded"),
            "{msg}"
        );
    }
}

#[test]
fn npy_header_with_deeply_nested_brackets_is_refused_at_once() {
    // Found by the npy fuzzer: unclosed brackets make the header parser (py_literal, used
    // by npyz) backtrack exponentially; 16 `{` took 431 s in the old reader.
    for (open, tail) in [("{", "1"), ("[", "1, 10), }"), ("(", "1]")] {
        let header = format!(
            "{{'descr': '<f4', 'fortran_order': False, 'shape': {}{tail}\n",
            open.repeat(16)
        );
        let bytes = npy(1, None, &header, b"");
        let start = std::time::Instant::now();
        let msg = npy_error(&bytes, Some(bytes.len() as u64));
        assert!(
            msg.contains("t.npy") && msg.contains("nests brackets 17 deep"),
            "{msg}"
        );
        assert!(
            start.elapsed() < std::time::Duration::from_secs(1),
            "{:?}",
            start.elapsed()
        );
    }
    // A plain header (depth 2) and a structured dtype's (depth 4) still reach the dtype check.
    let header = "{'descr': [('a', '<f4', (2,))], 'fortran_order': False, 'shape': (1,), }\n";
    let msg = npy_error(&npy(1, None, header, &[0u8; 8]), None);
    assert!(msg.contains("not supported"), "{msg}");
}

#[test]
fn npy_repeated_shape_key_is_checked_as_npyz_reads_it() {
    // Found by the npy fuzzer: with `'shape'` given twice the check read the first (a
    // small shape) while npyz takes the last, whose strides overflow (a panic where
    // overflow checks are on, a wrapped value otherwise).
    let header = "{'descr': '<f4', 'fortran_order': False, 'shape': (5, 1, 1, 10), \
                  'shape': (0, 2, 1, 9535570675027320348), }\n";
    let bytes = npy(1, None, header, &[0u8; 8]);
    for len in [Some(bytes.len() as u64), None] {
        let msg = npy_error(&bytes, len);
        assert!(
            msg.contains("t.npy") && msg.contains("more than 2^64 values"),
            "{msg}"
        );
    }
    // The last shape is the one read.
    let header = "{'descr': '<f4', 'fortran_order': False, 'shape': (7, 7), 'shape': (1, 10), }\n";
    let (data, shape) = read_npy_f32_from(
        &npy(1, None, header, &[0u8; 40])[..],
        None,
        Path::new("t.npy"),
    )
    .unwrap();
    assert_eq!((data.len(), shape), (10, vec![1, 10]));
}

/// The sidecar target's check (`fuzz/fuzz_targets/sidecar.rs`).
fn check_sidecar(data: &[u8]) {
    use vkbrdf::stream::shard::{parse_sidecar, Sidecar};
    let text = String::from_utf8_lossy(data);
    let path = Path::new("part.npy.shard.json");
    match parse_sidecar::<Sidecar>(&text, path, "shard sidecar") {
        Ok(car) => {
            if car.validate().is_ok() {
                let c = car.counts();
                assert!(c.invalid + c.below_horizon + c.saturated <= c.tuples);
            }
        }
        Err(e) => assert!(e.to_string().contains("part.npy.shard.json"), "{e}"),
    }
    if let Err(e) =
        parse_sidecar::<vkbrdf::table::shard::TableSidecar>(&text, path, "table sidecar")
    {
        assert!(e.to_string().contains("part.npy.shard.json"), "{e}");
    }
}

#[test]
fn sidecar_corpus_replays_without_panic() {
    replay("sidecar", 2, check_sidecar);
}
