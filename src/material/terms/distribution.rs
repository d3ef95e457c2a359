//! The microfacet distributions D of FORMULAS.md §2: each one's parameter, name, range,
//! kernel code and feature. Their formulas: `reference::distribution` (f64) and
//! `glsl/terms.glsl`; the rules that combine them with a geometry: [`super::legality`].

use super::{Convention, Illegal, Term};
use crate::material::Roughness;

/// Microfacet distribution D (FORMULAS.md §2) with its parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Distribution {
    /// Torrance–Sparrow 1967 Gaussian `exp(-(δ/m)²)` (isotropic only).
    Gaussian {
        /// Width `m > 0` (radians).
        m: f64,
    },
    /// Beckmann, normalised by the convention's `k`; anisotropic in `modern` only.
    Beckmann(Roughness),
    /// GGX / Trowbridge–Reitz; anisotropic in `modern` only.
    Ggx(Roughness),
    /// Normalised Blinn–Phong NDF `(e+2)/(2π) cos_h^e`.
    Blinn {
        /// Exponent `e ≥ 0`.
        exponent: f64,
    },
    /// Estevez & Kulla 2017 sheen ("cloth"), `(2 + 1/m)/(2π) sin_h^(1/m)` (isotropic only).
    Charlie {
        /// `0 < m ≤ 1`: the paper's α = r², not an rms slope.
        m: f64,
    },
}

/// A distribution's name without its parameter (FORMULAS.md §2): what the legality rules
/// read, and what the check matrix and the test strategies enumerate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DistributionKind {
    /// `gaussian`.
    Gaussian,
    /// `beckmann`.
    Beckmann,
    /// `ggx`.
    Ggx,
    /// `blinn`.
    Blinn,
    /// `charlie`.
    Charlie,
}

impl DistributionKind {
    /// Every distribution, in the order the materials help lists them.
    pub const ALL: [DistributionKind; 5] = [
        DistributionKind::Gaussian,
        DistributionKind::Beckmann,
        DistributionKind::Ggx,
        DistributionKind::Blinn,
        DistributionKind::Charlie,
    ];

    /// The distribution's name, kernel code (`GpuMaterial` `kind.y`) and feature.
    pub const fn term(self) -> Term {
        match self {
            DistributionKind::Gaussian => Term {
                toml_name: "gaussian",
                gpu_code: ("DIST_GAUSSIAN", 1),
                feature: Some((6, "HAS_D_GAUSSIAN")),
            },
            DistributionKind::Beckmann => Term {
                toml_name: "beckmann",
                gpu_code: ("DIST_BECKMANN", 2),
                feature: Some((7, "HAS_D_BECKMANN")),
            },
            DistributionKind::Ggx => Term {
                toml_name: "ggx",
                gpu_code: ("DIST_GGX", 3),
                feature: Some((8, "HAS_D_GGX")),
            },
            DistributionKind::Blinn => Term {
                toml_name: "blinn",
                gpu_code: ("DIST_BLINN", 4),
                feature: Some((9, "HAS_D_BLINN")),
            },
            DistributionKind::Charlie => Term {
                toml_name: "charlie",
                gpu_code: ("DIST_CHARLIE", 5),
                feature: Some((30, "HAS_D_CHARLIE")),
            },
        }
    }

    /// The spelling in a materials file (`distribution = "..."`).
    pub fn toml_name(self) -> &'static str {
        self.term().toml_name
    }

    /// The distribution a materials file names, if any.
    pub fn from_toml_name(name: &str) -> Option<DistributionKind> {
        DistributionKind::ALL
            .into_iter()
            .find(|d| d.toml_name() == name)
    }

    /// Whether its parameter is `exponent` (blinn) rather than `roughness`.
    pub fn takes_exponent(self) -> bool {
        self == DistributionKind::Blinn
    }

    /// The distribution of this kind with roughness `r`, when it takes one (not `blinn`) and
    /// `r` is legal for it (see [`legality`](super::legality): gaussian and charlie are isotropic only).
    pub fn with_roughness(self, r: Roughness) -> Option<Distribution> {
        match (self, r) {
            (DistributionKind::Beckmann, r) => Some(Distribution::Beckmann(r)),
            (DistributionKind::Ggx, r) => Some(Distribution::Ggx(r)),
            (DistributionKind::Gaussian, Roughness::Isotropic(m)) => {
                Some(Distribution::Gaussian { m })
            }
            (DistributionKind::Charlie, Roughness::Isotropic(m)) => {
                Some(Distribution::Charlie { m })
            }
            _ => None,
        }
    }

    /// Whether it has Smith's Λ (and a Beckmann or GGX roughness), which the Smith and
    /// Schlick–Smith geometry terms need ([`Geometry::legality`](super::Geometry::legality)).
    pub fn has_lambda(self) -> bool {
        matches!(self, DistributionKind::Beckmann | DistributionKind::Ggx)
    }

    /// Its own rule (FORMULAS.md §2), whatever the geometry: whether anisotropic roughness
    /// (when `anisotropic`) is defined for it in `convention`.
    pub fn legality(self, convention: Convention, anisotropic: bool) -> Result<(), Illegal> {
        use DistributionKind as D;
        let d = self.toml_name();
        let illegal = |message: String| {
            Err(Illegal {
                key: "roughness",
                message,
            })
        };
        if !anisotropic {
            return Ok(());
        }
        match self {
            D::Beckmann | D::Ggx if convention != Convention::Modern => illegal(format!(
                "anisotropic `{d}` exists in the `modern` convention only"
            )),
            D::Beckmann | D::Ggx => Ok(()),
            D::Blinn => illegal("distribution `blinn` takes an `exponent`, not a roughness".into()),
            D::Gaussian | D::Charlie => illegal(format!(
                "distribution `{d}` is isotropic only; give one number"
            )),
        }
    }

    /// The largest roughness the formula is defined for (FORMULAS.md §2): `charlie`'s m is
    /// the paper's α = r² ≤ 1; the others are bounded only by the parser's general range.
    pub fn max_roughness(self) -> Option<f64> {
        (self == DistributionKind::Charlie).then_some(1.0)
    }
}

impl Distribution {
    /// The distribution's name without its parameter.
    pub fn kind(&self) -> DistributionKind {
        match self {
            Distribution::Gaussian { .. } => DistributionKind::Gaussian,
            Distribution::Beckmann(_) => DistributionKind::Beckmann,
            Distribution::Ggx(_) => DistributionKind::Ggx,
            Distribution::Blinn { .. } => DistributionKind::Blinn,
            Distribution::Charlie { .. } => DistributionKind::Charlie,
        }
    }

    /// Its name and parameter as `vkbrdf materials` lists them (`ggx m=0.3`, `blinn e=50`).
    pub fn describe(&self) -> String {
        match *self {
            Distribution::Gaussian { m } => format!("gaussian m={m}"),
            Distribution::Beckmann(r) => format!("beckmann {}", r.describe()),
            Distribution::Ggx(r) => format!("ggx {}", r.describe()),
            Distribution::Blinn { exponent } => format!("blinn e={exponent}"),
            Distribution::Charlie { m } => format!("charlie m={m}"),
        }
    }

    /// The angular width of its lobe (radians), where `vkbrdf check` aims half vectors.
    pub fn lobe_width(&self) -> f64 {
        match *self {
            Distribution::Gaussian { m } => m,
            Distribution::Beckmann(r) | Distribution::Ggx(r) => r.xy().0.max(r.xy().1),
            Distribution::Blinn { exponent } => exponent_lobe_width(exponent),
            // Sheen peaks at grazing h (sin_h = 1): aimed anywhere, i.e. uniformly.
            Distribution::Charlie { .. } => 1.0,
        }
    }
}

/// The angular width (radians) of a lobe `cos^e`: `sqrt(2/(e + 2))`.
pub fn exponent_lobe_width(e: f64) -> f64 {
    (2.0 / (e + 2.0)).sqrt()
}
