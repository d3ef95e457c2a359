//! The streamed evaluation's stages, each timed on its own, beside the whole file-to-file
//! run (`vkbrdf eval`'s path, [`crate::stream::evaluate`]): reading the `.npy` in chunks,
//! the engine on chunks already in memory (on Vulkan split into the host's upload, wait and
//! readback, with the kernel's own rate from device timestamps), and writing the outputs.
//! The pipeline overlaps the three, so end to end can approach the slowest stage's rate;
//! the ratio of the two is what the streaming issue targets (≥ 0.8).
//!
//! The input file is written once and read once before timing, so every stage reads it
//! from the page cache.

use crate::backend::{Backend, Request};
use crate::batch::rows::{NpyRows, RowsChunk};
use crate::batch::{write_npy_f32, Batch};
use crate::cancel::Cancel;
use crate::error::Result;
use crate::material::Material;
use crate::stats::median;
use crate::stream::{self, StreamJob};
use std::path::Path;
use std::time::Instant;

/// One engine's stage rates on one scenario (tuples per second; `None` where the engine
/// has no such stage), each beside its ceiling, and the bound the cores set.
#[derive(Debug, Clone, serde::Serialize)]
pub struct StageRow {
    /// Engine (`cpu`, `vulkan`, `reference`).
    pub backend: String,
    /// Scenario name.
    pub scenario: String,
    /// Tuples in the file.
    pub tuples: usize,
    /// Rows per chunk (from the memory budget, as `eval` chooses them).
    pub chunk_rows: usize,
    /// Reading and checking the `.npy` chunk by chunk, into a reused buffer as `eval` does.
    pub read: f64,
    /// Read's ceiling: the same file copied from the page cache into one reused buffer of
    /// a chunk's size (`read(2)`, no checks).
    pub read_ceiling: f64,
    /// The engine on chunks in memory (`Backend::evaluate_into`, outputs included).
    pub engine: f64,
    /// Vulkan: grouping and copying rows into device-visible memory (host time).
    pub upload: Option<f64>,
    /// Vulkan: upload's ceiling, the host→device copy rate of a transfer command (its
    /// bytes: the rows' floats and a `u32` of order).
    pub upload_ceiling: Option<f64>,
    /// Vulkan: the kernel alone, from device timestamps (tuples resident on the device).
    pub kernel: Option<f64>,
    /// Vulkan: copying results out of device-visible memory (host time).
    pub readback: Option<f64>,
    /// Vulkan: readback's ceiling, the device→host copy rate of a transfer command (12
    /// bytes a tuple).
    pub readback_ceiling: Option<f64>,
    /// Vulkan: the host's own copies into and out of mapped memory, bytes per second.
    pub link: Option<crate::gpu::LinkRates>,
    /// Writing the outputs, chunk by chunk, to a staged `.npy` renamed at the end (fsync
    /// included; a fresh path, as a first `eval` writes).
    pub write: f64,
    /// Write's ceiling: the same bytes written to a fresh file with large `write(2)`s into
    /// the page cache (no staging, no fsync).
    pub write_ceiling: f64,
    /// CPU seconds per tuple of each stage run on its own (read, engine, write): process
    /// CPU time, every thread of the stage counted.
    pub cpu_s_per_tuple: [f64; 3],
    /// The machine's cores (what the stages share).
    pub cores: usize,
    /// The bound the cores set when the stages share them: cores ÷ the stages' summed CPU
    /// seconds per tuple.
    pub cores_bound: f64,
    /// `vkbrdf eval`'s streamed path, file to file (a fresh output path, fsync included).
    pub end_to_end: f64,
    /// The slowest of read, engine and write (the stages that run in parallel), or
    /// `cores` when the cores' bound is lower still.
    pub slowest: String,
    /// End to end over the lower of the slowest stage's rate and the cores' bound (the
    /// host-path issue's target: ≥ 0.8).
    pub ratio: f64,
}

/// The engine under test: any [`Backend`], or the Vulkan one, which also reports its
/// host stages and its kernel alone.
pub enum Engine<'a> {
    /// An engine timed as a whole.
    Any(&'a mut dyn Backend),
    /// The Vulkan kernel, with upload, kernel and readback rates.
    Vulkan(&'a mut crate::gpu::VulkanBackend),
}

impl Engine<'_> {
    fn backend(&mut self) -> &mut dyn Backend {
        match self {
            Engine::Any(b) => &mut **b,
            Engine::Vulkan(v) => &mut **v,
        }
    }
}

/// Process CPU time in seconds (every thread).
fn cpu_now() -> f64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ProcessCPUTime);
    t.tv_sec as f64 + 1e-9 * t.tv_nsec as f64
}

/// Runs `f`, returning its wall and CPU seconds.
fn timed<T>(f: impl FnOnce() -> Result<T>) -> Result<(T, f64, f64)> {
    let (wall, cpu) = (Instant::now(), cpu_now());
    let v = f()?;
    Ok((v, wall.elapsed().as_secs_f64(), cpu_now() - cpu))
}

/// Wall and CPU seconds of each repeat of one stage.
#[derive(Default)]
struct Times {
    wall: Vec<f64>,
    cpu: Vec<f64>,
}

impl Times {
    fn push(&mut self, wall: f64, cpu: f64) {
        self.wall.push(wall);
        self.cpu.push(cpu);
    }
}

/// Times the stages and the end-to-end run of `backend` on `batch` written to a file in
/// `dir`, each `repeats` times (median).
pub fn measure(
    mut engine: Engine,
    scenario: &str,
    batch: &Batch,
    materials: &[Material],
    dir: &Path,
    max_memory: u64,
    repeats: usize,
) -> Result<StageRow> {
    let n = batch.len();
    let input = dir.join("stages-input.npy");
    let output = dir.join("stages-output.npy");
    write_npy_f32(&input, batch.as_slice(), batch.columns())?;
    let chunk = stream::chunk_rows(max_memory, 4 * batch.columns(), batch.columns(), false);
    // The read stage and its ceiling in the pieces `eval` reads on this engine.
    let piece = stream::read_rows(
        engine.backend(),
        max_memory,
        4 * batch.columns(),
        batch.columns(),
    );
    // Warm: the page cache holds the file, the engine has compiled its kernel.
    let chunks = read_all(&input, materials.len(), chunk)?;
    let first = engine
        .backend()
        .evaluate(&chunks[0], materials, &Request::default())?;
    let mut out = first.clone();
    read_pass(&input, materials.len(), piece)?;

    let [mut read, mut copy, mut eng, mut write, mut write_copy, mut e2e] =
        std::array::from_fn::<Times, 6, _>(|_| Times::default());
    let (mut upload_s, mut readback_s) = (Vec::new(), Vec::new());
    let cancel = Cancel::new();
    // The write stage writes one evaluated chunk's values for every chunk (the rate does
    // not depend on the values).
    let blocks: Vec<&[f32]> = chunks.iter().map(|c| &first.brdf[..3 * c.len()]).collect();
    for _ in 0..repeats.max(1) {
        let ((), w, c) = timed(|| read_pass(&input, materials.len(), piece))?;
        read.push(w, c);
        let ((), w, c) = timed(|| copy_pass(&input, piece * 4 * batch.columns()))?;
        copy.push(w, c);

        if let Engine::Vulkan(v) = &mut engine {
            v.reset_host_stages();
        }
        // As the pipeline does it: each chunk into a reused output.
        let ((), w, c) = timed(|| {
            for ch in &chunks {
                engine
                    .backend()
                    .evaluate_into(ch, materials, &Request::default(), &mut out)?;
            }
            Ok(())
        })?;
        eng.push(w, c);
        if let Engine::Vulkan(v) = &engine {
            let s = v.host_stages();
            upload_s.push(s.upload_s);
            readback_s.push(s.readback_s);
        }

        remove(&output);
        let ((), w, c) = timed(|| stream::write_chunks(&output, n as u64, 3, &blocks, &cancel))?;
        write.push(w, c);
        remove(&output);
        let ((), w, c) = timed(|| write_copy_pass(&output, &blocks))?;
        write_copy.push(w, c);

        let job = StreamJob {
            spike: None,
            input: &input,
            materials,
            output: &output,
            terms: None,
            max_memory,
            strict: false,
            shard: None,
            materials_file: &input,
            material: None,
            spectral: None,
        };
        remove(&output);
        let (_, w, c) = timed(|| stream::evaluate(&job, engine.backend(), &cancel, |_, _| {}))?;
        e2e.push(w, c);
    }
    let (kernel, link) = match &mut engine {
        Engine::Vulkan(v) => (
            Some(n as f64 / v.kernel_seconds(batch, materials, &Request::default(), 3)?),
            Some(v.link_rates((4 * (batch.columns() + 1) * chunk) as u64, repeats.max(3))?),
        ),
        Engine::Any(_) => (None, None),
    };
    let _ = std::fs::remove_file(&input);
    remove(&output);
    let rate = |s: Vec<f64>| n as f64 / median(s).max(1e-12);
    let opt_rate = |s: Vec<f64>| (!s.is_empty()).then(|| rate(s));
    let per_tuple = |t: &Times| median(t.cpu.clone()) / n as f64;
    let cpu_s_per_tuple = [per_tuple(&read), per_tuple(&eng), per_tuple(&write)];
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    let cores_bound = cores as f64 / cpu_s_per_tuple.iter().sum::<f64>().max(1e-18);
    let (read, engine_rate, write) = (rate(read.wall), rate(eng.wall), rate(write.wall));
    let (slowest, bound) = [
        ("read", read),
        ("engine", engine_rate),
        ("write", write),
        ("cores", cores_bound),
    ]
    .into_iter()
    .min_by(|a, b| a.1.total_cmp(&b.1))
    .expect("four bounds");
    let end_to_end = rate(e2e.wall);
    Ok(StageRow {
        backend: engine.backend().name(),
        scenario: scenario.to_string(),
        tuples: n,
        chunk_rows: chunk,
        read,
        read_ceiling: rate(copy.wall),
        engine: engine_rate,
        upload: opt_rate(upload_s),
        upload_ceiling: link.map(|l| l.host_to_device / (4 * (batch.columns() + 1)) as f64),
        kernel,
        readback: opt_rate(readback_s),
        readback_ceiling: link.map(|l| l.device_to_host / 12.0),
        link,
        write,
        write_ceiling: rate(write_copy.wall),
        cpu_s_per_tuple,
        cores,
        cores_bound,
        end_to_end,
        slowest: slowest.to_string(),
        ratio: end_to_end / bound,
    })
}

/// Removes a previous run's output (untimed): every timed write goes to a fresh path, as
/// a first `eval` does, so no run pays for freeing the last one's pages.
fn remove(path: &Path) {
    let _ = std::fs::remove_file(path);
}

/// The whole file as chunks of `chunk` rows, read and checked as `eval` reads it.
fn read_all(path: &Path, material_count: usize, chunk: usize) -> Result<Vec<Batch<'static>>> {
    let mut rows = NpyRows::open(path, material_count)?;
    let mut chunks = Vec::new();
    while let Some((_, b)) = rows.next_chunk(chunk)? {
        chunks.push(b);
    }
    Ok(chunks)
}

/// The read stage as `eval`'s reader runs it: every chunk mapped where the page cache
/// holds it and checked there, or (mapped reads off: not Linux, no handler) read and
/// checked into the one buffer the last chunk gave back.
fn read_pass(path: &Path, material_count: usize, chunk: usize) -> Result<()> {
    let mut rows = NpyRows::open(path, material_count)?;
    let mut spare = Vec::new();
    while let Some((_, c)) = rows.next_in_place(chunk, spare, |_, _| Ok(()))? {
        spare = match c {
            RowsChunk::Mapped(_) => Vec::new(),
            RowsChunk::Read(b) => b.into_data(),
        };
    }
    Ok(())
}

/// Read's ceiling: the file copied from the page cache into one reused buffer of `bytes`.
fn copy_pass(path: &Path, bytes: usize) -> Result<()> {
    use std::io::Read;
    let io = |source| crate::error::Error::Io {
        path: path.to_owned(),
        source,
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut buffer = vec![0u8; bytes.max(1)];
    while file.read(&mut buffer).map_err(io)? > 0 {}
    Ok(())
}

/// Write's ceiling: `blocks` written to a fresh file with one `write(2)` each, into the
/// page cache (no fsync: what the memory allows; the write stage's own fsync is the disk's
/// share, which the early writeback hides behind the run).
fn write_copy_pass(path: &Path, blocks: &[&[f32]]) -> Result<()> {
    use std::io::Write;
    let io = |source| crate::error::Error::Io {
        path: path.to_owned(),
        source,
    };
    let mut file = std::fs::File::create(path).map_err(io)?;
    for b in blocks {
        file.write_all(bytemuck::cast_slice(b)).map_err(io)?;
    }
    Ok(())
}

/// Prints the stage table, then each stage's share of its ceiling and the cores' bound.
pub fn print(rows: &[StageRow]) {
    if rows.is_empty() {
        return;
    }
    println!("\nstreamed eval, file to file (page cache), by stage, M tuples/s:");
    println!(
        "  {:<26} {:<11} {:>9} {:>7} {:>7} {:>7} {:>7} {:>8} {:>7} {:>7} {:>7}  {:<7} {:>6}",
        "backend",
        "scenario",
        "tuples",
        "read",
        "engine",
        "upload",
        "kernel",
        "readback",
        "write",
        "cores",
        "e2e",
        "slowest",
        "ratio"
    );
    let m = |x: f64| format!("{:.1}", x / 1e6);
    let o = |x: Option<f64>| x.map_or("-".to_string(), m);
    for r in rows {
        println!(
            "  {:<26} {:<11} {:>9} {:>7} {:>7} {:>7} {:>7} {:>8} {:>7} {:>7} {:>7}  {:<7} {:>5.2}×",
            short(&r.backend),
            r.scenario,
            r.tuples,
            m(r.read),
            m(r.engine),
            o(r.upload),
            o(r.kernel),
            o(r.readback),
            m(r.write),
            m(r.cores_bound),
            m(r.end_to_end),
            r.slowest,
            r.ratio
        );
    }
    println!(
        "\neach stage against its ceiling (M tuples/s: page-cache copy for read, which the mapped read skips and may pass, host→device and device→host transfers for upload and readback, write(2) to the page cache for write), and CPU ns a tuple:"
    );
    println!(
        "  {:<26} {:<11} {:>9} {:>7} {:>9} {:>7} {:>9} {:>7} {:>9} {:>7} {:>13}",
        "backend",
        "scenario",
        "read/ceil",
        "share",
        "upl/ceil",
        "share",
        "rdbk/ceil",
        "share",
        "write/ceil",
        "share",
        "cpu ns r/e/w"
    );
    let pair = |x: f64, c: f64| format!("{}/{}", m(x), m(c));
    let share = |x: f64, c: f64| format!("{:.2}", x / c.max(1e-12));
    for r in rows {
        let opt = |x: Option<f64>, c: Option<f64>| match (x, c) {
            (Some(x), Some(c)) => (pair(x, c), share(x, c)),
            _ => ("-".into(), "-".into()),
        };
        let (up, ups) = opt(r.upload, r.upload_ceiling);
        let (rb, rbs) = opt(r.readback, r.readback_ceiling);
        let ns = r
            .cpu_s_per_tuple
            .map(|s| format!("{:.1}", s * 1e9))
            .join("/");
        println!(
            "  {:<26} {:<11} {:>9} {:>7} {:>9} {:>7} {:>9} {:>7} {:>9} {:>7} {:>13}",
            short(&r.backend),
            r.scenario,
            pair(r.read, r.read_ceiling),
            share(r.read, r.read_ceiling),
            up,
            ups,
            rb,
            rbs,
            pair(r.write, r.write_ceiling),
            share(r.write, r.write_ceiling),
            ns
        );
        if let Some(l) = r.link {
            println!(
                "  {:<26} host memcpy into / out of mapped memory ({} thread(s), as eval copies): {:.1} / {:.1} GB/s; transfers host→device / device→host: {:.1} / {:.1} GB/s",
                "",
                l.copy_threads,
                l.host_to_mapped / 1e9,
                l.mapped_to_host / 1e9,
                l.host_to_device / 1e9,
                l.device_to_host / 1e9
            );
        }
    }
    println!(
        "  (cores: {} ÷ the summed CPU seconds a tuple of read, engine and write — the bound when the stages share the cores; ratio: e2e over the lower of it and the slowest stage)",
        rows[0].cores
    );
}

/// An engine's name cut to the table's column (the device's full name is in the JSON).
fn short(name: &str) -> String {
    name.chars().take(26).collect()
}
