//! No Fresnel factor: `F = 1` (FORMULAS.md §4).

/// The spelling in a materials file.
pub const NAME: &str = "none";
/// The work the formula comes from.
pub const CITATION: &str = "FORMULAS.md §4";
