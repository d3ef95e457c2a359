//! One loss evaluation: the specular basis of every sample from one bulk evaluation on
//! the engine, then, on the host, the exact per-channel solve of the linear coefficients
//! (quadratic losses) and the loss.
//!
//! Per channel the model is `f = a/π + spec`, with `a` the diffuse albedo and
//! - Schlick's F0 free: `spec = b (F0 A + B)`, `A = D·G·K (1 − (1 − c)⁵)`,
//!   `B = D·G·K (1 − c)⁵` (the terms D, G, K come from the same evaluation; `c = v·h`);
//!   with `b` free too it is solved as `p·D·G·K + q·B` with `p = b F0`, `q = b (1 − F0)`,
//!   both ≥ 0, so that `0 ≤ F0 ≤ 1` holds by construction;
//! - otherwise `spec = b S`, `S` the model's f at unit specular albedo (D·G·F·K for
//!   Cook–Torrance, the lobe for the others).

use super::data::FitData;
use super::linear::{Normal, MAX_UNKNOWNS};
use super::losses::{self, Loss};
use super::params::{Linear, Space};
use crate::backend::{Backend, Output, Request};
use crate::error::Result;
use std::f64::consts::FRAC_1_PI;

/// The columns of one channel's linear problem.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Column {
    /// `1/π`: the diffuse albedo.
    Diffuse,
    /// `D·G·K`: `p = b F0` (F0 and the specular albedo free).
    Dgk,
    /// `D·G·K (1 − c)⁵`: `q = b (1 − F0)`.
    Grazing,
    /// `b A`: F0 with a fixed specular albedo (upper bound 1).
    F0Scaled,
    /// `S`: the specular albedo.
    Spec,
}

/// A loss evaluator over one data set, reusing its engine output between evaluations.
pub struct Problem<'a> {
    data: &'a FitData,
    space: &'a Space,
    loss: Loss,
    backend: &'a mut dyn Backend,
    out: Output,
    columns: Vec<Column>,
    /// The quadratic loss's weight per sample, `w cos² θ_i`.
    weights: Vec<f64>,
    /// Sample evaluations made (one per sample per loss evaluation).
    pub sample_evaluations: u64,
    /// Seconds in the engine.
    pub engine_seconds: f64,
}

impl<'a> Problem<'a> {
    /// An evaluator of `loss` for `space` on `data`.
    pub fn new(
        data: &'a FitData,
        space: &'a Space,
        loss: Loss,
        backend: &'a mut dyn Backend,
    ) -> Problem<'a> {
        let mut columns = Vec::new();
        if space.solve_linear {
            use super::params::Param;
            if space.is_free(Param::Diffuse) {
                columns.push(Column::Diffuse);
            }
            if space.has_specular() {
                match (space.f0_free(), space.is_free(Param::Specular)) {
                    (true, true) => columns.extend([Column::Dgk, Column::Grazing]),
                    (true, false) => columns.push(Column::F0Scaled),
                    (false, true) => columns.push(Column::Spec),
                    (false, false) => {}
                }
            }
        }
        Problem {
            data,
            space,
            loss,
            backend,
            out: Output::default(),
            columns,
            weights: if loss.is_quadratic() {
                (0..data.len())
                    .map(|i| loss.quadratic_weight(data, i))
                    .collect()
            } else {
                Vec::new()
            },
            sample_evaluations: 0,
            engine_seconds: 0.0,
        }
    }

    /// The basis at `u`: one bulk evaluation.
    fn basis(&mut self, u: &[f64]) -> Result<()> {
        let m = self.space.basis_material(u);
        let request = Request {
            terms: self.space.f0_free(),
        };
        let t = std::time::Instant::now();
        self.backend.evaluate_local_into(
            &self.data.batch,
            std::slice::from_ref(&m),
            &request,
            &mut self.out,
        )?;
        self.engine_seconds += t.elapsed().as_secs_f64();
        self.sample_evaluations += self.data.len() as u64;
        Ok(())
    }

    #[inline]
    fn spec_parts(&self, i: usize, c: usize) -> (f64, f64) {
        spec_parts(self.data, &self.out, self.space.f0_free(), i, c)
    }

    /// The loss at `u` and the linear coefficients it was evaluated with (solved, for
    /// the quadratic losses; from `u` otherwise).
    pub fn evaluate(&mut self, u: &[f64]) -> Result<(f64, Linear)> {
        self.basis(u)?;
        if !self.space.solve_linear || !self.loss.is_quadratic() {
            let lin = self.space.linear_at(u, &self.space.start_linear());
            let model = self.values(&lin);
            return Ok((losses::value(self.loss, self.data, &model), lin));
        }
        let fixed = self.space.linear_at(u, &self.space.start_linear());
        let k = self.columns.len();
        let diffuse_col = self.columns.contains(&Column::Diffuse);
        // The specular part not solved for, per channel: `b·B` (F0 solved, b fixed),
        // `b·S` (nothing specular solved), or nothing.
        let spec_rest = if !self.space.has_specular() || self.columns.contains(&Column::Dgk) {
            0
        } else if self.space.f0_free() {
            1
        } else if self.columns.contains(&Column::Spec) {
            0
        } else {
            2
        };
        let n = self.data.len();
        let threads = std::thread::available_parallelism()
            .map_or(1, |t| t.get())
            .min(n.div_ceil(4096))
            .max(1);
        let (data, out, f0_free, columns, weights) = (
            self.data,
            &self.out,
            self.space.f0_free(),
            &self.columns,
            &self.weights,
        );
        let pass = |range: std::ops::Range<usize>| {
            let mut normal = [Normal::new(k); 3];
            for i in range {
                let w = weights[i];
                for (c, normal) in normal.iter_mut().enumerate() {
                    let (a, b) = spec_parts(data, out, f0_free, i, c);
                    let mut rest = data.values[i][c];
                    if !diffuse_col {
                        rest -= fixed.diffuse[c] * FRAC_1_PI;
                    }
                    match spec_rest {
                        1 => rest -= fixed.specular[c] * b,
                        2 => rest -= fixed.specular[c] * a,
                        _ => {}
                    }
                    let mut phi = [0.0; MAX_UNKNOWNS];
                    for (j, col) in columns.iter().enumerate() {
                        phi[j] = match col {
                            Column::Diffuse => FRAC_1_PI,
                            Column::Dgk => a + b,
                            Column::Grazing => b,
                            Column::F0Scaled => fixed.specular[c] * a,
                            Column::Spec => a,
                        };
                    }
                    normal.add(w, &phi, rest);
                }
            }
            normal
        };
        let parts: Vec<[Normal; 3]> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..threads)
                .map(|t| {
                    let range = t * n / threads..(t + 1) * n / threads;
                    scope.spawn(move || pass(range))
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("no panic in the pass"))
                .collect()
        });
        let mut normal = [Normal::new(k); 3];
        for part in &parts {
            for c in 0..3 {
                normal[c].absorb(&part[c]);
            }
        }
        let mut lin = fixed;
        let mut total = 0.0;
        for (c, normal) in normal.iter().enumerate() {
            let mut upper = [f64::INFINITY; MAX_UNKNOWNS];
            if let Some(j) = self.columns.iter().position(|&x| x == Column::F0Scaled) {
                upper[j] = 1.0;
            }
            let (x, obj) = normal.solve(&upper);
            total += obj;
            for (j, col) in self.columns.iter().enumerate() {
                match col {
                    Column::Diffuse => lin.diffuse[c] = x[j],
                    Column::Dgk => {
                        let q = self
                            .columns
                            .iter()
                            .position(|&x| x == Column::Grazing)
                            .map_or(0.0, |g| x[g]);
                        lin.specular[c] = x[j] + q;
                        lin.f0[c] = if x[j] + q > 0.0 {
                            x[j] / (x[j] + q)
                        } else {
                            fixed.f0[c]
                        };
                    }
                    Column::Grazing => {}
                    Column::F0Scaled => lin.f0[c] = x[j],
                    Column::Spec => lin.specular[c] = x[j],
                }
            }
        }
        Ok((total, lin))
    }

    /// The model's f per sample (RGB) for the basis last evaluated and coefficients `lin`.
    fn values(&self, lin: &Linear) -> Vec<[f64; 3]> {
        (0..self.data.len())
            .map(|i| {
                std::array::from_fn(|c| {
                    let (a, b) = self.spec_parts(i, c);
                    let spec = if !self.space.has_specular() {
                        0.0
                    } else if self.space.f0_free() {
                        lin.specular[c] * (lin.f0[c] * a + b)
                    } else {
                        lin.specular[c] * a
                    };
                    lin.diffuse[c] * FRAC_1_PI + spec
                })
            })
            .collect()
    }

    /// The model's f per sample at `u` with linear coefficients `solved` (merged as
    /// [`Space::linear_at`] does).
    pub fn model(&mut self, u: &[f64], solved: &Linear) -> Result<Vec<[f64; 3]>> {
        self.basis(u)?;
        let lin = self.space.linear_at(u, solved);
        Ok(self.values(&lin))
    }
}

/// `(A, B)` of sample `i` when F0 is free (`A + B = D·G·K`), else `(S_c, 0)`.
#[inline]
fn spec_parts(data: &FitData, out: &Output, f0_free: bool, i: usize, c: usize) -> (f64, f64) {
    if f0_free {
        let t = out.terms.as_ref().expect("terms were requested");
        let dgk = f64::from(t[6 * i]) * f64::from(t[6 * i + 1]) * f64::from(t[6 * i + 5]);
        let g = (1.0 - data.cos_d[i]).powi(5);
        (dgk * (1.0 - g), dgk * g)
    } else {
        (f64::from(out.brdf[3 * i + c]), 0.0)
    }
}
