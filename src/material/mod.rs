//! Materials: the models, terms and conventions of FORMULAS.md §2–§6 as validated Rust
//! values. A [`Material`] can only hold a legal combination: the enums carry exactly the
//! parameters their formula needs, so the evaluators never re-check them.
//!
//! Materials come from TOML ([`parse_materials`]) or from [`presets`].

pub mod merl;
mod model;
mod parse;
pub mod precision;
mod preset_toml;
pub mod presets;
mod ranges;
pub mod spectral;

pub use crate::terms::f::schlick::f0_from_ior;
pub use crate::terms::{
    legality, Convention, Distribution, DistributionKind, Fresnel, FresnelKind, Geometry, Illegal,
    Rgb, Roughness, Term,
};

pub use model::{CookTorrance, Material, Measured, Model};
pub use parse::{load_materials, parse_materials, parse_materials_in, MAX_MATERIALS};
