//! FORMULAS.md §6: the models, each returning the BRDF per RGB channel in 1/sr (no cosine)
//! and its terms. Non-microfacet models report D = the specular lobe per unit `c_spec`
//! (0 for Lambert) and G = F = K = 1.

use super::evaluation::{Evaluation, Status};
use super::frame::Frame;
pub use super::terms::{fresnel_f, microfacet_d, microfacet_g, projected_roughness2};
use crate::material::{CookTorrance, Material, Model, Roughness};
use crate::terms::math::cos_pow;
use std::f64::consts::PI;

/// Evaluates `m` on a valid, above-horizon frame.
pub fn evaluate_model(fr: &Frame, m: &Material) -> Evaluation {
    let (lobe, rs) = match &m.model {
        Model::Lambert => (0.0, None),
        Model::Phong { exponent } => (phong_lobe(fr, *exponent), None),
        Model::BlinnPhong { exponent } => (blinn_phong_lobe(fr, *exponent), None),
        Model::Rtr { exponent } => (rtr_lobe(fr, *exponent), None),
        Model::Ward { roughness } => (ward_lobe(fr, *roughness), None),
        Model::CookTorrance(ct) => (0.0, Some(cook_torrance_terms(fr, ct))),
        Model::Measured(data) => return measured(fr, data),
        Model::Htsg(p) => return htsg(fr, p, m.diffuse),
    };
    let diffuse = m.diffuse.map(|c| c / PI);
    match rs {
        None => Evaluation {
            status: Status::Valid,
            brdf: std::array::from_fn(|c| diffuse[c] + m.specular[c] * lobe),
            d: lobe,
            g: 1.0,
            f: [1.0; 3],
            k: 1.0,
        },
        Some(Terms { d, g, f, k }) => {
            let ct = m.cook_torrance().expect("matched above");
            let ln_k = ct.convention.ln_k(fr.cos_i, fr.cos_o);
            Evaluation {
                status: Status::Valid,
                brdf: std::array::from_fn(|c| {
                    ct.diffuse_weight * diffuse[c]
                        + ct.specular_weight * m.specular[c] * specular_product(d, g, f[c], k, ln_k)
                }),
                d,
                g,
                f,
                k,
            }
        }
    }
}

/// A measured (MERL) material: f by half/difference lookup (FORMULAS.md §7). Measured
/// data has no D·G·F·K decomposition: its terms are reported as D = 0, G = F = K = 1.
pub fn measured(fr: &Frame, m: &crate::material::Measured) -> Evaluation {
    Evaluation {
        status: Status::Valid,
        brdf: m.data.lookup_with(m.lookup, fr.l, fr.v, fr.n),
        d: 0.0,
        g: 1.0,
        f: [1.0; 3],
        k: 1.0,
    }
}

/// The geometry HTSG reads (FORMULAS.md §8), from the frame: `sin θ = |n × w|` of the
/// unit vectors (absolute error ~1e-16; S1 and K(θ) depend on it only where `x = τ cot
/// θ/(2σ0)` is O(1), i.e. sin θ ≥ ~0.05 for the accepted σ0/τ ≤ 10).
pub fn htsg_angles(fr: &Frame) -> crate::terms::htsg::Angles {
    let sin = |w: [f64; 3]| super::frame::length_squared(super::frame::cross(fr.n, w)).sqrt();
    crate::terms::htsg::Angles {
        cos_i: fr.cos_i,
        cos_o: fr.cos_o,
        sin_i: sin(fr.l),
        sin_o: sin(fr.v),
        c: fr.c,
        sin2_h: fr.sin2_h,
    }
}

/// He, Torrance, Sillion & Greenberg 1991 (FORMULAS.md §8): `ρ_dd + a/π` per channel, the
/// terms as §8's "Outputs" defines them.
pub fn htsg(fr: &Frame, p: &crate::terms::htsg::Htsg, a: crate::material::Rgb) -> Evaluation {
    let t = crate::terms::htsg::evaluate(p, &htsg_angles(fr));
    Evaluation {
        status: Status::Valid,
        brdf: std::array::from_fn(|c| t.rho_dd[c] + a[c] / PI),
        d: t.d,
        g: t.g,
        f: t.f,
        k: t.k,
    }
}

/// `D·G·F·K` for one channel. At extreme grazing (cosines near 1e-170, reachable only from
/// f64 callers) K overflows to ∞ while D or G underflows to 0, and the direct product is
/// 0·∞ = NaN; then it is formed in the log domain with `ln K` taken from the cosines.
fn specular_product(d: f64, g: f64, f: f64, k: f64, ln_k: f64) -> f64 {
    let direct = d * g * f * k;
    if direct.is_finite() {
        direct
    } else {
        (d.ln() + g.ln() + f.ln() + ln_k).exp()
    }
}

/// Lewis 1994, "Making shaders more physically plausible" (modified, normalised Phong):
/// `(e+2)/(2π) max(0, r·v)^e` with `r = 2 cos_i n − l`.
pub fn phong_lobe(fr: &Frame, e: f64) -> f64 {
    // r·v = 1 − |r − v|²/2 for unit r and v. Near the lobe's peak (r ≈ v) `(r·v)^e` is taken
    // from |r − v|² (see `cos_pow`): r·v itself is 1 − ε rounded to 53 bits, and
    // `powf(e)` would turn that into a relative error of ~e·u (1e-11 at e = 10⁴).
    let r = [0, 1, 2].map(|k| 2.0 * fr.cos_i * fr.n[k] - fr.l[k]);
    let d = [0, 1, 2].map(|k| r[k] - fr.v[k]);
    let half_d2 = 0.5 * super::frame::length_squared(d);
    let lobe = if e == 0.0 {
        1.0 // max(0, r·v)^0, also where r·v ≤ 0
    } else if half_d2 < 0.5 {
        // r·v = 1 − half_d2 > 1/2, and sin² of the angle between r and v is
        // 1 − (r·v)² = half_d2 (2 − half_d2).
        cos_pow(1.0 - half_d2, half_d2 * (2.0 - half_d2), e)
    } else {
        // r·v = 2 cos_i cos_o − l·v, the same value without forming r.
        (2.0 * fr.cos_i * fr.cos_o - fr.l_dot_v).max(0.0).powf(e)
    };
    (e + 2.0) / (2.0 * PI) * lobe
}

/// The seed's Blinn–Phong (Blinn 1977), as a BRDF: `cos_h^e / (π cos_i)`. The `1/cos_i`
/// makes the shading equation's `cos_h^e` independent of the incident cosine; it also
/// makes the model non-reciprocal.
pub fn blinn_phong_lobe(fr: &Frame, e: f64) -> f64 {
    cos_pow(fr.cos_h, fr.sin2_h, e) / (PI * fr.cos_i)
}

/// Akenine-Möller, Haines & Hoffman, "Real-Time Rendering" 3rd ed. §5.5 (the seed's
/// shading equation): `(e+8)/(8π) cos_h^e`.
pub fn rtr_lobe(fr: &Frame, e: f64) -> f64 {
    (e + 8.0) / (8.0 * PI) * cos_pow(fr.cos_h, fr.sin2_h, e)
}

/// Ward 1992, "Measuring and modeling anisotropic reflection":
/// `exp(−((hx/mx)² + (hy/my)²)/hz²) / (4π mx my √(cos_i cos_o))`. Isotropic: the exponent
/// is `−tan²δ/m²`, computed from `|n × h|²` (no tangent needed).
pub fn ward_lobe(fr: &Frame, roughness: Roughness) -> f64 {
    let (mx, my) = roughness.xy();
    let arg = match (roughness, fr.h_local()) {
        (Roughness::Anisotropic(..), Some([hx, hy, hz])) => {
            -((hx / mx).powi(2) + (hy / my).powi(2)) / (hz * hz)
        }
        _ => -fr.tan2_h() / (mx * mx),
    };
    // √cos_i √cos_o, not √(cos_i cos_o): the product underflows to 0 (and f to ∞) for
    // cosines below ~1e-162, reachable from f64 callers.
    arg.exp() / (4.0 * PI * mx * my * fr.cos_i.sqrt() * fr.cos_o.sqrt())
}

/// The microfacet terms of a Cook–Torrance material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Terms {
    /// D (§2).
    pub d: f64,
    /// G (§3).
    pub g: f64,
    /// F per channel (§4).
    pub f: [f64; 3],
    /// K (§5).
    pub k: f64,
}

/// D, G, F and K of a Cook–Torrance material (Cook & Torrance 1982, "A reflectance model
/// for computer graphics"; conventions per FORMULAS.md §5).
pub fn cook_torrance_terms(fr: &Frame, ct: &CookTorrance) -> Terms {
    Terms {
        d: microfacet_d(fr, ct),
        g: microfacet_g(fr, ct),
        f: [0, 1, 2].map(|c| fresnel_f(fr.c, fr.sin2_d, &ct.fresnel, c)),
        k: ct.convention.k(fr.cos_i, fr.cos_o),
    }
}
