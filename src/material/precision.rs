//! Precision variants: the user's choice between the exact terms of FORMULAS.md and cheaper
//! approximations with a measured error (`vkbrdf bench` reports both, side by side).
//!
//! `fast` rewrites a Cook–Torrance material before evaluation:
//! - exact dielectric or conductor Fresnel → Schlick with the same `F0`
//!   (`((n−1)² + k²)/((n+1)² + k²)`), no complex arithmetic;
//! - Smith–Beckmann (`smith`, `smith-correlated`; the erf/erfc path) → Walter et al.'s
//!   rational `smith-fast` (≤ 0.35 % per G1).
//!
//! Everything else (the other models, GGX's Smith, which is already a square root) is left
//! as it is. The material is marked [`Precision::Fast`]; a Vulkan kernel whose materials
//! are all fast also swaps the kernel's accurate `exp`, `log`, `ln cos` and `atan2` for
//! the device's built-in functions (`FAST_MATH` in glsl/math.glsl: on lavapipe `exp` is up
//! to 65 ulp off, `ln cos` from `cos` loses the relative precision near the peak). The CPU
//! reference evaluates the rewritten terms in f64. Errors are always measured against the
//! reference of the **exact** material.

pub use super::model::Precision;
use super::model::{Material, Model};
use crate::terms::f::schlick::f0_from_ior;
use crate::terms::{Distribution, Fresnel, Geometry};

/// `m` rewritten for `precision` (a clone for `Exact`; measured materials stay exact).
pub fn apply(m: &Material, precision: Precision) -> Material {
    let mut out = m.clone();
    if precision == Precision::Exact || matches!(m.model, Model::Measured(_)) {
        return out;
    }
    out.precision = Precision::Fast;
    if let Model::CookTorrance(ct) = &mut out.model {
        ct.fresnel = match ct.fresnel {
            Fresnel::Dielectric { ior } => Fresnel::Schlick {
                f0: f0_from_ior(ior, [0.0; 3]),
            },
            Fresnel::Conductor { ior, extinction } => Fresnel::Schlick {
                f0: f0_from_ior(ior, extinction),
            },
            f => f,
        };
        if matches!(ct.distribution, Distribution::Beckmann(_))
            && matches!(ct.geometry, Geometry::Smith | Geometry::SmithCorrelated)
        {
            ct.geometry = Geometry::SmithFast;
        }
    }
    out
}

/// Every material of a table rewritten for `precision`.
pub fn apply_all(materials: &[Material], precision: Precision) -> Vec<Material> {
    materials.iter().map(|m| apply(m, precision)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::presets::preset;

    #[test]
    fn fast_replaces_exact_fresnel_and_smith_beckmann_only() {
        let gold = preset("gold").unwrap().unwrap();
        let fast = apply(&gold, Precision::Fast);
        let ct = fast.cook_torrance().unwrap();
        let Fresnel::Schlick { f0 } = ct.fresnel else {
            panic!("gold's conductor Fresnel must become Schlick: {ct:?}")
        };
        // F0 of gold's red channel: ((0.166−1)² + 3.15²)/((1.166)² + 3.15²).
        let want =
            ((0.166f64 - 1.0).powi(2) + 3.15f64.powi(2)) / (1.166f64.powi(2) + 3.15f64.powi(2));
        assert!((f0[0] - want).abs() < 1e-15);
        assert_eq!(
            ct.geometry,
            Geometry::SmithCorrelated,
            "GGX keeps its Smith G"
        );
        let plastic = apply(&preset("shiny-plastic").unwrap().unwrap(), Precision::Fast);
        assert_eq!(
            plastic.cook_torrance().unwrap().geometry,
            Geometry::SmithFast,
            "Smith–Beckmann becomes smith-fast"
        );
        assert_eq!(apply(&gold, Precision::Exact), gold);
    }
}
