//! A table's two axes (x = μ = cos_o, y = roughness) and how engines place their texels on
//! them: what the DFG and albedo tables share, below both.

use super::{texel_centre, Grid};
use crate::error::{Error, Result};

/// What a table's roughness coordinate `y` means.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RoughnessAxis {
    /// `y = α` (GGX α, Beckmann m).
    Alpha,
    /// `y = r`, perceptual roughness, `α = r²` (UE4, Filament).
    Perceptual,
}

impl RoughnessAxis {
    /// The α of coordinate `y`.
    pub fn alpha(self, y: f64) -> f64 {
        match self {
            RoughnessAxis::Alpha => y,
            RoughnessAxis::Perceptual => y * y,
        }
    }

    /// `alpha` or `perceptual` (the option's value).
    pub fn name(self) -> &'static str {
        match self {
            RoughnessAxis::Alpha => "alpha",
            RoughnessAxis::Perceptual => "perceptual",
        }
    }
}

/// Where a table's texels sit on its axes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sampling {
    /// Texel centres: column `i` ↔ `x = (i + ½)/W`, row `j` ↔ `y = (j + ½)/H`.
    Centres,
    /// Both ends included: `x = i/(W − 1)`, `y = j/(H − 1)` (needs W, H ≥ 2).
    Endpoints,
    /// Filament's `DFG()` (libs/ibl/src/CubemapIBL.cpp): `x = (i + ½)/W`, and row `j` ↔
    /// `y = min(1, (H − j + ½)/H)` — rows top-down from rough to smooth, shifted by one
    /// texel from the centres, the first row clamped to 1.
    Filament,
}

impl Sampling {
    /// The `(x, y)` of texel `(i, j)` of `grid`.
    pub fn coords(self, grid: Grid, i: usize, j: usize) -> (f64, f64) {
        let end = |k: usize, n: usize| k as f64 / (n - 1) as f64;
        match self {
            Sampling::Centres => (texel_centre(i, grid.width), texel_centre(j, grid.height)),
            Sampling::Endpoints => (end(i, grid.width), end(j, grid.height)),
            Sampling::Filament => {
                let h = grid.height as f64;
                (
                    texel_centre(i, grid.width),
                    ((h - j as f64 + 0.5) / h).min(1.0),
                )
            }
        }
    }

    /// How the provenance states it.
    pub fn describe(self) -> &'static str {
        match self {
            Sampling::Centres => "texel centres: x = (i + 0.5)/W, y = (j + 0.5)/H",
            Sampling::Endpoints => "endpoints included: x = i/(W - 1), y = j/(H - 1)",
            Sampling::Filament => {
                "Filament's DFG(): x = (i + 0.5)/W, y = min(1, (H - j + 0.5)/H) (row 0 roughest)"
            }
        }
    }
}

/// The smallest μ and α an endpoint table evaluates: `f` is 0 at μ = 0 (below the horizon,
/// FORMULAS.md §1) and α = 0 is no microfacet material, so the first column and row hold the
/// limits μ → 0 and α → 0, evaluated at 2⁻¹⁰ (within the integrator's measured accuracy
/// range, α ≥ 1/1024).
pub const ENDPOINT_FLOOR: f64 = 1.0 / 1024.0;

/// A table's two axes: x = μ = cos_o, y = roughness.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Axes {
    /// What `y` means.
    pub roughness: RoughnessAxis,
    /// Where the texels sit.
    pub sampling: Sampling,
}

impl Axes {
    /// The project's default: `y = α` at texel centres.
    pub const DEFAULT: Axes = Axes {
        roughness: RoughnessAxis::Alpha,
        sampling: Sampling::Centres,
    };

    /// Refuses a grid the sampling cannot place (endpoints need two texels per side).
    pub fn check(&self, grid: Grid) -> Result<()> {
        if self.sampling == Sampling::Endpoints && (grid.width < 2 || grid.height < 2) {
            return Err(Error::Table(format!(
                "--sampling endpoints needs at least 2 texels per side (x = i/(W - 1)); \
                 --size {}x{} has one",
                grid.width, grid.height
            )));
        }
        Ok(())
    }

    /// The `(μ, α)` of every texel, row-major (row j ↔ roughness, column i ↔ μ), the
    /// endpoint zeros at [`ENDPOINT_FLOOR`].
    pub fn points(&self, grid: Grid) -> Vec<(f64, f64)> {
        self.points_of_rows(grid, 0..grid.height)
    }

    /// [`Axes::points`] of the rows `rows` only (a shard's band).
    pub fn points_of_rows(&self, grid: Grid, rows: std::ops::Range<usize>) -> Vec<(f64, f64)> {
        rows.flat_map(|j| (0..grid.width).map(move |i| (i, j)))
            .map(|(i, j)| {
                let (x, y) = self.sampling.coords(grid, i, j);
                // Only the exact zeros of the endpoint sampling move.
                let floor = |t: f64| if t == 0.0 { ENDPOINT_FLOOR } else { t };
                (floor(x), floor(self.roughness.alpha(y)))
            })
            .collect()
    }

    /// How the provenance states them.
    pub fn describe(&self) -> String {
        let y = match self.roughness {
            RoughnessAxis::Alpha => "y = alpha",
            RoughnessAxis::Perceptual => "y = r (perceptual roughness), alpha = r^2",
        };
        let floor = match self.sampling {
            Sampling::Endpoints => "; mu = 0 and alpha = 0 evaluated at 2^-10 (the limits)",
            _ => "",
        };
        format!("x = mu = cos_o, {y}; {}{floor}", self.sampling.describe())
    }
}
