//! The Fresnel terms F of FORMULAS.md §4 at `c = v·h`, one channel at a time, one file each.

use super::family::family;
use super::term::Rgb;

family! {
    /// A Fresnel term's name without its parameters: what the parser offers and the check
    /// matrix enumerates. The discriminant is the code of `GpuMaterial`'s `kind.w & 0xff`
    /// and of the CPU lanes.
    pub enum FresnelKind {
        /// `none`.
        None = 0 => none, "FRESNEL_NONE", None;
        /// `dielectric`.
        Dielectric = 1 => dielectric, "FRESNEL_DIELECTRIC", Some((14, "HAS_F_DIELECTRIC"));
        /// `conductor`.
        Conductor = 2 => conductor, "FRESNEL_CONDUCTOR", Some((15, "HAS_F_CONDUCTOR"));
        /// `schlick`.
        Schlick = 3 => schlick, "FRESNEL_SCHLICK", Some((16, "HAS_F_SCHLICK"));
    }
}

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
