//! The material of a local-frame batch: the user's choice (`--material NAME|INDEX`) read,
//! and whether a material may evaluate the local form at all (it has no tangent column).

use crate::error::{Error, Result};
use crate::material::Material;
use std::path::Path;

/// The material of a local-frame batch from the user's choice (`--material NAME|INDEX`): an
/// index into `materials` or a material's name; with no choice, the only material of a
/// one-material table. Errors name `source` (the batch) and list the materials when the
/// choice matches none or a table of several leaves it open.
pub fn local_material(
    choice: Option<&str>,
    materials: &[Material],
    source: &Path,
) -> Result<usize> {
    let listing = || {
        materials
            .iter()
            .enumerate()
            .map(|(i, m)| format!("{i} `{}`", m.name))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let err = |message: String| Error::Batch {
        path: source.to_owned(),
        message,
    };
    let index = match choice {
        None if materials.len() == 1 => 0,
        None => {
            return Err(err(format!(
                "a 6-column local-frame batch (Lx Ly Lz Vx Vy Vz) has one material for every row, and the materials file defines {}: choose one with --material NAME|INDEX ({})",
                materials.len(),
                listing()
            )))
        }
        Some(c) => match materials.iter().position(|m| m.name == c) {
            Some(i) => i,
            None => c.trim().parse::<usize>().ok().filter(|&i| i < materials.len()).ok_or_else(|| {
                err(format!(
                    "--material {c:?} is neither a material's name nor an index in 0..{} (the materials file defines {})",
                    materials.len(),
                    listing()
                ))
            })?,
        },
    };
    check_local_material(index, materials, source)?;
    Ok(index)
}

/// Checks that `material` may evaluate a local-frame batch: an index into `materials`
/// and not anisotropic (the local form has no tangent column). `source` names the batch.
pub fn check_local_material(material: usize, materials: &[Material], source: &Path) -> Result<()> {
    let err = |message: String| Error::Batch {
        path: source.to_owned(),
        message,
    };
    let Some(m) = materials.get(material) else {
        return Err(err(format!(
            "material {material} is not an index in 0..{} (the materials file defines {})",
            materials.len(),
            materials.len()
        )));
    };
    if m.is_anisotropic() {
        return Err(err(format!(
            "material {material} (`{}`) is anisotropic (roughness [mx, my]) and needs a tangent, which the 6-column local-frame form (Lx Ly Lz Vx Vy Vz, N = +z) does not carry; give rows of shape (n, 13) instead",
            m.name
        )));
    }
    Ok(())
}
