//! `FeatureSet`: what a batch needs (models, distributions, G, F, conventions,
//! anisotropy) and which outputs were asked for. The Vulkan backend compiles one kernel
//! variant per feature set, so code a batch does not use is never run.

use crate::backend::Request;
use crate::batch::columns::{ColumnBatch, MaterialColumn};
use crate::batch::Batch;
use crate::material::{Convention, DistributionKind, FresnelKind, Geometry, Material, Model, Term};
use crate::precision::Precision;

macro_rules! features {
    ($($(#[$doc:meta])* $name:ident = $bit:expr, $define:literal;)*) => {
        /// A set of features, one bit each.
        #[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct FeatureSet(u64);
        impl FeatureSet {
            $($(#[$doc])* pub const $name: FeatureSet = FeatureSet(1 << $bit);)*
            /// The features that are not a term's (a term's comes from its
            /// `material::Term`), with the preprocessor name the kernel tests.
            const OTHERS_NAMED: &'static [(FeatureSet, &'static str)] = &[$((FeatureSet::$name, $define)),*];
        }
    };
}

features! {
    /// A `lambert` material.
    LAMBERT = 0, "HAS_LAMBERT";
    /// A `phong` material.
    PHONG = 1, "HAS_PHONG";
    /// A `blinn-phong` material.
    BLINN_PHONG = 2, "HAS_BLINN_PHONG";
    /// An `rtr` material.
    RTR = 3, "HAS_RTR";
    /// A `ward` material.
    WARD = 4, "HAS_WARD";
    /// A `cook-torrance` material.
    COOK_TORRANCE = 5, "HAS_COOK_TORRANCE";
    /// Some material has anisotropic roughness (needs tangents).
    ANISOTROPIC = 20, "HAS_ANISOTROPIC";
    /// The batch carries tangents (13 columns).
    TANGENTS = 21, "HAS_TANGENTS";
    /// Terms are written.
    TERMS = 22, "WRITE_TERMS";
    /// Smith–Beckmann Λ (uses erf): Beckmann with `smith` or `smith-correlated`.
    LAMBDA_BECKMANN = 23, "HAS_LAMBDA_BECKMANN";
    /// Smith–GGX Λ.
    LAMBDA_GGX = 24, "HAS_LAMBDA_GGX";
    /// A measured (MERL) material: the kernel looks its table up (BINDING_MERL).
    MEASURED = 25, "HAS_MEASURED";
    /// The kernel makes its own directions: the half/difference slice grid of
    /// `table slice`, from the push constants (no tuple is read).
    GENERATED_SLICE = 26, "GENERATE_HALF_DIFF";
    /// The kernel makes importance-sampled directions and sums per block: the albedo and
    /// DFG tables (no tuple is read but each point's sampling constants).
    GENERATED_IMPORTANCE = 28, "GENERATE_IMPORTANCE";
    /// The batch uses several materials: each chunk is evaluated in an order grouped by
    /// material (a host-side counting sort), so a subgroup's lanes share one material's
    /// code path (mixed-8 kernel 3.3x on lavapipe).
    BUCKETED = 29, "BUCKETED";
    /// An `htsg` material (FORMULAS.md §8; with the conductor Fresnel's code).
    HTSG = 33, "HAS_HTSG";
    /// Every material is the fast precision variant: the device's own exp/log/atan2.
    FAST_MATH = 27, "FAST_MATH";
}

/// The feature of a term (`terms` says its bit and name, in its family's list), under the name the
/// code uses for it.
macro_rules! term_features {
    ($($(#[$doc:meta])* $name:ident = $term:expr;)*) => {
        impl FeatureSet {
            $($(#[$doc])* pub const $name: FeatureSet = FeatureSet::of_term($term);)*
        }
    };
}

term_features! {
    /// Gaussian D.
    D_GAUSSIAN = DistributionKind::Gaussian.term();
    /// Beckmann D.
    D_BECKMANN = DistributionKind::Beckmann.term();
    /// GGX D.
    D_GGX = DistributionKind::Ggx.term();
    /// Blinn D.
    D_BLINN = DistributionKind::Blinn.term();
    /// Charlie (Estevez & Kulla 2017 sheen) D.
    D_CHARLIE = DistributionKind::Charlie.term();
    /// V-cavity G.
    G_COOK_TORRANCE = Geometry::CookTorrance.term();
    /// Separable Smith G.
    G_SMITH = Geometry::Smith.term();
    /// Height-correlated Smith G.
    G_SMITH_CORRELATED = Geometry::SmithCorrelated.term();
    /// Walter's rational Smith–Beckmann fit.
    G_SMITH_FAST = Geometry::SmithFast.term();
    /// Schlick–Smith G (Schlick 1994, Karis 2013's k).
    G_SCHLICK_SMITH = Geometry::SchlickSmith.term();
    /// Neubelt & Pettineo 2013 cloth G.
    G_NEUBELT = Geometry::Neubelt.term();
    /// Exact dielectric Fresnel.
    F_DIELECTRIC = FresnelKind::Dielectric.term();
    /// Exact conductor Fresnel (complex arithmetic).
    F_CONDUCTOR = FresnelKind::Conductor.term();
    /// Schlick Fresnel.
    F_SCHLICK = FresnelKind::Schlick.term();
    /// The `seed` convention.
    CONV_SEED = Convention::Seed.term();
    /// The `cook-torrance-1982` convention.
    CONV_CT1982 = Convention::CookTorrance1982.term();
    /// The `modern` convention.
    CONV_MODERN = Convention::Modern.term();
}

impl FeatureSet {
    /// The empty set.
    pub const EMPTY: FeatureSet = FeatureSet(0);

    /// The feature that compiles `term`'s kernel code (empty for a term without code).
    pub const fn of_term(term: Term) -> FeatureSet {
        match term.feature {
            Some((bit, _)) => FeatureSet(1 << bit),
            None => FeatureSet(0),
        }
    }

    /// Every feature with the preprocessor name the kernel tests (`#if HAS_...`), by bit:
    /// the terms' (from `terms`) and the others.
    pub fn all_named() -> Vec<(FeatureSet, &'static str)> {
        let mut named: Vec<(FeatureSet, &'static str)> = crate::terms::all_terms()
            .filter_map(|t| {
                t.feature
                    .map(|(_, define)| (FeatureSet::of_term(t), define))
            })
            .chain(FeatureSet::OTHERS_NAMED.iter().copied())
            .collect();
        named.sort_by_key(|(f, _)| f.0);
        named
    }

    /// Every kernel feature (the all-features kernel, the baseline of the specialisation
    /// measurement). `MEASURED` is left out: a measured material needs its table bound,
    /// which only a batch that has one uploads; `GENERATED_SLICE`, `GENERATED_IMPORTANCE` and `BUCKETED` are input modes and `FAST_MATH` a precision
    /// variant, not features.
    pub fn all() -> FeatureSet {
        FeatureSet::all_named()
            .into_iter()
            .filter(|(f, _)| {
                *f != FeatureSet::MEASURED
                    && *f != FeatureSet::GENERATED_SLICE
                    && *f != FeatureSet::FAST_MATH
                    && *f != FeatureSet::GENERATED_IMPORTANCE
                    && *f != FeatureSet::BUCKETED
            })
            .fold(FeatureSet::EMPTY, |a, (f, _)| a | f)
    }

    /// `self` less the features of `other`.
    pub fn without(self, other: FeatureSet) -> FeatureSet {
        FeatureSet(self.0 & !other.0)
    }

    /// Whether every feature of `other` is in `self`.
    pub fn contains(self, other: FeatureSet) -> bool {
        self.0 & other.0 == other.0
    }

    /// The raw bits (stable within one build; used for cache keys and logs).
    pub fn bits(self) -> u64 {
        self.0
    }

    /// The features one material needs.
    pub fn of_material(m: &Material) -> FeatureSet {
        let mut f = match &m.model {
            Model::Lambert => FeatureSet::LAMBERT,
            Model::Phong { .. } => FeatureSet::PHONG,
            Model::BlinnPhong { .. } => FeatureSet::BLINN_PHONG,
            Model::Rtr { .. } => FeatureSet::RTR,
            Model::Ward { .. } => FeatureSet::WARD,
            Model::Measured(_) => FeatureSet::MEASURED,
            Model::Htsg(_) => FeatureSet::HTSG | FeatureSet::F_CONDUCTOR,
            Model::CookTorrance(ct) => {
                let mut f = FeatureSet::COOK_TORRANCE;
                f |= FeatureSet::of_term(ct.distribution.kind().term());
                f |= FeatureSet::of_term(ct.geometry.term());
                if matches!(ct.geometry, Geometry::Smith | Geometry::SmithCorrelated) {
                    f |= match ct.distribution.kind() {
                        DistributionKind::Beckmann => FeatureSet::LAMBDA_BECKMANN,
                        _ => FeatureSet::LAMBDA_GGX,
                    };
                }
                f |= FeatureSet::of_term(ct.fresnel.kind().term());
                f | FeatureSet::of_term(ct.convention.term())
            }
        };
        if m.is_anisotropic() {
            f |= FeatureSet::ANISOTROPIC;
        }
        f
    }

    /// What evaluating `batch` with `materials` needs: the union over the materials the
    /// batch actually references, plus tangents and outputs, and `BUCKETED` when it
    /// references more than one material.
    pub fn of_batch(batch: &Batch, materials: &[Material], request: &Request) -> FeatureSet {
        let mut used = vec![false; materials.len()];
        for i in 0..batch.len() {
            used[batch.material(i)] = true;
        }
        FeatureSet::of_used(&used, materials, batch.has_tangents(), request)
    }

    /// [`FeatureSet::of_batch`] for a batch given as columns.
    pub fn of_columns(
        batch: &ColumnBatch,
        materials: &[Material],
        request: &Request,
    ) -> FeatureSet {
        let mut used = vec![false; materials.len()];
        match batch.materials() {
            MaterialColumn::Every(m) if !batch.is_empty() => used[m] = true,
            MaterialColumn::Every(_) => {}
            MaterialColumn::Each(m) => m.iter().for_each(|&i| used[i as usize] = true),
        }
        FeatureSet::of_used(&used, materials, batch.tangent().is_some(), request)
    }

    /// [`FeatureSet::of_batch`] of a batch that uses every material of `materials`.
    pub fn of_used_all(materials: &[Material], tangents: bool, request: &Request) -> FeatureSet {
        FeatureSet::of_used(&vec![true; materials.len()], materials, tangents, request)
    }

    /// The union of [`FeatureSet::of_material`] over `materials`.
    pub fn of_materials(materials: &[Material]) -> FeatureSet {
        materials
            .iter()
            .fold(FeatureSet::EMPTY, |f, m| f | FeatureSet::of_material(m))
    }

    /// The features of the materials marked `used`, with tangents and the request's outputs.
    fn of_used(
        used: &[bool],
        materials: &[Material],
        tangents: bool,
        request: &Request,
    ) -> FeatureSet {
        let mut f = materials
            .iter()
            .zip(used)
            .filter(|(_, &u)| u)
            .fold(FeatureSet::EMPTY, |a, (m, _)| {
                a | FeatureSet::of_material(m)
            });
        // Built-in math only when every material used asked for the fast variant: an exact
        // material in the same batch keeps the accurate functions (and fast ones then run
        // with them, still with their rewritten terms).
        let used_fast = materials.iter().zip(used).filter(|(_, &u)| u);
        if used.iter().any(|&u| u)
            && used_fast
                .clone()
                .all(|(m, _)| m.precision == Precision::Fast)
        {
            f |= FeatureSet::FAST_MATH;
        }
        if used.iter().filter(|&&u| u).count() > 1 {
            f |= FeatureSet::BUCKETED;
        }
        if tangents {
            f |= FeatureSet::TANGENTS;
        }
        if request.terms {
            f |= FeatureSet::TERMS;
        }
        f
    }

    /// These features and `forced`'s, but the tangent layout and the terms output as they
    /// are here (they follow the batch and the request, not a kernel choice).
    pub fn with_forced(self, forced: FeatureSet) -> FeatureSet {
        self | forced.without(FeatureSet::TANGENTS | FeatureSet::TERMS)
    }

    /// The preprocessor names of the features in this set.
    pub fn defines(self) -> impl Iterator<Item = &'static str> {
        FeatureSet::all_named()
            .into_iter()
            .filter(move |(f, _)| self.contains(*f))
            .map(|(_, n)| n)
    }
}

impl std::ops::BitOr for FeatureSet {
    type Output = FeatureSet;
    fn bitor(self, rhs: FeatureSet) -> FeatureSet {
        FeatureSet(self.0 | rhs.0)
    }
}

impl std::ops::BitOrAssign for FeatureSet {
    fn bitor_assign(&mut self, rhs: FeatureSet) {
        self.0 |= rhs.0;
    }
}

impl std::fmt::Display for FeatureSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<&str> = self
            .defines()
            .map(|n| n.trim_start_matches("HAS_"))
            .collect();
        write!(
            f,
            "{}",
            if names.is_empty() {
                "(none)".to_string()
            } else {
                names.join("+")
            }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::presets::preset;
    use crate::precision::apply;
    use std::path::Path;

    fn batch(materials: &[usize], count: usize) -> Batch<'static> {
        let data = materials
            .iter()
            .flat_map(|&m| [0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, m as f32])
            .collect();
        Batch::new(data, 10, count, Path::new("test")).unwrap()
    }

    #[test]
    fn fast_math_only_when_every_material_used_is_fast() {
        let gold = preset("gold").unwrap().unwrap();
        let fast = apply(&gold, Precision::Fast);
        let table = [gold, fast];
        let r = Request::default();
        let of = |rows: &[usize]| FeatureSet::of_batch(&batch(rows, 2), &table, &r);
        assert!(of(&[1, 1]).contains(FeatureSet::FAST_MATH));
        assert!(!of(&[0, 1]).contains(FeatureSet::FAST_MATH));
        assert!(!of(&[0]).contains(FeatureSet::FAST_MATH));
        assert!(!of(&[]).contains(FeatureSet::FAST_MATH));
        assert!(!FeatureSet::all().contains(FeatureSet::FAST_MATH));
    }

    #[test]
    fn every_feature_has_its_own_bit_and_name() {
        // The terms say their bits in their family lists (`terms`), the others here: a new term that
        // reused a bit would compile another term's code under its name.
        let named = FeatureSet::all_named();
        for (i, (a, an)) in named.iter().enumerate() {
            assert_eq!(a.bits().count_ones(), 1, "{an}");
            for (b, bn) in &named[i + 1..] {
                assert_ne!(a, b, "{an} and {bn} share a bit");
                assert_ne!(an, bn);
            }
        }
        assert_eq!(FeatureSet::D_GGX.bits(), 1 << 8);
        assert!(FeatureSet::all().contains(FeatureSet::G_NEUBELT));
    }
}
