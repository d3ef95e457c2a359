//! The glare / normalisation conventions of FORMULAS.md §5: each one's name, kernel code
//! and feature. Their formulas: `reference::convention` (f64) and `glsl/terms.glsl`.

use super::Term;

/// The glare / normalisation convention (FORMULAS.md §5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Convention {
    /// The seed lecture: Beckmann `k = 4`, `K = 1/cos_o`.
    Seed,
    /// Cook & Torrance 1982: `k = 1`, `K = 1/(π cos_i cos_o)`.
    CookTorrance1982,
    /// Walter et al. 2007 (default): `k = π`, `K = 1/(4 cos_i cos_o)`.
    Modern,
}

impl Convention {
    /// Every convention.
    pub const ALL: [Convention; 3] = [
        Convention::Seed,
        Convention::CookTorrance1982,
        Convention::Modern,
    ];

    /// The convention's name, kernel code and feature.
    pub const fn term(self) -> Term {
        match self {
            Convention::Seed => Term {
                toml_name: "seed",
                gpu_code: ("CONV_SEED", 1),
                feature: Some((17, "HAS_CONV_SEED")),
            },
            Convention::CookTorrance1982 => Term {
                toml_name: "cook-torrance-1982",
                gpu_code: ("CONV_CT1982", 2),
                feature: Some((18, "HAS_CONV_CT1982")),
            },
            Convention::Modern => Term {
                toml_name: "modern",
                gpu_code: ("CONV_MODERN", 3),
                feature: Some((19, "HAS_CONV_MODERN")),
            },
        }
    }

    /// The spelling in a materials file (`convention = "..."`).
    pub fn toml_name(self) -> &'static str {
        self.term().toml_name
    }

    /// The convention a materials file names, if any.
    pub fn from_toml_name(name: &str) -> Option<Convention> {
        Convention::ALL.into_iter().find(|c| c.toml_name() == name)
    }
}
