//! [`VulkanStream`]: the Vulkan backend's [`OverlappedStream`] — the chunks of a stream go
//! into the ring of [`FRAMES_IN_FLIGHT`] slots one after another, across calls, so the
//! device evaluates chunk k while the host copies chunk k + 1 in and chunk k − 2 out.
//! [`Backend::evaluate_into`](crate::backend::Backend::evaluate_into) on one chunk at a
//! time waits for its own chunk before it returns, and left the device idle while the host
//! copied (on the H200, end to end ran at 1/80 of the kernel).
//!
//! Each chunk is exactly one slot's dispatch, evaluated as a call on that chunk alone
//! would: the same pipeline choice (the fold decided on the chunk's rows), the same
//! grouping by material, the same counts.

use super::state::{Pending, VulkanBackend, FRAMES_IN_FLIGHT};
use crate::backend::{Counts, Output, OverlappedStream, Request, StreamChunk, TERM_COLUMNS};
use crate::batch::Batch;
use crate::error::{Error, FailedChunk, Result};
use crate::features::FeatureSet;
use crate::gpu::layout::{gpu_materials, GpuMaterial, PushConstants};
use crate::material::Material;
use std::collections::VecDeque;

/// A chunk in flight: its slot, where its outputs go, and where it sits in the stream.
struct InFlight {
    slot: usize,
    out: Output,
    index: u64,
    rows: std::ops::Range<u64>,
}

/// See the module docs. Created by [`VulkanBackend`]'s
/// [`Backend::overlapped`](crate::backend::Backend::overlapped).
pub(super) struct VulkanStream<'a> {
    backend: &'a mut VulkanBackend,
    materials: &'a [Material],
    gpu: Vec<GpuMaterial>,
    request: Request,
    total_rows: u64,
    /// Rows a slot holds (the backend's chunk for this material table and budget).
    chunk: usize,
    /// Chunks submitted so far (the next one's index).
    submitted: u64,
    /// Rows of the stream's first chunk: every chunk's but the last, so the count of chunks
    /// errors give.
    stream_chunk: u64,
    in_flight: VecDeque<InFlight>,
    /// Slots the stream uses in turn: one more than the chunks left in flight when
    /// `submit` returns
    /// ([`VulkanOptions::chunks_in_flight`](crate::gpu::VulkanOptions::chunks_in_flight),
    /// at most `FRAMES_IN_FLIGHT − 1`), so the next chunk always finds its slot free and a
    /// stream that keeps nothing in flight reuses one slot's buffers.
    ring: usize,
}

impl<'a> VulkanStream<'a> {
    /// Uploads what every chunk reads (MERL tables, the material table) and sizes the
    /// chunks. Precondition: nothing is pending (true between calls).
    pub(super) fn new(
        backend: &'a mut VulkanBackend,
        materials: &'a [Material],
        request: Request,
        total_rows: u64,
    ) -> Result<VulkanStream<'a>> {
        let chunk = backend.chunk_tuples(materials.len())?;
        let depth = match backend.options.chunks_in_flight {
            Some(k) => k.min(FRAMES_IN_FLIGHT - 1),
            None if backend.is_cpu_device() => 0,
            None => FRAMES_IN_FLIGHT - 1,
        };
        backend.upload_measured(materials)?;
        let gpu = gpu_materials(materials);
        backend.upload_materials(&gpu)?;
        Ok(VulkanStream {
            backend,
            materials,
            gpu,
            request,
            total_rows,
            chunk,
            submitted: 0,
            stream_chunk: chunk as u64,
            in_flight: VecDeque::with_capacity(FRAMES_IN_FLIGHT),
            ring: depth + 1,
        })
    }

    /// Where chunk `index` (rows `rows`) failed, for its error.
    fn failed(&self, index: u64, rows: std::ops::Range<u64>) -> FailedChunk {
        FailedChunk {
            index,
            count: self
                .total_rows
                .div_ceil(self.stream_chunk.max(1))
                .max(index + 1),
            rows,
            max_gpu_memory: self.backend.options.max_gpu_memory,
        }
    }

    /// Loads `batch` into the next slot and submits its dispatch.
    fn start(&mut self, batch: &Batch, index: u64, rows: std::ops::Range<u64>) -> Result<()> {
        let s = (index % self.ring as u64) as usize;
        let b = &mut *self.backend;
        let features = b.batch_features(batch, self.materials, &self.request);
        b.last_features = Some(features);
        // The fold is decided on the chunk's rows, as a call on the chunk alone decides it:
        // a folded conductor takes F's fitted polynomial, so deciding on the stream's rows
        // would change the bits with the batch's size, and a shard's from the whole run's.
        let pipeline = b.pipeline_for(features, (&self.gpu, self.materials), batch.len())?;
        let per_invocation = b.rows_per_invocation();
        let (len, terms) = (batch.len(), features.contains(FeatureSet::TERMS));
        let material_count = self.materials.len();
        let order = b.load_chunk(
            s,
            batch.as_slice(),
            batch.columns(),
            material_count,
            features.contains(FeatureSet::BUCKETED),
            terms,
        )?;
        let pending = Pending {
            brdf: 0..len * 3,
            terms: terms.then(|| 0..len * TERM_COLUMNS),
            first_row: 0,
            order,
        };
        let push = PushConstants::rows(len as u32, material_count as u32, rows.start as u32);
        b.submit(s, pipeline, push, pending, per_invocation)
    }

    /// Completes the oldest chunk in flight (see [`OverlappedStream::finish_oldest`]).
    fn complete_oldest(&mut self) -> Result<Option<Output>> {
        let Some(mut f) = self.in_flight.pop_front() else {
            return Ok(None);
        };
        match self
            .backend
            .finish_chunk(f.slot, f.index as usize, &mut f.out)
        {
            Ok(()) => Ok(Some(f.out)),
            Err(e) => {
                let chunk = self.failed(f.index, f.rows);
                self.abandon();
                Err(e.in_chunk(chunk))
            }
        }
    }

    /// After an error: waits for the device and forgets every chunk in flight.
    fn abandon(&mut self) {
        self.in_flight.clear();
        self.backend.recover();
    }
}

impl OverlappedStream for VulkanStream<'_> {
    fn max_chunk_rows(&self) -> usize {
        self.chunk
    }

    fn submit(
        &mut self,
        chunk: StreamChunk<'_>,
        first_row: u64,
        mut out: Output,
    ) -> Result<Option<Output>> {
        self.backend.cancel.check()?;
        let len = chunk.len();
        if len > self.chunk {
            return Err(Error::Unsupported(format!(
                "a stream chunk of {len} rows exceeds the device's chunk of {} rows \
                 (OverlappedStream::max_chunk_rows)",
                self.chunk
            )));
        }
        let (index, rows) = (self.submitted, first_row..first_row + len as u64);
        if index == 0 {
            self.stream_chunk = len as u64;
        }
        // The outputs a call on this chunk alone starts from (`Output::zeroed`), reusing
        // `out`'s allocations; every float is overwritten on readback.
        out.brdf.resize(3 * len, 0.0);
        out.terms = self.request.terms.then(|| {
            let mut t = out.terms.take().unwrap_or_default();
            t.resize(TERM_COLUMNS * len, 0.0);
            t
        });
        out.counts = Counts {
            tuples: len as u64,
            ..Counts::default()
        };
        let started = match chunk {
            StreamChunk::Rows(batch) => self.start(batch, index, rows.clone()),
            StreamChunk::Local(local) => self.start(&local.rows(0..len), index, rows.clone()),
        };
        if let Err(e) = started {
            let failed = self.failed(index, rows);
            self.abandon();
            return Err(e.in_chunk(failed));
        }
        self.submitted += 1;
        self.in_flight.push_back(InFlight {
            slot: (index % self.ring as u64) as usize,
            out,
            index,
            rows,
        });
        // The ring's other slots hold the chunks left in flight; with all of them taken,
        // the oldest completes (its slot is the next chunk's).
        if self.in_flight.len() == self.ring {
            return self.complete_oldest();
        }
        Ok(None)
    }

    fn finish_oldest(&mut self) -> Result<Option<Output>> {
        self.complete_oldest()
    }
}

impl Drop for VulkanStream<'_> {
    fn drop(&mut self) {
        // A stream left with chunks in flight (the caller stopped on an error or a cancel):
        // the device may still write the slots' buffers, so wait before they are reused.
        if !self.in_flight.is_empty() {
            self.abandon();
        }
    }
}
