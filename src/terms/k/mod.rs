//! The glare / normalisation conventions of FORMULAS.md §5, one file each: the factor K of
//! `R_s = D·G·F·K` and the Beckmann normalisation constant `k` each pairs with it.

use super::family::family;
pub use lane::LaneK;

pub mod lane;

family! {
    /// The glare / normalisation convention (FORMULAS.md §5). The discriminant is the code
    /// of `GpuMaterial`'s `(kind.w >> 8) & 0xff`.
    pub enum Convention {
        /// The seed lecture: Beckmann `k = 4`, `K = 1/cos_o`.
        Seed = 1 => seed, "CONV_SEED", Some((17, "HAS_CONV_SEED"));
        /// Cook & Torrance 1982: `k = 1`, `K = 1/(π cos_i cos_o)`.
        CookTorrance1982 = 2 => cook_torrance_1982, "CONV_CT1982", Some((18, "HAS_CONV_CT1982"));
        /// Walter et al. 2007 (default): `k = π`, `K = 1/(4 cos_i cos_o)`.
        Modern = 3 => modern, "CONV_MODERN", Some((19, "HAS_CONV_MODERN"));
    }
}

impl Convention {
    /// K in f64.
    pub fn k(self, cos_i: f64, cos_o: f64) -> f64 {
        match self {
            Convention::Seed => seed::k(cos_i, cos_o),
            Convention::CookTorrance1982 => cook_torrance_1982::k(cos_i, cos_o),
            Convention::Modern => modern::k(cos_i, cos_o),
        }
    }

    /// `ln K`, from the cosines' logarithms: finite even where `K` itself overflows
    /// (cosines near 1e-170, reachable from f64 callers), so the product `D·G·F·K` can be
    /// formed in the log domain there.
    pub fn ln_k(self, cos_i: f64, cos_o: f64) -> f64 {
        match self {
            Convention::Seed => seed::ln_k(cos_i, cos_o),
            Convention::CookTorrance1982 => cook_torrance_1982::ln_k(cos_i, cos_o),
            Convention::Modern => modern::ln_k(cos_i, cos_o),
        }
    }

    /// The Beckmann normalisation `k` in `exp(−tan²δ/m²)/(k m² cos⁴δ)`.
    pub fn beckmann_k(self) -> f64 {
        match self {
            Convention::Seed => seed::BECKMANN_K,
            Convention::CookTorrance1982 => cook_torrance_1982::BECKMANN_K,
            Convention::Modern => modern::BECKMANN_K,
        }
    }

    /// K's lane form.
    pub fn lane_k(self) -> LaneK {
        match self {
            Convention::Seed => seed::LANE_K,
            Convention::CookTorrance1982 => cook_torrance_1982::LANE_K,
            Convention::Modern => modern::LANE_K,
        }
    }
}
