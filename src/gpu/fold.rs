//! What a folded pipeline is specialised to (`Kernels::folded`, docs/VULKAN.md): the
//! batch's one material as its table row (specialization constants 1–29,
//! `glsl/bindings.glsl`) and, for a Cook–Torrance conductor whose F has a fitted
//! polynomial within the metal form's budget (`terms::f::conductor::poly`, the CPU
//! engine's), that polynomial's coefficients (constants 31–76,
//! `glsl/f_poly_constants.glsl`, read by `conductor_f_poly` in `glsl/terms.glsl`).

use super::layout::GpuMaterial;
use crate::material::{Fresnel, Material, Model};
use crate::terms::f::conductor::poly::{Polynomial, DEGREE};

/// The constant id of `MATERIAL_F_POLY`; the coefficients follow it, red's constant term
/// first (`F_POLY_R0` … `F_POLY_R14`, then green's, then blue's).
const F_POLY_ID: u32 = 31;

/// A folded pipeline's specialization: the material's row and, where it has one, F's
/// polynomial (its coefficients as rounded to f32, which the written bound is for).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Fold {
    /// The material's table row (`gpu::layout::gpu_material`).
    pub material: GpuMaterial,
    /// F's coefficients per channel, constant term first.
    pub f_poly: Option<[[f32; DEGREE + 1]; 3]>,
}

impl Fold {
    /// The fold of `material`, whose table row the batch made (`row`).
    pub fn new(row: &GpuMaterial, material: &Material) -> Fold {
        let f_poly = match &material.model {
            Model::CookTorrance(ct) => match ct.fresnel {
                Fresnel::Conductor { ior, extinction } => Polynomial::fitted(ior, extinction),
                _ => None,
            },
            _ => None,
        };
        Fold {
            material: *row,
            f_poly: f_poly.map(|p| p.b),
        }
    }

    /// The specialization constants after the material's: `(id, 32-bit value)` for
    /// `MATERIAL_F_POLY` and, when it is true, the 45 coefficients.
    pub fn f_poly_constants(&self) -> Vec<(u32, u32)> {
        let Some(b) = &self.f_poly else {
            return vec![(F_POLY_ID, ash::vk::FALSE)];
        };
        let coefficients = b.iter().flatten().map(|c| c.to_bits());
        std::iter::once(ash::vk::TRUE)
            .chain(coefficients)
            .enumerate()
            .map(|(i, bits)| (F_POLY_ID + i as u32, bits))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::layout::gpu_material;

    fn material(toml: &str) -> Material {
        crate::material::parse_materials(&format!("[[material]]\nname = \"m\"\n{toml}"), "test")
            .expect("valid")
            .remove(0)
    }

    /// A metal gets its polynomial (ids 31–76, the coefficients' bits in channel order); a
    /// Schlick material and a conductor without the metal form (η near 1) get none.
    #[test]
    fn only_a_fitted_conductor_carries_coefficients() {
        let metal = material(
            "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 0.3\n\
             geometry = \"smith\"\nfresnel = \"conductor\"\nior = [0.2, 0.92, 1.1]\n\
             extinction = [3.9, 2.45, 2.14]\n",
        );
        let fold = Fold::new(&gpu_material(&metal), &metal);
        let b = fold.f_poly.expect("the bench's metal has a fit");
        let constants = fold.f_poly_constants();
        assert_eq!(constants.len(), 46);
        assert_eq!(constants[0], (31, ash::vk::TRUE));
        assert_eq!(constants[1], (32, b[0][0].to_bits()));
        assert_eq!(constants[45], (76, b[2][DEGREE].to_bits()));
        for toml in [
            "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 0.3\n\
             geometry = \"smith\"\nfresnel = \"schlick\"\nf0 = 0.04\n",
            "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 0.3\n\
             geometry = \"smith\"\nfresnel = \"conductor\"\nior = 1.0\nextinction = 0.0\n",
        ] {
            let m = material(toml);
            let fold = Fold::new(&gpu_material(&m), &m);
            assert_eq!(fold.f_poly, None, "{toml}");
            assert_eq!(fold.f_poly_constants(), vec![(31, ash::vk::FALSE)]);
        }
    }
}
