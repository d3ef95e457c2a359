//! The microfacet distributions D of FORMULAS.md §2, one file each. Each returns D in 1/sr
//! (the normalised forms satisfy `∫ D cos_h dω_h = 1`); none includes G, F or the
//! 1/(4 cos cos) factor. Smith's Λ belongs to the distribution (Heitz 2014), so the two
//! that have one (Beckmann, GGX) define it in their file too.

use super::family::family;
use super::k::Convention;
use super::term::Illegal;

pub mod rules;

family! {
    /// A distribution's name without its parameter (FORMULAS.md §2): what the legality rules
    /// read, and what the check matrix and the test strategies enumerate. The discriminant
    /// is the code of `GpuMaterial`'s `kind.y` and of the CPU lanes.
    pub enum DistributionKind {
        /// `gaussian`.
        Gaussian = 1 => gaussian, "DIST_GAUSSIAN", Some((6, "HAS_D_GAUSSIAN"));
        /// `beckmann`.
        Beckmann = 2 => beckmann, "DIST_BECKMANN", Some((7, "HAS_D_BECKMANN"));
        /// `ggx`.
        Ggx = 3 => ggx, "DIST_GGX", Some((8, "HAS_D_GGX"));
        /// `blinn`.
        Blinn = 4 => blinn, "DIST_BLINN", Some((9, "HAS_D_BLINN"));
        /// `charlie`.
        Charlie = 5 => charlie, "DIST_CHARLIE", Some((30, "HAS_D_CHARLIE"));
    }
}

/// Roughness `m > 0` (rms slope; GGX calls it α), isotropic or per tangent axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Roughness {
    /// One `m` for every direction.
    Isotropic(f64),
    /// `[mx, my]` along the tangent `t` and bitangent `b`.
    Anisotropic(f64, f64),
}

impl Roughness {
    /// `(mx, my)`, equal for an isotropic roughness.
    pub fn xy(self) -> (f64, f64) {
        match self {
            Roughness::Isotropic(m) => (m, m),
            Roughness::Anisotropic(x, y) => (x, y),
        }
    }
    /// Whether the roughness is given per axis (needs a tangent).
    pub fn is_anisotropic(self) -> bool {
        matches!(self, Roughness::Anisotropic(..))
    }

    /// As `vkbrdf materials` lists it: `m=0.3` or `m=[0.1, 0.4]`.
    pub fn describe(self) -> String {
        match self {
            Roughness::Isotropic(m) => format!("m={m}"),
            Roughness::Anisotropic(x, y) => format!("m=[{x}, {y}]"),
        }
    }
}

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

impl DistributionKind {
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
        match self {
            DistributionKind::Gaussian => gaussian::HAS_LAMBDA,
            DistributionKind::Beckmann => beckmann::HAS_LAMBDA,
            DistributionKind::Ggx => ggx::HAS_LAMBDA,
            DistributionKind::Blinn => blinn::HAS_LAMBDA,
            DistributionKind::Charlie => charlie::HAS_LAMBDA,
        }
    }

    /// Its own rule (FORMULAS.md §2), whatever the geometry: whether anisotropic roughness
    /// (when `anisotropic`) is defined for it in `convention`. Each term's file says its own.
    pub fn legality(self, convention: Convention, anisotropic: bool) -> Result<(), Illegal> {
        if !anisotropic {
            return Ok(());
        }
        let rule = match self {
            DistributionKind::Gaussian => gaussian::anisotropic(convention),
            DistributionKind::Beckmann => beckmann::anisotropic(convention),
            DistributionKind::Ggx => ggx::anisotropic(convention),
            DistributionKind::Blinn => blinn::anisotropic(convention),
            DistributionKind::Charlie => charlie::anisotropic(convention),
        };
        rule.map_err(|message| Illegal {
            key: "roughness",
            message,
        })
    }

    /// The largest roughness the formula is defined for (FORMULAS.md §2): `charlie`'s m is
    /// the paper's α = r² ≤ 1; the others are bounded only by the parser's general range.
    pub fn max_roughness(self) -> Option<f64> {
        (self == DistributionKind::Charlie).then_some(charlie::MAX_M)
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
