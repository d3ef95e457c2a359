//! Tuples where GGX's D is steepest in h, for the tests of the f32 local frames (the CPU
//! engine's `frame_local32`, the kernel's `frame_scalars_local32`): their error is D's
//! slope times the frame's turn of h, largest at tan θ_h = m and small c; and where
//! Beckmann's is, in its tails.

/// Unit `(l, v)` pairs about N = +z whose half vector sits at tan θ_h = m/2, m and 2m
/// (three azimuths each), with c = l·h from `c_min` to 1 in 40 steps and three planes of
/// l − v each; pairs with a cosine below 1e-3 are left out.
pub fn ggx_pairs(m: f64, c_min: f64) -> Vec<([f64; 3], [f64; 3])> {
    pairs_at(&[0.5 * m, m, 2.0 * m], c_min)
}

/// [`ggx_pairs`] for Beckmann, whose D's slope `2 tan θ_h (1/(m² cos² θ_h) − 2)` grows
/// without bound: h at tan θ_h = m, 3m and 9m, and either side of tan²θ_h/m² = 174 (13.19m),
/// where the lanes' `exp(−x/2)` reaches its cut-off at −87 and D goes to 0.
pub fn beckmann_pairs(m: f64, c_min: f64) -> Vec<([f64; 3], [f64; 3])> {
    pairs_at(&[m, 3.0 * m, 9.0 * m, 13.18 * m, 13.2 * m], c_min)
}

/// The pairs of [`ggx_pairs`] with h at each of `tans` (tan θ_h).
fn pairs_at(tans: &[f64], c_min: f64) -> Vec<([f64; 3], [f64; 3])> {
    let mut pairs = Vec::new();
    for &t in tans {
        let th = t.atan();
        for phi in [0.3f64, 1.9, 4.0] {
            let h = [th.sin() * phi.cos(), th.sin() * phi.sin(), th.cos()];
            // Two unit vectors perpendicular to h.
            let a = [-phi.sin(), phi.cos(), 0.0];
            let b = [
                h[1] * a[2] - h[2] * a[1],
                h[2] * a[0] - h[0] * a[2],
                h[0] * a[1] - h[1] * a[0],
            ];
            for k in 0..40 {
                let c = c_min + (1.0 - c_min) * f64::from(k) / 39.0;
                let (cd, sd) = (c, (1.0 - c * c).sqrt());
                for psi in [0.2f64, 1.3, 2.6] {
                    let w: [f64; 3] = std::array::from_fn(|j| psi.cos() * a[j] + psi.sin() * b[j]);
                    let l: [f64; 3] = std::array::from_fn(|j| cd * h[j] + sd * w[j]);
                    let v: [f64; 3] = std::array::from_fn(|j| cd * h[j] - sd * w[j]);
                    if l[2] >= 1e-3 && v[2] >= 1e-3 {
                        pairs.push((l, v));
                    }
                }
            }
        }
    }
    pairs
}
