//! The CIE 1931 2° standard observer and illuminant D65 on the 5 nm grid 360–830 nm, and
//! the reductions of a spectrum to CIE XYZ, linear sRGB and CIELAB (FORMULAS.md §9).
//!
//! The tables are the CIE's own (CIE 018:2019 data; `data/SOURCES.md` gives the DOIs and
//! the licence, CC BY-SA 4.0), shipped as CSV and parsed once.

use std::sync::OnceLock;

/// The grid's first wavelength, in nm.
pub const FIRST_NM: f64 = 360.0;
/// The grid's step, in nm.
pub const STEP_NM: f64 = 5.0;
/// Samples on the grid: 360, 365, …, 830 nm.
pub const SAMPLES: usize = 95;

/// The CIE tables on the grid.
#[derive(Debug)]
pub struct Tables {
    /// x̄, ȳ, z̄ at each grid wavelength.
    pub cmf: [[f64; 3]; SAMPLES],
    /// D65's relative spectral power at each grid wavelength.
    pub d65: [f64; SAMPLES],
}

/// The illuminant that weights a reflectance spectrum's reduction to colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Illuminant {
    /// CIE standard illuminant D65: sRGB's white; a constant reflectance 1 reduces to
    /// sRGB (1, 1, 1).
    #[default]
    D65,
    /// The equal-energy illuminant E (`S = 1`): a constant spectrum 1 reduces to XYZ
    /// (1, 1, 1), which is sRGB (1.205, 0.948, 0.909), not white.
    E,
}

impl Illuminant {
    /// The name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Illuminant::D65 => "d65",
            Illuminant::E => "e",
        }
    }
}

/// The grid's wavelength `i` in nm.
pub fn wavelength(i: usize) -> f64 {
    FIRST_NM + STEP_NM * i as f64
}

/// The tables, parsed from the shipped CSV files on first use.
pub fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(|| {
        let cmf_rows = rows(include_str!("data/cie1931-2deg-5nm.csv"), 4);
        let d65_rows = rows(include_str!("data/cie-d65-5nm.csv"), 2);
        let mut t = Tables {
            cmf: [[0.0; 3]; SAMPLES],
            d65: [0.0; SAMPLES],
        };
        for i in 0..SAMPLES {
            let (c, d) = (&cmf_rows[i], &d65_rows[i]);
            // The shipped files are fixed; a wrong grid is a build defect, caught by the tests.
            assert!(c[0] == wavelength(i) && d[0] == wavelength(i), "CIE grid");
            t.cmf[i] = [c[1], c[2], c[3]];
            t.d65[i] = d[1];
        }
        t
    })
}

/// The numeric rows of a shipped CSV (header skipped), `columns` numbers each.
fn rows(text: &str, columns: usize) -> Vec<Vec<f64>> {
    let out: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            l.split(',')
                .map(|x| {
                    x.trim()
                        .parse::<f64>()
                        .expect("shipped CIE table is numeric")
                })
                .collect::<Vec<f64>>()
        })
        .collect();
    assert!(
        out.len() == SAMPLES && out.iter().all(|r| r.len() == columns),
        "shipped CIE table has {SAMPLES} rows of {columns}"
    );
    out
}

/// The quadrature weights `S(λ) x̄ȳz̄(λ) / Σ S(λ) ȳ(λ)` of FORMULAS.md §9 for `illuminant`:
/// `XYZ = Σ_λ f(λ) w(λ)`, so that a constant reflectance 1 has `Y = 1`.
pub fn weights(illuminant: Illuminant) -> [[f64; 3]; SAMPLES] {
    let t = tables();
    let s = |i: usize| match illuminant {
        Illuminant::D65 => t.d65[i],
        Illuminant::E => 1.0,
    };
    let norm: f64 = (0..SAMPLES).map(|i| s(i) * t.cmf[i][1]).sum();
    std::array::from_fn(|i| std::array::from_fn(|c| s(i) * t.cmf[i][c] / norm))
}

/// XYZ of a spectrum sampled on the grid (`values[i]` at [`wavelength`]`(i)`), weighted by
/// `illuminant` (FORMULAS.md §9), summed in the grid's order.
pub fn to_xyz(values: &[f64], illuminant: Illuminant) -> [f64; 3] {
    assert_eq!(values.len(), SAMPLES, "a spectrum on the CIE grid");
    let w = weights(illuminant);
    let mut xyz = [0.0; 3];
    for (v, wi) in values.iter().zip(&w) {
        for c in 0..3 {
            xyz[c] += v * wi[c];
        }
    }
    xyz
}

/// The sRGB primaries' and white's chromaticities (IEC 61966-2-1).
const SRGB_PRIMARIES: [[f64; 2]; 3] = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]];
/// sRGB's white, D65's chromaticity as the standard writes it.
const SRGB_WHITE: [f64; 2] = [0.3127, 0.3290];

/// A 3×3 matrix, row-major.
pub type Matrix3 = [[f64; 3]; 3];

/// The linear-sRGB → XYZ matrix, derived from the primaries and white (so that sRGB
/// (1, 1, 1) is the white with Y = 1), and its inverse.
pub fn srgb_matrices() -> &'static (Matrix3, Matrix3) {
    static M: OnceLock<(Matrix3, Matrix3)> = OnceLock::new();
    M.get_or_init(|| {
        let xyz = |[x, y]: [f64; 2]| [x / y, 1.0, (1.0 - x - y) / y];
        let p: [[f64; 3]; 3] = std::array::from_fn(|j| xyz(SRGB_PRIMARIES[j]));
        // Columns are the primaries' XYZ; scale each so that their sum is the white.
        let cols = [
            [p[0][0], p[1][0], p[2][0]],
            [p[0][1], p[1][1], p[2][1]],
            [p[0][2], p[1][2], p[2][2]],
        ];
        let s = mul(&inverse(&cols), xyz(SRGB_WHITE));
        let to_xyz: [[f64; 3]; 3] =
            std::array::from_fn(|r| std::array::from_fn(|c| cols[r][c] * s[c]));
        (to_xyz, inverse(&to_xyz))
    })
}

/// XYZ → linear sRGB, unclamped (a value outside [0, 1] is a colour outside sRGB's gamut
/// or brighter than its white, as gold's red is).
pub fn xyz_to_srgb(xyz: [f64; 3]) -> [f64; 3] {
    mul(&srgb_matrices().1, xyz)
}

/// Linear sRGB → XYZ.
pub fn srgb_to_xyz(rgb: [f64; 3]) -> [f64; 3] {
    mul(&srgb_matrices().0, rgb)
}

/// The linear sRGB of a spectrum on the grid weighted by `illuminant`.
pub fn to_srgb(values: &[f64], illuminant: Illuminant) -> [f64; 3] {
    xyz_to_srgb(to_xyz(values, illuminant))
}

/// The white of the tables: D65's XYZ with Y = 1 (0.95047, 1, 1.08897).
pub fn d65_white() -> [f64; 3] {
    to_xyz(&[1.0; SAMPLES], Illuminant::D65)
}

/// CIELAB (CIE 1976 L*a*b*) of `xyz` relative to `white`.
pub fn lab(xyz: [f64; 3], white: [f64; 3]) -> [f64; 3] {
    let f = |t: f64| {
        const D: f64 = 6.0 / 29.0;
        if t > D * D * D {
            t.cbrt()
        } else {
            t / (3.0 * D * D) + 4.0 / 29.0
        }
    };
    let [fx, fy, fz] = [
        f(xyz[0] / white[0]),
        f(xyz[1] / white[1]),
        f(xyz[2] / white[2]),
    ];
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// ΔE*ab (CIE 1976) between two linear sRGB colours, in CIELAB with the D65 white.
pub fn delta_e_srgb(a: [f64; 3], b: [f64; 3]) -> f64 {
    let w = d65_white();
    let (la, lb) = (lab(srgb_to_xyz(a), w), lab(srgb_to_xyz(b), w));
    ((la[0] - lb[0]).powi(2) + (la[1] - lb[1]).powi(2) + (la[2] - lb[2]).powi(2)).sqrt()
}

fn mul(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

/// The inverse of a 3×3 matrix by cofactors (the sRGB matrices are well conditioned).
pub fn inverse(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let c = |r: usize, k: usize| {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
        m[r1][k1] * m[r2][k2] - m[r1][k2] * m[r2][k1]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    std::array::from_fn(|r| std::array::from_fn(|k| c(k, r) / det))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// FORMULAS.md §9's checks on the tables themselves (values from the CIE's publications).
    #[test]
    fn tables_meet_the_published_figures() {
        let t = tables();
        let y_sum: f64 = t.cmf.iter().map(|c| c[1]).sum::<f64>() * STEP_NM;
        assert!((y_sum - 106.857).abs() < 1e-3, "Σ ȳ Δλ = {y_sum}");
        let w = d65_white();
        for (got, want) in w.iter().zip([0.95047, 1.0, 1.08897]) {
            assert!((got - want).abs() < 1e-4, "D65 white {w:?}");
        }
        let rgb = to_srgb(&[1.0; SAMPLES], Illuminant::D65);
        assert!(
            rgb.iter().all(|c| (c - 1.0).abs() < 5e-4),
            "D65 in sRGB {rgb:?}"
        );
        let e = to_srgb(&[1.0; SAMPLES], Illuminant::E);
        for (got, want) in e.iter().zip([1.205, 0.948, 0.909]) {
            assert!((got - want).abs() < 1e-3, "E in sRGB {e:?}");
        }
    }

    #[test]
    fn srgb_matrix_is_the_standard_one() {
        // IEC 61966-2-1's XYZ → sRGB matrix, to the 4 decimals the standard prints.
        let m = srgb_matrices().1;
        let want = [
            [3.2406, -1.5372, -0.4986],
            [-0.9689, 1.8758, 0.0415],
            [0.0557, -0.2040, 1.0570],
        ];
        for r in 0..3 {
            for c in 0..3 {
                assert!((m[r][c] - want[r][c]).abs() < 1e-3, "{m:?}");
            }
        }
        let i = mul(&srgb_matrices().0, xyz_to_srgb([0.3, 0.2, 0.1]));
        assert!((i[0] - 0.3).abs() < 1e-14 && (i[2] - 0.1).abs() < 1e-14);
    }

    #[test]
    fn delta_e_of_a_colour_with_itself_is_zero_and_grows() {
        assert_eq!(delta_e_srgb([0.2, 0.4, 0.6], [0.2, 0.4, 0.6]), 0.0);
        assert!(delta_e_srgb([0.5, 0.5, 0.5], [0.5, 0.5, 0.51]) > 0.3);
    }
}
