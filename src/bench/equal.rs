//! The comparison with Mitsuba 3's LLVM backend at equal bytes: Mitsuba's `roughconductor`
//! reads 24 bytes a tuple (wi, wo, six Dr.Jit arrays) and writes 12, so the engine gets the
//! same — the local-frame batch ([`crate::batch::LocalBatch`]) held as six columns,
//! evaluated into a reused output — on the same directions, in the same run. Beside it, the engine's 1 → 2-thread ratio on an
//! in-cache batch and Lambert against the memory-copy ceiling for its 36 bytes a tuple.

use super::{max_rel_err, median, memcpy_ceiling, peers, scenarios};
use crate::backend::{Backend, Output, Request};
use crate::batch::{LocalBatch, LocalLayout};
use crate::cpu::CpuEngine;
use crate::error::Result;
use crate::material::Material;
use std::path::Path;
use std::time::Instant;

/// The local form held as six columns (`LocalLayout::Columns`): Mitsuba gets `wi` and
/// `wo` as Dr.Jit arrays, a column a component, so the engine gets the same layout.
fn columns(local: LocalBatch) -> LocalBatch {
    local.to_layout(LocalLayout::Columns)
}

/// Bytes a tuple moves in the local form: 6 floats in, 3 out.
pub const LOCAL_BYTES: usize = 36;

/// One equal-bytes point: the engine and the peer on the same tuples.
#[derive(Debug, Clone, serde::Serialize)]
pub struct EqualBytesRow {
    /// Our scenario (`mitsuba-beckmann`, `mitsuba-ggx`, `lambert`).
    pub scenario: String,
    /// What the engine is compared with: `mitsuba` (its LLVM backend), `memcpy` (a copy of
    /// the same bytes), or `cpu 1 thread` (the thread-scaling row).
    pub peer: String,
    /// Tuples per call.
    pub tuples: usize,
    /// Bytes a tuple moves (in + out), the same for both sides.
    pub bytes_per_tuple: usize,
    /// The instruction set the engine ran (`avx512`, `avx2+fma`, `scalar`).
    pub instruction_set: String,
    /// The engine's worker threads.
    pub threads: usize,
    /// The engine's median evaluations per second.
    pub cpu_evals_per_s: f64,
    /// The engine's cycles per evaluation (seconds × TSC rate, all threads' wall time).
    pub cpu_cycles_per_eval: Option<f64>,
    /// The engine's max relative error against the f64 reference.
    pub cpu_max_rel_err: f64,
    /// The peer's median evaluations per second, when it ran.
    pub peer_evals_per_s: Option<f64>,
    /// The peer's cycles per evaluation.
    pub peer_cycles_per_eval: Option<f64>,
    /// The peer's max relative error against the f64 reference, when it returns values.
    pub peer_max_rel_err: Option<f64>,
    /// Engine over peer (with several pairs, the median of the pairs' ratios).
    pub ratio: Option<f64>,
    /// Each engine/peer pair's ratio, in the order run (`--pairs`; one pair: empty).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pair_ratios: Vec<f64>,
    /// Why the peer did not run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skipped: Option<String>,
}

/// The TSC rate in Hz from /proc/cpuinfo's `cpu MHz` (what this VM reports), if it says.
pub fn tsc_hz() -> Option<f64> {
    let info = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("cpu MHz"))?;
    line.split(':')
        .nth(1)?
        .trim()
        .parse::<f64>()
        .ok()
        .map(|m| m * 1e6)
}

/// Warm-up before a timed series: calls for at least this long (and at least one). A
/// peer's process leaves the machine disturbed for several milliseconds after it exits
/// (measured: the engine's first ~5 calls at 262,144 tuples ran at half rate right after
/// a Mitsuba run, then recovered), which one warm-up call did not cover; the peer's own
/// warm-up (its JIT compile) is longer than this.
const WARM_UP: std::time::Duration = std::time::Duration::from_millis(50);

/// Median seconds of `repeats` calls of the engine on `local` (after 50 ms of
/// untimed calls), evaluating into the same output each time, and that output.
pub fn time_local(
    engine: &mut CpuEngine,
    local: &LocalBatch,
    materials: &[Material],
    repeats: usize,
) -> Result<(f64, Output)> {
    let request = Request::default();
    let mut out = Output::default();
    let warm = Instant::now();
    loop {
        engine.evaluate_local_into(local, materials, &request, &mut out)?;
        if warm.elapsed() >= WARM_UP {
            break;
        }
    }
    let mut secs = Vec::with_capacity(repeats);
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        engine.evaluate_local_into(local, materials, &request, &mut out)?;
        secs.push(t.elapsed().as_secs_f64());
    }
    Ok((median(secs), out))
}

/// The equal-bytes rows: each Mitsuba scenario at each of `sizes` against the peer (run
/// with `script` unless `no_peers`) in `pairs` interleaved engine/peer pairs, the engine
/// timed before and after each peer run (the median of both: the machine may be shared),
/// each rate the median over the pairs and the ratio the median of the pairs' ratios
/// (Dr.Jit's rate swings 2× between runs on a shared machine); then 1 → 2 threads on the
/// smallest size of `mitsuba-ggx`, and Lambert against the copy ceiling at the largest
/// size.
pub fn rows(
    script: &Path,
    sizes: &[usize],
    repeats: usize,
    no_peers: bool,
    pairs: usize,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<EqualBytesRow>> {
    let pairs = pairs.max(1);
    let hz = tsc_hz();
    let cyc = |evals_per_s: f64| hz.map(|h| h / evals_per_s);
    let isa = crate::cpu::instruction_set().to_string();
    // An engine forced to AVX2 meets Dr.Jit restricted to AVX2 too (8 lanes, no AVX-512
    // instruction), so that an AVX-512 machine also measures the AVX2 comparison.
    let peer_isa: Vec<&str> = if isa == "avx2+fma" {
        vec!["--llvm-isa", "avx2"]
    } else {
        Vec::new()
    };
    let mut engine = CpuEngine::new();
    let threads = engine.threads();
    let mut out = Vec::new();
    let row = |scenario: &str, peer: &str, n: usize, threads: usize, evals: f64, err: f64| {
        EqualBytesRow {
            scenario: scenario.into(),
            peer: peer.into(),
            tuples: n,
            bytes_per_tuple: LOCAL_BYTES,
            instruction_set: isa.clone(),
            threads,
            cpu_evals_per_s: evals,
            cpu_cycles_per_eval: cyc(evals),
            cpu_max_rel_err: err,
            peer_evals_per_s: None,
            peer_cycles_per_eval: None,
            peer_max_rel_err: None,
            ratio: None,
            pair_ratios: Vec::new(),
            skipped: None,
        }
    };
    for name in ["mitsuba-beckmann", "mitsuba-ggx"] {
        let sc = scenarios::by_name(name).expect("the Mitsuba scenarios exist");
        let ps = sc.peer.expect("the Mitsuba scenarios have a peer");
        for &n in sizes {
            let rows_batch = scenarios::batch(&sc, n, 42);
            let local =
                columns(scenarios::local_batch(&sc, n, 42).expect("one material, no tangents"));
            let (mut engine_rates, mut peer_rates, mut ratios) = (vec![], vec![], vec![]);
            let (mut err, mut peer) = (0.0, None);
            for pair in 1..=pairs {
                let of = if pairs > 1 {
                    format!(" (pair {pair} of {pairs})")
                } else {
                    String::new()
                };
                progress(&format!("equal bytes: cpu {name} on {n} tuples{of}"));
                let (before, o) = time_local(&mut engine, &local, &sc.materials, repeats)?;
                err = max_rel_err(&rows_batch, &sc.materials, &o.brdf, 20_000);
                if !no_peers {
                    progress(&format!("equal bytes: mitsuba {ps} on {n} tuples{of}"));
                    peer = Some(peers::run_with(
                        script,
                        "mitsuba",
                        ps,
                        &rows_batch,
                        repeats,
                        &peer_isa,
                    ));
                }
                let (after, _) = time_local(&mut engine, &local, &sc.materials, repeats)?;
                let rate = n as f64 / median(vec![before, after]);
                engine_rates.push(rate);
                if let Some(v) = peer.as_ref().and_then(|p| p.evals_per_s) {
                    peer_rates.push(v);
                    ratios.push(rate / v);
                }
            }
            let mut r = row(name, "mitsuba", n, threads, median(engine_rates), err);
            match peer {
                None => r.skipped = Some("--no-peers".into()),
                Some(p) => {
                    r.skipped = p.skipped.clone();
                    if !peer_rates.is_empty() {
                        let v = median(peer_rates);
                        r.peer_evals_per_s = Some(v);
                        r.peer_cycles_per_eval = cyc(v);
                        r.ratio = Some(median(ratios.clone()));
                    }
                    r.peer_max_rel_err = p
                        .brdf
                        .as_ref()
                        .map(|f| max_rel_err(&rows_batch, &sc.materials, f, 20_000));
                    if pairs > 1 {
                        r.pair_ratios = ratios;
                    }
                }
            }
            out.push(r);
        }
    }
    // 1 → 2 threads where the arithmetic decides: in cache, a microfacet scenario.
    if let Some(&n) = sizes.iter().min() {
        let sc = scenarios::by_name("mitsuba-ggx").expect("exists");
        let local = columns(scenarios::local_batch(&sc, n, 42).expect("local"));
        let rows_batch = scenarios::batch(&sc, n, 42);
        let mut one = CpuEngine::with_threads(1);
        let mut two = CpuEngine::with_threads(2);
        progress(&format!("equal bytes: 1 and 2 threads on {n} tuples"));
        // Pairs in turn, as against Mitsuba: a neighbour's burst then lands on one pair,
        // whose ratio the median sets aside (the ratio of two medians took it whole).
        let (mut s1, mut s2, mut ratios) = (Vec::new(), Vec::new(), Vec::new());
        let mut last = Output::default();
        for _ in 0..pairs.max(3) {
            let one_s = time_local(&mut one, &local, &sc.materials, repeats)?.0;
            let (two_s, o) = time_local(&mut two, &local, &sc.materials, repeats)?;
            ratios.push(one_s / two_s);
            s1.push(one_s);
            s2.push(two_s);
            last = o;
        }
        let (e1, e2) = (n as f64 / median(s1), n as f64 / median(s2));
        let mut r = row(
            "mitsuba-ggx",
            "cpu 1 thread",
            n,
            2,
            e2,
            max_rel_err(&rows_batch, &sc.materials, &last.brdf, 20_000),
        );
        r.peer_evals_per_s = Some(e1);
        r.peer_cycles_per_eval = cyc(e1);
        r.ratio = Some(median(ratios.clone()));
        if pairs > 1 {
            r.pair_ratios = ratios;
        }
        out.push(r);
    }
    // Lambert moves its bytes and little else: against a copy of the same bytes.
    if let Some(&n) = sizes.iter().max() {
        let sc = scenarios::by_name("lambert").expect("exists");
        let local = columns(scenarios::local_batch(&sc, n, 42).expect("local"));
        let rows_batch = scenarios::batch(&sc, n, 42);
        progress(&format!(
            "equal bytes: lambert and a copy of {LOCAL_BYTES} B on {n} tuples"
        ));
        let (secs, o) = time_local(&mut engine, &local, &sc.materials, repeats)?;
        // memcpy_ceiling moves (columns + 3) floats a tuple: 6 + 3 = 36 bytes.
        let copy = memcpy_ceiling(n, 6, repeats);
        let e = n as f64 / secs;
        let mut r = row(
            "lambert",
            "memcpy",
            n,
            threads,
            e,
            max_rel_err(&rows_batch, &sc.materials, &o.brdf, 20_000),
        );
        r.peer_evals_per_s = Some(copy);
        r.peer_cycles_per_eval = cyc(copy);
        r.ratio = Some(e / copy);
        out.push(r);
    }
    Ok(out)
}

/// The rows as a text table.
pub fn table(rows: &[EqualBytesRow]) -> String {
    let mut s = String::from(
        "equal bytes (36 B a tuple: the engine on the local form held as six columns, as Dr.Jit holds wi and wo; reused output):\n",
    );
    s += &format!(
        "{:<17} {:<13} {:>9} {:>9} {:>11} {:>9} {:>11} {:>9} {:>7} {:>10} {:>10}\n",
        "scenario",
        "vs",
        "tuples",
        "isa/thr",
        "cpu M/s",
        "cpu cyc",
        "peer M/s",
        "peer cyc",
        "ratio",
        "cpu err",
        "peer err"
    );
    let f = |x: Option<f64>, scale: f64, prec: usize| {
        x.map_or("-".to_string(), |v| format!("{:.*}", prec, v * scale))
    };
    for r in rows {
        s += &format!(
            "{:<17} {:<13} {:>9} {:>9} {:>11.1} {:>9} {:>11} {:>9} {:>7} {:>10.2e} {:>10}{}\n",
            r.scenario,
            r.peer,
            r.tuples,
            format!("{}/{}", r.instruction_set, r.threads),
            r.cpu_evals_per_s / 1e6,
            f(r.cpu_cycles_per_eval, 1.0, 1),
            f(r.peer_evals_per_s, 1e-6, 1),
            f(r.peer_cycles_per_eval, 1.0, 1),
            f(r.ratio, 1.0, 2),
            r.cpu_max_rel_err,
            r.peer_max_rel_err
                .map_or("-".to_string(), |e| format!("{e:.2e}")),
            r.skipped
                .as_ref()
                .map_or(String::new(), |w| format!("  (peer skipped: {w})")),
        );
        if !r.pair_ratios.is_empty() {
            let each: Vec<String> = r.pair_ratios.iter().map(|x| format!("{x:.2}")).collect();
            s += &format!(
                "{:<17} {:<13} {:>9} ratio the median of {} pairs: {}\n",
                "",
                "",
                "",
                r.pair_ratios.len(),
                each.join(", ")
            );
        }
    }
    // A variant forced by VKBRDF_CPU_ISA: Dr.Jit is restricted to AVX2 alongside AVX2,
    // else it compiles for the host.
    let best = crate::cpu::Isa::best().to_string();
    if let Some(r) = rows.iter().find(|r| r.instruction_set != best) {
        s += &if r.instruction_set == "avx2+fma" {
            "(the engine ran `avx2+fma` as VKBRDF_CPU_ISA asked; Mitsuba's kernels were \
             compiled for an AVX2-only CPU too, 8 lanes: peer.py --llvm-isa avx2)\n"
                .to_string()
        } else {
            format!(
                "(the engine ran `{}` as VKBRDF_CPU_ISA asked; Mitsuba compiles for this CPU's \
                 best instruction set, `{best}`)\n",
                r.instruction_set
            )
        };
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row_on(isa: &str) -> EqualBytesRow {
        EqualBytesRow {
            scenario: "mitsuba-ggx".into(),
            peer: "mitsuba".into(),
            tuples: 16,
            bytes_per_tuple: 36,
            instruction_set: isa.into(),
            threads: 1,
            cpu_evals_per_s: 1e6,
            cpu_cycles_per_eval: None,
            cpu_max_rel_err: 0.0,
            peer_evals_per_s: None,
            peer_cycles_per_eval: None,
            peer_max_rel_err: None,
            ratio: None,
            pair_ratios: Vec::new(),
            skipped: None,
        }
    }

    /// With several pairs the table prints each pair's ratio under the row's median, in
    /// the order run; with one pair, no such line.
    #[test]
    fn the_table_lists_the_pairs_ratios_under_their_median() {
        let mut r = row_on(&crate::cpu::Isa::best().to_string());
        assert!(!table(&[r.clone()]).contains("pairs"));
        r.ratio = Some(0.7);
        r.pair_ratios = vec![0.71, 0.5, 0.7];
        let t = table(&[r]);
        assert!(
            t.contains("ratio the median of 3 pairs: 0.71, 0.50, 0.70"),
            "{t}"
        );
    }

    /// The table says when the engine ran a variant other than the host's best, which the
    /// peer's JIT does not follow, and only then.
    #[test]
    fn the_table_names_a_forced_instruction_set() {
        let best = crate::cpu::Isa::best().to_string();
        assert!(!table(&[row_on(&best)]).contains("VKBRDF_CPU_ISA"));
        if best != "scalar" {
            let t = table(&[row_on("scalar")]);
            assert!(
                t.contains("ran `scalar`") && t.contains(&format!("`{best}`")),
                "{t}"
            );
        }
    }
}
