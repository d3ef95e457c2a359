//! Error statistics shared by the conformance, stress and benchmark reports: relative error
//! against the f64 reference with an absolute floor, its maximum (with the worst tuple) and
//! its 99th percentile from a log-binned histogram (no per-tuple storage, so 10⁷-tuple runs
//! stay small).

/// Histogram resolution: bins per decade of relative error. The p99 is reported as the upper
/// edge of its bin, so it overstates the true p99 by at most a factor 10^(1/40) ≈ 1.06.
const BINS_PER_DECADE: f64 = 40.0;
/// Smallest resolved error (below it everything lands in bin 0): 1e-12, far under f32's
/// 6e-8 rounding.
const LOG10_MIN: f64 = -12.0;
/// Decades covered above `LOG10_MIN` (errors up to 1e4; larger ones go to the last bin).
const DECADES: usize = 16;

/// `|x − r| / max(|r|, floor)`: relative error, absolute below `floor`. A non-finite `x`
/// (where `r` is finite) is an infinite error.
pub fn relative_error(x: f64, r: f64, floor: f64) -> f64 {
    if x == r {
        return 0.0;
    }
    if !x.is_finite() {
        return f64::INFINITY;
    }
    (x - r).abs() / r.abs().max(floor)
}

/// Accumulated error statistics of one bin (a combination, a term, a regime).
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorStats {
    /// Values compared.
    pub count: u64,
    /// Largest relative error seen.
    pub max: f64,
    /// Index (caller-defined: tuple row) of the largest error.
    pub worst: Option<u64>,
    histogram: Vec<u64>,
}

impl Default for ErrorStats {
    fn default() -> Self {
        ErrorStats {
            count: 0,
            max: 0.0,
            worst: None,
            histogram: vec![0; DECADES * BINS_PER_DECADE as usize + 1],
        }
    }
}

impl ErrorStats {
    /// Records one relative error `e` for item `index`.
    pub fn add(&mut self, e: f64, index: u64) {
        self.count += 1;
        if e > self.max || self.worst.is_none() {
            self.max = self.max.max(e);
            self.worst = Some(index);
        }
        let bin = if e <= 0.0 {
            0
        } else {
            (((e.log10() - LOG10_MIN) * BINS_PER_DECADE).ceil().max(0.0) as usize)
                .min(self.histogram.len() - 1)
        };
        self.histogram[bin] += 1;
    }

    /// Merges another bin's statistics into this one (`worst` follows the larger max).
    pub fn merge(&mut self, other: &ErrorStats) {
        if other.max > self.max || self.worst.is_none() {
            self.max = other.max;
            self.worst = other.worst;
        }
        self.count += other.count;
        for (a, b) in self.histogram.iter_mut().zip(&other.histogram) {
            *a += b;
        }
    }

    /// The `q`-quantile (0 < q ≤ 1) as the upper edge of its histogram bin, capped by the
    /// exact maximum.
    pub fn quantile(&self, q: f64) -> f64 {
        if self.count == 0 {
            return 0.0;
        }
        let target = (q * self.count as f64).ceil() as u64;
        let mut seen = 0;
        for (bin, &n) in self.histogram.iter().enumerate() {
            seen += n;
            if seen >= target {
                if bin == 0 {
                    return if self.max <= 10f64.powf(LOG10_MIN) {
                        self.max
                    } else {
                        10f64.powf(LOG10_MIN)
                    };
                }
                return 10f64
                    .powf(LOG10_MIN + bin as f64 / BINS_PER_DECADE)
                    .min(self.max);
            }
        }
        self.max
    }

    /// The 99th percentile.
    pub fn p99(&self) -> f64 {
        self.quantile(0.99)
    }
}

/// Median of a non-empty list (timings: the gpu module's and the benchmarks').
pub fn median(mut xs: Vec<f64>) -> f64 {
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    if n % 2 == 1 {
        xs[n / 2]
    } else {
        (xs[n / 2 - 1] + xs[n / 2]) / 2.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn p99_is_within_one_bin_of_the_truth() {
        let mut s = ErrorStats::default();
        // 1000 errors 1e-7 … 1e-4 spaced evenly in log: the true p99 is the 990th.
        let errs: Vec<f64> = (0..1000)
            .map(|i| 10f64.powf(-7.0 + 3.0 * i as f64 / 999.0))
            .collect();
        for (i, &e) in errs.iter().enumerate() {
            s.add(e, i as u64);
        }
        let truth = errs[989];
        assert!(
            s.p99() >= truth && s.p99() <= truth * 10f64.powf(1.0 / BINS_PER_DECADE) * 1.0001,
            "{} vs {truth}",
            s.p99()
        );
        assert_eq!(s.max, errs[999]);
        assert_eq!(s.worst, Some(999));
    }

    #[test]
    fn relative_error_uses_the_floor_and_flags_non_finite() {
        // |ref| = 1 is above the floor: the plain relative error.
        assert_eq!(relative_error(1.0 + 1e-6, 1.0, 1e-6), (1.0 + 1e-6) - 1.0);
        assert!((relative_error(2e-9, 1e-9, 1e-6) - 1e-3).abs() < 1e-15);
        assert_eq!(relative_error(f64::NAN, 1.0, 1e-6), f64::INFINITY);
        assert_eq!(relative_error(0.0, 0.0, 1e-6), 0.0);
    }
}
