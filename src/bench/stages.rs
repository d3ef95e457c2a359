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
use crate::batch::rows::NpyRows;
use crate::batch::{write_npy_f32, Batch};
use crate::cancel::Cancel;
use crate::error::Result;
use crate::material::Material;
use crate::stats::median;
use crate::stream::{self, StreamJob};
use std::path::Path;
use std::time::Instant;

/// One engine's stage rates on one scenario (tuples per second; `None` where the engine
/// has no such stage).
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
    /// Reading and checking the `.npy` chunk by chunk.
    pub read: f64,
    /// The engine on chunks in memory (`Backend::evaluate`, outputs included).
    pub engine: f64,
    /// Vulkan: grouping and copying rows into device-visible memory (host time).
    pub upload: Option<f64>,
    /// Vulkan: the kernel alone, from device timestamps (tuples resident on the device).
    pub kernel: Option<f64>,
    /// Vulkan: copying results out of device-visible memory (host time).
    pub readback: Option<f64>,
    /// Writing the outputs, chunk by chunk, to a staged `.npy` renamed at the end.
    pub write: f64,
    /// `vkbrdf eval`'s streamed path, file to file.
    pub end_to_end: f64,
    /// The slowest of read, engine and write (the stages that run in parallel).
    pub slowest: String,
    /// End to end over the slowest stage's rate.
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
    // Warm: the page cache holds the file, the engine has compiled its kernel.
    let chunks = read_all(&input, materials.len(), chunk)?;
    let first = engine
        .backend()
        .evaluate(&chunks[0], materials, &Request::default())?;
    let mut out = first.clone();

    let mut read_s = Vec::new();
    let mut engine_s = Vec::new();
    let mut upload_s = Vec::new();
    let mut readback_s = Vec::new();
    let mut write_s = Vec::new();
    let mut e2e_s = Vec::new();
    let cancel = Cancel::new();
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        drop(read_all(&input, materials.len(), chunk)?);
        read_s.push(t.elapsed().as_secs_f64());

        if let Engine::Vulkan(v) = &mut engine {
            v.reset_host_stages();
        }
        // As the pipeline does it: each chunk into a reused output.
        let t = Instant::now();
        for c in &chunks {
            engine
                .backend()
                .evaluate_into(c, materials, &Request::default(), &mut out)?;
        }
        engine_s.push(t.elapsed().as_secs_f64());
        if let Engine::Vulkan(v) = &engine {
            let s = v.host_stages();
            upload_s.push(s.upload_s);
            readback_s.push(s.readback_s);
        }

        // The write stage writes one evaluated chunk's values for every chunk (the rate
        // does not depend on the values).
        let blocks: Vec<&[f32]> = chunks.iter().map(|c| &first.brdf[..3 * c.len()]).collect();
        let t = Instant::now();
        stream::write_chunks(&output, n as u64, 3, &blocks, &cancel)?;
        write_s.push(t.elapsed().as_secs_f64());

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
        let t = Instant::now();
        stream::evaluate(&job, engine.backend(), &cancel, |_, _| {})?;
        e2e_s.push(t.elapsed().as_secs_f64());
    }
    let kernel = match &mut engine {
        Engine::Vulkan(v) => {
            Some(n as f64 / v.kernel_seconds(batch, materials, &Request::default(), 3)?)
        }
        Engine::Any(_) => None,
    };
    let _ = std::fs::remove_file(&input);
    let _ = std::fs::remove_file(&output);
    let rate = |s: Vec<f64>| n as f64 / median(s).max(1e-12);
    let opt_rate = |s: Vec<f64>| (!s.is_empty()).then(|| rate(s));
    let (read, engine_rate, write) = (rate(read_s), rate(engine_s), rate(write_s));
    let (slowest, slowest_rate) = [("read", read), ("engine", engine_rate), ("write", write)]
        .into_iter()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("three stages");
    let end_to_end = rate(e2e_s);
    Ok(StageRow {
        backend: engine.backend().name(),
        scenario: scenario.to_string(),
        tuples: n,
        chunk_rows: chunk,
        read,
        engine: engine_rate,
        upload: opt_rate(upload_s),
        kernel,
        readback: opt_rate(readback_s),
        write,
        end_to_end,
        slowest: slowest.to_string(),
        ratio: end_to_end / slowest_rate,
    })
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

/// Prints the stage table.
pub fn print(rows: &[StageRow]) {
    if rows.is_empty() {
        return;
    }
    println!("\nstreamed eval, file to file (page cache), by stage, M tuples/s:");
    println!(
        "  {:<26} {:<10} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8}  {:<7} {:>6}",
        "backend",
        "scenario",
        "tuples",
        "read",
        "engine",
        "upload",
        "kernel",
        "readback",
        "write",
        "e2e",
        "slowest",
        "ratio"
    );
    let m = |x: f64| format!("{:.1}", x / 1e6);
    let o = |x: Option<f64>| x.map_or("-".to_string(), m);
    for r in rows {
        println!(
            "  {:<26} {:<10} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8}  {:<7} {:>5.2}×",
            r.backend,
            r.scenario,
            r.tuples,
            m(r.read),
            m(r.engine),
            o(r.upload),
            o(r.kernel),
            o(r.readback),
            m(r.write),
            m(r.end_to_end),
            r.slowest,
            r.ratio
        );
    }
}
