//! The streamed path of an engine driven as one (a device): three stages overlap, a
//! reader thread, the engine on the calling thread, and a writer thread (see
//! [`evaluate`]).

use super::job::{NpyOut, Setup, StreamJob, StreamSummary};
use crate::atomic::Staged;
use crate::backend::{Backend, Output, OverlappedStream, Request, StreamChunk, TERM_COLUMNS};
use crate::batch::rows::{MappedRows, NpyRows, RowsChunk};
use crate::batch::{check_tangent_rows, Batch, LocalBatch};
use crate::cancel::Cancel;
use crate::error::Result;
use crate::material::Material;

/// Evaluates the rows `setup.part` of `rows` on `backend` chunk by chunk, into staged
/// outputs (`None` when `strict` found an invalid tuple: nothing is to be written).
pub(super) fn evaluate(
    job: &StreamJob,
    setup: &Setup,
    mut rows: NpyRows,
    backend: &mut dyn Backend,
    cancel: &Cancel,
    mut progress: impl FnMut(u64, u64),
) -> Result<(StreamSummary, Option<Vec<Staged>>)> {
    let Setup {
        local,
        ref part,
        chunk,
        out_columns,
        ref request,
    } = *setup;
    let n = part.end - part.start;
    let mut brdf = NpyOut::start(job.output, n, out_columns, cancel)?;
    let mut terms = match job.terms {
        Some(path) => Some(NpyOut::start(path, n, TERM_COLUMNS, cancel)?),
        None => None,
    };
    let mut spike = match job.spike {
        Some(path) => Some(NpyOut::start(path, n, 3, cancel)?),
        None => None,
    };
    // A spectral job evaluates each chunk several times (its basis or wavelength
    // materials), call by call; every other job streams its chunks through the engine's
    // overlapped form, whose chunks may be smaller (a device's slot).
    let mut engine = match job.spectral {
        None => Engine::Stream(backend.overlapped(job.materials, *request, n)?),
        Some(_) => Engine::Calls(backend),
    };
    let chunk = match &engine {
        Engine::Stream(stream) => chunk.min(stream.max_chunk_rows()),
        Engine::Calls(_) => chunk,
    };
    let mut summary = StreamSummary {
        chunk_rows: chunk,
        ..StreamSummary::default()
    };
    summary.counts.tuples = n;
    // Three stages overlap: a reader thread reads chunk k+1 while the engine evaluates chunk
    // k on this thread and a writer thread writes chunk k-1. One chunk waits in each
    // channel, so at most about five are alive at once (`chunk_rows` divides the budget).
    // The writer hands each written output back, and the engine evaluates into it again:
    // a few buffers serve the whole batch, faulted in and zeroed once.
    let (read_tx, read_rx) = std::sync::mpsc::sync_channel::<Result<(u64, Chunk, f64)>>(1);
    let (write_tx, write_rx) = std::sync::mpsc::sync_channel::<(Output, Vec<f32>)>(1);
    let (recycle_tx, recycle_rx) = std::sync::mpsc::channel::<Output>();
    // Spent input buffers go back to the reader, which reads the next chunk into one.
    let (spent_tx, spent_rx) = std::sync::mpsc::sync_channel::<Vec<f32>>(2);
    let (written, evaluated) = std::thread::scope(|scope| {
        let reader = scope.spawn(move || loop {
            let t = std::time::Instant::now();
            let next = match local {
                Some(m) => rows
                    .next_local(chunk, m, job.materials)
                    .map(|c| c.map(|(first, b)| (first, Chunk::Local(b)))),
                // Mapped where the page cache holds the rows (the engine's copy into its
                // staging memory is then the only one), else read into a spare buffer.
                None => rows
                    .next_in_place(
                        chunk,
                        spent_rx.try_recv().unwrap_or_default(),
                        |batch, first| {
                            check_tangent_rows(
                                batch.as_slice(),
                                batch.columns(),
                                first,
                                job.materials,
                                job.input,
                            )
                        },
                    )
                    .map(|c| {
                        c.map(|(first, c)| match c {
                            RowsChunk::Mapped(m) => (first, Chunk::Mapped(m)),
                            RowsChunk::Read(b) => (first, Chunk::Rows(b)),
                        })
                    }),
            };
            let message = match next {
                Ok(None) => break,
                Ok(Some((first, batch))) => Ok((first, batch, t.elapsed().as_secs_f64())),
                Err(e) => Err(e),
            };
            let failed = message.is_err();
            if read_tx.send(message).is_err() || failed {
                break; // the evaluator stopped, or this was the error it will report
            }
        });
        let writer = scope.spawn(
            move || -> Result<(NpyOut, Option<NpyOut>, Option<NpyOut>, f64)> {
                let mut write_s = 0.0;
                for (out, spikes) in write_rx {
                    let t = std::time::Instant::now();
                    brdf.rows(&out.brdf)?;
                    if let (Some(w), Some(v)) = (terms.as_mut(), out.terms.as_ref()) {
                        w.rows(v)?;
                    }
                    if let Some(w) = spike.as_mut() {
                        w.rows(&spikes)?;
                    }
                    write_s += t.elapsed().as_secs_f64();
                    // The evaluator may have stopped; then the buffer is simply dropped.
                    let _ = recycle_tx.send(out);
                }
                Ok((brdf, terms, spike, write_s))
            },
        );
        let evaluated = (|| -> Result<()> {
            // Chunks the engine holds: their first row, rows and spike weights, oldest first.
            let mut held = std::collections::VecDeque::new();
            let mut done = |out: Output, summary: &mut StreamSummary, held: &mut Held| {
                let (first, len, spikes) = held.pop_front().expect("one held chunk an output");
                let mut counted = out.counts;
                counted.first_invalid = counted.first_invalid.map(|r| r + first);
                summary.counts.absorb(&counted);
                summary.chunks += 1;
                progress(first + len as u64 - part.start, n);
                write_tx.send((out, spikes)).is_ok() // false: the writer failed (reported below)
            };
            for message in read_rx {
                cancel.check()?;
                let (first, batch, read_s) = message?;
                summary.read_s += read_s;
                let t = std::time::Instant::now();
                let out = recycle_rx.try_recv().unwrap_or_default();
                // The spike's weights, when asked for: the host's f64 form (cheap next to
                // the BRDF's series), in the same chunk, so all outputs advance together.
                let spikes = match job.spike.is_some() {
                    false => Vec::new(),
                    true => batch.with_rows(|rows| spike_rows(rows, job.materials)),
                };
                held.push_back((first, batch.len(), spikes));
                let finished = batch.with_rows(|rows| match &mut engine {
                    Engine::Stream(stream) => stream.submit(rows, first, out),
                    Engine::Calls(backend) => {
                        let mut out = out;
                        evaluate_chunk(rows, &mut **backend, job, request, &mut out)?;
                        Ok(Some(out))
                    }
                })?;
                // A mapped chunk's page lost while the engine read it read as zeros.
                if let Chunk::Mapped(m) = &batch {
                    m.lost_page()?;
                }
                summary.eval_s += t.elapsed().as_secs_f64();
                if let Chunk::Rows(b) = batch {
                    let _ = spent_tx.try_send(b.into_data()); // full: the reader has spares
                }
                if let Some(out) = finished {
                    if !done(out, &mut summary, &mut held) {
                        return Ok(());
                    }
                }
            }
            if let Engine::Stream(stream) = &mut engine {
                loop {
                    cancel.check()?;
                    let t = std::time::Instant::now();
                    let Some(out) = stream.finish_oldest()? else {
                        break;
                    };
                    summary.eval_s += t.elapsed().as_secs_f64();
                    if !done(out, &mut summary, &mut held) {
                        break;
                    }
                }
            }
            Ok(())
        })();
        drop(write_tx);
        let written = writer.join().expect("the writer thread does not panic");
        reader.join().expect("the reader thread does not panic");
        (written, evaluated)
    });
    evaluated?;
    let (brdf, terms, spike, write_s) = written?;
    summary.write_s = write_s;
    if job.strict && summary.counts.invalid > 0 {
        return Ok((summary, None)); // the writers drop: their temporary files go
    }
    let mut staged = vec![brdf.finish()?];
    if let Some(w) = terms {
        staged.push(w.finish()?);
    }
    if let Some(w) = spike {
        staged.push(w.finish()?);
    }
    Ok((summary, Some(staged)))
}

/// What evaluates the chunks: the engine's stream, or (a spectral job) the engine itself.
enum Engine<'a> {
    Stream(Box<dyn OverlappedStream + 'a>),
    Calls(&'a mut dyn Backend),
}

/// The chunks an engine holds, oldest first: first row, rows, spike weights.
type Held = std::collections::VecDeque<(u64, usize, Vec<f32>)>;

/// One chunk as read: rows (copied or mapped), or the local-frame form.
enum Chunk {
    Rows(Batch<'static>),
    Mapped(MappedRows),
    Local(LocalBatch),
}

impl Chunk {
    /// Rows in the chunk.
    fn len(&self) -> usize {
        match self {
            Chunk::Rows(b) => b.len(),
            Chunk::Mapped(m) => m.len(),
            Chunk::Local(b) => b.len(),
        }
    }

    /// `use_rows` on the chunk as an engine's stream takes it.
    fn with_rows<T>(&self, use_rows: impl FnOnce(StreamChunk<'_>) -> T) -> T {
        match self {
            Chunk::Rows(b) => use_rows(StreamChunk::Rows(b)),
            Chunk::Mapped(m) => use_rows(StreamChunk::Rows(&m.batch())),
            Chunk::Local(b) => use_rows(StreamChunk::Local(b)),
        }
    }
}

/// `rows`' outputs into `out` on `backend` with `materials`.
fn evaluate_into(
    rows: StreamChunk<'_>,
    backend: &mut dyn Backend,
    materials: &[Material],
    request: &Request,
    out: &mut Output,
) -> Result<()> {
    match rows {
        StreamChunk::Rows(b) => backend.evaluate_into(b, materials, request, out),
        StreamChunk::Local(b) => backend.evaluate_local_into(b, materials, request, out),
    }
}

/// The job's outputs of `rows` into `out`: the materials' BRDF, or the spectral job's
/// (its evaluations at the basis or wavelength materials, combined per row).
fn evaluate_chunk(
    rows: StreamChunk<'_>,
    backend: &mut dyn Backend,
    job: &StreamJob,
    request: &Request,
    out: &mut Output,
) -> Result<()> {
    let Some(s) = job.spectral else {
        return evaluate_into(rows, backend, job.materials, request, out);
    };
    type Row<'a> = Box<dyn Fn(usize) -> ([f32; 3], [f32; 3], usize) + Sync + 'a>;
    let row: Row = match rows {
        StreamChunk::Rows(b) => Box::new(crate::spectral_eval::batch_rows(b)),
        StreamChunk::Local(b) => Box::new(crate::spectral_eval::local_rows(b)),
    };
    let triplets = backend.is_reference();
    s.evaluate_with(
        rows.len(),
        triplets,
        &row,
        |m, o| evaluate_into(rows, backend, m, request, o),
        out,
    )
}

/// `ρ_s` of each row of `rows` ([`crate::reference::htsg_spike_rows`]); every material is
/// HTSG's (`spike_allowed` checked it before any work), so no row can fail.
fn spike_rows(rows: StreamChunk<'_>, materials: &[Material]) -> Vec<f32> {
    let weights = match rows {
        StreamChunk::Rows(b) => crate::reference::htsg_spike_rows(b, materials),
        StreamChunk::Local(b) => crate::reference::htsg_spike_rows(&b.rows(0..b.len()), materials),
    };
    weights.unwrap_or_default()
}
