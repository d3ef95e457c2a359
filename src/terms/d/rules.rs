//! The anisotropy rules several distributions share, below their files and their list.

use crate::terms::k::Convention;

/// The rule of the distributions without anisotropic roughness, for their files.
pub fn isotropic_only(name: &str) -> Result<(), String> {
    Err(format!(
        "distribution `{name}` is isotropic only; give one number"
    ))
}

/// The rule of the distributions with anisotropic roughness in `modern` only.
pub fn anisotropic_in_modern(name: &str, convention: Convention) -> Result<(), String> {
    if convention == Convention::Modern {
        Ok(())
    } else {
        Err(format!(
            "anisotropic `{name}` exists in the `modern` convention only"
        ))
    }
}
