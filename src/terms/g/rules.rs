//! The rule the Smith terms share, below their files and their list.

use crate::terms::d::DistributionKind;

/// The rule every Smith term shares: it takes Λ from the distribution.
pub fn needs_lambda(distribution: DistributionKind) -> Result<(), String> {
    if distribution.has_lambda() {
        Ok(())
    } else {
        let d = distribution.toml_name();
        Err(format!("Smith G needs a Λ for the distribution, and `{d}` has none; use `cook-torrance`, `neubelt` or `none`, or distribution `beckmann`/`ggx`"))
    }
}
