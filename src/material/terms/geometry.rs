//! The geometric attenuation terms G of FORMULAS.md §3: each one's name, kernel code and
//! feature. Their formulas: `reference::geometry` (f64) and `glsl/terms.glsl`; the rules
//! that combine them with a distribution: [`super::legality`].

use super::{DistributionKind, Illegal, Term};

/// Geometric attenuation G (FORMULAS.md §3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Geometry {
    /// `G = 1`.
    None,
    /// Blinn's V-cavity, as in the seed and Cook–Torrance.
    CookTorrance,
    /// Separable Smith `G1(v)·G1(l)`.
    Smith,
    /// Height-correlated Smith `1/(1 + Λ(v) + Λ(l))`.
    SmithCorrelated,
    /// Walter et al. 2007 rational fit of Smith–Beckmann (Beckmann only).
    SmithFast,
    /// Schlick 1994 / Karis 2013: separable `G1 = cos/(cos + k(1 − cos))`, k from the
    /// Beckmann or GGX roughness (isotropic only).
    SchlickSmith,
    /// Neubelt & Pettineo 2013 (cloth): `cos_i cos_o/(cos_i + cos_o − cos_i cos_o)`.
    Neubelt,
}

impl Geometry {
    /// The geometry term's name, kernel code (`GpuMaterial` `kind.z`) and feature (none
    /// for `G = 1`, which has no code).
    pub const fn term(self) -> Term {
        match self {
            Geometry::None => Term {
                toml_name: "none",
                gpu_code: ("GEOM_NONE", 0),
                feature: None,
            },
            Geometry::CookTorrance => Term {
                toml_name: "cook-torrance",
                gpu_code: ("GEOM_COOK_TORRANCE", 1),
                feature: Some((10, "HAS_G_COOK_TORRANCE")),
            },
            Geometry::Smith => Term {
                toml_name: "smith",
                gpu_code: ("GEOM_SMITH", 2),
                feature: Some((11, "HAS_G_SMITH")),
            },
            Geometry::SmithCorrelated => Term {
                toml_name: "smith-correlated",
                gpu_code: ("GEOM_SMITH_CORRELATED", 3),
                feature: Some((12, "HAS_G_SMITH_CORRELATED")),
            },
            Geometry::SmithFast => Term {
                toml_name: "smith-fast",
                gpu_code: ("GEOM_SMITH_FAST", 4),
                feature: Some((13, "HAS_G_SMITH_FAST")),
            },
            Geometry::SchlickSmith => Term {
                toml_name: "schlick-smith",
                gpu_code: ("GEOM_SCHLICK_SMITH", 5),
                feature: Some((31, "HAS_G_SCHLICK_SMITH")),
            },
            Geometry::Neubelt => Term {
                toml_name: "neubelt",
                gpu_code: ("GEOM_NEUBELT", 6),
                feature: Some((32, "HAS_G_NEUBELT")),
            },
        }
    }

    /// Its rules with `distribution` (FORMULAS.md §3): whether this geometry term is
    /// defined for `distribution` (with anisotropic roughness, when `anisotropic`).
    pub fn legality(
        self,
        distribution: DistributionKind,
        anisotropic: bool,
    ) -> Result<(), Illegal> {
        let d = distribution.toml_name();
        let g = self.toml_name();
        let illegal = |message: String| {
            Err(Illegal {
                key: "geometry",
                message,
            })
        };
        let smith = matches!(
            self,
            Geometry::Smith | Geometry::SmithCorrelated | Geometry::SmithFast
        );
        let without_lambda = !distribution.has_lambda();
        if smith && without_lambda {
            return illegal(format!("Smith G needs a Λ for the distribution, and `{d}` has none; use `cook-torrance`, `neubelt` or `none`, or distribution `beckmann`/`ggx`"));
        }
        if self == Geometry::SchlickSmith && without_lambda {
            return illegal(format!("`schlick-smith` takes its k from a Beckmann or GGX roughness, and `{d}` has none; use `cook-torrance`, `neubelt` or `none`, or distribution `beckmann`/`ggx`"));
        }
        if self == Geometry::SmithFast && distribution != DistributionKind::Beckmann {
            return illegal("`smith-fast` is a fit of Smith–Beckmann (Beckmann only); use `smith` or `smith-correlated` with ggx".into());
        }
        if self == Geometry::SchlickSmith && anisotropic {
            return illegal(format!("`{g}` is defined for isotropic roughness only; give one roughness, or use `smith` or `smith-correlated`"));
        }
        Ok(())
    }

    /// The spelling in a materials file (`geometry = "..."`).
    pub fn toml_name(self) -> &'static str {
        self.term().toml_name
    }

    /// Every geometry term, in the order the materials help lists them.
    pub const ALL: [Geometry; 7] = [
        Geometry::None,
        Geometry::CookTorrance,
        Geometry::Smith,
        Geometry::SmithCorrelated,
        Geometry::SmithFast,
        Geometry::SchlickSmith,
        Geometry::Neubelt,
    ];

    /// The geometry term a materials file names, if any.
    pub fn from_toml_name(name: &str) -> Option<Geometry> {
        Geometry::ALL.into_iter().find(|g| g.toml_name() == name)
    }
}
