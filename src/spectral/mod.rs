//! Spectra (FORMULAS.md §9): the CIE observer and D65 ([`cie`]), measured indices of
//! refraction as functions of λ ([`index`], read from refractiveindex.info files by [`rii`],
//! shipped in [`datasets`]), RGB up-sampled to reflectance spectra ([`upsample`]), and the
//! reductions of a spectral index to RGB ([`colour`]). A layer below the materials, which
//! hold these; evaluating at wavelengths is [`crate::spectral_eval`]'s.

pub mod cie;
pub mod colour;
pub mod datasets;
pub mod index;
pub mod keys;
pub mod rii;
pub mod upsample;
pub mod wavelengths;

pub use colour::RgbReduction;
pub use index::{Curve, IndexSpectrum, SpectralIndex};
pub use wavelengths::Wavelengths;
