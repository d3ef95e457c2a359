//! How the engine evaluates a material group ([`Plan`]): which lanes, with which
//! constants, prepared once per batch from the material (in f64 where the lanes use f64,
//! then rounded once). Below the engine's dispatch (`cpu::block`), above the lanes.

use super::isa::Isa;
use super::kernel::{Params, FAST_MIN_ROUGHNESS};
use crate::material::{Distribution, Fresnel, Material, Model, Roughness};
use crate::terms::d::{beckmann, blinn, charlie, ggx};
use crate::terms::f::{conductor, dielectric, schlick};
use crate::terms::g::schlick_smith;
use crate::terms::{DistributionKind, FresnelKind, Geometry};
use std::f64::consts::PI;

/// How a material group is evaluated.
#[derive(Debug, Clone, Copy)]
pub enum Plan {
    /// Lambert in the lanes.
    Lambert(Params),
    /// Cook–Torrance in the lanes.
    Microfacet {
        /// The distribution.
        d: DistributionKind,
        /// Whether its roughness is anisotropic (GGX and Beckmann: the tangent frame,
        /// `src/cpu/aniso.rs`).
        aniso: bool,
        /// The geometry term.
        g: Geometry,
        /// The Fresnel term.
        f: FresnelKind,
        /// The material's constants.
        p: Params,
    },
    /// One of the empirical lobe models (Phong, Blinn–Phong, RTR, isotropic Ward) in the
    /// lanes ([`super::lobes`]).
    Lobe {
        /// The lobe model ([`crate::cpu::lobes::Lobe`]).
        model: crate::cpu::lobes::Lobe,
        /// The material's constants.
        p: Params,
    },
    /// An HTSG material in the lanes ([`crate::cpu::htsg`]); `p` holds its diffuse `a/π`
    /// and the conductor's constants.
    Htsg {
        /// The diffuse and conductor constants.
        p: Params,
        /// The model's own constants.
        h: crate::terms::htsg::LaneConstants,
    },
    /// A measured (MERL) material: the half/difference angles in f64 lanes, then the
    /// table lookup (`src/cpu/measured.rs`; the data is the material's).
    Measured,
    /// Every tuple through the f64 reference.
    Reference,
}

/// GGX's test of the local f32 frame (`ggx::local_frame_guard_for_f`) with D's budget
/// what F's lane form leaves of the metal form's 48u: F = 1 0u, Schlick's written bound
/// (`schlick::LANE_BOUND_U`), the conductor's fitted polynomial its own bound, any other
/// form the whole 48u.
fn ggx_guard(p: &Params, f: FresnelKind) -> f32 {
    let f_u = match f {
        FresnelKind::None => 0.0,
        FresnelKind::Schlick => schlick::LANE_BOUND_U,
        FresnelKind::Conductor => match (&p.conductor_segments, &p.conductor_poly) {
            (Some(tables), _) => tables.bound_u,
            (None, Some(poly)) => poly.bound_u,
            (None, None) => conductor::METAL_FORM_BUDGET,
        },
        FresnelKind::Dielectric => conductor::METAL_FORM_BUDGET,
    };
    ggx::local_frame_guard_for_f(p.m2, f_u)
}

/// Beckmann's [`beckmann::lane_exp_floor`] for the material of `p` and its Fresnel term
/// (F's largest: 1, or a Schlick F0 above 1).
fn beckmann_exp_floor(p: &Params, f: &Fresnel) -> f32 {
    let max3 = |a: [f64; 3]| a.into_iter().fold(0.0f64, f64::max);
    let spec_max = max3(p.spec.map(f64::from));
    let f_max = match f {
        Fresnel::Schlick { f0 } => max3(*f0),
        _ => 1.0,
    };
    beckmann::lane_exp_floor(p.d_norm, spec_max, f_max)
}

fn f32x3(a: [f64; 3]) -> [f32; 3] {
    a.map(|x| x as f32)
}

impl Plan {
    /// The plan for `m`: the lanes for Lambert and for isotropic Cook–Torrance with GGX or
    /// Beckmann (any geometry, Fresnel and convention), the reference for everything else.
    pub fn for_material(m: &Material) -> Plan {
        let mut p = Params {
            diffuse: f32x3(m.diffuse.map(|c| c / PI)),
            spec: f32x3(m.specular),
            ..Params::default()
        };
        let ct = match &m.model {
            Model::Lambert => return Plan::Lambert(p),
            Model::CookTorrance(ct) => ct,
            Model::Measured(_) => return Plan::Measured,
            Model::Htsg(h) => {
                p.conductor = conductor::LaneConstants::new(h.ior, h.extinction);
                return Plan::Htsg {
                    p,
                    h: crate::terms::htsg::LaneConstants::new(h),
                };
            }
            _ => {
                return match crate::cpu::lobes::params(m, p) {
                    Some((model, p)) => Plan::Lobe { model, p },
                    None => Plan::Reference,
                }
            }
        };
        // m for the distributions with an rms slope (0 for Blinn; Charlie's m is not one).
        let d = ct.distribution.kind();
        let mut aniso = false;
        let mr = match ct.distribution {
            Distribution::Ggx(Roughness::Isotropic(mr))
            | Distribution::Beckmann(Roughness::Isotropic(mr)) => mr,
            Distribution::Gaussian { m } => {
                p.inv_m2_f = (1.0 / (m * m)) as f32;
                m
            }
            Distribution::Blinn { exponent } => {
                p.exponent = exponent as f32;
                p.d_norm_f = blinn::norm(exponent) as f32;
                0.0
            }
            Distribution::Charlie { m } => {
                p.exponent = (1.0 / m) as f32;
                p.d_norm_f = charlie::norm(m) as f32;
                0.0
            }
            // Anisotropic GGX and Beckmann (modern convention only): D's normalisation
            // 1/(π mx my) for both.
            Distribution::Ggx(Roughness::Anisotropic(mx, my))
            | Distribution::Beckmann(Roughness::Anisotropic(mx, my)) => {
                p.aniso = crate::cpu::aniso::roughness(mx, my);
                p.d_norm = 1.0 / (PI * mx * my);
                aniso = true;
                0.0
            }
        };
        // The rms-slope distributions' constants; the others set theirs above.
        let slope = !aniso && matches!(d, DistributionKind::Ggx | DistributionKind::Beckmann);
        p.diffuse = f32x3(m.diffuse.map(|c| ct.diffuse_weight * c / PI));
        p.spec = f32x3(m.specular.map(|c| ct.specular_weight * c));
        if slope {
            p.m2 = mr * mr;
            p.inv_m2 = 1.0 / p.m2;
            p.d_norm = match d {
                DistributionKind::Ggx => p.m2 / PI,
                _ => 1.0 / (ct.convention.beckmann_k() * p.m2),
            };
        }
        p.k = ct.convention.lane_k();
        let g = ct.geometry;
        if g == Geometry::SchlickSmith {
            // The parser allows it with isotropic GGX and Beckmann only.
            p.schlick_k = schlick_smith::k(d == DistributionKind::Ggx, mr) as f32;
        }
        match ct.fresnel {
            Fresnel::None => {}
            Fresnel::Schlick { f0 } => p.f0 = f32x3(f0),
            Fresnel::Dielectric { ior } => {
                p.ior = ior;
                p.mu2m1 = ior.map(dielectric::mu2m1);
            }
            Fresnel::Conductor { ior, extinction } => {
                p.conductor = conductor::LaneConstants::new(ior, extinction);
            }
        }
        let f = ct.fresnel.kind();
        p.fast_frame = slope && mr >= FAST_MIN_ROUGHNESS && f != FresnelKind::Dielectric;
        if slope {
            (p.m2_f, p.inv_m2_f, p.d_norm_f) = (p.m2 as f32, p.inv_m2 as f32, p.d_norm as f32);
            p.m_f = mr as f32;
            p.ggx_local_guard = ggx_guard(&p, f);
            p.d_exp_floor = beckmann_exp_floor(&p, &ct.fresnel);
        }
        Plan::Microfacet { d, aniso, g, f, p }
    }

    /// The plan whose microfacet blocks leave the lanes their f32 frame cannot serve to the
    /// caller ([`Params::defer_slow`]).
    pub fn with_deferred_slow(mut self) -> Plan {
        if let Plan::Microfacet { p, .. } = &mut self {
            p.defer_slow = true;
        }
        self
    }

    /// The plan with the conductor's F as its fitted polynomial on the f32 frames' lanes
    /// (`conductor::poly`), where material `m` (this plan's) has one within the metal
    /// form's budget and the engine runs on `isa` = AVX-512 or AVX2+FMA, and GGX's
    /// certificate with the budget F then leaves (`ggx::local_frame_guard_for_f`). On
    /// AVX-512 its FMAs read the coefficients as broadcast operands and it is 7–11 % faster
    /// than the metal form; on AVX2 as fast, with fewer lanes left to another frame and F
    /// 1.4–6.6u off instead of 3.9–8u (docs/CPU_ENGINE.md). `scalar` keeps the metal form.
    /// On AVX-512 the segment tables (`conductor::segments`) take the polynomial's place
    /// where they fit: 5 multiply-adds and 6 permutes a channel instead of 14
    /// multiply-adds, and F within ~3.5u instead of 5–21u (round 22).
    pub fn with_conductor_poly(mut self, m: &Material, isa: Isa) -> Plan {
        if let (Plan::Microfacet { p, f, .. }, Model::CookTorrance(ct)) = (&mut self, &m.model) {
            if let Fresnel::Conductor { ior, extinction } = ct.fresnel {
                if isa != Isa::Scalar && p.fast_frame && p.conductor.metal {
                    if isa == Isa::Avx512 {
                        p.conductor_segments =
                            conductor::segments::Segments::fitted(ior, extinction);
                    }
                    // Where the tables are taken no lane reads the polynomial.
                    if p.conductor_segments.is_none() {
                        p.conductor_poly = conductor::poly::Polynomial::fitted(ior, extinction);
                    }
                    p.ggx_local_guard = ggx_guard(p, *f);
                }
            }
        }
        self
    }

    /// The plan with the general f32 frame in every lane of the f32 frame, and no lane left
    /// to the caller: what a lane whose local f32 frame D's certificate refused takes
    /// (`kernel::Params::general_frame_only`).
    pub fn general_frame_only(mut self) -> Plan {
        if let Plan::Microfacet { p, .. } = &mut self {
            p.general_frame_only = true;
            p.defer_slow = false;
        }
        self
    }

    /// The plan with the f64 frame in every lane: what a deferred lane takes.
    pub fn f64_frame(mut self) -> Plan {
        if let Plan::Microfacet { p, .. } = &mut self {
            p.fast_frame = false;
        }
        self
    }

    /// The plan with the terms (D, G, F, K) formed in the lanes when `terms` (see
    /// [`Params::terms`]); without them the microfacet lanes never divide them out.
    pub fn with_terms(mut self, terms: bool) -> Plan {
        if let Plan::Microfacet { p, .. } = &mut self {
            p.terms = terms;
        }
        self
    }

    /// Whether the plan runs in the lanes.
    pub fn is_simd(&self) -> bool {
        !matches!(self, Plan::Reference)
    }

    /// Whether the plan reads the tangent (anisotropic roughness): rows without tangent
    /// columns then go to the reference, which counts them invalid.
    pub fn needs_tangent(&self) -> bool {
        match self {
            Plan::Microfacet { aniso, .. } => *aniso,
            Plan::Lobe { model, .. } => *model == crate::cpu::lobes::Lobe::WardAniso,
            _ => false,
        }
    }
}
