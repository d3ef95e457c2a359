//! The one evaluation interface: the CPU reference and the Vulkan evaluator both implement
//! [`Backend`], so tests, tables and benchmarks take any backend.

use crate::batch::columns::ColumnBatch;
use crate::batch::{Batch, LocalBatch};
use crate::directions::{ImportanceJob, SliceGrid};
use crate::error::Result;
use crate::material::Material;

/// What the caller wants back besides the BRDF.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Request {
    /// Also return the terms D, G, F_r, F_g, F_b, K per tuple.
    pub terms: bool,
}

/// One kind of batch a caller is about to evaluate ([`Backend::prepare_kernels`]).
#[derive(Debug, Clone, Copy)]
pub struct KernelPlan<'a> {
    /// The materials the batch uses (every one of them).
    pub materials: &'a [crate::material::Material],
    /// The [`Backend::share_kernels`] hint in force when it runs (empty: none).
    pub shared: &'a [crate::material::Material],
    /// Whether its rows carry tangents.
    pub tangents: bool,
    /// What it asks for.
    pub request: Request,
}

/// Tuple counts of one evaluation.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    /// Tuples in the batch.
    pub tuples: u64,
    /// Invalid tuples (zero or non-finite L, V, N, or a bad tangent for an anisotropic
    /// material): their outputs are 0 (FORMULAS.md §1).
    pub invalid: u64,
    /// Valid tuples with `cos_i ≤ 0` or `cos_o ≤ 0`: their outputs are 0.
    pub below_horizon: u64,
    /// Valid tuples with an output whose exact value exceeds the largest finite float32
    /// (`f32::MAX`): that output is `f32::MAX` (FORMULAS.md §1, "Overflow"). Every output
    /// the evaluation computes counts (the three BRDF channels and the terms D, G, F, K),
    /// whether or not the terms were requested, so the count does not depend on the
    /// request.
    pub saturated: u64,
    /// Row of the first invalid tuple, if any.
    pub first_invalid: Option<u64>,
}

impl Counts {
    /// Adds the invalid, below-horizon and saturated counts of another part of the batch (a chunk or a
    /// thread's share); the first invalid row is the smaller of the two. `tuples` is left
    /// to the caller, who knows the batch.
    pub fn absorb(&mut self, part: &Counts) {
        self.invalid += part.invalid;
        self.below_horizon += part.below_horizon;
        self.saturated += part.saturated;
        self.first_invalid = match (self.first_invalid, part.first_invalid) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
    }
}

/// Number of term columns: D, G, F_r, F_g, F_b, K.
pub const TERM_COLUMNS: usize = 6;

/// The result of evaluating a batch.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Output {
    /// `n × 3` RGB BRDF values in 1/sr (no cosine), row-major.
    pub brdf: Vec<f32>,
    /// `n × 6` terms (D, G, F_r, F_g, F_b, K) when requested.
    pub terms: Option<Vec<f32>>,
    /// Invalid / below-horizon / saturated counts.
    pub counts: Counts,
}

impl Output {
    /// All-zero outputs for `n` tuples (terms too when `terms`), `counts.tuples = n`: what a
    /// backend fills in.
    pub fn zeroed(n: usize, terms: bool) -> Output {
        Output {
            brdf: vec![0.0; n * 3],
            terms: terms.then(|| vec![0.0; n * TERM_COLUMNS]),
            counts: Counts {
                tuples: n as u64,
                ..Counts::default()
            },
        }
    }
}

/// Rows of a local-frame batch expanded to 10-column rows at a time by the default
/// [`Backend::evaluate_local_into`]: large enough to keep a device busy, small enough that
/// the expansion (40 bytes a row) stays a fraction of the batch's own memory.
pub const LOCAL_EXPAND_ROWS: usize = 1 << 18;

/// Rows of a [`ColumnBatch`] gathered into rows at a time by the default
/// [`Backend::evaluate_columns_into`], 10–13 MiB: 2^20 made lavapipe's calls 1.5× slower
/// (python_host.py, 4·10^6 rows).
pub const COLUMNS_GATHER_ROWS: usize = 1 << 18;

/// An evaluator of BRDF batches.
pub trait Backend {
    /// A short human-readable name (e.g. `cpu-reference`, `vulkan: llvmpipe`).
    fn name(&self) -> String;

    /// Evaluates every tuple of `batch` with the material table `materials` (which the
    /// batch's material column indexes).
    fn evaluate(
        &mut self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
    ) -> Result<Output>;

    /// [`Backend::evaluate`] into `out`, whose buffers an engine may reuse: a caller that
    /// evaluates batch after batch (the streaming path, a benchmark) hands back the previous
    /// output and saves allocating and zero-filling fresh memory for each. `out`'s previous
    /// contents do not matter; afterwards it holds exactly what `evaluate` would return.
    /// The default calls `evaluate`.
    fn evaluate_into(
        &mut self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
        out: &mut Output,
    ) -> Result<()> {
        *out = self.evaluate(batch, materials, request)?;
        Ok(())
    }

    /// Evaluates a local-frame batch (`Lx Ly Lz Vx Vy Vz`, N = +z, one material) into
    /// `out` (as [`Backend::evaluate_into`]); the result equals that of the 10-column rows
    /// with N = (0, 0, 1). The default expands [`LOCAL_EXPAND_ROWS`] rows at a time into
    /// ordinary rows and evaluates those; an engine that reads the local form directly
    /// overrides it.
    fn evaluate_local_into(
        &mut self,
        batch: &LocalBatch,
        materials: &[Material],
        request: &Request,
        out: &mut Output,
    ) -> Result<()> {
        evaluate_in_parts(
            self,
            batch.len(),
            LOCAL_EXPAND_ROWS,
            |range, _| batch.rows(range),
            materials,
            request,
            out,
        )
    }

    /// Evaluates a batch given as columns ([`ColumnBatch`]) into `out` (as
    /// [`Backend::evaluate_into`]); the result equals that of the same rows given as one
    /// array. The default gathers [`COLUMNS_GATHER_ROWS`] rows at a time and evaluates
    /// those; an engine that reads columns overrides it.
    fn evaluate_columns_into(
        &mut self,
        batch: &ColumnBatch,
        materials: &[Material],
        request: &Request,
        out: &mut Output,
    ) -> Result<()> {
        evaluate_in_parts(
            self,
            batch.len(),
            COLUMNS_GATHER_ROWS,
            |range, buffer| batch.rows(range, buffer),
            materials,
            request,
            out,
        )
    }

    /// Whether this is the f64 reference, the judge: a spectral evaluation then takes the
    /// triplet way, the RGB evaluations of the materials at each wavelength, so that it
    /// judges the engines' factored way independently ([`crate::spectral_eval`]).
    fn is_reference(&self) -> bool {
        false
    }

    /// Gives the backend a cancellation token: [`Backend::evaluate`] and the table paths
    /// check it between chunks and return [`crate::Error::Cancelled`] once it is set. The
    /// default ignores it (an engine that never checks still finishes correctly).
    fn set_cancel(&mut self, _cancel: crate::cancel::Cancel) {}

    /// A hint: the next batches draw their materials from `materials` (empty: no hint). An
    /// engine that compiles a kernel per set of features may then compile one for all of
    /// them and share it, where the caller runs many small related batches (`check`'s
    /// combinations); each batch still evaluates only its own materials. The default
    /// ignores it.
    fn share_kernels(&mut self, _materials: &[crate::material::Material]) {}

    /// A hint: batches like each of `plans` follow. An engine that compiles a kernel per
    /// set of features may compile all of them now, several at once (`check` on a fresh
    /// machine spends most of its time compiling). An error is one a batch of that plan
    /// would have met; the default does nothing.
    fn prepare_kernels(&mut self, _plans: &[KernelPlan<'_>]) -> crate::error::Result<()> {
        Ok(())
    }

    /// Single-thread copies of this engine, one a core, for [`crate::stream::evaluate`]:
    /// each reads, checks, evaluates and writes its own slices of the batch, so a slice
    /// stays in its core's cache from the file to the output and no stage waits on
    /// another's thread. `None` (the default) for an engine the stream drives as one
    /// (a device, whose host threads feed it). A copy must give the same bits as the
    /// engine (every engine evaluates tuple by tuple).
    fn stream_workers(&self) -> Option<Vec<Box<dyn Backend + Send>>> {
        None
    }

    /// A stream of chunks of a batch of `total_rows` rows over `materials`
    /// ([`OverlappedStream`]). An engine that can keep several chunks in flight (a device:
    /// it computes one chunk while the host copies the next in and the last out)
    /// overrides it; the default evaluates each chunk when it is submitted, by
    /// [`Backend::evaluate_into`] or [`Backend::evaluate_local_into`]. An error is one that
    /// setting up the first chunk would have met (a device without f64 refusing measured
    /// materials, a material table over the device's limits).
    fn overlapped<'a>(
        &'a mut self,
        materials: &'a [Material],
        request: Request,
        _total_rows: u64,
    ) -> Result<Box<dyn OverlappedStream + 'a>> {
        Ok(Box::new(CallByCall {
            backend: self,
            materials,
            request,
        }))
    }

    /// The engine's own direction generators, if it has them ([`GeneratedDirections`]):
    /// the tables then send a material and a grid or sampling plan instead of tuples. The
    /// default is none, and the tables build the tuples on the host.
    fn generated_directions(&mut self) -> Option<&mut dyn GeneratedDirections> {
        None
    }
}

/// One chunk of a stream, as [`OverlappedStream::submit`] takes it.
#[derive(Clone, Copy)]
pub enum StreamChunk<'a> {
    /// Rows of 10 or 13 columns.
    Rows(&'a Batch<'a>),
    /// The local-frame form (N = +z, one material).
    Local(&'a LocalBatch),
}

impl StreamChunk<'_> {
    /// Rows in the chunk.
    pub fn len(&self) -> usize {
        match self {
            StreamChunk::Rows(b) => b.len(),
            StreamChunk::Local(b) => b.len(),
        }
    }

    /// Whether the chunk has no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A stream of chunks ([`Backend::overlapped`]): the chunks' outputs come back in
/// submission order, each exactly what [`Backend::evaluate_into`] (or
/// [`Backend::evaluate_local_into`]) gives for that chunk alone, its counts' first invalid
/// row counted from the chunk's first row. Dropping it with chunks in flight waits for the
/// device and discards them.
pub trait OverlappedStream {
    /// The most rows one chunk may have (a device's chunk for its memory budget); a larger
    /// chunk is refused with an error.
    fn max_chunk_rows(&self) -> usize;

    /// Starts evaluating `chunk` into `out` (its previous contents do not matter); the
    /// chunk's rows are copied or consumed before this returns, so the caller may reuse
    /// its buffers. `first_row`, the chunk's place in the batch, names it in errors.
    /// Returns the oldest chunk's output when this call completed it: an engine with
    /// every slot in flight completes the oldest first; one without overlap, this chunk.
    fn submit(
        &mut self,
        chunk: StreamChunk<'_>,
        first_row: u64,
        out: Output,
    ) -> Result<Option<Output>>;

    /// Completes the oldest chunk in flight and returns its output; `None` when none is.
    fn finish_oldest(&mut self) -> Result<Option<Output>>;
}

/// [`Backend::overlapped`]'s default: each chunk evaluated when it is submitted.
struct CallByCall<'a, B: Backend + ?Sized> {
    backend: &'a mut B,
    materials: &'a [Material],
    request: Request,
}

impl<B: Backend + ?Sized> OverlappedStream for CallByCall<'_, B> {
    fn max_chunk_rows(&self) -> usize {
        usize::MAX
    }

    fn submit(
        &mut self,
        chunk: StreamChunk<'_>,
        _first_row: u64,
        mut out: Output,
    ) -> Result<Option<Output>> {
        match chunk {
            StreamChunk::Rows(b) => {
                self.backend
                    .evaluate_into(b, self.materials, &self.request, &mut out)?
            }
            StreamChunk::Local(b) => {
                self.backend
                    .evaluate_local_into(b, self.materials, &self.request, &mut out)?
            }
        }
        Ok(Some(out))
    }

    fn finish_oldest(&mut self) -> Result<Option<Output>> {
        Ok(None) // `submit` returned every chunk's output
    }
}

/// The default forms' common loop: `n` rows evaluated `part` at a time as ordinary rows,
/// which `rows` makes for a range of row indices (given the previous part's allocation
/// to reuse), their outputs and counts joined into `out` as one evaluation's (the first
/// invalid row counted from the first part's first row).
#[allow(clippy::too_many_arguments)]
fn evaluate_in_parts<B: Backend + ?Sized>(
    backend: &mut B,
    n: usize,
    part: usize,
    mut rows: impl FnMut(std::ops::Range<usize>, Vec<f32>) -> Batch<'static>,
    materials: &[Material],
    request: &Request,
    out: &mut Output,
) -> Result<()> {
    out.brdf.clear();
    out.brdf.reserve(3 * n);
    out.terms = request.terms.then(|| out.terms.take().unwrap_or_default());
    if let Some(t) = out.terms.as_mut() {
        t.clear();
        t.reserve(TERM_COLUMNS * n);
    }
    out.counts = Counts {
        tuples: n as u64,
        ..Counts::default()
    };
    let mut evaluated = Output::default();
    let mut buffer = Vec::new();
    let mut start = 0;
    while start < n {
        let end = n.min(start + part);
        let batch = rows(start..end, buffer);
        backend.evaluate_into(&batch, materials, request, &mut evaluated)?;
        buffer = batch.into_data();
        out.brdf.extend_from_slice(&evaluated.brdf);
        if let (Some(t), Some(p)) = (out.terms.as_mut(), evaluated.terms.as_ref()) {
            t.extend_from_slice(p);
        }
        let mut c = evaluated.counts;
        c.first_invalid = c.first_invalid.map(|r| r + start as u64);
        out.counts.absorb(&c);
        start = end;
    }
    Ok(())
}

/// Tables whose directions an engine makes itself (the Vulkan kernel does, on the device):
/// where the directions come from is its own concept beside [`Backend::evaluate`]'s batch
/// of tuples ([`crate::directions`] holds the grids and sampling plans).
pub trait GeneratedDirections {
    /// The half/difference slice `grid` of `material` (row-major texels, θ_h fastest)
    /// with the directions made by the engine, or `None` when it has no such path for this
    /// grid: the caller then builds the tuples ([`crate::table::slice::compute`] does).
    fn half_diff_slice(
        &mut self,
        material: &Material,
        grid: SliceGrid,
        request: &Request,
    ) -> Option<Result<Output>>;

    /// For each point of `job`, `(1/N) Σ x` and `(1/N) Σ x (1 − c)⁵` over its N samples,
    /// `x = f cos_i / pdf(l)`, with the sample directions made by the engine; or `None`
    /// when it has no such path for this job (the caller then sends the samples as tuples,
    /// as [`crate::table::albedo::integrate`] does). `progress` is called with the number
    /// of samples done since its last call.
    fn importance_sums(
        &mut self,
        job: &ImportanceJob,
        progress: &mut dyn FnMut(u64),
    ) -> Option<Result<Vec<[f64; 2]>>>;
}
