//! The CPU reference: FORMULAS.md evaluated in f64, term by term, written for clarity and
//! exactness rather than speed. It is the judge every other backend is measured against.
//!
//! The submodules follow FORMULAS.md: §1 [`frame`] (inputs, validity, derived quantities),
//! §2–§5 [`terms`] (which term of each family a material names, on the frame: the
//! formulas are the terms' own f64 forms in `crate::terms`), §6 [`models`] (f).

mod evaluation;
pub mod frame;
pub mod models;
pub mod terms;

pub use evaluation::{Evaluation, Status};

use crate::backend::{Backend, Counts, Output, Request, TERM_COLUMNS};
use crate::batch::columns::ColumnBatch;
use crate::batch::{Batch, Tuple};
use crate::cancel::Cancel;
use crate::error::Result;
use crate::material::Material;

/// `x` as an output float32 (FORMULAS.md §1, "Overflow"): beyond the largest finite
/// float32 it is `f32::MAX`. Without the clamp, `as f32` rounds it to +inf.
pub fn to_output_f32(x: f64) -> f32 {
    if x > f64::from(f32::MAX) {
        f32::MAX
    } else {
        x as f32
    }
}

/// Evaluates one tuple given in f64 (any lengths; `t` only read by anisotropic materials).
pub fn evaluate(
    l: [f64; 3],
    v: [f64; 3],
    n: [f64; 3],
    t: Option<[f64; 3]>,
    m: &Material,
) -> Evaluation {
    let Some(frame) = frame::Frame::new(l, v, n, t, m.is_anisotropic()) else {
        return Evaluation::zero(Status::Invalid);
    };
    if frame.cos_i <= 0.0 || frame.cos_o <= 0.0 {
        return Evaluation::zero(Status::BelowHorizon);
    }
    models::evaluate_model(&frame, m)
}

/// The mirror spike's weight `ρ_s` per channel (FORMULAS.md §8) of an HTSG material for
/// one tuple: `None` for any other model; 0 where the tuple is invalid or below the horizon
/// (as its BRDF is). It reads L and N only (`ρ_s` is a function of `θ_i`); V decides the
/// tuple's status like every output's.
pub fn htsg_spike(t: &Tuple, m: &Material) -> Option<crate::material::Rgb> {
    let crate::material::Model::Htsg(p) = &m.model else {
        return None;
    };
    let w = |a: [f32; 3]| a.map(f64::from);
    let Some(fr) = frame::Frame::new(w(t.l), w(t.v), w(t.n), None, false) else {
        return Some([0.0; 3]);
    };
    if fr.cos_i <= 0.0 || fr.cos_o <= 0.0 {
        return Some([0.0; 3]);
    }
    let angles = models::htsg_angles(&fr);
    Some(crate::terms::htsg::spike(p, angles.cos_i, angles.sin_i))
}

/// [`htsg_spike`] of every row of `batch` as float32, row-major `(n, 3)`; the first row
/// whose material is not HTSG's is the error (its index in the batch).
pub fn htsg_spike_rows(
    batch: &crate::batch::Batch,
    materials: &[Material],
) -> Result<Vec<f32>, usize> {
    let mut v = Vec::with_capacity(3 * batch.len());
    for i in 0..batch.len() {
        let t = batch.tuple(i);
        let s = htsg_spike(&t, &materials[t.material]).ok_or(i)?;
        v.extend(s.map(|x| x as f32));
    }
    Ok(v)
}

/// Evaluates one batch tuple (its f32 inputs widened exactly to f64).
pub fn evaluate_tuple(t: &Tuple, m: &Material) -> Evaluation {
    let w = |a: [f32; 3]| a.map(f64::from);
    evaluate(w(t.l), w(t.v), w(t.n), t.t.map(w), m)
}

/// The CPU reference as a [`Backend`]: every tuple through [`evaluate_tuple`], spread over
/// the machine's cores with scoped threads (results are independent of the thread count).
#[derive(Debug, Clone)]
pub struct CpuReference {
    threads: usize,
    cancel: Cancel,
}

impl Default for CpuReference {
    fn default() -> Self {
        Self::new()
    }
}

impl CpuReference {
    /// A reference backend using every available core.
    pub fn new() -> CpuReference {
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        CpuReference {
            threads,
            cancel: Cancel::new(),
        }
    }
}

impl Backend for CpuReference {
    fn name(&self) -> String {
        "cpu-reference (f64)".to_string()
    }

    fn is_reference(&self) -> bool {
        true
    }

    fn set_cancel(&mut self, cancel: Cancel) {
        self.cancel = cancel;
    }

    fn evaluate(
        &mut self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
    ) -> Result<Output> {
        self.evaluate_tuples(batch.len(), |i| batch.tuple(i), materials, request)
    }

    /// Tuple by tuple from the columns, as from rows: no rows are gathered.
    fn evaluate_columns_into(
        &mut self,
        batch: &ColumnBatch,
        materials: &[Material],
        request: &Request,
        out: &mut Output,
    ) -> Result<()> {
        *out = self.evaluate_tuples(batch.len(), |i| batch.tuple(i), materials, request)?;
        Ok(())
    }
}

impl CpuReference {
    /// Tuples `tuple(0..n)` split over the threads (see [`Backend::evaluate`]).
    fn evaluate_tuples(
        &self,
        n: usize,
        tuple: impl Fn(usize) -> Tuple + Sync,
        materials: &[Material],
        request: &Request,
    ) -> Result<Output> {
        let mut brdf = vec![0f32; n * 3];
        let mut terms = if request.terms {
            vec![0f32; n * TERM_COLUMNS]
        } else {
            Vec::new()
        };
        let per_thread = n.div_ceil(self.threads.max(1)).max(1);
        let cancel = &self.cancel;
        let counts: Vec<Counts> = std::thread::scope(|s| {
            let term_chunks: Vec<Option<&mut [f32]>> = if request.terms {
                terms
                    .chunks_mut(per_thread * TERM_COLUMNS)
                    .map(Some)
                    .collect()
            } else {
                (0..n.div_ceil(per_thread)).map(|_| None).collect()
            };
            let handles: Vec<_> = brdf
                .chunks_mut(per_thread * 3)
                .zip(term_chunks)
                .enumerate()
                .map(|(c, (out, mut tout))| {
                    let tuple = &tuple;
                    s.spawn(move || {
                        let start = c * per_thread;
                        let mut counts = Counts::default();
                        for (j, rgb) in out.chunks_exact_mut(3).enumerate() {
                            if j % 4096 == 0 && cancel.is_cancelled() {
                                break;
                            }
                            let i = start + j;
                            let tuple = tuple(i);
                            let e = evaluate_tuple(&tuple, &materials[tuple.material]);
                            match e.status {
                                Status::Invalid => {
                                    counts.invalid += 1;
                                    counts.first_invalid.get_or_insert(i as u64);
                                }
                                Status::BelowHorizon => counts.below_horizon += 1,
                                Status::Valid => counts.saturated += u64::from(e.saturated()),
                            }
                            for (dst, src) in rgb.iter_mut().zip(e.brdf) {
                                *dst = to_output_f32(src);
                            }
                            if let Some(t) = tout.as_deref_mut() {
                                for (dst, src) in t[j * TERM_COLUMNS..(j + 1) * TERM_COLUMNS]
                                    .iter_mut()
                                    .zip(e.terms())
                                {
                                    *dst = to_output_f32(src);
                                }
                            }
                        }
                        counts
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("reference worker panicked"))
                .collect()
        });
        self.cancel.check()?;
        let mut total = Counts {
            tuples: n as u64,
            ..Counts::default()
        };
        for c in &counts {
            total.absorb(c);
        }
        Ok(Output {
            brdf,
            terms: request.terms.then_some(terms),
            counts: total,
        })
    }
}
