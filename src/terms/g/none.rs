//! No geometric attenuation: `G = 1` (FORMULAS.md §3). Defined with every distribution.

use crate::terms::d::DistributionKind;

/// The spelling in a materials file.
pub const NAME: &str = "none";
/// The work the formula comes from.
pub const CITATION: &str = "FORMULAS.md §3";

/// Its rule: defined with every distribution.
pub fn legality(_: DistributionKind, _anisotropic: bool) -> Result<(), String> {
    Ok(())
}
