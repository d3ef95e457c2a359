//! The Fresnel terms F of FORMULAS.md §4: each one's parameters, name, kernel code and
//! feature. Their formulas: `reference::fresnel` (f64) and `glsl/terms.glsl`.

use super::Term;
use crate::material::Rgb;

/// Fresnel term F (FORMULAS.md §4), per RGB channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fresnel {
    /// `F = 1`.
    None,
    /// Exact unpolarised dielectric Fresnel with relative IOR `μ`.
    Dielectric {
        /// Relative index of refraction per channel (> 0; < 1 gives total internal reflection).
        ior: Rgb,
    },
    /// Exact conductor Fresnel with complex `η = n + ik`.
    Conductor {
        /// Real part `n` per channel.
        ior: Rgb,
        /// Imaginary part `k` per channel.
        extinction: Rgb,
    },
    /// Schlick's approximation with reflectance at normal incidence `F0`.
    Schlick {
        /// `F0` per channel (given, or derived from `ior`/`extinction` at parse time).
        f0: Rgb,
    },
}

/// A Fresnel term's name without its parameters: what the parser offers and the check
/// matrix enumerates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FresnelKind {
    /// `none`.
    None,
    /// `dielectric`.
    Dielectric,
    /// `conductor`.
    Conductor,
    /// `schlick`.
    Schlick,
}

impl FresnelKind {
    /// Every Fresnel term, in the order the materials help lists them.
    pub const ALL: [FresnelKind; 4] = [
        FresnelKind::None,
        FresnelKind::Dielectric,
        FresnelKind::Conductor,
        FresnelKind::Schlick,
    ];

    /// The Fresnel term's name, kernel code (`GpuMaterial` `kind.w & 0xff`) and feature
    /// (none for `F = 1`, which has no code).
    pub const fn term(self) -> Term {
        match self {
            FresnelKind::None => Term {
                toml_name: "none",
                gpu_code: ("FRESNEL_NONE", 0),
                feature: None,
            },
            FresnelKind::Dielectric => Term {
                toml_name: "dielectric",
                gpu_code: ("FRESNEL_DIELECTRIC", 1),
                feature: Some((14, "HAS_F_DIELECTRIC")),
            },
            FresnelKind::Conductor => Term {
                toml_name: "conductor",
                gpu_code: ("FRESNEL_CONDUCTOR", 2),
                feature: Some((15, "HAS_F_CONDUCTOR")),
            },
            FresnelKind::Schlick => Term {
                toml_name: "schlick",
                gpu_code: ("FRESNEL_SCHLICK", 3),
                feature: Some((16, "HAS_F_SCHLICK")),
            },
        }
    }

    /// The spelling in a materials file (`fresnel = "..."`).
    pub fn toml_name(self) -> &'static str {
        self.term().toml_name
    }

    /// The Fresnel term a materials file names, if any.
    pub fn from_toml_name(name: &str) -> Option<FresnelKind> {
        FresnelKind::ALL.into_iter().find(|f| f.toml_name() == name)
    }
}

impl Fresnel {
    /// The Fresnel term's name without its parameters.
    pub fn kind(&self) -> FresnelKind {
        match self {
            Fresnel::None => FresnelKind::None,
            Fresnel::Dielectric { .. } => FresnelKind::Dielectric,
            Fresnel::Conductor { .. } => FresnelKind::Conductor,
            Fresnel::Schlick { .. } => FresnelKind::Schlick,
        }
    }
}
