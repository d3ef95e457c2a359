//! The validated material value: [`Material`], its [`Model`] and their parts, and the
//! [`Precision`] variant it records. Below the parser, the presets and the fast rewrite,
//! which all build or rewrite one.

use crate::terms::{Convention, Distribution, Fresnel, Geometry, Rgb, Roughness};

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
    pub precision: Precision,
    /// The spectral index behind the RGB `ior`/`extinction` (or Schlick `f0`), when the
    /// materials file gave `ior` as a spectrum (FORMULAS.md §9); `None` for an RGB material.
    pub spectral: Option<std::sync::Arc<crate::spectral::SpectralIndex>>,
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
    /// He, Torrance, Sillion & Greenberg 1991: the wave-optical model of FORMULAS.md §8
    /// (`diffuse` is its uniform-diffuse albedo `a`; `specular` does not apply).
    Htsg(crate::terms::htsg::Htsg),
}

/// A measured material's data and where it came from.
#[derive(Clone)]
pub struct Measured {
    /// The MERL file, as resolved when the materials were loaded.
    pub path: std::path::PathBuf,
    /// The table (shared: a 17 MB file is read once per materials file).
    pub data: std::sync::Arc<super::merl::MeasuredMerl>,
    /// How the table is read between sample points (`lookup = "nearest" | "linear"`).
    pub lookup: super::merl::Lookup,
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

impl Model {
    /// The model's spelling in a materials file (`model = "..."`).
    pub fn toml_name(&self) -> &'static str {
        match self {
            Model::Lambert => "lambert",
            Model::Phong { .. } => "phong",
            Model::BlinnPhong { .. } => "blinn-phong",
            Model::Rtr { .. } => "rtr",
            Model::Ward { .. } => "ward",
            Model::CookTorrance(_) => "cook-torrance",
            Model::Measured(_) => "merl",
            Model::Htsg(_) => crate::terms::htsg::NAME,
        }
    }
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

/// Which variant of the terms to evaluate.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum Precision {
    /// The formulas of FORMULAS.md as written.
    #[default]
    Exact,
    /// Schlick for exact Fresnel, `smith-fast` for Smith–Beckmann.
    Fast,
}

impl Precision {
    /// The label used in reports.
    pub fn label(self) -> &'static str {
        match self {
            Precision::Exact => "exact",
            Precision::Fast => "fast",
        }
    }
}
