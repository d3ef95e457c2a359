//! A batch over several materials in an interleaved order, with invalid and below-horizon
//! rows, and the seeded values it is made of (the CPU engine's tests).

use super::materials;
use vkbrdf::batch::{memory_source, Batch};
use vkbrdf::material::Material;

/// Seeded values uniform in [−1, 1) (a 64-bit LCG's top 24 bits).
pub fn uniform(seed: u64) -> impl FnMut() -> f32 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }
}

/// Rows over several materials in an interleaved order, with invalid and below-horizon rows.
pub fn mixed_batch(n: usize) -> (Batch<'static>, Vec<Material>) {
    let mats = materials(
        r#"
        [[material]]
        name = "ggx"
        model = "cook-torrance"
        distribution = "ggx"
        geometry = "smith-correlated"
        fresnel = "conductor"
        ior = [0.2, 0.9, 1.1]
        extinction = [3.9, 2.4, 2.2]
        roughness = 0.3
        [[material]]
        name = "matte"
        model = "lambert"
        diffuse = [0.5, 0.4, 0.3]
        [[material]]
        name = "ward"
        model = "ward"
        roughness = 0.2
        specular = [0.1, 0.1, 0.1]
        [[material]]
        name = "beck"
        model = "cook-torrance"
        distribution = "beckmann"
        geometry = "smith"
        fresnel = "dielectric"
        ior = [1.5, 1.5, 1.5]
        roughness = 0.05
        "#,
    );
    let mut rows = Vec::with_capacity(n * 10);
    let mut rnd = uniform(12345);
    for i in 0..n {
        let l = [rnd(), rnd(), rnd().abs() + 0.01];
        let mut v = [rnd(), rnd(), rnd().abs() + 0.01];
        if i % 97 == 3 {
            v[2] = -v[2]; // below the horizon
        }
        let mut nrm = [0.0, 0.0, 1.0];
        if i % 101 == 7 {
            nrm = [0.0, 0.0, 0.0]; // invalid
        }
        if i % 103 == 9 {
            nrm = [f32::NAN, 0.0, 1.0]; // invalid
        }
        rows.extend_from_slice(&l);
        rows.extend_from_slice(&v);
        rows.extend_from_slice(&nrm);
        rows.push(((i * 7) % 4) as f32);
    }
    let batch = Batch::new(rows, 10, mats.len(), &memory_source()).expect("batch");
    (batch, mats)
}
