//! The linear part of a fit: per channel, `min Σ wᵢ (Σⱼ xⱼ φᵢⱼ − yᵢ)²` over at most three
//! coefficients `0 ≤ xⱼ ≤ uⱼ`, from its normal equations in f64.
//!
//! Solved exactly by enumerating the active sets (each coefficient free, at 0 or at its
//! upper bound: at most 3³ = 27 small systems): a convex quadratic's minimum over a box
//! is the stationary point of one face, so the best feasible stationary point is it. For
//! two or three unknowns this is simpler than, and gives the same answer as, Lawson and
//! Hanson's active-set NNLS (1974, *Solving Least Squares Problems*, ch. 23).

/// Unknowns per channel at most: diffuse, and two specular columns.
pub const MAX_UNKNOWNS: usize = 3;

/// The normal equations `M x = r` of one channel's weighted least-squares problem, with
/// `Σ w y²` for the objective's value.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Normal {
    /// Number of unknowns (0 to [`MAX_UNKNOWNS`]).
    pub k: usize,
    /// `Σ w φ φᵀ`.
    pub m: [[f64; MAX_UNKNOWNS]; MAX_UNKNOWNS],
    /// `Σ w φ y`.
    pub r: [f64; MAX_UNKNOWNS],
    /// `Σ w y²`.
    pub yy: f64,
}

impl Normal {
    /// An empty system of `k` unknowns.
    pub fn new(k: usize) -> Normal {
        assert!(k <= MAX_UNKNOWNS, "at most {MAX_UNKNOWNS} unknowns");
        Normal {
            k,
            ..Normal::default()
        }
    }

    /// Adds sample `y` with basis values `phi` (the first `k` used) and weight `w`.
    #[inline]
    #[allow(clippy::needless_range_loop)] // the upper triangle: b from a
    pub fn add(&mut self, w: f64, phi: &[f64; MAX_UNKNOWNS], y: f64) {
        for a in 0..self.k {
            let wa = w * phi[a];
            self.r[a] += wa * y;
            for b in a..self.k {
                self.m[a][b] += wa * phi[b];
            }
        }
        self.yy += w * y * y;
    }

    /// Adds another part's sums (a thread's share of the samples).
    pub fn absorb(&mut self, other: &Normal) {
        for a in 0..self.k {
            self.r[a] += other.r[a];
            for b in a..self.k {
                self.m[a][b] += other.m[a][b];
            }
        }
        self.yy += other.yy;
    }

    /// `Σ w (φ·x − y)²` at `x`.
    pub fn objective(&self, x: &[f64; MAX_UNKNOWNS]) -> f64 {
        let mut s = self.yy;
        for a in 0..self.k {
            s -= 2.0 * x[a] * self.r[a];
            for b in 0..self.k {
                s += x[a] * x[b] * self.sym(a, b);
            }
        }
        s.max(0.0)
    }

    fn sym(&self, a: usize, b: usize) -> f64 {
        if a <= b {
            self.m[a][b]
        } else {
            self.m[b][a]
        }
    }

    /// The minimiser over `0 ≤ x ≤ upper` (an upper bound may be infinite) and its
    /// objective.
    pub fn solve(&self, upper: &[f64; MAX_UNKNOWNS]) -> ([f64; MAX_UNKNOWNS], f64) {
        let mut best = ([0.0; MAX_UNKNOWNS], self.objective(&[0.0; MAX_UNKNOWNS]));
        let states = 3usize.pow(self.k as u32);
        for code in 0..states {
            // State of unknown a: 0 free, 1 at zero, 2 at its upper bound.
            let state = |a: usize| (code / 3usize.pow(a as u32)) % 3;
            if (0..self.k).any(|a| state(a) == 2 && !upper[a].is_finite()) {
                continue;
            }
            let mut x = [0.0; MAX_UNKNOWNS];
            for a in 0..self.k {
                if state(a) == 2 {
                    x[a] = upper[a];
                }
            }
            let free: Vec<usize> = (0..self.k).filter(|&a| state(a) == 0).collect();
            if !free.is_empty() {
                // M_ff x_f = r_f − M_fb x_b.
                let n = free.len();
                let mut a = [[0.0; MAX_UNKNOWNS + 1]; MAX_UNKNOWNS];
                for (i, &p) in free.iter().enumerate() {
                    for (j, &q) in free.iter().enumerate() {
                        a[i][j] = self.sym(p, q);
                    }
                    a[i][n] = self.r[p]
                        - (0..self.k)
                            .filter(|b| state(*b) != 0)
                            .map(|b| self.sym(p, b) * x[b])
                            .sum::<f64>();
                }
                let Some(sol) = gauss(&mut a, n) else {
                    continue;
                };
                if free
                    .iter()
                    .zip(&sol)
                    .any(|(&p, &s)| !(s >= 0.0 && s <= upper[p]))
                {
                    continue;
                }
                for (&p, &s) in free.iter().zip(&sol) {
                    x[p] = s;
                }
            }
            let obj = self.objective(&x);
            if obj < best.1 {
                best = (x, obj);
            }
        }
        best
    }
}

/// Solves the `n × n` system in the augmented matrix `a` (column `n` the right-hand side)
/// by Gaussian elimination with partial pivoting; `None` when it is singular (a pivot below
/// 1e-12 of the largest diagonal entry: the column is, in f64, a combination of the others,
/// and a smaller active set describes the same minimum).
#[allow(clippy::needless_range_loop)] // row operations read two rows at once
fn gauss(a: &mut [[f64; MAX_UNKNOWNS + 1]; MAX_UNKNOWNS], n: usize) -> Option<Vec<f64>> {
    let scale = (0..n).map(|i| a[i][i].abs()).fold(0.0, f64::max);
    if scale <= 0.0 || !scale.is_finite() {
        return None;
    }
    for col in 0..n {
        let p = (col..n).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))?;
        if a[p][col].abs() <= 1e-12 * scale {
            return None;
        }
        a.swap(col, p);
        for row in col + 1..n {
            let f = a[row][col] / a[col][col];
            for j in col..=n {
                a[row][j] -= f * a[col][j];
            }
        }
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|j| a[i][j] * x[j]).sum();
        x[i] = (a[i][n] - s) / a[i][i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn system(rows: &[([f64; 3], f64)], k: usize) -> Normal {
        let mut n = Normal::new(k);
        for (phi, y) in rows {
            n.add(1.0, phi, *y);
        }
        n
    }

    #[test]
    fn an_exact_nonnegative_combination_is_recovered() {
        // y = 2 φ0 + 0.5 φ1 on independent columns.
        let rows: Vec<([f64; 3], f64)> = (0..20)
            .map(|i| {
                let t = i as f64 / 19.0;
                ([1.0, t * t, 0.0], 2.0 + 0.5 * t * t)
            })
            .collect();
        let (x, obj) = system(&rows, 2).solve(&[f64::INFINITY; 3]);
        assert!(
            (x[0] - 2.0).abs() < 1e-12 && (x[1] - 0.5).abs() < 1e-12,
            "{x:?}"
        );
        assert!(obj < 1e-12, "{obj}"); // Σwy² − 2xᵀr + xᵀMx cancels to ~1e-16 Σwy²
    }

    #[test]
    fn a_negative_unconstrained_optimum_is_held_at_zero_and_an_upper_bound_holds() {
        // y = 1 − t: the best x1 for φ = [1, t] is −1; with x1 ≥ 0 it is 0 and x0 the mean.
        let rows: Vec<([f64; 3], f64)> = (0..11)
            .map(|i| {
                let t = i as f64 / 10.0;
                ([1.0, t, 0.0], 1.0 - t)
            })
            .collect();
        let (x, _) = system(&rows, 2).solve(&[f64::INFINITY; 3]);
        assert_eq!(x[1], 0.0);
        assert!((x[0] - 0.5).abs() < 1e-12);
        // y = 3 φ0 with x0 ≤ 1: held at 1.
        let rows = [([1.0, 0.0, 0.0], 3.0)];
        let (x, obj) = system(&rows, 1).solve(&[1.0, 0.0, 0.0]);
        assert_eq!(x[0], 1.0);
        assert!((obj - 4.0).abs() < 1e-12);
    }

    #[test]
    fn a_zero_column_does_not_stop_the_solve() {
        let rows = [([1.0, 0.0, 0.0], 2.0), ([1.0, 0.0, 0.0], 2.0)];
        let (x, obj) = system(&rows, 2).solve(&[f64::INFINITY; 3]);
        assert_eq!((x[0], x[1]), (2.0, 0.0));
        assert!(obj < 1e-12, "{obj}"); // Σwy² − 2xᵀr + xᵀMx cancels to ~1e-16 Σwy²
    }
}
