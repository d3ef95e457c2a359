//! The lanes a chunk's fast paths leave to others: the reference ([`rescue`]) and the
//! blocks gathered for another frame ([`Deferred`]), each written into the lane's place.

use super::work::{Source, Tally, Work};
use crate::backend::{Counts, TERM_COLUMNS};
use crate::cpu::dispatch::block;
use crate::cpu::kernel::{Inputs, Outputs, LANES};
use crate::cpu::plan::Plan;
use crate::material::Material;
use crate::reference::{evaluate_tuple, to_output_f32, Status};
use crate::terms::math::MulAdd;

/// Writes the f64 reference's result for batch row `row` at position `j` of the chunk and
/// counts its status.
pub(super) fn rescue(
    batch: Source,
    m: &Material,
    row: usize,
    j: usize,
    w: &mut Work,
    counts: &mut Counts,
) {
    let e = evaluate_tuple(&batch.tuple(row), m);
    match e.status {
        Status::Invalid => {
            counts.invalid += 1;
            counts.first_invalid = Some(
                counts
                    .first_invalid
                    .map_or(row as u64, |f| f.min(row as u64)),
            );
        }
        Status::BelowHorizon => counts.below_horizon += 1,
        Status::Valid => counts.saturated += u64::from(e.saturated()),
    }
    for (ch, x) in e.brdf.into_iter().enumerate() {
        w.brdf[j * 3 + ch] = to_output_f32(x);
    }
    if let Some(t) = w.terms.as_deref_mut() {
        for (c, x) in e.terms().into_iter().enumerate() {
            t[j * TERM_COLUMNS + c] = to_output_f32(x);
        }
    }
}

/// The lanes whose bits are set in `bits`, lowest first.
#[inline(always)]
pub(super) fn lanes_of(mut bits: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (bits != 0).then(|| {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            k
        })
    })
}

/// The lanes a chunk's blocks left to the f64 frame ([`Params::defer_slow`](crate::cpu::kernel::Params::defer_slow)),
/// gathered into one block: a few lanes in a hundred cost a few blocks in a hundred, where
/// running the f64 frame over each block that had one cost a third of the blocks. Each
/// lane's result depends on its own tuple alone, so where it is evaluated does not change
/// it.
pub(super) struct Deferred {
    inp: Inputs,
    /// Each lane's output position in the chunk and its batch row.
    at: [(usize, usize); LANES],
    n: usize,
}

impl Deferred {
    pub(super) fn new() -> Deferred {
        Deferred {
            inp: Inputs::default(),
            at: [(0, 0); LANES],
            n: 0,
        }
    }

    /// A lane's L, V, N `x` (output position `j`, batch row `row`); whether the block is
    /// full.
    #[inline(always)]
    pub(super) fn push_lane(&mut self, x: [f32; 9], j: usize, row: usize) -> bool {
        // `n < LANES` always (a full block is run before the next push); the mask says so
        // to the compiler, which then drops the bounds checks.
        let n = self.n % LANES;
        for c in 0..9 {
            self.inp.v[c][n] = x[c];
        }
        self.at[n] = (j, row);
        self.n = n + 1;
        self.n == LANES
    }

    /// The gathered lanes on `plan64` (the group's f64 frame, or its general f32 frame),
    /// into their places in `w`, rescued where the lanes say so.
    pub(super) fn run<S: pulp::Simd, A: MulAdd>(
        &mut self,
        cx: Chunk<S>,
        plan64: &Plan,
        w: &mut Work,
        counts: &mut Counts,
        tally: &mut Tally,
    ) {
        let Chunk { simd, z, batch, m } = cx;
        let n = self.n;
        if n == 0 {
            return;
        }
        // The unused lanes repeat the first (computed and dropped).
        for k in n..LANES {
            for c in 0..9 {
                self.inp.v[c][k] = self.inp.v[c][0];
            }
        }
        let mut out = [Outputs::default()];
        block::<S, A>(simd, plan64, std::slice::from_ref(&self.inp), &mut out, z);
        tally.deferred += n as u64;
        for (k, &(j, row)) in self.at[..n].iter().enumerate() {
            if out[0].rescue[k] {
                rescue(batch, m, row, j, w, counts);
                tally.rescued += 1;
            } else {
                write_lane(&out[0], k, j, w);
            }
        }
        self.n = 0;
    }
}

/// Lane `k` of `out` into output position `j`.
#[inline(always)]
pub(super) fn write_lane(out: &Outputs, k: usize, j: usize, w: &mut Work) {
    for ch in 0..3 {
        w.brdf[j * 3 + ch] = out.brdf[ch][k];
    }
    if let Some(t) = w.terms.as_deref_mut() {
        for c in 0..TERM_COLUMNS {
            t[j * TERM_COLUMNS + c] = out.terms[c][k];
        }
    }
}

/// What every lane a chunk leaves to another frame is evaluated with: the instruction
/// set, whether the rows' N is +z (the local form), the batch and its material.
#[derive(Clone, Copy)]
pub(super) struct Chunk<'a, S> {
    pub(super) simd: S,
    pub(super) z: bool,
    pub(super) batch: Source<'a>,
    pub(super) m: &'a Material,
}

/// Where a chunk's fast paths send the lanes they cannot serve: the f64 frame (`c` below
/// `FAST_MIN_C`) and the general f32 frame (the local frame's certificate refused them),
/// each a [`Deferred`] queue with its group's plan for that frame.
pub(super) struct Elsewhere<'a, S> {
    cx: Chunk<'a, S>,
    queues: [(Plan, Deferred); 2],
}

/// [`Elsewhere`]'s queue for the f64 frame.
pub(super) const F64_FRAME: usize = 0;
/// [`Elsewhere`]'s queue for the general f32 frame.
pub(super) const GENERAL_FRAME: usize = 1;

impl<'a, S: pulp::Simd> Elsewhere<'a, S> {
    pub(super) fn new(plan: &Plan, cx: Chunk<'a, S>) -> Elsewhere<'a, S> {
        Elsewhere {
            cx,
            queues: [
                (plan.f64_frame(), Deferred::new()),
                (plan.general_frame_only(), Deferred::new()),
            ],
        }
    }

    /// What the queues' lanes are evaluated with.
    pub(super) fn chunk(&self) -> Chunk<'a, S> {
        self.cx
    }

    /// A lane's L, V, N `x` (output position `j`, batch row `row`) into queue `to`
    /// ([`F64_FRAME`] or [`GENERAL_FRAME`]), which runs when full.
    #[inline(always)]
    pub(super) fn push<A: MulAdd>(
        &mut self,
        to: usize,
        x: [f32; 9],
        (j, row): (usize, usize),
        w: &mut Work,
        counts: &mut Counts,
        tally: &mut Tally,
    ) {
        let (plan, queue) = &mut self.queues[to];
        if queue.push_lane(x, j, row) {
            queue.run::<S, A>(self.cx, plan, w, counts, tally);
        }
    }

    /// Runs what both queues still hold (at the end of a chunk).
    pub(super) fn finish<A: MulAdd>(
        &mut self,
        w: &mut Work,
        counts: &mut Counts,
        tally: &mut Tally,
    ) {
        for (plan, queue) in &mut self.queues {
            queue.run::<S, A>(self.cx, plan, w, counts, tally);
        }
    }
}
