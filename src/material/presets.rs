//! Built-in materials. Each preset is written as the TOML a user would write, and parsed by
//! the same code as a materials file, so a preset can never hold what a file could not.
//!
//! Metal data: complex refractive index `n + ik` at the three wavelengths vkbrdf uses for
//! R, G and B: **650 nm, 550 nm and 450 nm**, read (3 significant digits, linear
//! interpolation between tabulated points) from
//! - gold, silver, copper: P. B. Johnson and R. W. Christy, "Optical Constants of the Noble
//!   Metals", Phys. Rev. B 6, 4370 (1972);
//! - aluminium: A. D. Rakić, "Algorithm for the determination of intrinsic optical constants
//!   of metal films: application to aluminum", Appl. Opt. 34, 4755 (1995);
//!
//! both as tabulated by refractiveindex.info. Dielectrics: glass 1.5, water 1.33 (the
//! usual round values; dispersion is ignored).
//!
//! Each of these six has a **spectral form**, `NAME-spectral` (`gold-spectral`, …): the same
//! material with `ior` the shipped measured spectrum (`crate::spectral::datasets`; fused
//! silica for glass), evaluated at any wavelengths with `vkbrdf eval --wavelengths` and,
//! in RGB, through the Mitsuba reduction (FORMULAS.md §9). The plain name keeps the
//! three-wavelength RGB values above.

use super::model::Material;
pub use super::preset_toml::{body, NAMES, SPECTRAL};
use crate::error::MaterialError;

/// A preset as a validated material named `name`.
pub fn preset(name: &str) -> Option<Result<Material, MaterialError>> {
    body(name).map(|b| super::parse::parse_preset(name, &b))
}

/// Every preset, validated, in [`NAMES`] order.
pub fn all() -> Vec<Material> {
    NAMES
        .iter()
        .map(|n| {
            preset(n)
                .expect("listed")
                .expect("presets validate (tested)")
        })
        .collect()
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_spectral_form_is_listed_and_spectral() {
        for name in super::SPECTRAL {
            assert!(super::NAMES.contains(name), "{name}");
            let m = super::preset(name).unwrap().unwrap();
            assert!(m.spectral.is_some(), "{name}");
            let rgb = super::preset(name.trim_end_matches("-spectral"))
                .unwrap()
                .unwrap();
            assert!(rgb.spectral.is_none(), "{name}");
        }
    }

    #[test]
    fn every_preset_validates() {
        for name in super::NAMES {
            let m = super::preset(name).unwrap();
            assert!(m.is_ok(), "{name}: {:?}", m.err());
        }
    }
}
