//! How many combinations `vkbrdf check` runs, derived from the term lists and the legality
//! rules — not from `check::combinations`, whose count it checks.

use vkbrdf::terms::{legality, Convention, DistributionKind, FresnelKind, Geometry};

/// The models `check` runs without terms: Lambert, Phong, Blinn–Phong, RTR, Ward
/// isotropic and anisotropic, and HTSG (FORMULAS.md §8).
const PLAIN_MODELS: usize = 7;
/// The measured combinations: a MERL table looked up `nearest` and `linear`.
const MERL_LOOKUPS: usize = 2;

/// Every legal Cook–Torrance shape (convention × distribution × isotropic or anisotropic ×
/// geometry, as `terms::legality` allows) with each Fresnel term, the plain models and the
/// MERL lookups.
pub fn check_combination_count() -> usize {
    let mut shapes = 0;
    for c in Convention::ALL {
        for d in DistributionKind::ALL {
            for anisotropic in [false, true] {
                for g in Geometry::ALL {
                    shapes += usize::from(legality(c, d, anisotropic, g).is_ok());
                }
            }
        }
    }
    PLAIN_MODELS + shapes * FresnelKind::ALL.len() + MERL_LOOKUPS
}

/// The spectral rows `check` adds (FORMULAS.md §9): the six spectral presets and the
/// up-sampled `shiny-plastic`.
const SPECTRAL_ROWS: usize = 7;

/// The rows of a `vkbrdf check` report: the combinations and the spectral rows.
pub fn check_row_count() -> usize {
    check_combination_count() + SPECTRAL_ROWS
}
