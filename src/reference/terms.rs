//! FORMULAS.md §2–§5 on the reference's frame: which term of each family a Cook–Torrance
//! material names, given the frame's quantities. The formulas are the terms' own f64 forms
//! (`crate::terms`, one file each); this file only dispatches, exhaustively.

use super::frame::{cross, dot, length_squared, Frame};
use crate::material::{CookTorrance, Distribution, Fresnel, Geometry, Roughness};
use crate::terms::{d, f, g};

/// D of §2 for the material's distribution.
pub fn microfacet_d(fr: &Frame, ct: &CookTorrance) -> f64 {
    let h_local = || fr.h_local().expect("anisotropic frame has a tangent");
    match ct.distribution {
        Distribution::Gaussian { m } => d::gaussian::d(fr.cos_h, fr.sin2_h, m),
        Distribution::Beckmann(Roughness::Isotropic(m)) => {
            d::beckmann::d(fr.cos_h, fr.sin2_h, m, ct.convention.beckmann_k())
        }
        Distribution::Beckmann(Roughness::Anisotropic(mx, my)) => {
            d::beckmann::d_aniso(h_local(), mx, my)
        }
        Distribution::Ggx(Roughness::Isotropic(m)) => d::ggx::d(fr.cos_h, fr.sin2_h, m),
        Distribution::Ggx(Roughness::Anisotropic(mx, my)) => d::ggx::d_aniso(h_local(), mx, my),
        Distribution::Blinn { exponent } => d::blinn::d(fr.cos_h, fr.sin2_h, exponent),
        Distribution::Charlie { m } => d::charlie::d(fr.cos_h, fr.sin2_h, m),
    }
}

/// `m² tan²θ(w)` for direction `w` (§3), or for anisotropic roughness
/// `(mx² (w·t)² + my² (w·b)²)/(n·w)²`. Uses `|n × w|²` for `sin²θ`.
pub fn projected_roughness2(fr: &Frame, w: [f64; 3], cos_w: f64, roughness: Roughness) -> f64 {
    match (roughness, fr.tb) {
        (Roughness::Anisotropic(mx, my), Some((t, b))) => {
            ((mx * dot(w, t)).powi(2) + (my * dot(w, b)).powi(2)) / (cos_w * cos_w)
        }
        _ => {
            let (m, _) = roughness.xy();
            m * m * length_squared(cross(fr.n, w)) / (cos_w * cos_w)
        }
    }
}

/// G of §3 for the material's geometry term.
pub fn microfacet_g(fr: &Frame, ct: &CookTorrance) -> f64 {
    let roughness = match ct.distribution {
        Distribution::Beckmann(r) | Distribution::Ggx(r) => Some(r),
        _ => None,
    };
    let x = |w, cos_w| {
        projected_roughness2(
            fr,
            w,
            cos_w,
            roughness.expect("Smith needs beckmann/ggx (validated)"),
        )
    };
    let lambda = |w, cos_w| match ct.distribution {
        Distribution::Beckmann(_) => d::beckmann::lambda(x(w, cos_w)),
        Distribution::Ggx(_) => d::ggx::lambda(x(w, cos_w)),
        Distribution::Gaussian { .. }
        | Distribution::Blinn { .. }
        | Distribution::Charlie { .. } => {
            unreachable!("Smith needs a distribution with Λ (validated)")
        }
    };
    match ct.geometry {
        Geometry::None => 1.0,
        Geometry::CookTorrance => g::cook_torrance::g(fr.cos_h, fr.cos_i, fr.cos_o, fr.c),
        Geometry::Smith => g::smith::g(lambda(fr.v, fr.cos_o), lambda(fr.l, fr.cos_i)),
        Geometry::SmithCorrelated => {
            g::smith_correlated::g(lambda(fr.v, fr.cos_o), lambda(fr.l, fr.cos_i))
        }
        Geometry::SmithFast => {
            g::smith_fast::g1(x(fr.v, fr.cos_o)) * g::smith_fast::g1(x(fr.l, fr.cos_i))
        }
        Geometry::SchlickSmith => {
            let m = roughness
                .expect("schlick-smith needs beckmann/ggx (validated)")
                .xy()
                .0;
            // 1 − cos_w = |n × w|²/(1 + cos_w): the subtraction carries cos_w's absolute
            // error (~1e-16), which k (up to 8e3) multiplies into G near normal incidence.
            let one_minus = |w, cos_w: f64| length_squared(cross(fr.n, w)) / (1.0 + cos_w);
            let k = g::schlick_smith::k(matches!(ct.distribution, Distribution::Ggx(_)), m);
            g::schlick_smith::g1(fr.cos_o, one_minus(fr.v, fr.cos_o), k)
                * g::schlick_smith::g1(fr.cos_i, one_minus(fr.l, fr.cos_i), k)
        }
        Geometry::Neubelt => g::neubelt::g(fr.cos_i, fr.cos_o),
    }
}

/// F of §4 for channel `ch` at `c = v·h`, given also `sin2_d = 1 − c²` (accurate).
pub fn fresnel_f(c: f64, sin2_d: f64, fresnel: &Fresnel, ch: usize) -> f64 {
    match *fresnel {
        Fresnel::None => 1.0,
        Fresnel::Dielectric { ior } => f::dielectric::f_with_sin2(c, sin2_d, ior[ch]),
        Fresnel::Conductor { ior, extinction } => f::conductor::f(c, ior[ch], extinction[ch]),
        Fresnel::Schlick { f0 } => f::schlick::f(c, f0[ch]),
    }
}
