//! `FeatureSet`: what a batch needs (models, distributions, G, F, conventions,
//! anisotropy) and which outputs were asked for. The Vulkan backend compiles one kernel
//! variant per feature set, so code a batch does not use is never run (DESIGN.md).

use crate::backend::Request;
use crate::batch::Batch;
use crate::material::{Convention, Distribution, Fresnel, Geometry, Material, Model};
use crate::precision::Precision;

macro_rules! features {
    ($($(#[$doc:meta])* $name:ident = $bit:expr, $define:literal;)*) => {
        /// A set of features, one bit each.
        #[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct FeatureSet(u64);
        impl FeatureSet {
            $($(#[$doc])* pub const $name: FeatureSet = FeatureSet(1 << $bit);)*
            /// Every feature with the preprocessor name the kernel tests (`#if HAS_...`).
            pub const ALL_NAMED: &'static [(FeatureSet, &'static str)] = &[$((FeatureSet::$name, $define)),*];
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
    /// Gaussian D.
    D_GAUSSIAN = 6, "HAS_D_GAUSSIAN";
    /// Beckmann D.
    D_BECKMANN = 7, "HAS_D_BECKMANN";
    /// GGX D.
    D_GGX = 8, "HAS_D_GGX";
    /// Blinn D.
    D_BLINN = 9, "HAS_D_BLINN";
    /// V-cavity G.
    G_COOK_TORRANCE = 10, "HAS_G_COOK_TORRANCE";
    /// Separable Smith G.
    G_SMITH = 11, "HAS_G_SMITH";
    /// Height-correlated Smith G.
    G_SMITH_CORRELATED = 12, "HAS_G_SMITH_CORRELATED";
    /// Walter's rational Smith–Beckmann fit.
    G_SMITH_FAST = 13, "HAS_G_SMITH_FAST";
    /// Exact dielectric Fresnel.
    F_DIELECTRIC = 14, "HAS_F_DIELECTRIC";
    /// Exact conductor Fresnel (complex arithmetic).
    F_CONDUCTOR = 15, "HAS_F_CONDUCTOR";
    /// Schlick Fresnel.
    F_SCHLICK = 16, "HAS_F_SCHLICK";
    /// The `seed` convention.
    CONV_SEED = 17, "HAS_CONV_SEED";
    /// The `cook-torrance-1982` convention.
    CONV_CT1982 = 18, "HAS_CONV_CT1982";
    /// The `modern` convention.
    CONV_MODERN = 19, "HAS_CONV_MODERN";
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
    /// Every material is the fast precision variant: the device's own exp/log/atan2.
    FAST_MATH = 27, "FAST_MATH";
    /// Charlie (Estevez & Kulla 2017 sheen) D.
    D_CHARLIE = 30, "HAS_D_CHARLIE";
    /// Schlick–Smith G (Schlick 1994, Karis 2013's k).
    G_SCHLICK_SMITH = 31, "HAS_G_SCHLICK_SMITH";
    /// Neubelt & Pettineo 2013 cloth G.
    G_NEUBELT = 32, "HAS_G_NEUBELT";
}

impl FeatureSet {
    /// The empty set.
    pub const EMPTY: FeatureSet = FeatureSet(0);

    /// Every kernel feature (the all-features kernel, the baseline of the specialisation
    /// measurement). `MEASURED` is left out: a measured material needs its table bound,
    /// which only a batch that has one uploads; `GENERATED_SLICE`, `GENERATED_IMPORTANCE` and `BUCKETED` are input modes and `FAST_MATH` a precision
    /// variant, not features.
    pub fn all() -> FeatureSet {
        FeatureSet::ALL_NAMED
            .iter()
            .filter(|(f, _)| {
                *f != FeatureSet::MEASURED
                    && *f != FeatureSet::GENERATED_SLICE
                    && *f != FeatureSet::FAST_MATH
                    && *f != FeatureSet::GENERATED_IMPORTANCE
                    && *f != FeatureSet::BUCKETED
            })
            .fold(FeatureSet::EMPTY, |a, (f, _)| a | *f)
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
            Model::CookTorrance(ct) => {
                let mut f = FeatureSet::COOK_TORRANCE;
                f |= match ct.distribution {
                    Distribution::Gaussian { .. } => FeatureSet::D_GAUSSIAN,
                    Distribution::Beckmann(_) => FeatureSet::D_BECKMANN,
                    Distribution::Ggx(_) => FeatureSet::D_GGX,
                    Distribution::Blinn { .. } => FeatureSet::D_BLINN,
                    Distribution::Charlie { .. } => FeatureSet::D_CHARLIE,
                };
                f |= match ct.geometry {
                    Geometry::None => FeatureSet::EMPTY,
                    Geometry::CookTorrance => FeatureSet::G_COOK_TORRANCE,
                    Geometry::Smith => FeatureSet::G_SMITH,
                    Geometry::SmithCorrelated => FeatureSet::G_SMITH_CORRELATED,
                    Geometry::SmithFast => FeatureSet::G_SMITH_FAST,
                    Geometry::SchlickSmith => FeatureSet::G_SCHLICK_SMITH,
                    Geometry::Neubelt => FeatureSet::G_NEUBELT,
                };
                if matches!(ct.geometry, Geometry::Smith | Geometry::SmithCorrelated) {
                    f |= match ct.distribution {
                        Distribution::Beckmann(_) => FeatureSet::LAMBDA_BECKMANN,
                        _ => FeatureSet::LAMBDA_GGX,
                    };
                }
                f |= match ct.fresnel {
                    Fresnel::None => FeatureSet::EMPTY,
                    Fresnel::Dielectric { .. } => FeatureSet::F_DIELECTRIC,
                    Fresnel::Conductor { .. } => FeatureSet::F_CONDUCTOR,
                    Fresnel::Schlick { .. } => FeatureSet::F_SCHLICK,
                };
                f | match ct.convention {
                    Convention::Seed => FeatureSet::CONV_SEED,
                    Convention::CookTorrance1982 => FeatureSet::CONV_CT1982,
                    Convention::Modern => FeatureSet::CONV_MODERN,
                }
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
        let mut f = materials
            .iter()
            .zip(&used)
            .filter(|(_, &u)| u)
            .fold(FeatureSet::EMPTY, |a, (m, _)| {
                a | FeatureSet::of_material(m)
            });
        // Built-in math only when every material used asked for the fast variant: an exact
        // material in the same batch keeps the accurate functions (and fast ones then run
        // with them, still with their rewritten terms).
        let used_fast = materials.iter().zip(&used).filter(|(_, &u)| u);
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
        if batch.has_tangents() {
            f |= FeatureSet::TANGENTS;
        }
        if request.terms {
            f |= FeatureSet::TERMS;
        }
        f
    }

    /// The preprocessor names of the features in this set.
    pub fn defines(self) -> impl Iterator<Item = &'static str> {
        FeatureSet::ALL_NAMED
            .iter()
            .filter(move |(f, _)| self.contains(*f))
            .map(|(_, n)| *n)
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
}
