//! Fitting analytic models to measured BRDFs (`vkbrdf fit`; docs/FITTING.md): from a MERL
//! binary or tuples with measured values to the parameters of a material a renderer takes.
//!
//! - [`data`]: the samples, their mask and their solid-angle weights;
//! - [`params`]: the free parameters, their bounds, the material at a point;
//! - [`losses`]: Ngan's L2, Löw's E1 and E2, the relative RMS;
//! - [`linear`]: the exact per-channel solve of the albedos and Schlick's F0;
//! - [`optimise`]: the bounded Nelder–Mead of the nonlinear parameters;
//! - [`report`]: the materials TOML, the Markdown report, the residual slice.
//!
//! One loss evaluation is one bulk evaluation of every sample on a [`Backend`] (the
//! specular basis: the model with unit albedos and no diffuse part), then one pass on the
//! host that solves the linear coefficients and sums the loss. The material's model and
//! terms never change between evaluations, only its numbers, so the Vulkan kernel is
//! compiled once (its pipelines are cached per `FeatureSet`).
//!
//! ```no_run
//! use vkbrdf::fit::{self, data::FitData, params::{Param, Space}};
//! let table = vkbrdf::material::merl::read("gold.binary".as_ref())?;
//! let data = FitData::from_merl(&table, None)?;
//! let start = vkbrdf::material::presets::preset("gold").unwrap()?;
//! let space = Space::new(&start, &[Param::Roughness, Param::Specular], &[], true)?;
//! let mut backend = vkbrdf::backend_choice::cpu_engine()?;
//! let result = fit::fit(&data, &space, &fit::Options::default(), &mut backend,
//!                       &vkbrdf::cancel::Cancel::new(), &mut |_| {})?;
//! println!("{:?} L2 {}", result.material, result.metrics.l2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod data;
pub mod linear;
pub mod losses;
pub mod optimise;
pub mod params;
pub mod problem;
pub mod report;

use crate::backend::Backend;
use crate::cancel::Cancel;
use crate::error::{Error, Result};
use crate::material::Material;
use data::FitData;
use losses::{Loss, Metrics};
use params::{Linear, Space};
use problem::Problem;
use rand::{Rng, SeedableRng};

/// Evaluations at most per start in the coarse phase: enough to find the basin, the
/// polish on all the data does the rest.
pub const COARSE_EVALUATIONS: u64 = 400;

/// Coarse results polished on all the data: the best one (a second doubled the time of a
/// full-MERL fit and never won in the round trips).
pub const FINE_STARTS: usize = 1;

/// Options of [`fit`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// The loss minimised.
    pub loss: Loss,
    /// Starting points: the start material's, then random ones in the bounds.
    pub starts: usize,
    /// Seed of the random starts.
    pub seed: u64,
    /// Evaluations at most per start in the coarse phase, and for the final polish.
    pub max_evaluations: u64,
    /// Data larger than twice this is subsampled to about this many samples for the
    /// multi-start phase; the best coarse result is then polished on all of it.
    pub coarse_samples: usize,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            loss: Loss::L2,
            starts: 8,
            seed: 1,
            max_evaluations: 1500,
            coarse_samples: 1 << 16,
        }
    }
}

/// Where a fit is (for a progress line).
#[derive(Debug, Clone, PartialEq)]
pub struct Progress {
    /// `coarse` (the multi-start phase on subsampled data) or `fine` (all the data).
    pub phase: &'static str,
    /// The start being run (0-based) and how many there are in this phase.
    pub start: (usize, usize),
    /// Evaluations so far, all phases.
    pub evaluations: u64,
    /// The best value of the loss in this phase.
    pub best: f64,
}

/// One start's outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct StartResult {
    /// `coarse` or `fine`.
    pub phase: &'static str,
    /// Its starting coordinates.
    pub from: Vec<f64>,
    /// Where it ended and the loss there (on that phase's data).
    pub minimum: optimise::Minimum,
}

/// A finished (or interrupted) fit.
#[derive(Debug, Clone)]
pub struct FitResult {
    /// The fitted material.
    pub material: Material,
    /// The optimiser's coordinates of it.
    pub u: Vec<f64>,
    /// Its linear coefficients.
    pub linear: Linear,
    /// Every metric on all the data.
    pub metrics: Metrics,
    /// Every metric of the start material (before fitting), for comparison.
    pub start_metrics: Metrics,
    /// The model's f per sample at the fit (the residual slice's input).
    pub model: Vec<[f64; 3]>,
    /// The loss minimised.
    pub loss: Loss,
    /// The starts' outcomes, coarse then fine.
    pub starts: Vec<StartResult>,
    /// Loss evaluations, all phases.
    pub evaluations: u64,
    /// Sample evaluations (one per sample per loss evaluation).
    pub sample_evaluations: u64,
    /// Seconds inside the engine's bulk evaluations.
    pub engine_seconds: f64,
    /// Seconds of the whole fit.
    pub seconds: f64,
    /// The engine's name.
    pub backend: String,
    /// Stopped early by the cancellation token: the best parameters so far.
    pub interrupted: bool,
}

/// Fits `space` to `data` on `backend`. `cancel` stops the search at its next evaluation:
/// the result is then the best point so far, marked [`FitResult::interrupted`] (the
/// backend is given a fresh token to evaluate it). Errors: the engine's.
pub fn fit(
    data: &FitData,
    space: &Space,
    options: &Options,
    backend: &mut dyn Backend,
    cancel: &Cancel,
    progress: &mut dyn FnMut(&Progress),
) -> Result<FitResult> {
    let t0 = std::time::Instant::now();
    let coords = &space.coords;
    let (lo, hi): (Vec<f64>, Vec<f64>) = coords.iter().map(|c| c.u_bounds()).unzip();
    let u0 = space.start_u();
    let step: Vec<f64> = (0..coords.len())
        .map(|i| {
            if hi[i].is_finite() {
                0.15 * (hi[i] - lo[i])
            } else {
                (0.25 * u0[i].abs()).max(0.05)
            }
        })
        .collect();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(options.seed);
    let mut from = vec![u0.clone()];
    for _ in 1..options.starts.max(1) {
        from.push(
            (0..coords.len())
                .map(|i| {
                    if hi[i].is_finite() {
                        rng.random_range(lo[i]..=hi[i])
                    } else {
                        u0[i].max(0.05) * rng.random_range(0.25..4.0)
                    }
                })
                .collect(),
        );
    }
    let mut interrupted = false;
    let mut failure: Option<Error> = None;
    let mut starts = Vec::new();
    let mut evaluations = 0u64;
    let mut sample_evaluations = 0u64;
    let mut engine_seconds = 0.0;
    let coarse_data;
    let coarse = data.len() > 2 * options.coarse_samples && !coords.is_empty();
    // The loss of f = 0 sets its scale: differences below 1e-12 of it are the engine's
    // f32 rounding, not information.
    let zero = losses::metrics(data, &vec![[0.0; 3]; data.len()]).get(options.loss);
    let nm = optimise::Options {
        max_evaluations: options.max_evaluations,
        fatol: 1e-12 * zero,
        ..optimise::Options::default()
    };
    let mut run = |phase: &'static str,
                   d: &FitData,
                   points: &[Vec<f64>],
                   backend: &mut dyn Backend,
                   interrupted: &mut bool,
                   failure: &mut Option<Error>,
                   evaluations: &mut u64|
     -> Vec<StartResult> {
        let mut problem = Problem::new(d, space, options.loss, backend);
        let mut out = Vec::new();
        let mut best = f64::INFINITY;
        for (k, x0) in points.iter().enumerate() {
            if *interrupted || failure.is_some() {
                break;
            }
            let mut objective = |u: &[f64]| -> Option<f64> {
                if cancel.is_cancelled() {
                    *interrupted = true;
                    return None;
                }
                match problem.evaluate(u) {
                    Ok((v, _)) => {
                        *evaluations += 1;
                        if v < best {
                            best = v;
                        }
                        if (*evaluations).is_multiple_of(25) {
                            progress(&Progress {
                                phase,
                                start: (k, points.len()),
                                evaluations: *evaluations,
                                best,
                            });
                        }
                        Some(v)
                    }
                    Err(Error::Cancelled) => {
                        *interrupted = true;
                        None
                    }
                    Err(e) => {
                        *failure = Some(e);
                        None
                    }
                }
            };
            let budget = if phase == "coarse" {
                nm.max_evaluations.min(COARSE_EVALUATIONS)
            } else {
                nm.max_evaluations
            };
            let nm = optimise::Options {
                max_evaluations: budget,
                ..nm
            };
            let minimum = optimise::minimise(&mut objective, x0, &step, &lo, &hi, nm);
            out.push(StartResult {
                phase,
                from: x0.clone(),
                minimum,
            });
        }
        sample_evaluations += problem.sample_evaluations;
        engine_seconds += problem.engine_seconds;
        out
    };
    let fine_from: Vec<Vec<f64>> = if coarse {
        let step_n = data.len().div_ceil(options.coarse_samples);
        coarse_data = data.subsample(step_n);
        let c = run(
            "coarse",
            &coarse_data,
            &from,
            backend,
            &mut interrupted,
            &mut failure,
            &mut evaluations,
        );
        let mut ranked: Vec<&StartResult> = c.iter().collect();
        ranked.sort_by(|a, b| a.minimum.value.total_cmp(&b.minimum.value));
        let picks: Vec<Vec<f64>> = ranked
            .iter()
            .take(FINE_STARTS)
            .map(|s| s.minimum.x.clone())
            .collect();
        starts.extend(c);
        picks
    } else {
        from
    };
    starts.extend(run(
        "fine",
        data,
        &fine_from,
        backend,
        &mut interrupted,
        &mut failure,
        &mut evaluations,
    ));
    if let Some(e) = failure {
        return Err(e);
    }
    // The best point: the best fine result, else (interrupted in the coarse phase) the
    // best coarse one, else the start.
    let best_u = starts
        .iter()
        .filter(|s| s.phase == "fine")
        .chain(starts.iter().filter(|s| s.phase == "coarse"))
        .filter(|s| s.minimum.value.is_finite())
        .min_by(|a, b| {
            (a.phase != "fine", a.minimum.value)
                .partial_cmp(&(b.phase != "fine", b.minimum.value))
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .map_or(u0.clone(), |s| s.minimum.x.clone());
    if interrupted {
        backend.set_cancel(Cancel::new());
    }
    let mut problem = Problem::new(data, space, options.loss, backend);
    let (_, linear) = problem.evaluate(&best_u)?;
    let model = problem.model(&best_u, &linear)?;
    let metrics = losses::metrics(data, &model);
    let start_model = problem.model(&u0, &space.start_linear())?;
    let start_metrics = losses::metrics(data, &start_model);
    sample_evaluations += problem.sample_evaluations;
    engine_seconds += problem.engine_seconds;
    let material = space.material(&best_u, &linear);
    let linear = space.linear_at(&best_u, &linear);
    Ok(FitResult {
        material,
        u: best_u,
        linear,
        metrics,
        start_metrics,
        model,
        loss: options.loss,
        starts,
        evaluations,
        sample_evaluations,
        engine_seconds,
        seconds: t0.elapsed().as_secs_f64(),
        backend: backend.name(),
        interrupted,
    })
}
