//! Precision variants (`exact` | `fast`): [`crate::material::precision`], re-exported here
//! for the commands and engines that choose one. The variant lives with the materials
//! because a `precision = "fast"` key rewrites the material it is parsed with.

pub use crate::material::precision::*;
