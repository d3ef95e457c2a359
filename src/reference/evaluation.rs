//! What the reference returns for one tuple ([`Evaluation`], its [`Status`]), below the
//! models that make it and the dispatch that returns it.

use crate::backend::TERM_COLUMNS;

/// The outcome class of one tuple (FORMULAS.md §1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// Evaluated normally.
    Valid,
    /// Zero or non-finite L, V or N, or a bad tangent for an anisotropic material: all 0.
    Invalid,
    /// `cos_i ≤ 0` or `cos_o ≤ 0`: all 0.
    BelowHorizon,
}

/// The f64 result of one tuple: the BRDF and its terms (FORMULAS.md §5, §6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evaluation {
    /// Which rule applied.
    pub status: Status,
    /// RGB BRDF in 1/sr.
    pub brdf: [f64; 3],
    /// Distribution term D (for non-microfacet models: the specular lobe per unit `c_spec`).
    pub d: f64,
    /// Geometric attenuation G.
    pub g: f64,
    /// Fresnel F per channel.
    pub f: [f64; 3],
    /// Glare / normalisation factor K.
    pub k: f64,
}

impl Evaluation {
    /// The all-zero result of an invalid or below-horizon tuple.
    pub fn zero(status: Status) -> Evaluation {
        Evaluation {
            status,
            brdf: [0.0; 3],
            d: 0.0,
            g: 0.0,
            f: [0.0; 3],
            k: 0.0,
        }
    }

    /// The six term columns `D, G, F_r, F_g, F_b, K`.
    pub fn terms(&self) -> [f64; TERM_COLUMNS] {
        [self.d, self.g, self.f[0], self.f[1], self.f[2], self.k]
    }

    /// Whether any output (a BRDF channel or a term) exceeds the largest finite float32:
    /// the tuple is *saturated* (FORMULAS.md §1, "Overflow"). Terms count whether or not
    /// they were requested, so every backend counts the same tuples for any request.
    pub fn saturated(&self) -> bool {
        self.brdf
            .iter()
            .chain(&self.terms())
            .any(|&x| x > f64::from(f32::MAX))
    }
}
