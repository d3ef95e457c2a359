//! Materials: the models, terms and conventions of FORMULAS.md §2–§6 as validated Rust
//! values. A [`Material`] can only hold a legal combination: the enums carry exactly the
//! parameters their formula needs, so the evaluators never re-check them.
//!
//! Materials come from TOML ([`parse_materials`]) or from [`presets`].

pub mod merl;
mod parse;
pub mod precision;
pub mod presets;

pub use parse::{load_materials, parse_materials, parse_materials_in};

/// An RGB triple (linear, per channel).
pub type Rgb = [f64; 3];

/// A validated material (FORMULAS.md §6).
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Unique name within its table.
    pub name: String,
    /// The reflection model and its parameters.
    pub model: Model,
    /// `c_diff`: diffuse colour (default black).
    pub diffuse: Rgb,
    /// `c_spec`: specular colour (default white).
    pub specular: Rgb,
    /// The variant evaluated: `Exact`, or `Fast` once [`super::precision::apply`] has
    /// rewritten the terms (the kernel then also uses the device's own exp/log/atan2).
    pub precision: super::precision::Precision,
}

/// The reflection models of FORMULAS.md §6, each with the parameters its formula uses.
#[derive(Debug, Clone, PartialEq)]
pub enum Model {
    /// `c_diff / π`.
    Lambert,
    /// Modified, normalised Phong with exponent `e`.
    Phong {
        /// Phong exponent `e ≥ 0`.
        exponent: f64,
    },
    /// The seed's Blinn–Phong, `c_spec · cos_h^e / (π cos_i)`.
    BlinnPhong {
        /// Exponent `e ≥ 0`.
        exponent: f64,
    },
    /// The seed's shading equation (RTR 3rd ed. §5.5), `(e+8)/(8π) cos_h^e`.
    Rtr {
        /// Exponent `e ≥ 0`.
        exponent: f64,
    },
    /// Ward 1992, isotropic or anisotropic.
    Ward {
        /// Roughness `m` or `[mx, my]`.
        roughness: Roughness,
    },
    /// Cook–Torrance microfacet model `d·c_diff/π + s·c_spec ⊗ D·G·F·K`.
    CookTorrance(CookTorrance),
    /// Measured data: a MERL binary (Matusik et al. 2003), looked up by half/difference
    /// angles (FORMULAS.md §7), nearest-bin or linear.
    Measured(Measured),
}

/// A measured material's data and where it came from.
#[derive(Clone)]
pub struct Measured {
    /// The MERL file, as resolved when the materials were loaded.
    pub path: std::path::PathBuf,
    /// The table (shared: a 17 MB file is read once per materials file).
    pub data: std::sync::Arc<merl::MeasuredMerl>,
    /// How the table is read between sample points (`lookup = "nearest" | "linear"`).
    pub lookup: merl::Lookup,
}

impl PartialEq for Measured {
    fn eq(&self, other: &Measured) -> bool {
        self.path == other.path
            && std::sync::Arc::ptr_eq(&self.data, &other.data)
            && self.lookup == other.lookup
    }
}

impl std::fmt::Debug for Measured {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Measured({}, {})",
            self.path.display(),
            self.lookup.toml_name()
        )
    }
}

/// Parameters of a Cook–Torrance material.
#[derive(Debug, Clone, PartialEq)]
pub struct CookTorrance {
    /// Which glare/normalisation convention (§5).
    pub convention: Convention,
    /// Microfacet distribution D (§2).
    pub distribution: Distribution,
    /// Geometric attenuation G (§3).
    pub geometry: Geometry,
    /// Fresnel term F (§4).
    pub fresnel: Fresnel,
    /// `s`: specular weight (default 1).
    pub specular_weight: f64,
    /// `d`: diffuse weight (default 0).
    pub diffuse_weight: f64,
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
}

/// The glare / normalisation convention (FORMULAS.md §5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Convention {
    /// The seed lecture: Beckmann `k = 4`, `K = 1/cos_o`.
    Seed,
    /// Cook & Torrance 1982: `k = 1`, `K = 1/(π cos_i cos_o)`.
    CookTorrance1982,
    /// Walter et al. 2007 (default): `k = π`, `K = 1/(4 cos_i cos_o)`.
    Modern,
}

impl Convention {
    /// Every convention.
    pub const ALL: [Convention; 3] = [
        Convention::Seed,
        Convention::CookTorrance1982,
        Convention::Modern,
    ];

    /// The spelling in a materials file (`convention = "..."`).
    pub fn toml_name(self) -> &'static str {
        match self {
            Convention::Seed => "seed",
            Convention::CookTorrance1982 => "cook-torrance-1982",
            Convention::Modern => "modern",
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

    /// The spelling in a materials file (`distribution = "..."`).
    pub fn toml_name(self) -> &'static str {
        match self {
            DistributionKind::Gaussian => "gaussian",
            DistributionKind::Beckmann => "beckmann",
            DistributionKind::Ggx => "ggx",
            DistributionKind::Blinn => "blinn",
            DistributionKind::Charlie => "charlie",
        }
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
    /// `r` is legal for it (see [`legality`]: gaussian and charlie are isotropic only).
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
}

/// A combination the contract does not define: the key to blame and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Illegal {
    /// The materials-file key the message is about (`roughness` or `geometry`).
    pub key: &'static str,
    /// What is wrong and what to use instead.
    pub message: String,
}

/// The legality rules of FORMULAS.md §2–§3, written once: whether `distribution` with
/// `geometry` (and anisotropic roughness, when `anisotropic`) in `convention` is a
/// material the contract defines. The parser, the check matrix (`check::combinations`) and
/// the test strategies all ask this function, so a new term adds its rule here only.
pub fn legality(
    convention: Convention,
    distribution: DistributionKind,
    anisotropic: bool,
    geometry: Geometry,
) -> Result<(), Illegal> {
    use DistributionKind as D;
    let d = distribution.toml_name();
    let g = geometry.toml_name();
    let illegal = |key, message: String| Err(Illegal { key, message });
    if anisotropic {
        match distribution {
            D::Beckmann | D::Ggx if convention != Convention::Modern => {
                return illegal(
                    "roughness",
                    format!("anisotropic `{d}` exists in the `modern` convention only"),
                )
            }
            D::Beckmann | D::Ggx => {}
            D::Blinn => {
                return illegal(
                    "roughness",
                    "distribution `blinn` takes an `exponent`, not a roughness".into(),
                )
            }
            D::Gaussian | D::Charlie => {
                return illegal(
                    "roughness",
                    format!("distribution `{d}` is isotropic only; give one number"),
                )
            }
        }
    }
    let smith = matches!(
        geometry,
        Geometry::Smith | Geometry::SmithCorrelated | Geometry::SmithFast
    );
    let without_lambda = matches!(distribution, D::Gaussian | D::Blinn | D::Charlie);
    if smith && without_lambda {
        return illegal("geometry", format!("Smith G needs a Λ for the distribution, and `{d}` has none; use `cook-torrance`, `neubelt` or `none`, or distribution `beckmann`/`ggx`"));
    }
    if geometry == Geometry::SchlickSmith && without_lambda {
        return illegal("geometry", format!("`schlick-smith` takes its k from a Beckmann or GGX roughness, and `{d}` has none; use `cook-torrance`, `neubelt` or `none`, or distribution `beckmann`/`ggx`"));
    }
    if geometry == Geometry::SmithFast && distribution != D::Beckmann {
        return illegal("geometry", "`smith-fast` is a fit of Smith–Beckmann (Beckmann only); use `smith` or `smith-correlated` with ggx".into());
    }
    if geometry == Geometry::SchlickSmith && anisotropic {
        return illegal("geometry", format!("`{g}` is defined for isotropic roughness only; give one roughness, or use `smith` or `smith-correlated`"));
    }
    Ok(())
}

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
    /// The spelling in a materials file (`geometry = "..."`).
    pub fn toml_name(self) -> &'static str {
        match self {
            Geometry::None => "none",
            Geometry::CookTorrance => "cook-torrance",
            Geometry::Smith => "smith",
            Geometry::SmithCorrelated => "smith-correlated",
            Geometry::SmithFast => "smith-fast",
            Geometry::SchlickSmith => "schlick-smith",
            Geometry::Neubelt => "neubelt",
        }
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

impl Material {
    /// The Cook–Torrance parameters, when this is a microfacet material.
    pub fn cook_torrance(&self) -> Option<&CookTorrance> {
        match &self.model {
            Model::CookTorrance(ct) => Some(ct),
            _ => None,
        }
    }

    /// Whether evaluating this material needs a tangent (anisotropic roughness).
    pub fn is_anisotropic(&self) -> bool {
        match &self.model {
            Model::Ward { roughness } => roughness.is_anisotropic(),
            Model::CookTorrance(ct) => match ct.distribution {
                Distribution::Beckmann(r) | Distribution::Ggx(r) => r.is_anisotropic(),
                _ => false,
            },
            _ => false,
        }
    }

    /// Whether the model obeys Helmholtz reciprocity `f(l, v) = f(v, l)`.
    /// Blinn–Phong (`1/cos_i`) and the seed convention (`K = 1/cos_o`) do not.
    pub fn is_reciprocal(&self) -> bool {
        match &self.model {
            Model::BlinnPhong { .. } => false,
            Model::CookTorrance(ct) => ct.convention != Convention::Seed,
            _ => true,
        }
    }
}

/// `F0 = ((n-1)² + k²)/((n+1)² + k²)`: reflectance at normal incidence (FORMULAS.md §4).
pub fn f0_from_ior(ior: Rgb, extinction: Rgb) -> Rgb {
    std::array::from_fn(|c| {
        let (n, k) = (ior[c], extinction[c]);
        ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k)
    })
}
