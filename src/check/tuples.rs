//! `vkbrdf check`'s tuples: seeded rows for one combination, where each term is hardest —
//! half of them with h aimed into the lobe at its own width, every fourth with N exactly
//! (0, 0, 1), the local shading frame the engines' local frames take — and every tuple
//! above the horizon by at least [`MIN_COS`].

use crate::batch::{Batch, COLUMNS_PLAIN, COLUMNS_TANGENT};
use crate::error::Result;
use crate::material::Material;
use crate::vector::{cross, dot, normalize_direct};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// Smallest `cos_i`, `cos_o` generated.
pub const MIN_COS: f64 = 1e-3;

fn unit(rng: &mut Pcg64Mcg) -> [f64; 3] {
    crate::sample::unit_vector(rng)
}

/// `x·t + y·b + z·n`.
fn local(t: [f64; 3], b: [f64; 3], n: [f64; 3], x: f64, y: f64, z: f64) -> [f64; 3] {
    std::array::from_fn(|k| x * t[k] + y * b[k] + z * n[k])
}

/// A direction of the hemisphere around n with `cos ≥ MIN_COS`, uniform in solid angle.
fn hemisphere(rng: &mut Pcg64Mcg, t: [f64; 3], b: [f64; 3], n: [f64; 3]) -> [f64; 3] {
    let z: f64 = rng.random_range(MIN_COS..1.0);
    let phi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let r = (1.0 - z * z).sqrt();
    local(t, b, n, r * phi.cos(), r * phi.sin(), z)
}

/// The angular width of a material's specular lobe (radians), used to aim half vectors.
fn lobe_width(m: &Material) -> f64 {
    use crate::material::Model;
    use crate::terms::d::exponent_lobe_width;
    match &m.model {
        Model::Lambert | Model::Measured(_) => 1.0,
        Model::Phong { exponent } | Model::BlinnPhong { exponent } | Model::Rtr { exponent } => {
            exponent_lobe_width(*exponent)
        }
        Model::Ward { roughness } => roughness.xy().0.max(roughness.xy().1),
        Model::CookTorrance(ct) => ct.distribution.lobe_width(),
        // The rough limit's Beckmann m, or the diffraction width 1/T of a smooth surface.
        Model::Htsg(p) => crate::terms::htsg::beckmann_m(p)
            .max(p.wavelengths[1] / (2.0 * std::f64::consts::PI * p.tau)),
    }
}

/// `tuples` rows over `materials` (material `i % materials.len()` on row `i`), with
/// tangent columns when `anisotropic`, seeded.
pub(super) fn rows(
    materials: &[Material],
    anisotropic: bool,
    tuples: usize,
    seed: u64,
) -> Result<Batch<'static>> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed.wrapping_add(0x5851_f42d_4c95_7f2d));
    let cols = if anisotropic {
        COLUMNS_TANGENT
    } else {
        COLUMNS_PLAIN
    };
    let mut data = Vec::with_capacity(tuples * cols);
    let scale = |rng: &mut Pcg64Mcg, v: [f64; 3]| {
        let s = 10f64.powf(rng.random_range(-2.0..2.0));
        v.map(|x| (x * s) as f32)
    };
    for i in 0..tuples {
        let mi = i % materials.len();
        // Every fourth row in the local shading frame, N exactly (0, 0, 1) and unscaled: the
        // form the peers and the bench use, which the engines' local frames take
        // (`frame_local32` on the CPU, `frame_scalars_f64_local` in the kernel). The draw is
        // made all the same, so that the other rows do not depend on this choice.
        let local_row = i % 4 == 3;
        let n = if local_row {
            let _ = unit(&mut rng);
            [0.0, 0.0, 1.0]
        } else {
            unit(&mut rng)
        };
        let t0 = normalize_direct(cross(
            n,
            if n[0].abs() < 0.9 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            },
        ));
        let b0 = cross(n, t0);
        let v = hemisphere(&mut rng, t0, b0, n);
        let l = if i % 2 == 0 {
            hemisphere(&mut rng, t0, b0, n)
        } else {
            // Aim h around n at the lobe's scale (Rayleigh-distributed angle) and reflect v
            // about it; keep it when it lands above the horizon, else fall back to uniform.
            let w = lobe_width(&materials[mi]).min(1.0);
            let mut l = None;
            for _ in 0..64 {
                let theta = 1.5 * w * (-2.0 * (1.0 - rng.random::<f64>()).ln()).sqrt();
                let phi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                if theta >= std::f64::consts::FRAC_PI_2 {
                    continue;
                }
                let h = local(
                    t0,
                    b0,
                    n,
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                );
                let vh = dot(v, h);
                let cand: [f64; 3] = std::array::from_fn(|k| 2.0 * vh * h[k] - v[k]);
                if vh > 0.0 && dot(cand, n) >= MIN_COS {
                    l = Some(cand);
                    break;
                }
            }
            l.unwrap_or_else(|| hemisphere(&mut rng, t0, b0, n))
        };
        data.extend(scale(&mut rng, l));
        data.extend(scale(&mut rng, v));
        let n_scaled = scale(&mut rng, n);
        data.extend(if local_row { [0.0, 0.0, 1.0] } else { n_scaled });
        data.push(mi as f32);
        if anisotropic {
            let t = loop {
                let t = unit(&mut rng);
                if dot(cross(n, t), cross(n, t)).sqrt() >= 0.1 {
                    break t;
                }
            };
            data.extend(scale(&mut rng, t));
        }
    }
    Batch::new(data, cols, materials.len(), &crate::batch::memory_source())
}
