//! A complex index of refraction `η(λ) = n(λ) + i k(λ)` as a spectrum: tabulated rows or a
//! Sellmeier formula, read linearly between rows and refused outside the data's range
//! (FORMULAS.md §9).

/// One real function of the wavelength.
#[derive(Debug, Clone, PartialEq)]
pub enum Curve {
    /// The same value at every wavelength.
    Constant(f64),
    /// Rows `(λ nm, value)`, strictly increasing in λ, read linearly between rows.
    Table(Vec<(f64, f64)>),
    /// refractiveindex.info's `formula 1` (Sellmeier): `n² − 1 = C1 + Σ Cᵢ λ² / (λ² − Cᵢ₊₁²)`,
    /// λ in µm, valid on `range_nm`.
    Sellmeier1 {
        /// `C1, C2, C3, …` as the file lists them.
        coefficients: Vec<f64>,
        /// Where the formula holds, in nm.
        range_nm: (f64, f64),
    },
    /// refractiveindex.info's `formula 2`: `n² − 1 = C1 + Σ Cᵢ λ² / (λ² − Cᵢ₊₁)`.
    Sellmeier2 {
        /// `C1, C2, C3, …` as the file lists them.
        coefficients: Vec<f64>,
        /// Where the formula holds, in nm.
        range_nm: (f64, f64),
    },
}

impl Curve {
    /// The wavelengths (nm) where the curve is defined.
    pub fn range(&self) -> (f64, f64) {
        match self {
            Curve::Constant(_) => (0.0, f64::INFINITY),
            Curve::Table(rows) => (rows[0].0, rows[rows.len() - 1].0),
            Curve::Sellmeier1 { range_nm, .. } | Curve::Sellmeier2 { range_nm, .. } => *range_nm,
        }
    }

    /// The value at `nm`, or `None` outside [`Curve::range`].
    pub fn at(&self, nm: f64) -> Option<f64> {
        let (lo, hi) = self.range();
        if !(lo..=hi).contains(&nm) {
            return None;
        }
        Some(match self {
            Curve::Constant(v) => *v,
            Curve::Table(rows) => {
                // The first row at or above nm; rows are increasing (checked when built).
                let j = rows.partition_point(|r| r.0 < nm).max(1);
                let ((x0, y0), (x1, y1)) = (rows[j - 1], rows[j]);
                if nm == x1 {
                    y1
                } else {
                    y0 + (y1 - y0) * (nm - x0) / (x1 - x0)
                }
            }
            Curve::Sellmeier1 { coefficients, .. } => sellmeier(coefficients, nm, true),
            Curve::Sellmeier2 { coefficients, .. } => sellmeier(coefficients, nm, false),
        })
    }

    /// Rows `(λ nm, value)` checked: at least two, finite, λ strictly increasing and > 0.
    pub fn table(rows: Vec<(f64, f64)>) -> Result<Curve, String> {
        if rows.len() < 2 {
            return Err(format!(
                "a table needs at least 2 rows, found {}",
                rows.len()
            ));
        }
        for (i, r) in rows.iter().enumerate() {
            if !(r.0.is_finite() && r.1.is_finite() && r.0 > 0.0) {
                return Err(format!(
                    "row {}: ({}, {}) is not a finite wavelength > 0 and value",
                    i + 1,
                    r.0,
                    r.1
                ));
            }
            if i > 0 && r.0 <= rows[i - 1].0 {
                return Err(format!(
                    "row {}: wavelength {} nm does not increase (the row before has {} nm)",
                    i + 1,
                    r.0,
                    rows[i - 1].0
                ));
            }
        }
        Ok(Curve::Table(rows))
    }
}

/// `n` from the Sellmeier sum; `squared_poles` for formula 1 (`λ² − C²`), not for formula 2.
fn sellmeier(c: &[f64], nm: f64, squared_poles: bool) -> f64 {
    let l2 = (nm / 1000.0).powi(2);
    let mut n2 = 1.0 + c.first().copied().unwrap_or(0.0);
    for pair in c[1.min(c.len())..].chunks(2) {
        if let [b, p] = pair {
            let pole = if squared_poles { p * p } else { *p };
            n2 += b * l2 / (l2 - pole);
        }
    }
    n2.max(0.0).sqrt()
}

/// `η(λ) = n(λ) + i k(λ)` with where it came from (for messages and reports).
#[derive(Debug, Clone, PartialEq)]
pub struct IndexSpectrum {
    /// Where the data came from: a data set's name, a file, or "inline rows".
    pub source: String,
    /// The real part.
    pub n: Curve,
    /// The imaginary part (extinction); `Constant(0)` for a lossless dielectric.
    pub k: Curve,
}

impl IndexSpectrum {
    /// The wavelengths (nm) where both parts are defined.
    pub fn range(&self) -> (f64, f64) {
        let (a, b) = (self.n.range(), self.k.range());
        (a.0.max(b.0), a.1.min(b.1))
    }

    /// `(n, k)` at `nm`, or an error naming the data's range.
    pub fn at(&self, nm: f64) -> Result<(f64, f64), String> {
        match (self.n.at(nm), self.k.at(nm)) {
            (Some(n), Some(k)) => Ok((n, k)),
            _ => {
                let (lo, hi) = self.range();
                Err(format!(
                    "{nm} nm is outside the data of {} ({lo}–{hi} nm); vkbrdf does not extrapolate a measured index",
                    self.source
                ))
            }
        }
    }

    /// `F0 = ((n − 1)² + k²) / ((n + 1)² + k²)` at `nm` (FORMULAS.md §4).
    pub fn f0(&self, nm: f64) -> Result<f64, String> {
        let (n, k) = self.at(nm)?;
        Ok(((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_reads_linearly_and_refuses_outside() {
        let c = Curve::table(vec![(400.0, 1.0), (500.0, 2.0), (600.0, 4.0)]).unwrap();
        assert_eq!(c.at(400.0), Some(1.0));
        assert_eq!(c.at(450.0), Some(1.5));
        assert_eq!(c.at(500.0), Some(2.0));
        assert_eq!(c.at(575.0), Some(3.5));
        assert_eq!(c.at(600.0), Some(4.0));
        assert_eq!(c.at(399.9), None);
        assert_eq!(c.at(600.1), None);
        assert!(Curve::table(vec![(400.0, 1.0), (400.0, 2.0)]).is_err());
        assert!(Curve::table(vec![(400.0, 1.0)]).is_err());
    }

    #[test]
    fn malitson_fused_silica_at_the_sodium_d_line() {
        // Malitson 1965's formula at 589.3 nm gives 1.4584 (his Table I).
        let c = Curve::Sellmeier1 {
            coefficients: vec![
                0.0, 0.6961663, 0.0684043, 0.4079426, 0.1162414, 0.8974794, 9.896161,
            ],
            range_nm: (210.0, 6700.0),
        };
        assert!((c.at(589.3).unwrap() - 1.4584).abs() < 1e-4);
    }
}

/// A material's spectral index and the reduction that gave its RGB form (what a
/// `Material` keeps of a spectral `ior`, FORMULAS.md §9).
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralIndex {
    /// `η(λ) = n(λ) + i k(λ)`.
    pub index: IndexSpectrum,
    /// How the material's RGB `ior`/`extinction` (or Schlick `f0`) were derived from it.
    pub reduction: super::RgbReduction,
    /// The Fresnel term the file named (HTSG's is the conductor's): what a spectral
    /// evaluation uses, whatever term the RGB reduction chose.
    pub fresnel: crate::terms::FresnelKind,
}
