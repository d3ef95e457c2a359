//! Evaluates one benchmark scenario's local form on the CPU engine, one thread, `REPS`
//! times — a harness for instruction counts, which repeat where timings on this shared
//! machine do not:
//!
//! ```text
//! cargo build --release --example cpu_engine_count
//! valgrind --tool=callgrind --callgrind-out-file=/dev/null \
//!     target/release/examples/cpu_engine_count mitsuba-ggx 262144 1
//! valgrind … cpu_engine_count mitsuba-ggx 262144 3
//! ```
//!
//! A fourth argument `columns` evaluates the same L and V as two `(n, 3)` columns with N
//! given once (`ColumnBatch`) instead of the local form; `planar`, the local form held as
//! six columns (`LocalLayout::Columns`) instead of rows; `rows`, the scenario's 10-column
//! rows (N = +z a row: the lane loops).
//!
//! For counts by source line, build with `--profile profiling` (the release profile drops
//! the line tables) and annotate `target/profiling/examples/cpu_engine_count`'s output
//! with `callgrind_annotate`.
//!
//! Instructions per evaluation = (count at 3 − count at 1) / (2 × tuples): the set-up (the
//! scenario's tuples, the materials) cancels. Valgrind 3.19 hides AVX-512 from the program,
//! so the counts describe the AVX2+FMA path (`instruction set:` says which ran).

use std::path::Path;
use vkbrdf::backend::{Backend, Output, Request};
use vkbrdf::batch::columns::ColumnBatch;
use vkbrdf::batch::LocalLayout;
use vkbrdf::bench::scenarios;
use vkbrdf::cpu::CpuEngine;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("mitsuba-ggx", String::as_str);
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(262_144);
    let reps: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(1);
    let Some(s) = scenarios::by_name(name) else {
        eprintln!("unknown scenario {name}");
        std::process::exit(2);
    };
    let Some(batch) = scenarios::local_batch(&s, n, 1) else {
        eprintln!("{name} has no local form (several materials or tangents)");
        std::process::exit(2);
    };
    // `planar` as a fourth argument: the local form held as six columns.
    let batch = if args.get(3).is_some_and(|a| a == "planar") {
        batch.to_layout(LocalLayout::Columns)
    } else {
        batch
    };
    // `columns` as a fourth argument: the same L and V as two (n, 3) columns, N given once.
    let columns = args.get(3).is_some_and(|a| a == "columns");
    // `rows` as a fourth argument: the same tuples as 10-column rows with N = (0, 0, 1),
    // which the lane loops take (a block at a time, not the register path).
    let rows = args
        .get(3)
        .is_some_and(|a| a == "rows")
        .then(|| scenarios::batch(&s, n, 1));
    let l: Vec<f32> = (0..n).flat_map(|i| batch.row(i)[..3].to_vec()).collect();
    let v: Vec<f32> = (0..n).flat_map(|i| batch.row(i)[3..].to_vec()).collect();
    let (z, m) = ([0.0f32, 0.0, 1.0], [batch.material() as f32]);
    let cols =
        ColumnBatch::new([&l, &v, &z], None, &m, n, &s.materials, Path::new("c")).expect("columns");
    // As the CLI does: a VKBRDF_CPU_ISA this CPU cannot run is an error, not the best
    // variant in its place (benches/cpu_count_check.sh skips such rows by this exit).
    let isa = vkbrdf::cpu::Isa::from_env().unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(2);
    });
    let mut engine = CpuEngine::with_isa(1, isa);
    let mut out = Output::default();
    for _ in 0..reps {
        if let Some(rows) = &rows {
            engine
                .evaluate_into(rows, &s.materials, &Request::default(), &mut out)
                .expect("evaluates");
        } else if columns {
            engine
                .evaluate_columns_into(&cols, &s.materials, &Request::default(), &mut out)
                .expect("evaluates");
        } else {
            engine
                .evaluate_local_into(&batch, &s.materials, &Request::default(), &mut out)
                .expect("evaluates");
        }
    }
    println!(
        "instruction set: {}; {name}: {n} tuples × {reps}; tally {:?}; first {:?}",
        vkbrdf::cpu::instruction_set(),
        engine.last_tally(),
        &out.brdf[..3]
    );
}
