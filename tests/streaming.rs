//! `vkbrdf eval` streams: a batch larger than `--max-memory` is read, evaluated and written
//! chunk by chunk, with the same output as one chunk, in bounded memory; `--strict`, the
//! first invalid row and the batch's errors keep their meaning across chunks.

mod common;

use common::{eval, generate, path, stderr};
use std::path::Path;

fn materials(dir: &Path) -> std::path::PathBuf {
    let m = dir.join("m.toml");
    std::fs::write(
        &m,
        "[[material]]\nname = \"gold\"\npreset = \"gold\"\n\n[[material]]\nname = \"l\"\nmodel = \"lambert\"\ndiffuse = 0.5\n",
    )
    .expect("write materials");
    m
}

/// The number after `label` in the eval summary line.
fn figure(text: &str, label: &str) -> u64 {
    let at = text
        .find(label)
        .unwrap_or_else(|| panic!("no {label:?} in {text}"));
    text[..at]
        .split_whitespace()
        .last()
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("no number before {label:?} in {text}"))
}

#[test]
fn a_batch_larger_than_its_budget_streams_to_the_same_output() {
    let dir = tempfile::tempdir().expect("tempdir");
    let m = materials(dir.path());
    let t = dir.path().join("t.npy");
    assert!(generate(&m, 600_000, &t).status.success());
    let (a, at) = (dir.path().join("a.npy"), dir.path().join("at.npy"));
    let (b, bt) = (dir.path().join("b.npy"), dir.path().join("bt.npy"));
    let whole = eval(
        &m,
        &t,
        &[
            "-o",
            path(&a),
            "--terms",
            path(&at),
            "--backend",
            "reference",
            "--max-memory",
            "1GiB",
        ],
    );
    assert!(whole.status.success(), "{}", stderr(&whole));
    let streamed = eval(
        &m,
        &t,
        &[
            "-o",
            path(&b),
            "--terms",
            path(&bt),
            "--backend",
            "reference",
            "--max-memory",
            "1MiB",
        ],
    );
    let text = stderr(&streamed);
    assert!(streamed.status.success(), "{text}");
    // A budget of 1 GiB would hold the batch at once; chunks stop at MAX_CHUNK_ROWS so the
    // stages overlap.
    let biggest = 600_000u64.div_ceil(vkbrdf::stream::MAX_CHUNK_ROWS as u64);
    assert_eq!(
        figure(&stderr(&whole), "chunk(s)"),
        biggest,
        "{}",
        stderr(&whole)
    );
    assert!(figure(&text, "chunk(s)") > 10, "{text}");
    assert_eq!(
        std::fs::read(&a).unwrap(),
        std::fs::read(&b).unwrap(),
        "BRDF differs"
    );
    assert_eq!(
        std::fs::read(&at).unwrap(),
        std::fs::read(&bt).unwrap(),
        "terms differ"
    );
    // 24 MB in and 21.6 MB out: in chunks of MAX_CHUNK_ROWS (1 GiB budget) the run peaks
    // near 42 MiB; streamed in 1 MiB it stays near 15 MiB.
    if text.contains("peak memory") {
        let peak = figure(&text, "MiB");
        assert!(peak < 24, "streamed run peaked at {peak} MiB: {text}");
        let whole_peak = figure(&stderr(&whole), "MiB");
        assert!(whole_peak > peak + 10, "{}", stderr(&whole));
    }
}

/// A batch of 100 000 rows whose invalid tuple (a zero L) and bad materials (index 7) lie
/// at the rows given.
fn batch_with(
    dir: &Path,
    zero_l_row: Option<usize>,
    bad_material_rows: &[usize],
) -> std::path::PathBuf {
    let n = 100_000;
    let mut data = Vec::with_capacity(n * 10);
    for i in 0..n {
        let l = if Some(i) == zero_l_row {
            [0.0, 0.0, 0.0]
        } else {
            [0.3, 0.2, 0.9]
        };
        let material = if bad_material_rows.contains(&i) {
            7.0
        } else {
            (i % 2) as f32
        };
        data.extend_from_slice(&l);
        data.extend_from_slice(&[-0.2, 0.1, 0.8, 0.0, 0.0, 1.0, material]);
    }
    let t = dir.join("t.npy");
    vkbrdf::batch::write_npy_f32(&t, &data, 10).expect("write batch");
    t
}

#[test]
fn strict_and_the_first_invalid_row_hold_across_chunks() {
    // The reference streams through the pipeline, the CPU engine through its workers.
    for backend in ["reference", "cpu"] {
        strict_holds_across_chunks(backend);
    }
}

fn strict_holds_across_chunks(backend: &str) {
    let dir = tempfile::tempdir().expect("tempdir");
    let m = materials(dir.path());
    let t = batch_with(dir.path(), Some(70_000), &[]);
    let out = dir.path().join("o.npy");
    let r = eval(
        &m,
        &t,
        &[
            "-o",
            path(&out),
            "--backend",
            backend,
            "--max-memory",
            "1MiB",
            "--strict",
        ],
    );
    let text = stderr(&r);
    assert_eq!(r.status.code(), Some(1), "{backend}: {text}");
    assert!(
        text.contains("70000"),
        "the first invalid row is named: {text}"
    );
    assert!(!out.exists(), "--strict wrote an output");
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.contains("partial"))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
    // Without --strict the run succeeds and counts the one invalid tuple; --json says so
    // on standard output for scripts.
    let r = eval(
        &m,
        &t,
        &[
            "-o",
            path(&out),
            "--backend",
            backend,
            "--max-memory",
            "1MiB",
            "--json",
        ],
    );
    assert!(
        r.status.success() && stderr(&r).contains("1 invalid"),
        "{}",
        stderr(&r)
    );
    let doc: serde_json::Value = serde_json::from_slice(&r.stdout).expect("JSON summary");
    assert_eq!(doc["invalid"], 1);
    assert_eq!(doc["first_invalid_row"], 70_000);
    assert_eq!(doc["tuples"], 100_000);
    assert_eq!(doc["written"], true);
}

#[test]
fn a_bad_material_in_a_later_chunk_is_named_by_its_batch_row() {
    for backend in ["reference", "cpu"] {
        bad_material_is_named(backend);
    }
}

/// Two bad rows in different chunks: the first in the batch is named, whichever worker
/// meets its own first (the CPU engine's workers take slices side by side).
fn bad_material_is_named(backend: &str) {
    let dir = tempfile::tempdir().expect("tempdir");
    let m = materials(dir.path());
    let t = batch_with(dir.path(), None, &[90_000, 99_000]);
    let out = dir.path().join("o.npy");
    std::fs::write(&out, b"previous").unwrap();
    let r = eval(
        &m,
        &t,
        &[
            "-o",
            path(&out),
            "--backend",
            backend,
            "--max-memory",
            "1MiB",
        ],
    );
    let text = stderr(&r);
    assert_eq!(r.status.code(), Some(2), "{backend}: {text}");
    assert!(
        text.contains("row 90000") && text.contains("material value 7"),
        "{text}"
    );
    assert_eq!(
        std::fs::read(&out).unwrap(),
        b"previous",
        "the previous output is kept"
    );
}

#[test]
fn max_memory_is_checked() {
    let dir = tempfile::tempdir().expect("tempdir");
    let m = materials(dir.path());
    let t = batch_with(dir.path(), None, &[]);
    let out = dir.path().join("o.npy");
    for bad in ["0", "12", "1KiB", "2TiB", "lots", "5 parsecs"] {
        let r = eval(&m, &t, &["-o", path(&out), "--max-memory", bad]);
        assert_eq!(
            r.status.code(),
            Some(2),
            "--max-memory {bad}: {}",
            stderr(&r)
        );
        assert!(stderr(&r).contains("--max-memory"), "{}", stderr(&r));
    }
}

/// `eval --shard K/N` parts joined by `merge` equal one run, byte for byte, BRDF and terms,
/// for N = 1, 3 and 7 and for N larger than the batch (empty parts).
#[test]
fn merged_shards_equal_the_unsharded_run() {
    let dir = tempfile::tempdir().expect("tempdir");
    let m = materials(dir.path());
    for (rows, n) in [(1000usize, 1u64), (1000, 3), (1000, 7), (5, 7)] {
        let t = dir.path().join(format!("t{rows}.npy"));
        assert!(generate(&m, rows, &t).status.success());
        let (a, at) = (dir.path().join("a.npy"), dir.path().join("at.npy"));
        let whole = eval(
            &m,
            &t,
            &[
                "-o",
                path(&a),
                "--terms",
                path(&at),
                "--backend",
                "reference",
            ],
        );
        assert!(whole.status.success(), "{}", stderr(&whole));
        let mut parts = Vec::new();
        for k in 1..=n {
            let p = dir.path().join(format!("p{k}.npy"));
            let pt = dir.path().join(format!("pt{k}.npy"));
            let shard = format!("{k}/{n}");
            let r = eval(
                &m,
                &t,
                &[
                    "-o",
                    path(&p),
                    "--terms",
                    path(&pt),
                    "--backend",
                    "reference",
                    "--shard",
                    &shard,
                ],
            );
            assert!(r.status.success(), "shard {shard}: {}", stderr(&r));
            assert!(vkbrdf::stream::shard::sidecar_path(&p).exists());
            parts.push(p);
        }
        let (b, bt) = (dir.path().join("b.npy"), dir.path().join("bt.npy"));
        let mut args = vec!["merge", "-o", path(&b), "--terms", path(&bt)];
        args.extend(parts.iter().rev().map(|p| path(p))); // order does not matter
        let r = common::vkbrdf(&args);
        assert!(r.status.success(), "merge {n}: {}", stderr(&r));
        assert!(
            stderr(&r).contains(&format!("{rows} tuples")),
            "{}",
            stderr(&r)
        );
        assert_eq!(
            std::fs::read(&a).unwrap(),
            std::fs::read(&b).unwrap(),
            "N = {n}"
        );
        assert_eq!(
            std::fs::read(&at).unwrap(),
            std::fs::read(&bt).unwrap(),
            "N = {n}"
        );
        for k in 1..=n {
            for f in [
                format!("p{k}.npy"),
                format!("pt{k}.npy"),
                format!("p{k}.npy.shard.json"),
            ] {
                std::fs::remove_file(dir.path().join(f)).unwrap();
            }
        }
    }
}

/// Parts that do not belong together are refused, naming the part and the reason; nothing
/// is written.
#[test]
fn merge_refuses_parts_that_do_not_belong_together() {
    let dir = tempfile::tempdir().expect("tempdir");
    let m = materials(dir.path());
    let t = dir.path().join("t.npy");
    let u = dir.path().join("u.npy");
    assert!(generate(&m, 300, &t).status.success());
    assert!(vkbrdf::batch::write_npy_f32(
        &u,
        &[0.3, 0.2, 0.9, -0.2, 0.1, 0.8, 0.0, 0.0, 1.0, 0.0],
        10
    )
    .is_ok());
    let part = |input: &Path, name: &str, shard: &str| {
        let p = dir.path().join(name);
        let r = eval(
            &m,
            input,
            &["-o", path(&p), "--backend", "reference", "--shard", shard],
        );
        assert!(r.status.success(), "{}", stderr(&r));
        p
    };
    let p1 = part(&t, "p1.npy", "1/3");
    let p2 = part(&t, "p2.npy", "2/3");
    let p3 = part(&t, "p3.npy", "3/3");
    let q2 = part(&t, "q2.npy", "2/2");
    let other = part(&u, "o3.npy", "3/3");
    let out = dir.path().join("out.npy");
    let cases: Vec<(Vec<&Path>, &str)> = vec![
        (vec![&p1, &p2], "missing"),
        (vec![&p1, &p2, &p2, &p3], "twice"),
        (vec![&p1, &p2, &q2], "number of shards"),
        (vec![&p1, &p2, &other], "input"),
    ];
    for (parts, why) in cases {
        let mut args = vec!["merge", "-o", path(&out)];
        args.extend(parts.iter().map(|p| path(p)));
        let r = common::vkbrdf(&args);
        assert_eq!(r.status.code(), Some(2), "{why}: {}", stderr(&r));
        assert!(stderr(&r).contains(why), "{why}: {}", stderr(&r));
        assert!(!out.exists(), "{why}: an output was written");
    }
    // A part without its sidecar names the sidecar it looked for.
    std::fs::remove_file(vkbrdf::stream::shard::sidecar_path(&p3)).unwrap();
    let r = common::vkbrdf(&["merge", "-o", path(&out), path(&p1), path(&p2), path(&p3)]);
    assert_eq!(r.status.code(), Some(2), "{}", stderr(&r));
    assert!(stderr(&r).contains("p3.npy.shard.json"), "{}", stderr(&r));
    // --shard values are checked.
    for bad in ["0/3", "4/3", "3", "a/b", "1/0"] {
        let r = eval(&m, &t, &["-o", path(&out), "--shard", bad]);
        assert_eq!(r.status.code(), Some(2), "--shard {bad}: {}", stderr(&r));
    }
}

/// `vkbrdf bench` times each stage of the streamed path on its own and the whole of it:
/// every engine's row carries a positive rate for read, engine and write and end to end,
/// each beside a positive ceiling, the stages' CPU time and the cores' bound it gives
/// (cores ÷ the summed CPU seconds a tuple); it names the lowest of the three stages and
/// that bound, and its ratio is end to end over that lowest rate.
#[test]
fn bench_reports_each_streaming_stage() {
    let dir = tempfile::tempdir().expect("tempdir");
    let json = dir.path().join("bench.json");
    let out = common::vkbrdf(&[
        "bench",
        "--quick",
        "--no-peers",
        "--scenario",
        "lambert",
        "--repeats",
        "1",
        "--sustained-tuples",
        "1000",
        "--stage-tuples",
        "5000",
        "--json",
        path(&json),
    ]);
    assert!(out.status.success(), "bench: {}", stderr(&out));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("json")).expect("parses");
    let rows = report["stages"].as_array().expect("a stages array");
    assert!(
        rows.iter()
            .any(|r| r["backend"].as_str().unwrap_or("").starts_with("cpu")),
        "the CPU engine has a row: {rows:?}"
    );
    for r in rows {
        let rate = |k: &str| r[k].as_f64().unwrap_or(f64::NAN);
        for k in ["read", "engine", "write", "end_to_end"] {
            assert!(rate(k).is_finite() && rate(k) > 0.0, "{k} in {r}");
        }
        assert_eq!(r["tuples"], 5000, "{r}");
        for k in ["read_ceiling", "write_ceiling", "cores_bound"] {
            assert!(rate(k).is_finite() && rate(k) > 0.0, "{k} in {r}");
        }
        let cpu: Vec<f64> = r["cpu_s_per_tuple"]
            .as_array()
            .expect("cpu_s_per_tuple")
            .iter()
            .map(|x| x.as_f64().expect("a number"))
            .collect();
        assert!(cpu.len() == 3 && cpu.iter().all(|&s| s >= 0.0), "{r}");
        let cores = r["cores"].as_f64().expect("cores");
        assert!(cores >= 1.0, "{r}");
        let bound = cores / cpu.iter().sum::<f64>();
        assert!((rate("cores_bound") - bound).abs() <= 1e-9 * bound, "{r}");
        let slowest = r["slowest"].as_str().expect("slowest");
        let min = [
            ("read", "read"),
            ("engine", "engine"),
            ("write", "write"),
            ("cores", "cores_bound"),
        ]
        .into_iter()
        .map(|(name, k)| (name, rate(k)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("four");
        assert_eq!(slowest, min.0, "{r}");
        assert!(
            (rate("ratio") - rate("end_to_end") / min.1).abs() < 1e-9 * rate("ratio"),
            "{r}"
        );
        if r["backend"].as_str().unwrap_or("").starts_with("vulkan") {
            for k in [
                "upload",
                "kernel",
                "readback",
                "upload_ceiling",
                "readback_ceiling",
            ] {
                assert!(rate(k).is_finite() && rate(k) > 0.0, "{k} in {r}");
            }
        }
    }
}

/// A `.npy` of `rows` (row-major, `columns` wide) in the given dtype and order.
fn write_npy_as(path: &Path, rows: &[f32], columns: usize, f64s: bool, fortran: bool) {
    let n = rows.len() / columns;
    let values: Vec<f32> = if fortran {
        (0..columns)
            .flat_map(|j| (0..n).map(move |i| i * columns + j))
            .map(|k| rows[k])
            .collect()
    } else {
        rows.to_vec()
    };
    let bytes: Vec<u8> = if f64s {
        values
            .iter()
            .flat_map(|&x| (x as f64).to_le_bytes())
            .collect()
    } else {
        values.iter().flat_map(|&x| x.to_le_bytes()).collect()
    };
    let descr = if f64s { "<f8" } else { "<f4" };
    common::npy::write_npy(path, descr, fortran, &[n, columns], &bytes);
}

/// float64 and Fortran-order batches take the streamed path chunk by chunk (1 MiB chunks,
/// a shard, tangent columns, the local form) and give the bytes the C-order float32 batch
/// gives; a bad
/// material in a Fortran-order file is named by its batch row.
#[test]
fn float64_and_fortran_order_stream_to_the_same_output() {
    let dir = tempfile::tempdir().expect("tempdir");
    let m = materials(dir.path());
    let t = dir.path().join("t.npy");
    assert!(generate(&m, 150_000, &t).status.success());
    let batch = vkbrdf::batch::Batch::read_npy(&t, 2).expect("read");
    let rows = batch.as_slice().to_vec();
    let mut with_tangents = Vec::with_capacity(rows.len() / 10 * 13);
    for r in rows.chunks_exact(10) {
        with_tangents.extend_from_slice(r);
        with_tangents.extend_from_slice(&[1.0, 0.0, 0.0]);
    }
    // The local form (Lx Ly Lz Vx Vy Vz, material `gold`): a float32 Fortran-order file is
    // read as columns, straight into the engine's batch (`LocalLayout::Columns`).
    let local: Vec<f32> = rows
        .chunks_exact(10)
        .flat_map(|r| r[..6].to_vec())
        .collect();
    for (name, data, columns) in [
        ("plain", &rows, 10),
        ("tangents", &with_tangents, 13),
        ("local", &local, 6),
    ] {
        let run = |input: &Path, out: &str, extra: &[&str]| {
            let o = dir.path().join(out);
            let mut args = vec!["-o", path(&o), "--backend", "cpu", "--max-memory", "1MiB"];
            if columns == 6 {
                args.extend_from_slice(&["--material", "gold"]);
            }
            args.extend_from_slice(extra);
            let r = eval(&m, input, &args);
            assert!(r.status.success(), "{name} {out}: {}", stderr(&r));
            std::fs::read(&o).expect("output")
        };
        let c32 = dir.path().join(format!("{name}-c32.npy"));
        write_npy_as(&c32, data, columns, false, false);
        let want = run(&c32, "want.npy", &[]);
        let want_shard = run(&c32, "want-2of3.npy", &["--shard", "2/3"]);
        for (f64s, fortran) in [(false, true), (true, false), (true, true)] {
            let input = dir.path().join(format!("{name}-{f64s}-{fortran}.npy"));
            write_npy_as(&input, data, columns, f64s, fortran);
            let label = format!("{name}, float64 {f64s}, Fortran {fortran}");
            assert!(
                run(&input, "got.npy", &[]) == want,
                "{label}: output differs"
            );
            assert!(
                run(&input, "got-2of3.npy", &["--shard", "2/3"]) == want_shard,
                "{label}: shard 2/3 differs"
            );
        }
    }
    let mut bad = rows.clone();
    bad[123_456 * 10 + 9] = 2.5;
    let f = dir.path().join("bad-fortran.npy");
    write_npy_as(&f, &bad, 10, false, true);
    let r = eval(
        &m,
        &f,
        &[
            "-o",
            path(&dir.path().join("x.npy")),
            "--max-memory",
            "1MiB",
        ],
    );
    assert!(!r.status.success());
    assert!(stderr(&r).contains("row 123456"), "{}", stderr(&r));
}

/// The CPU engine's stream workers (each reads, evaluates and writes its own slices, in
/// whatever order they finish) write exactly what one call over the whole batch computes:
/// mixed materials, a tail slice shorter than the others, the terms, slices of every size
/// the budget allows, and a shard whose part starts mid-slice.
/// The values' bits, for comparisons that hold bit for bit.
fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// The BRDF at `o` and the terms at `ot` are `want`'s rows `rows`, bit for bit (`label`
/// names the run in failures).
fn assert_written_as(
    o: &Path,
    ot: &Path,
    want: &vkbrdf::backend::Output,
    rows: std::ops::Range<usize>,
    label: &str,
) {
    let (brdf, shape) = vkbrdf::batch::read_npy_f32(o).expect("BRDF");
    assert_eq!(shape, [rows.len() as u64, 3], "{label}");
    let (terms, _) = vkbrdf::batch::read_npy_f32(ot).expect("terms");
    assert!(
        bits(&brdf) == bits(&want.brdf[rows.start * 3..rows.end * 3]),
        "{label}: BRDF differs from one call"
    );
    let want_terms = want.terms.as_deref().expect("terms");
    assert!(
        bits(&terms) == bits(&want_terms[rows.start * 6..rows.end * 6]),
        "{label}: terms differ from one call"
    );
}

#[test]
fn the_cpu_engines_workers_write_what_one_call_computes() {
    use vkbrdf::backend::{Backend, Request};
    let dir = tempfile::tempdir().expect("tempdir");
    let m = materials(dir.path());
    let t = dir.path().join("t.npy");
    let n = 300_001;
    assert!(generate(&m, n, &t).status.success());
    let table = vkbrdf::material::load_materials(&m).expect("materials");
    let batch = vkbrdf::batch::Batch::read_npy(&t, table.len()).expect("batch");
    let want = vkbrdf::cpu::CpuEngine::with_threads(1)
        .evaluate(&batch, &table, &Request { terms: true })
        .expect("one call");
    let (o, ot) = (dir.path().join("o.npy"), dir.path().join("ot.npy"));
    for extra in [
        &["--max-memory", "1MiB"][..],
        &["--max-memory", "512MiB"],
        &["--shard", "2/3"],
    ] {
        let mut args = vec!["-o", path(&o), "--terms", path(&ot), "--backend", "cpu"];
        args.extend_from_slice(extra);
        let r = eval(&m, &t, &args);
        assert!(r.status.success(), "{extra:?}: {}", stderr(&r));
        let rows = match extra[0] {
            "--shard" => n / 3..2 * n / 3,
            _ => 0..n,
        };
        assert_written_as(&o, &ot, &want, rows, &format!("{extra:?}"));
    }
}

#[test]
fn the_vulkan_stream_keeps_chunks_in_flight_and_writes_what_one_call_computes() {
    // `eval` on Vulkan keeps chunks in flight across the stream's chunks
    // (`Backend::overlapped`; VKBRDF_CHUNKS_IN_FLIGHT 0, 1 and 2 — a GPU's default, the
    // whole ring of three slots) and copies split over threads (VKBRDF_HOST_COPY_THREADS):
    // with a 2 MiB device budget a slot holds ~7,600 rows, so 300,001 rows cycle the ring
    // ~40 times; mixed materials take the grouped kernel, two invalid
    // rows lie in different chunks, a shard starts mid-chunk, and a local-frame input
    // streams too. Each output must equal one `evaluate` call's bits (the kernel evaluates
    // tuple by tuple).
    use vkbrdf::backend::{Backend, Request};
    let Some(mut gpu) = common::vulkan() else {
        return;
    };
    let dir = tempfile::tempdir().expect("tempdir");
    let m = materials(dir.path());
    let table = vkbrdf::material::load_materials(&m).expect("materials");
    let n = 300_001;
    let mut data = vkbrdf::sample::sample_batch(n, table.len(), 5, false).into_data();
    for row in [1_000, 250_000] {
        data[row * 10..row * 10 + 3].fill(0.0); // L = 0: invalid
    }
    let t = dir.path().join("t.npy");
    vkbrdf::batch::write_npy_f32(&t, &data, 10).expect("write batch");
    let batch = vkbrdf::batch::Batch::new(data, 10, table.len(), &t).expect("batch");
    let want = gpu
        .evaluate(&batch, &table, &Request { terms: true })
        .expect("one call");
    assert_eq!(want.counts.first_invalid, Some(1_000));
    let (o, ot) = (dir.path().join("o.npy"), dir.path().join("ot.npy"));
    // `depth` chunks in flight; the host's copies split over 3 threads where the depth is 2
    // and in the default case (2^17-row chunks: 5 MiB, so the copies do split).
    let run = |depth: &str, args: &[&str]| {
        let threads = if matches!(depth, "2" | "default") {
            "3"
        } else {
            "1"
        };
        std::process::Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
            .arg("eval")
            .args(["-m", path(&m)])
            .args(args)
            .env("VKBRDF_CHUNKS_IN_FLIGHT", depth)
            .env("VKBRDF_HOST_COPY_THREADS", threads)
            .output()
            .expect("run vkbrdf")
    };
    let budget = ["--max-gpu-memory", "2M"];
    for (depth, extra) in [
        ("0", &["--max-memory", "1MiB"][..]),
        ("1", &["--max-memory", "1MiB"]),
        ("2", &["--max-memory", "1MiB"]),
        ("1", &["--shard", "2/3"]),
        ("2", &["--shard", "2/3"]),
        ("default", &[]),
    ] {
        let mut args = vec!["-i", path(&t), "-o", path(&o), "--terms", path(&ot)];
        args.extend(["--backend", "vulkan", "--json"]);
        if depth != "default" {
            args.extend(budget);
        }
        args.extend_from_slice(extra);
        let r = run(depth, &args);
        let extra = (depth, extra);
        assert!(r.status.success(), "{extra:?}: {}", stderr(&r));
        let doc: serde_json::Value = serde_json::from_slice(&r.stdout).expect("JSON summary");
        let rows = match extra.1.first() {
            Some(&"--shard") => n / 3..2 * n / 3,
            _ => 0..n,
        };
        if rows.start == 0 {
            assert_eq!(doc["invalid"], 2, "{extra:?}");
            assert_eq!(doc["first_invalid_row"], 1_000, "{extra:?}");
        } else {
            assert_eq!(doc["invalid"], 0, "{extra:?}");
        }
        assert_written_as(&o, &ot, &want, rows, &format!("{extra:?}"));
    }
    // The library's stream: chunks of at most `max_chunk_rows` come back in order, each as
    // a call on it alone; a larger chunk is an error, not a panic.
    {
        use vkbrdf::backend::{Output, StreamChunk};
        let options = vkbrdf::gpu::VulkanOptions {
            max_gpu_memory: 2 << 20,
            chunks_in_flight: Some(2),
            ..vkbrdf::gpu::VulkanOptions::default()
        };
        let mut small = common::vulkan_with(options).expect("a device (found above)");
        let request = Request { terms: false };
        let mut stream = small.overlapped(&table, request, n as u64).expect("stream");
        let max = stream.max_chunk_rows();
        assert!(max < n, "{max}");
        let err = stream
            .submit(StreamChunk::Rows(&batch), 0, Output::default())
            .expect_err("an oversized chunk is refused");
        assert!(err.to_string().contains("max_chunk_rows"), "{err}");
        let cols = batch.columns();
        let parts: Vec<_> = (0..5)
            .map(|k| {
                let rows = batch.as_slice()[k * max * cols..(k + 1) * max * cols].to_vec();
                vkbrdf::batch::Batch::new(rows, cols, table.len(), &t).expect("part")
            })
            .collect();
        let mut outs = Vec::new();
        for (k, part) in parts.iter().enumerate() {
            let first = (k * max) as u64;
            let done = stream.submit(StreamChunk::Rows(part), first, Output::default());
            outs.extend(done.expect("submit"));
        }
        while let Some(out) = stream.finish_oldest().expect("finish") {
            outs.push(out);
        }
        assert_eq!(outs.len(), parts.len());
        for (k, out) in outs.iter().enumerate() {
            assert!(
                bits(&out.brdf) == bits(&want.brdf[k * max * 3..(k + 1) * max * 3]),
                "library stream, chunk {k}: BRDF differs from one call"
            );
        }
        // Row 1,000 (invalid) lies in the first chunk, counted from its first row.
        assert_eq!(outs[0].counts.first_invalid, Some(1_000));
    }
    // The local-frame form: six columns, material 0, against its rows' one call.
    let local: Vec<f32> = batch
        .as_slice()
        .chunks_exact(10)
        .flat_map(|r| r[..6].to_vec())
        .collect();
    let lt = dir.path().join("local.npy");
    vkbrdf::batch::write_npy_f32(&lt, &local, 6).expect("write local batch");
    let rows: Vec<f32> = local
        .chunks_exact(6)
        .flat_map(|r| [r[0], r[1], r[2], r[3], r[4], r[5], 0.0, 0.0, 1.0, 0.0])
        .collect();
    let rows = vkbrdf::batch::Batch::new(rows, 10, table.len(), &lt).expect("rows");
    let want = gpu
        .evaluate(&rows, &table, &Request::default())
        .expect("one call");
    for depth in ["0", "2"] {
        let mut args = vec!["-i", path(&lt), "-o", path(&o), "--backend", "vulkan"];
        args.extend(["--material", "0"]);
        args.extend(budget);
        let r = run(depth, &args);
        assert!(r.status.success(), "local, {depth}: {}", stderr(&r));
        let (brdf, _) = vkbrdf::batch::read_npy_f32(&o).expect("BRDF");
        assert!(
            bits(&brdf) == bits(&want.brdf),
            "local, {depth}: BRDF differs from one call"
        );
    }
}
