//! One home per term (FORMULAS.md §2–§5), as pbrt-v4 and Mitsuba 3 keep one class per
//! distribution: a file per term family holds each term's parameters, its spelling in a
//! materials file, its kernel code and its kernel feature ([`Term`]), and this module holds
//! the rules that combine them ([`legality`]). The layers above ask these instead of
//! naming the terms: the parser (names, ranges, rules), `features` (the feature bit and
//! its `HAS_*` macro), `gpu::layout` (the codes injected into the GLSL), `check` and the
//! test strategies (`ALL` and the rules). The formulas themselves stay in the layers that
//! evaluate them: `reference/` (f64, the judge) and `glsl/terms.glsl` (f32), one function
//! per term, same name and citation in both.

pub mod convention;
pub mod distribution;
pub mod fresnel;
pub mod geometry;

pub use convention::Convention;
pub use distribution::{Distribution, DistributionKind};
pub use fresnel::{Fresnel, FresnelKind};
pub use geometry::Geometry;

/// What the layers above the materials need to know about one term, said once.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Term {
    /// The spelling in a materials file.
    pub toml_name: &'static str,
    /// The macro the kernel compares a material's code against and its value (the
    /// `GpuMaterial` slot is the family's: `kind.y` D, `kind.z` G, `kind.w` F and
    /// convention; `gpu::layout` injects every code into the GLSL).
    pub gpu_code: (&'static str, u32),
    /// The kernel feature that compiles the term's code: its bit in `FeatureSet` and its
    /// preprocessor name (`HAS_*`); `None` for a term with no code (`G = 1`, `F = 1`).
    pub feature: Option<(u32, &'static str)>,
}

/// Every term of every family, for the tables built from them (kernel codes, features).
pub fn all_terms() -> impl Iterator<Item = Term> {
    DistributionKind::ALL
        .into_iter()
        .map(DistributionKind::term)
        .chain(Geometry::ALL.into_iter().map(Geometry::term))
        .chain(FresnelKind::ALL.into_iter().map(FresnelKind::term))
        .chain(Convention::ALL.into_iter().map(Convention::term))
}

/// A combination the contract does not define: the key to blame and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Illegal {
    /// The materials-file key the message is about (`roughness` or `geometry`).
    pub key: &'static str,
    /// What is wrong and what to use instead.
    pub message: String,
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
                for b in &family[i + 1..] {
                    assert_ne!(a.gpu_code.1, b.gpu_code.1, "{a:?} and {b:?} share a code");
                    assert_ne!(a.toml_name, b.toml_name);
                }
            }
        }
        for d in DistributionKind::ALL {
            assert_eq!(DistributionKind::from_toml_name(d.toml_name()), Some(d));
        }
        for g in Geometry::ALL {
            assert_eq!(Geometry::from_toml_name(g.toml_name()), Some(g));
        }
        for f in FresnelKind::ALL {
            assert_eq!(FresnelKind::from_toml_name(f.toml_name()), Some(f));
        }
        for c in Convention::ALL {
            assert_eq!(Convention::from_toml_name(c.toml_name()), Some(c));
        }
    }
}
