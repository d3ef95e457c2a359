//! A bounded Nelder–Mead simplex (Nelder & Mead 1965, with the dimension-adapted
//! coefficients of Gao & Han 2012), restarted from its best point until a restart no
//! longer improves: the optimiser of the nonlinear parameters (docs/FITTING.md says why
//! this one). Bounds are kept by projecting each trial point onto the box.

/// Why a run stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stop {
    /// The simplex collapsed: values within the tolerance of each other.
    Converged,
    /// The evaluation budget ran out.
    Budget,
    /// The objective asked to stop (cancelled, or an error to report).
    Stopped,
}

/// The result of a minimisation.
#[derive(Debug, Clone, PartialEq)]
pub struct Minimum {
    /// The best point.
    pub x: Vec<f64>,
    /// Its value.
    pub value: f64,
    /// Evaluations made.
    pub evaluations: u64,
    /// Why it stopped.
    pub stop: Stop,
}

/// Options of [`minimise`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// At most this many evaluations.
    pub max_evaluations: u64,
    /// Stop when the simplex's values differ by at most `ftol · (|best| + tiny)`.
    pub ftol: f64,
    /// A restart that improves the best value by less than this fraction ends the run.
    pub restart_gain: f64,
    /// Stop when the simplex's values differ by at most this much (the loss's scale
    /// times a small number: values closer than the engine's f32 rounding mean nothing).
    pub fatol: f64,
    /// Stop when every vertex is within this fraction of its initial step of the best.
    pub xtol: f64,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            max_evaluations: 2000,
            ftol: 1e-10,
            restart_gain: 1e-7,
            fatol: 0.0,
            xtol: 1e-7,
        }
    }
}

/// Minimises `f` over the box `[lo, hi]` from `x0` with initial steps `step` (the
/// simplex's edge per coordinate). `f` returns `None` to stop the run at once (the best
/// point so far is returned, [`Stop::Stopped`]).
pub fn minimise(
    f: &mut dyn FnMut(&[f64]) -> Option<f64>,
    x0: &[f64],
    step: &[f64],
    lo: &[f64],
    hi: &[f64],
    options: Options,
) -> Minimum {
    let n = x0.len();
    let clamp = |x: &mut Vec<f64>| {
        for i in 0..n {
            x[i] = x[i].clamp(lo[i], hi[i]);
        }
    };
    let mut evaluations = 0u64;
    let mut x0 = x0.to_vec();
    clamp(&mut x0);
    let Some(f0) = f(&x0) else {
        return Minimum {
            x: x0,
            value: f64::INFINITY,
            evaluations: 1,
            stop: Stop::Stopped,
        };
    };
    evaluations += 1;
    let mut best = (x0, f0);
    if n == 0 {
        return Minimum {
            x: best.0,
            value: best.1,
            evaluations,
            stop: Stop::Converged,
        };
    }
    let mut scale = 1.0;
    loop {
        let budget = options.max_evaluations.saturating_sub(evaluations);
        let (x, v, used, stop) = simplex_run(f, &best, step, scale, lo, hi, budget, &options);
        evaluations += used;
        let gain = (best.1 - v) / best.1.abs().max(f64::MIN_POSITIVE);
        if v < best.1 {
            best = (x, v);
        }
        if stop != Stop::Converged || gain < options.restart_gain {
            return Minimum {
                x: best.0,
                value: best.1,
                evaluations,
                stop,
            };
        }
        // A fresh, smaller simplex at the best point: Nelder–Mead can stall on a
        // degenerate simplex away from a minimum (McKinnon 1998); a restart cures it.
        scale = (scale * 0.5).max(1e-3);
    }
}

/// One simplex run from `start`; returns its best point and value, the evaluations used
/// and why it stopped.
#[allow(clippy::too_many_arguments)]
fn simplex_run(
    f: &mut dyn FnMut(&[f64]) -> Option<f64>,
    start: &(Vec<f64>, f64),
    step: &[f64],
    scale: f64,
    lo: &[f64],
    hi: &[f64],
    budget: u64,
    options: &Options,
) -> (Vec<f64>, f64, u64, Stop) {
    let n = start.0.len();
    let nf = n as f64;
    // Gao & Han 2012: reflection 1, expansion 1 + 2/n, contraction 0.75 − 1/(2n),
    // shrink 1 − 1/n.
    let (alpha, gamma, rho, sigma) = (1.0, 1.0 + 2.0 / nf, 0.75 - 0.5 / nf, 1.0 - 1.0 / nf);
    let project = |mut x: Vec<f64>| {
        for i in 0..n {
            x[i] = x[i].clamp(lo[i], hi[i]);
        }
        x
    };
    let mut used = 0u64;
    let mut simplex: Vec<(Vec<f64>, f64)> = vec![start.clone()];
    for i in 0..n {
        let mut x = start.0.clone();
        let s = step[i] * scale;
        // Step into the box: away from the bound the start sits on.
        x[i] = if x[i] + s <= hi[i] {
            x[i] + s
        } else {
            x[i] - s
        };
        let x = project(x);
        if used >= budget {
            break;
        }
        let Some(v) = f(&x) else {
            return best_of(simplex, used + 1, Stop::Stopped);
        };
        used += 1;
        simplex.push((x, v));
    }
    if simplex.len() < n + 1 {
        return best_of(simplex, used, Stop::Budget);
    }
    loop {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (fb, fw) = (simplex[0].1, simplex[n].1);
        let small = (1..=n).all(|k| {
            (0..n).all(|i| (simplex[k].0[i] - simplex[0].0[i]).abs() <= options.xtol * step[i])
        });
        if fw - fb <= options.ftol * fb.abs() + options.fatol || small {
            return best_of(simplex, used, Stop::Converged);
        }
        if used >= budget {
            return best_of(simplex, used, Stop::Budget);
        }
        let centroid: Vec<f64> = (0..n)
            .map(|i| simplex[..n].iter().map(|p| p.0[i]).sum::<f64>() / nf)
            .collect();
        let along = |t: f64| -> Vec<f64> {
            project(
                (0..n)
                    .map(|i| centroid[i] + t * (simplex[n].0[i] - centroid[i]))
                    .collect(),
            )
        };
        macro_rules! eval {
            ($x:expr) => {{
                let x = $x;
                used += 1;
                match f(&x) {
                    Some(v) => (x, v),
                    None => return best_of(simplex, used, Stop::Stopped),
                }
            }};
        }
        let r = eval!(along(-alpha));
        if r.1 < simplex[0].1 {
            let e = eval!(along(-alpha * gamma));
            simplex[n] = if e.1 < r.1 { e } else { r };
            continue;
        }
        if r.1 < simplex[n - 1].1 {
            simplex[n] = r;
            continue;
        }
        let c = if r.1 < simplex[n].1 {
            eval!(along(-alpha * rho))
        } else {
            eval!(along(rho))
        };
        if c.1 < simplex[n].1.min(r.1) {
            simplex[n] = c;
            continue;
        }
        // Shrink towards the best point.
        for k in 1..=n {
            let x: Vec<f64> = (0..n)
                .map(|i| simplex[0].0[i] + sigma * (simplex[k].0[i] - simplex[0].0[i]))
                .collect();
            simplex[k] = eval!(project(x));
        }
    }
}

fn best_of(simplex: Vec<(Vec<f64>, f64)>, used: u64, stop: Stop) -> (Vec<f64>, f64, u64, Stop) {
    let best = simplex
        .into_iter()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("the start is in the simplex");
    (best.0, best.1, used, stop)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_minimum_of_rosenbrock_in_its_box() {
        let mut f = |x: &[f64]| Some(100.0 * (x[1] - x[0] * x[0]).powi(2) + (1.0 - x[0]).powi(2));
        let m = minimise(
            &mut f,
            &[-1.2, 1.0],
            &[0.5, 0.5],
            &[-2.0, -2.0],
            &[2.0, 2.0],
            Options::default(),
        );
        assert!(
            (m.x[0] - 1.0).abs() < 1e-4 && (m.x[1] - 1.0).abs() < 1e-4,
            "{m:?}"
        );
    }

    #[test]
    fn a_minimum_outside_the_box_ends_on_its_boundary() {
        // (x − 3)² + (y + 1)² over [0, 1]²: the minimum is at (1, 0).
        let mut f = |x: &[f64]| Some((x[0] - 3.0).powi(2) + (x[1] + 1.0).powi(2));
        let m = minimise(
            &mut f,
            &[0.5, 0.5],
            &[0.2, 0.2],
            &[0.0, 0.0],
            &[1.0, 1.0],
            Options::default(),
        );
        assert!((m.x[0] - 1.0).abs() < 1e-6 && m.x[1].abs() < 1e-6, "{m:?}");
    }

    #[test]
    fn stops_when_the_objective_says_so_and_keeps_the_best_point() {
        let mut calls = 0;
        let mut f = |x: &[f64]| {
            calls += 1;
            (calls < 10).then(|| x[0] * x[0])
        };
        let m = minimise(&mut f, &[1.0], &[0.5], &[-5.0], &[5.0], Options::default());
        assert_eq!(m.stop, Stop::Stopped);
        assert!(m.value < 1.0);
    }
}
