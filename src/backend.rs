//! The one evaluation interface: the CPU reference and the Vulkan evaluator both implement
//! [`Backend`], so tests, tables and benchmarks take any backend.

use crate::batch::Batch;
use crate::error::Result;
use crate::material::Material;

/// What the caller wants back besides the BRDF.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Request {
    /// Also return the terms D, G, F_r, F_g, F_b, K per tuple.
    pub terms: bool,
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

/// A half/difference slice grid (see [`crate::table::slice`]; its `from_half_diff` makes the directions): `width` θ_h columns ×
/// `height` θ_d rows, φ_d = 90°, n = +z, tangent +x.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SliceGrid {
    /// θ_h columns.
    pub width: u32,
    /// θ_d rows.
    pub height: u32,
    /// θ_h = x·π/2 (`true`) or x²·π/2, MERL's spacing (`false`).
    pub linear: bool,
}

impl SliceGrid {
    /// Texels in the grid.
    pub fn texels(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }
}

/// One `(μ, α)` point of an importance-sampled table integral ([`crate::table::albedo`]
/// states the method): its sampling constants, computed in f64 on the host and rounded
/// once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImportancePoint {
    /// The view direction `v` (unit, n = +z).
    pub v: [f32; 3],
    /// `G1(v)` (GGX's visible-normal density).
    pub g1: f32,
    /// GGX: the stretched view's hemisphere frame `t1`, `t2`, `v_h` and `s = (1 + v_h.z)/2`.
    pub frame: [[f32; 3]; 3],
    /// See `frame`.
    pub s: f32,
    /// The roughness α.
    pub alpha: f32,
    /// Index into the job's material table.
    pub material: u32,
}

/// An importance-sampled table integral for [`Backend::importance_sums`].
#[derive(Debug, Clone, Copy)]
pub struct ImportanceJob<'a> {
    /// GGX by its visible normals (`true`) or Beckmann by `D cos_h`.
    pub ggx: bool,
    /// The points.
    pub points: &'a [ImportancePoint],
    /// The materials the points index (F = 1 Cook–Torrance).
    pub materials: &'a [Material],
    /// Hammersley points per `(μ, α)` point.
    pub samples: u32,
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

    /// Gives the backend a cancellation token: [`Backend::evaluate`] and the table paths
    /// check it between chunks and return [`crate::Error::Cancelled`] once it is set. The
    /// default ignores it (an engine that never checks still finishes correctly).
    fn set_cancel(&mut self, _cancel: crate::cancel::Cancel) {}

    /// The half/difference slice `grid` of `material` (row-major texels, θ_h fastest)
    /// with the directions made by the backend itself, or `None` when it has no such path
    /// (or none for this grid): the caller then builds the tuples
    /// ([`crate::table::slice::compute`] does). The Vulkan backend makes them on the device
    /// for grids up to 2²⁴ texels.
    fn half_diff_slice(
        &mut self,
        _material: &Material,
        _grid: SliceGrid,
        _request: &Request,
    ) -> Option<Result<Output>> {
        None
    }

    /// For each point of `job`, `(1/N) Σ x` and `(1/N) Σ x (1 − c)⁵` over its N samples,
    /// `x = f cos_i / pdf(l)`, with the sample directions made by the backend itself; or
    /// `None` when it has no such path (the caller then sends the samples as tuples, as
    /// [`crate::table::albedo::integrate`] does). The Vulkan backend makes them on the
    /// device.
    /// `progress` is called with the number of samples done since its last call.
    fn importance_sums(
        &mut self,
        _job: &ImportanceJob,
        _progress: &mut dyn FnMut(u64),
    ) -> Option<Result<Vec<[f64; 2]>>> {
        None
    }
}
