//! The empirical lobe models in the lanes (FORMULAS.md §6): Phong, Blinn–Phong, RTR and
//! isotropic Ward, each `c_diff/π + c_spec · lobe` with the terms D = lobe, G = F = K = 1.
//! The frame is the f64 one (`frame::frame64`: these lobes raise cosines to exponents
//! up to 1e4 and more, which multiply the frame's error), the lobe's `ln`/`exp` f32, as
//! the kernel's `glsl/models.glsl` computes them, function for function. Anisotropic Ward
//! adds the tangent frame (`src/cpu/aniso.rs`).

// The lane loops index several arrays with the same lane number (see `kernel`).
#![allow(clippy::needless_range_loop)]

use super::aniso::{lane_tangent, slope2, tangent};
use super::frame::frame64;
use super::kernel::{lane_inputs, Inputs, Outputs, Params, LANES, OUTPUT_LIMIT};
use crate::material::{Material, Model, Roughness};
use crate::terms::math::{exp_neg, log_cos};
use std::f64::consts::PI;

/// An empirical lobe model; the discriminant is the lanes' const parameter ([`lobe_block`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Lobe {
    /// Modified, normalised Phong.
    Phong = 0,
    /// The seed's Blinn–Phong.
    BlinnPhong = 1,
    /// RTR's shading equation.
    Rtr = 2,
    /// Isotropic Ward.
    Ward = 3,
    /// Anisotropic Ward (needs the tangent).
    WardAniso = 4,
}

impl Lobe {
    /// The lobe whose code is `code`, in a `const` block (an unknown code is then a
    /// compile error).
    pub const fn from_code(code: u8) -> Lobe {
        match code {
            0 => Lobe::Phong,
            1 => Lobe::BlinnPhong,
            2 => Lobe::Rtr,
            3 => Lobe::Ward,
            4 => Lobe::WardAniso,
            _ => panic!("no lobe has this code"),
        }
    }
}

/// Lobe model: modified, normalised Phong.
pub const L_PHONG: u8 = Lobe::Phong as u8;
/// Lobe model: the seed's Blinn–Phong.
pub const L_BLINN_PHONG: u8 = Lobe::BlinnPhong as u8;
/// Lobe model: RTR's shading equation.
pub const L_RTR: u8 = Lobe::Rtr as u8;
/// Lobe model: isotropic Ward.
pub const L_WARD: u8 = Lobe::Ward as u8;
/// Lobe model: anisotropic Ward (needs the tangent).
pub const L_WARD_ANISO: u8 = Lobe::WardAniso as u8;

/// The lobe model and constants of an empirical model (`p` holds its diffuse and specular
/// colours): its lobe's exponent and normalisation, formed in f64 and rounded once; `None`
/// for a model that is not a lobe.
pub fn params(m: &Material, mut p: Params) -> Option<(Lobe, Params)> {
    let model = match m.model {
        Model::Phong { exponent } => {
            p.exponent = exponent as f32;
            p.d_norm_f = ((exponent + 2.0) / (2.0 * PI)) as f32;
            Lobe::Phong
        }
        Model::BlinnPhong { exponent } => {
            p.exponent = exponent as f32;
            p.d_norm_f = (1.0 / PI) as f32;
            Lobe::BlinnPhong
        }
        Model::Rtr { exponent } => {
            p.exponent = exponent as f32;
            p.d_norm_f = ((exponent + 8.0) / (8.0 * PI)) as f32;
            Lobe::Rtr
        }
        Model::Ward {
            roughness: Roughness::Isotropic(r),
        } => {
            p.inv_m2 = 1.0 / (r * r);
            p.d_norm_f = (1.0 / (4.0 * PI * r * r)) as f32;
            Lobe::Ward
        }
        Model::Ward {
            roughness: Roughness::Anisotropic(mx, my),
        } => {
            p.aniso = super::aniso::roughness(mx, my);
            p.d_norm_f = (1.0 / (4.0 * PI * mx * my)) as f32;
            Lobe::WardAniso
        }
        _ => return None,
    };
    Some((model, p))
}

/// One block of lobe model `M` (a [`Lobe`]'s code). Writes the BRDF and D (the
/// caller sets G = F = K = 1 once a chunk, `kernel::lambert_terms`, whose D the block
/// overwrites).
#[inline(always)]
pub fn lobe_block<const M: u8>(p: &Params, inp: &Inputs, out: &mut Outputs) {
    for k in 0..LANES {
        let f = frame64(&lane_inputs(inp, k));
        let (cos_i, cos_h, sin2_h) = (f.cos_i as f32, f.cos_h as f32, f.sin2_h as f32);
        // cos_h^e (Blinn–Phong, RTR): e ln cos_h ≤ 0, so exp_neg suffices; cos_h ≥ GRAZING
        // on every lane that is kept, so the log's argument is a normal number. A value,
        // not a closure: LLVM left the closure a call a lane, and nothing vectorised
        // (157 cycles an evaluation); the other models' variants drop it unused.
        let cos_h_e = exp_neg(p.exponent * log_cos(cos_h, sin2_h));
        // A lane that must go to the reference although its frame is fine.
        let mut hard = false;
        // The anisotropic Ward's tangent frame (the others' variants do not compute it).
        let t = tangent(&f, lane_tangent(inp, k));
        let lobe = match const { Lobe::from_code(M) } {
            Lobe::Phong => {
                // Lewis 1994: (e + 2)/(2π) max(0, r·v)^e; pow(0, e) is 0, or 1 for e = 0.
                let rv = f.rv as f32;
                let pow = exp_neg(p.exponent * log_cos(rv, f.sin2_rv as f32));
                let pow = if rv > 0.0 {
                    pow
                } else if p.exponent == 0.0 {
                    1.0
                } else {
                    0.0
                };
                // An r·v below f32's normal range has no f32 logarithm here (and with a
                // small exponent its power is not small): the reference takes it.
                hard = rv > 0.0 && rv < f32::MIN_POSITIVE;
                p.d_norm_f * pow
            }
            // Blinn 1977 as the seed writes it: cos_h^e/(π cos_i).
            Lobe::BlinnPhong => p.d_norm_f * cos_h_e / cos_i,
            // RTR 3rd ed. §5.5: (e + 8)/(8π) cos_h^e.
            Lobe::Rtr => p.d_norm_f * cos_h_e,
            Lobe::Ward | Lobe::WardAniso => {
                // Ward 1992: exp(−((hx/mx)² + (hy/my)²)/hz²)/(4π mx my √(cos_i cos_o)),
                // isotropic exp(−tan²δ/m²)/(4π m² …), the exponent and the root in f64
                // (tan² of a grazing h and m up to 1e-7 leave f32).
                let x = if M == L_WARD_ANISO {
                    hard = !t.ok;
                    (slope2(p, &t) / (f.cos_h * f.cos_h)) as f32
                } else {
                    (f.sin2_h / (f.cos_h * f.cos_h) * p.inv_m2) as f32
                };
                let inv_root = (1.0 / (f.cos_i * f.cos_o).sqrt()) as f32;
                p.d_norm_f * exp_neg(-x) * inv_root
            }
        };
        let mut size = lobe.abs();
        for ch in 0..3 {
            let b = p.diffuse[ch] + p.spec[ch] * lobe;
            out.brdf[ch][k] = b;
            size += b.abs();
        }
        out.terms[0][k] = lobe;
        // `<=` is false for NaN: one comparison catches both (see `microfacet_lane`).
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        let bad = !f.ok || hard || !(size <= OUTPUT_LIMIT);
        out.rescue[k] = bad;
    }
}
