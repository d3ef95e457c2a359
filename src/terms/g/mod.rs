//! The geometric attenuation terms G of FORMULAS.md §3 (shadowing and masking),
//! dimensionless in [0, 1] (except `smith-fast`, whose published fit peaks at 1.0000613 per
//! direction), one file each. The Smith terms take Λ from the distribution's file.

use super::d::DistributionKind;
use super::family::family;
use super::term::Illegal;

pub mod rules;

family! {
    /// Geometric attenuation G (FORMULAS.md §3). The discriminant is the code of
    /// `GpuMaterial`'s `kind.z` and of the CPU lanes.
    pub enum Geometry {
        /// `G = 1`.
        None = 0 => none, "GEOM_NONE", None;
        /// Blinn's V-cavity, as in the seed and Cook–Torrance.
        CookTorrance = 1 => cook_torrance, "GEOM_COOK_TORRANCE", Some((10, "HAS_G_COOK_TORRANCE"));
        /// Separable Smith `G1(v)·G1(l)`.
        Smith = 2 => smith, "GEOM_SMITH", Some((11, "HAS_G_SMITH"));
        /// Height-correlated Smith `1/(1 + Λ(v) + Λ(l))`.
        SmithCorrelated = 3 => smith_correlated, "GEOM_SMITH_CORRELATED", Some((12, "HAS_G_SMITH_CORRELATED"));
        /// Walter et al. 2007 rational fit of Smith–Beckmann (Beckmann only).
        SmithFast = 4 => smith_fast, "GEOM_SMITH_FAST", Some((13, "HAS_G_SMITH_FAST"));
        /// Schlick 1994 / Karis 2013: separable `G1 = cos/(cos + k(1 − cos))`, k from the
        /// Beckmann or GGX roughness (isotropic only).
        SchlickSmith = 5 => schlick_smith, "GEOM_SCHLICK_SMITH", Some((31, "HAS_G_SCHLICK_SMITH"));
        /// Neubelt & Pettineo 2013 (cloth): `cos_i cos_o/(cos_i + cos_o − cos_i cos_o)`.
        Neubelt = 6 => neubelt, "GEOM_NEUBELT", Some((32, "HAS_G_NEUBELT"));
    }
}

impl Geometry {
    /// Its rules with `distribution` (FORMULAS.md §3): whether this geometry term is
    /// defined for `distribution` (with anisotropic roughness, when `anisotropic`). Each
    /// term's file says its own.
    pub fn legality(
        self,
        distribution: DistributionKind,
        anisotropic: bool,
    ) -> Result<(), Illegal> {
        let rule = match self {
            Geometry::None => none::legality(distribution, anisotropic),
            Geometry::CookTorrance => cook_torrance::legality(distribution, anisotropic),
            Geometry::Smith => smith::legality(distribution, anisotropic),
            Geometry::SmithCorrelated => smith_correlated::legality(distribution, anisotropic),
            Geometry::SmithFast => smith_fast::legality(distribution, anisotropic),
            Geometry::SchlickSmith => schlick_smith::legality(distribution, anisotropic),
            Geometry::Neubelt => neubelt::legality(distribution, anisotropic),
        };
        rule.map_err(|message| Illegal {
            key: "geometry",
            message,
        })
    }
}
