//! # vkbrdf
//!
//! Bulk BRDF evaluation on Vulkan compute, checked against an independent f64 CPU
//! reference. Batches of `(L, V, N, material[, T])` tuples go in; RGB BRDF values (1/sr,
//! without the cosine) and, on request, the terms D, G, F and K come out.
//!
//! The contract for every number is `FORMULAS.md` (mirrored section by section by
//! [`reference`](mod@reference)); the data flow is materials → [`batch::Batch`] → [`features::FeatureSet`]
//! → [`backend::Backend::evaluate`] → [`backend::Output`].
//!
//! ```
//! use vkbrdf::{backend::{Backend, Request}, batch::Batch, material, reference::CpuReference};
//!
//! let materials = material::parse_materials(r#"
//!     [[material]]
//!     name = "matte"
//!     model = "lambert"
//!     diffuse = [0.5, 0.5, 0.5]
//! "#, "example").unwrap();
//! // One tuple: L = V = N = +z, material 0.
//! let rows = vec![0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0];
//! let batch = Batch::new(rows, 10, materials.len(), &vkbrdf::batch::memory_source()).unwrap();
//! let out = CpuReference::new().evaluate(&batch, &materials, &Request::default()).unwrap();
//! assert!((out.brdf[0] - 0.5 / std::f32::consts::PI).abs() < 1e-7);
//! ```
#![deny(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn)]
#![deny(clippy::undocumented_unsafe_blocks)]
#![warn(missing_docs)]

pub mod atomic;
pub mod backend;
pub mod backend_choice;
pub mod batch;
pub mod bench;
pub mod cancel;
pub mod check;
pub mod cpu;
pub mod directions;
pub mod error;
pub mod features;
pub mod fit;
pub mod gpu;
pub mod importance;
pub mod material;
pub mod precision;
pub mod reference;
pub mod sample;
pub mod spectral;
pub mod spectral_eval;
pub mod stats;
pub mod stream;
pub mod stress;
pub mod table;
pub mod terms;
pub mod vector;

pub use error::{Error, Result};
