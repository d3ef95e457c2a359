//! The albedo and DFG tables' importance-sampled sums made inside the engine
//! ([`GeneratedDirections::importance_sums`](crate::backend::GeneratedDirections::importance_sums)):
//! each worker makes a block of samples with the host's sampler ([`crate::importance`]),
//! evaluates them in the lanes and adds `f · cos_i/pdf` as it goes. No tuple batch exists
//! on the host, below-horizon samples are skipped instead of evaluated, and the samples
//! and their weights are the host path's value for value, so a point of at most
//! [`SAMPLE_BLOCK`] samples sums to the host path's bits (tests/cpu_engine.rs).
//!
//! The work is cut into items of one block of samples × a group of points, taken by every
//! core in turn; a point's block sums are added in block order, so the result does not
//! depend on the thread count.

use super::dispatch::apart;
use super::kernel::{self, Inputs, Outputs, Params, LANES};
use super::plan::Plan;
use super::CpuEngine;
use crate::batch::Tuple;
use crate::directions::ImportanceJob;
use crate::error::{Error, Result};
use crate::importance::{schlick_weight, Lobe, Sample, Samples, UnitSample, View};
use crate::material::Material;
use crate::reference::{evaluate_tuple, to_output_f32};
use crate::terms::math::{Fused, MulAdd, Rounded};
use std::marker::PhantomData;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;

/// Samples per work item: a point's sum runs over its samples in order within a block.
pub const SAMPLE_BLOCK: u32 = 4096;

/// Points per work item: they share the block's unit samples, made once per item.
const POINT_GROUP: usize = 32;

/// One point's sampler, material and lanes plan.
struct Point<'a> {
    view: View,
    plan: &'a Plan,
    material: &'a Material,
}

/// Evaluates one block of lanes of an F = 1 microfacet material (the tables' models) on
/// the N = +z form, or returns `false` for a plan the tables never send (the caller then
/// asks the reference for every lane). Narrower than [`super::dispatch::block`] on purpose: only
/// these variants are compiled for the sums.
#[inline(always)]
fn f_none_block<S: pulp::Simd, A: MulAdd>(
    simd: S,
    plan: &Plan,
    inp: &Inputs,
    out: &mut Outputs,
) -> bool {
    use crate::terms::{DistributionKind as D, FresnelKind, Geometry as G};
    use kernel::*;
    let Plan::Microfacet {
        d,
        aniso: false,
        g,
        f: FresnelKind::None,
        p,
    } = plan
    else {
        return false;
    };
    macro_rules! fused {
        ($d:expr, $g:expr) => {
            apart(simd, || {
                microfacet_block::<A, $d, $g, F_NONE, true>(p, inp, out)
            })
        };
    }
    match (*d, *g) {
        (D::Ggx, G::None) => fused!(D_GGX, G_NONE),
        (D::Ggx, G::CookTorrance) => fused!(D_GGX, G_CT),
        (D::Ggx, G::Smith) => fused!(D_GGX, G_SMITH),
        (D::Ggx, G::SmithCorrelated) => fused!(D_GGX, G_SMITH_CORRELATED),
        (D::Beckmann, G::None) => fused!(D_BECKMANN, G_NONE),
        (D::Beckmann, G::CookTorrance) => fused!(D_BECKMANN, G_CT),
        (D::Beckmann, G::Smith) => fused!(D_BECKMANN, G_SMITH),
        (D::Beckmann, G::SmithCorrelated) => fused!(D_BECKMANN, G_SMITH_CORRELATED),
        (D::Beckmann, G::SmithFast) => fused!(D_BECKMANN, G_SMITH_FAST),
        (D::Ggx, G::SchlickSmith) => {
            apart(simd, || two_pass::<A, D_GGX, G_SCHLICK_SMITH>(p, inp, out))
        }
        (D::Ggx, G::Neubelt) => apart(simd, || two_pass::<A, D_GGX, G_NEUBELT>(p, inp, out)),
        (D::Beckmann, G::SchlickSmith) => apart(simd, || {
            two_pass::<A, D_BECKMANN, G_SCHLICK_SMITH>(p, inp, out)
        }),
        (D::Beckmann, G::Neubelt) => {
            apart(simd, || two_pass::<A, D_BECKMANN, G_NEUBELT>(p, inp, out))
        }
        // The tables' importance sampler exists for GGX and Beckmann only (`importance`),
        // and smith-fast is Beckmann's.
        (D::Ggx, G::SmithFast) | (D::Gaussian | D::Blinn | D::Charlie, _) => return false,
    }
    true
}

/// The groups the engine runs in two passes ([`kernel::two_pass::dg_block64`]), with F = 1.
#[inline(always)]
fn two_pass<A: MulAdd, const D: u8, const G: u8>(p: &Params, inp: &Inputs, out: &mut Outputs) {
    let mut st = kernel::two_pass::Stage::default();
    kernel::two_pass::dg_block64::<A, D, G>(p, inp, &mut st);
    kernel::two_pass::f_block::<A, { kernel::F_NONE }>(p, &st, out);
}

/// One work item: samples `first..first + len` of every point in `points`.
struct ItemOp<'a> {
    points: &'a [Point<'a>],
    units: &'a [UnitSample],
    /// `units` as columns ([`UnitSample::columns`]), padded to whole blocks of lanes.
    cols: &'a [Vec<f64>; 3],
    sums: &'a mut [[f64; 2]],
}

impl pulp::WithSimd for ItemOp<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) {
        // `S` may lack FMA (the scalar variant): `a·b + c` rounded twice, as the chunks'.
        self.sums::<S, Rounded>(simd);
    }
}

impl ItemOp<'_> {
    /// The item's sums in `simd`'s lanes, forming `a·b + c` as `A` (the chunks' choice
    /// for the same instruction set, so that a table's lanes give `eval`'s bits).
    #[inline(always)]
    fn sums<S: pulp::Simd, A: MulAdd>(self, simd: S) {
        for (pt, sum) in self.points.iter().zip(self.sums.iter_mut()) {
            *sum = point_sums::<S, A>(simd, pt, self.units, self.cols);
        }
    }
}

/// [`ItemOp`] on AVX-512 and AVX2, `a·b + c` fused (as the chunks run them).
impl super::isa::WithFma for ItemOp<'_> {
    #[inline(always)]
    fn with_fma<S: super::transpose::Transpose + super::register::RegisterIo>(self, simd: S) {
        self.sums::<S, Fused>(simd);
    }
}

/// The samples of one point gathered into a block of lanes, and its sums so far.
struct Acc<'a, S, A> {
    simd: S,
    pt: &'a Point<'a>,
    v32: [f32; 3],
    inp: Inputs,
    out: Outputs,
    weights: [[f64; 2]; LANES],
    n: usize,
    sums: [f64; 2],
    /// How the lanes form `a·b + c`.
    mul_add: PhantomData<A>,
}

impl<'a, S: pulp::Simd, A: MulAdd> Acc<'a, S, A> {
    #[inline(always)]
    fn new(simd: S, pt: &'a Point<'a>) -> Acc<'a, S, A> {
        let v32 = pt.view.v.map(|x| x as f32);
        let mut inp = Inputs::default();
        for c in 0..3 {
            inp.v[3 + c] = [v32[c]; LANES];
        }
        inp.v[8] = [1.0; LANES];
        Acc {
            simd,
            pt,
            v32,
            inp,
            out: Outputs::default(),
            weights: [[0f64; 2]; LANES],
            n: 0,
            sums: [0f64; 2],
            mul_add: PhantomData,
        }
    }

    /// One sample into the next lane, the block evaluated when full. (Methods rather than
    /// closures: a closure LLVM leaves out of line is a call a lane and no vectors.)
    #[inline(always)]
    fn push(&mut self, s: Sample) {
        for c in 0..3 {
            self.inp.v[c][self.n] = s.l[c] as f32;
        }
        // The host's weights, `weight(c)` times `cos_i/pdf` (tables' DFG: [1, (1 − c)⁵]).
        self.weights[self.n] = [s.weight, schlick_weight(s.c) * s.weight];
        self.n += 1;
        if self.n == LANES {
            self.flush();
        }
    }

    /// A whole block of made samples (none to be made again), evaluated in place of
    /// [`Acc::push`]ing them one by one: the lanes are the block's lanes, a lane that is no
    /// sample (below the horizon) evaluates `l = v` and adds nothing. Each lane's result
    /// depends on its own tuple alone, and the sums take the samples in the same order, so
    /// this gives `push`'s bits without its per-sample gather (a scalar loop that was
    /// about a third of the sampler's time).
    #[inline(always)]
    fn block(&mut self, made: &Samples<LANES>) {
        if self.n > 0 {
            self.flush();
        }
        for c in 0..3 {
            for k in 0..LANES {
                self.inp.v[c][k] = if made.ok[k] {
                    made.l[c][k] as f32
                } else {
                    self.v32[c]
                };
            }
        }
        let lanes = f_none_block::<S, A>(self.simd, self.pt.plan, &self.inp, &mut self.out);
        for k in 0..LANES {
            if made.ok[k] {
                let w = [made.weight[k], schlick_weight(made.c[k]) * made.weight[k]];
                self.add(lanes, k, w);
            }
        }
    }

    /// Lane `k`'s f (the lanes', or the reference's where the lanes did not run or flagged
    /// it) times its weights, added to the sums.
    #[inline(always)]
    fn add(&mut self, lanes: bool, k: usize, w: [f64; 2]) {
        let f = if lanes && !self.out.rescue[k] {
            self.out.brdf[0][k]
        } else {
            let t = Tuple {
                l: [self.inp.v[0][k], self.inp.v[1][k], self.inp.v[2][k]],
                v: self.v32,
                n: [0.0, 0.0, 1.0],
                material: 0,
                t: None,
            };
            to_output_f32(evaluate_tuple(&t, self.pt.material).brdf[0])
        };
        let f = f64::from(f);
        for (s, w) in self.sums.iter_mut().zip(w) {
            *s += f * w;
        }
    }

    /// The lanes' results of the samples gathered so far, added in order.
    #[inline(always)]
    fn flush(&mut self) {
        let lanes = f_none_block::<S, A>(self.simd, self.pt.plan, &self.inp, &mut self.out);
        for k in 0..self.n {
            self.add(lanes, k, self.weights[k]);
        }
        self.n = 0;
    }
}

/// `[Σ x, Σ x (1 − c)⁵]`, `x = f · cos_i/pdf`, over the samples `units` of one point, in
/// sample order (a below-horizon sample adds nothing, as its weight 0 does on the host).
#[inline(always)]
fn point_sums<S: pulp::Simd, A: MulAdd>(
    simd: S,
    pt: &Point,
    units: &[UnitSample],
    cols: &[Vec<f64>; 3],
) -> [f64; 2] {
    let mut acc = Acc::<S, A>::new(simd, pt);
    if pt.view.has_lanes() {
        // `LANES` samples at a time in wide f64 registers.
        let mut made = Samples::<LANES>::default();
        for (j, u) in units.chunks(LANES).enumerate() {
            let col = |c: usize| -> &[f64; LANES] {
                cols[c][j * LANES..(j + 1) * LANES]
                    .try_into()
                    .expect("columns padded to whole blocks")
            };
            pt.view.lane_samples(col(0), col(1), col(2), &mut made);
            if u.len() == LANES && !made.redo.contains(&true) {
                acc.block(&made);
                continue;
            }
            for k in 0..u.len() {
                if made.redo[k] {
                    if let Some(s) = pt.view.sample_one(&u[k]) {
                        acc.push(s);
                    }
                } else if made.ok[k] {
                    acc.push(Sample {
                        l: [made.l[0][k], made.l[1][k], made.l[2][k]],
                        weight: made.weight[k],
                        c: made.c[k],
                    });
                }
            }
        }
    } else {
        for u in units {
            if let Some(s) = pt.view.sample(u) {
                acc.push(s);
            }
        }
    }
    if acc.n > 0 {
        acc.flush();
    }
    acc.sums
}

impl CpuEngine {
    /// See [`crate::backend::GeneratedDirections::importance_sums`].
    pub(super) fn sum_importance(
        &mut self,
        job: &ImportanceJob,
        progress: &mut dyn FnMut(u64),
    ) -> Result<Vec<[f64; 2]>> {
        let samples = job.checked_samples()?;
        let lobe = if job.ggx { Lobe::Ggx } else { Lobe::Beckmann };
        let plans: Vec<Plan> = job.materials.iter().map(Plan::for_material).collect();
        let mut points = Vec::with_capacity(job.points.len());
        for (i, p) in job.points.iter().enumerate() {
            let mi = p.material as usize;
            let (Some(plan), Some(material)) = (plans.get(mi), job.materials.get(mi)) else {
                return Err(Error::Table(format!(
                    "importance point {i} names material {mi} of {}",
                    job.materials.len()
                )));
            };
            points.push(Point {
                view: View::new(lobe, p.point[0], p.point[1]),
                plan,
                material,
            });
        }
        let blocks = samples.div_ceil(SAMPLE_BLOCK) as usize;
        let groups = points.len().div_ceil(POINT_GROUP);
        let items = blocks * groups;
        // Block sums, point-major: `block_sums[p * blocks + b]`.
        let block_sums = Mutex::new(vec![[0f64; 2]; points.len() * blocks]);
        let next = AtomicUsize::new(0);
        let done = AtomicU64::new(0);
        let helpers = self.threads.min(items).saturating_sub(1);
        let pool = if helpers > 0 { self.pool() } else { None };
        let cancel = &self.cancel;
        let arch = self.arch();
        // Items block-major, so a worker's consecutive items mostly share their unit
        // samples (made again only when the block changes).
        let work = |mut report: Option<&mut dyn FnMut(u64)>| {
            let mut units: Vec<UnitSample> = Vec::new();
            let mut cols: [Vec<f64>; 3] = Default::default();
            let mut units_of = usize::MAX;
            let mut sums = Vec::new();
            let mut reported = 0;
            loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= items || cancel.is_cancelled() {
                    break;
                }
                let (b, g) = (i / groups, i % groups);
                let first = b as u32 * SAMPLE_BLOCK;
                let len = SAMPLE_BLOCK.min(samples - first);
                if units_of != b {
                    units.clear();
                    units.extend((first..first + len).map(|k| UnitSample::new(k, samples)));
                    units_of = b;
                    for (c, col) in cols.iter_mut().enumerate() {
                        col.clear();
                        col.extend(units.iter().map(|u| u.columns(lobe)[c]));
                        col.resize(units.len().next_multiple_of(LANES), 0.0);
                    }
                }
                let group = &points[g * POINT_GROUP..points.len().min((g + 1) * POINT_GROUP)];
                sums.clear();
                sums.resize(group.len(), [0f64; 2]);
                super::isa::run_lanes(
                    arch,
                    ItemOp {
                        points: group,
                        units: &units,
                        cols: &cols,
                        sums: &mut sums,
                    },
                );
                {
                    let mut all = block_sums.lock().expect("sums lock");
                    for (j, s) in sums.iter().enumerate() {
                        all[(g * POINT_GROUP + j) * blocks + b] = *s;
                    }
                }
                let total = done.fetch_add(u64::from(len) * group.len() as u64, Ordering::Relaxed)
                    + u64::from(len) * group.len() as u64;
                if let Some(report) = report.as_deref_mut() {
                    report(total - reported);
                    reported = total;
                }
            }
        };
        match pool {
            None => work(Some(progress)),
            Some(pool) => pool.in_place_scope(|s| {
                for _ in 0..helpers {
                    s.spawn(|_| work(None));
                }
                work(Some(progress));
            }),
        }
        self.cancel.check()?;
        let block_sums = block_sums.into_inner().expect("sums lock");
        let n = f64::from(samples);
        Ok(block_sums
            .chunks(blocks)
            .map(|bs| {
                let mut s = [0f64; 2];
                for b in bs {
                    s[0] += b[0];
                    s[1] += b[1];
                }
                s.map(|x| x / n)
            })
            .collect())
    }
}
