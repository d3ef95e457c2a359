//! The terms of FORMULAS.md §2–§5, one file each, as pbrt-v4 keeps one class per
//! distribution and Mitsuba 3 one `MicrofacetDistribution`: a term's file holds its name in
//! a materials file and its citation, its legality rule, its f64 form (the reference's,
//! the judge) and its SIMD-lane form (the CPU engine's, f32 where the contract allows),
//! under one name. Its GLSL form is the block of the same name in `glsl/terms.glsl`.
//!
//! Each family is one list (`family!`, in `terms/family.rs`): `d/` the distributions D (§2), `g/` the
//! geometry terms G (§3), `f/` the Fresnel terms F (§4), `k/` the conventions with their
//! glare factor K (§5). The list numbers the terms (the codes both engines compare), names
//! their kernel feature, and generates the tables from a term to its file; the dispatches
//! over a family are exhaustive `match`es, so a term a table misses is a compile error.
//! The layers above (the reference's frame, the CPU engine's blocks, the kernel's
//! packing) ask these files instead of naming formulas themselves.

mod family;
pub mod term;

pub mod d;
pub mod f;
pub mod g;
pub mod htsg;
pub mod k;
pub mod math;
pub mod real;

pub use d::{Distribution, DistributionKind, Roughness};
pub use f::{Fresnel, FresnelKind};
pub use g::Geometry;
pub use k::Convention;
pub use term::{Illegal, Rgb, Term};

/// Every term of every family, for the tables built from them (kernel codes, features).
pub fn all_terms() -> impl Iterator<Item = Term> {
    DistributionKind::ALL
        .into_iter()
        .map(DistributionKind::term)
        .chain(Geometry::ALL.into_iter().map(Geometry::term))
        .chain(FresnelKind::ALL.into_iter().map(FresnelKind::term))
        .chain(Convention::ALL.into_iter().map(Convention::term))
}

/// The legality rules of FORMULAS.md §2–§3, written once, each in its term's file: whether
/// `distribution` with `geometry` (and anisotropic roughness, when `anisotropic`) in
/// `convention` is a material the contract defines. The distribution's own rules first
/// ([`DistributionKind::legality`]), then the geometry's with it ([`Geometry::legality`]).
/// The parser, the check matrix (`check::combinations`) and the test strategies all ask
/// this function, so a new term adds its rule in its own file only.
pub fn legality(
    convention: Convention,
    distribution: DistributionKind,
    anisotropic: bool,
    geometry: Geometry,
) -> Result<(), Illegal> {
    distribution.legality(convention, anisotropic)?;
    geometry.legality(distribution, anisotropic)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_distinct_within_a_family_and_names_round_trip() {
        let families: [Vec<Term>; 4] = [
            DistributionKind::ALL.map(DistributionKind::term).to_vec(),
            Geometry::ALL.map(Geometry::term).to_vec(),
            FresnelKind::ALL.map(FresnelKind::term).to_vec(),
            Convention::ALL.map(Convention::term).to_vec(),
        ];
        for family in &families {
            for (i, a) in family.iter().enumerate() {
                assert!(!a.citation.is_empty(), "{a:?} cites nothing");
                for b in &family[i + 1..] {
                    assert_ne!(a.gpu_code.1, b.gpu_code.1, "{a:?} and {b:?} share a code");
                    assert_ne!(a.toml_name, b.toml_name);
                }
            }
        }
        for d in DistributionKind::ALL {
            assert_eq!(DistributionKind::from_toml_name(d.toml_name()), Some(d));
            assert_eq!(DistributionKind::from_code(d.code()), d);
        }
        for g in Geometry::ALL {
            assert_eq!(Geometry::from_toml_name(g.toml_name()), Some(g));
            assert_eq!(Geometry::from_code(g.code()), g);
        }
        for f in FresnelKind::ALL {
            assert_eq!(FresnelKind::from_toml_name(f.toml_name()), Some(f));
            assert_eq!(FresnelKind::from_code(f.code()), f);
        }
        for c in Convention::ALL {
            assert_eq!(Convention::from_toml_name(c.toml_name()), Some(c));
            assert_eq!(Convention::from_code(c.code()), c);
        }
    }
}
