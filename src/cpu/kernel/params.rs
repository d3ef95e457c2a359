//! A material's constants as the lanes read them ([`Params`]).

use crate::terms::f::conductor;
use crate::terms::k::LaneK;

/// The constants of one material, prepared once per batch (in f64 where the lanes use
/// f64, then rounded once).
#[derive(Debug, Clone, Copy, Default)]
pub struct Params {
    /// `d · c_diff / π` (Lambert: `c_diff / π`).
    pub diffuse: [f32; 3],
    /// `s · c_spec`.
    pub spec: [f32; 3],
    /// `m²`.
    pub m2: f64,
    /// `1/m²`.
    pub inv_m2: f64,
    /// The D normalisation: `1/(k m²)` for Beckmann, `m²/π` for GGX.
    pub d_norm: f64,
    /// `m²`, `1/m²` and the D normalisation rounded to f32, for the f32 frame's D.
    pub m2_f: f32,
    /// See `m2_f`.
    pub inv_m2_f: f32,
    /// m rounded to f32 (smith-fast's `a = cos/(m sin)`).
    pub m_f: f32,
    /// See `m2_f`.
    pub d_norm_f: f32,
    /// Beckmann's f32 D: the argument of `exp` below which it is 0
    /// (`beckmann::lane_exp_floor`).
    pub d_exp_floor: f32,
    /// GGX's test of the local form's f32 frame (`ggx::local_frame_guard`).
    pub ggx_local_guard: f32,
    /// K (the convention's lane form).
    pub k: LaneK,
    /// Schlick's F0.
    pub f0: [f32; 3],
    /// Dielectric μ.
    pub ior: [f64; 3],
    /// Dielectric `μ² − 1`, as `(μ − 1)(μ + 1)`.
    pub mu2m1: [f64; 3],
    /// The conductor's constants.
    pub conductor: conductor::LaneConstants,
    /// The conductor's fitted polynomial, where the f32 lanes take it
    /// ([`conductor::poly::Polynomial::fit`]; `None` for every other material).
    pub conductor_poly: Option<conductor::poly::Polynomial>,
    /// The conductor's segment tables, where the f32 lanes take them instead of the
    /// polynomial ([`conductor::segments::Segments::fit`]: on AVX-512, whose permutes look
    /// them up; `None` for every other material and instruction set).
    pub conductor_segments: Option<conductor::segments::Segments>,
    /// Whether the caller asked for the terms (D, G, F, K): without them the lanes form
    /// D·G·K over one division and never divide out the terms (see `finish_lane`).
    pub terms: bool,
    /// Whether [`microfacet_block`](super::microfacet_block) leaves the lanes its f32 frame cannot serve to the
    /// caller ([`Outputs::slow`](super::Outputs::slow)), which gathers them from many blocks into blocks of the
    /// f64 frame, instead of running the f64 frame over its whole block for them.
    pub defer_slow: bool,
    /// Whether GGX's lanes with N = +z take the general f32 frame (`frame::frame`) rather than
    /// the local one (`frame_local32`): what the register path's refused lanes are
    /// gathered into (`Plan::general_frame_only`).
    pub general_frame_only: bool,
    /// Whether the material may take the f32 frame (see [`microfacet_block`](super::microfacet_block)): m ≥
    /// [`FAST_MIN_ROUGHNESS`](super::FAST_MIN_ROUGHNESS) and a Fresnel term other than the dielectric (whose f64
    /// evaluation near total internal reflection wants the f64 `c`).
    pub fast_frame: bool,
    /// The exponent of a `cos^e` lobe: Blinn's and the empirical models' `e`, Charlie's
    /// `1/m`.
    pub exponent: f32,
    /// Schlick–Smith's k (Karis 2013: `m/2` GGX, `m √(2/π)` Beckmann).
    pub schlick_k: f32,
    /// Anisotropic roughness `[1/mx², 1/my², mx², my²]`.
    pub aniso: [f64; 4],
}

impl Params {
    /// The lane form of the conductor's F on the f32 frames' lanes (`conductor::FORM_*`):
    /// the segment tables where the plan took them, else the polynomial where it fitted
    /// one, else the metal form (as its quotient where
    /// every channel's `Re η²` is negative), else the scaled form.
    pub fn conductor_form(&self) -> u8 {
        if self.conductor_segments.is_some() {
            conductor::FORM_TABLES
        } else if self.conductor_poly.is_some() {
            conductor::FORM_POLY
        } else if self.conductor.metal_quotient {
            conductor::FORM_QUOTIENT
        } else if self.conductor.metal {
            conductor::FORM_METAL
        } else {
            conductor::FORM_SCALED
        }
    }

    /// The conductor's polynomial ([`Params::conductor_poly`]), or zeros where there is
    /// none (a lane form asks for it only where there is one).
    #[inline(always)]
    pub fn conductor_poly(&self) -> &conductor::poly::Polynomial {
        self.conductor_poly
            .as_ref()
            .unwrap_or(&conductor::poly::Polynomial::NONE)
    }
}
