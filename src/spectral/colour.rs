//! The two common ways to give a spectral index an RGB form (FORMULAS.md §9), for a
//! spectral material evaluated in RGB:
//! - **Mitsuba 3's**: `n(λ)` and `k(λ)` each reduced to linear sRGB on their own with
//!   equal-energy weighting, negatives clamped to 0, then the exact Fresnel with those;
//! - **Filament's** (its `specular-color` tool): `F0(λ)` reduced to linear sRGB under D65,
//!   then Schlick with that F0.

use super::cie::{self, Illuminant, SAMPLES};
use super::index::{Curve, IndexSpectrum};
use crate::terms::Fresnel;

/// Which reduction gives a spectral material its RGB form.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum RgbReduction {
    /// n and k reduced separately (equal energy), then the exact Fresnel term.
    #[default]
    Mitsuba,
    /// F0 reduced under D65, then Schlick.
    Filament,
}

impl RgbReduction {
    /// Both, in the order reports list them.
    pub const ALL: [RgbReduction; 2] = [RgbReduction::Mitsuba, RgbReduction::Filament];

    /// The name in a materials file (`rgb = "mitsuba"`) and in reports.
    pub fn name(self) -> &'static str {
        match self {
            RgbReduction::Mitsuba => "mitsuba",
            RgbReduction::Filament => "filament",
        }
    }

    /// The reduction named `name`.
    pub fn from_name(name: &str) -> Option<RgbReduction> {
        Self::ALL.into_iter().find(|r| r.name() == name)
    }
}

/// `f(λ)` on the CIE grid, or the first wavelength where it fails.
fn on_grid(f: impl Fn(f64) -> Result<f64, String>) -> Result<Vec<f64>, String> {
    (0..SAMPLES).map(|i| f(cie::wavelength(i))).collect()
}

/// Mitsuba's RGB `(n, k)` of a spectral index.
pub fn mitsuba(index: &IndexSpectrum) -> Result<([f64; 3], [f64; 3]), String> {
    let n = on_grid(|nm| index.at(nm).map(|p| p.0))?;
    let k = on_grid(|nm| index.at(nm).map(|p| p.1))?;
    let rgb = |v: &[f64]| cie::to_srgb(v, Illuminant::E).map(|x| x.max(0.0));
    Ok((rgb(&n), rgb(&k)))
}

/// Filament's RGB `F0` of a spectral index (linear sRGB, unclamped: gold's red is above 1).
pub fn filament_f0(index: &IndexSpectrum) -> Result<[f64; 3], String> {
    Ok(cie::to_srgb(&on_grid(|nm| index.f0(nm))?, Illuminant::D65))
}

/// The RGB Fresnel term a spectral index gives `kind` under `reduction` (FORMULAS.md §9):
/// Mitsuba's reduced (n, k) with the exact term, or Filament's D65 F0 with Schlick
/// (clamped to [0, 1]: a Schlick F0 is a reflectance).
pub fn rgb_fresnel(
    kind: crate::terms::FresnelKind,
    index: &IndexSpectrum,
    reduction: RgbReduction,
) -> Result<Fresnel, String> {
    use crate::terms::FresnelKind as K;
    let positive = |v: [f64; 3]| v.map(|x| x.max(1e-6));
    Ok(match (reduction, kind) {
        (_, K::None) => Fresnel::None,
        (RgbReduction::Mitsuba, K::Dielectric) => Fresnel::Dielectric {
            ior: positive(mitsuba(index)?.0),
        },
        (RgbReduction::Mitsuba, K::Conductor) => {
            let (n, k) = mitsuba(index)?;
            Fresnel::Conductor {
                ior: positive(n),
                extinction: k,
            }
        }
        (RgbReduction::Mitsuba, K::Schlick) => {
            let (n, k) = mitsuba(index)?;
            Fresnel::Schlick {
                f0: crate::terms::f::schlick::f0_from_ior(positive(n), k),
            }
        }
        (RgbReduction::Filament, _) => {
            // A dielectric reads n only (FORMULAS.md §9).
            let mut i = index.clone();
            if kind == K::Dielectric {
                i.k = Curve::Constant(0.0);
            }
            Fresnel::Schlick {
                f0: filament_f0(&i)?.map(|x| x.clamp(0.0, 1.0)),
            }
        }
    })
}
