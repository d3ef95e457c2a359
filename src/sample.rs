//! Seeded sample batches: directions spread over the upper hemisphere around a random
//! normal, material indices cycling through the table. Used by `vkbrdf generate`, the
//! demo and the benchmarks; deterministic for a given seed.

use crate::batch::{Batch, COLUMNS_PLAIN, COLUMNS_TANGENT};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// A uniformly distributed unit vector.
pub fn unit_vector(rng: &mut impl Rng) -> [f64; 3] {
    let z: f64 = rng.random_range(-1.0..1.0);
    let phi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let r = (1.0 - z * z).max(0.0).sqrt();
    [r * phi.cos(), r * phi.sin(), z]
}

/// `n` tuples over `material_count` materials (row `i` uses material `i % material_count`).
/// L and V are uniform on the hemisphere of a random normal N (so almost every tuple is
/// above the horizon), with random lengths in [0.5, 2) to exercise normalisation; with
/// `tangents`, a random T not parallel to N is appended.
pub fn sample_batch(n: usize, material_count: usize, seed: u64, tangents: bool) -> Batch<'static> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let cols = if tangents {
        COLUMNS_TANGENT
    } else {
        COLUMNS_PLAIN
    };
    let mut data = Vec::with_capacity(n * cols);
    for i in 0..n {
        let nrm = unit_vector(&mut rng);
        let hemi = |rng: &mut Pcg64Mcg| {
            let mut w = unit_vector(rng);
            let d = w[0] * nrm[0] + w[1] * nrm[1] + w[2] * nrm[2];
            if d < 0.0 {
                w = [
                    w[0] - 2.0 * d * nrm[0],
                    w[1] - 2.0 * d * nrm[1],
                    w[2] - 2.0 * d * nrm[2],
                ];
            }
            let len: f64 = rng.random_range(0.5..2.0);
            w.map(|x| (x * len) as f32)
        };
        let l = hemi(&mut rng);
        let v = hemi(&mut rng);
        data.extend_from_slice(&l);
        data.extend_from_slice(&v);
        data.extend(nrm.map(|x| x as f32));
        data.push((i % material_count.max(1)) as f32);
        if tangents {
            data.extend(unit_vector(&mut rng).map(|x| x as f32));
        }
    }
    Batch::new(
        data,
        cols,
        material_count.max(1),
        &crate::batch::memory_source(),
    )
    .expect("generated batches are valid")
}
