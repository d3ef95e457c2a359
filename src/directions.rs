//! Where a table's directions come from when an engine makes them itself
//! ([`crate::backend::GeneratedDirections`]): a half/difference grid, or the sampling plan
//! of an importance-sampled integral. Plain data, computed on the host.

use crate::material::Material;

/// A half/difference slice grid (see [`crate::table::slice`]; its `from_half_diff` makes the directions): `width` θ_h columns ×
/// `height` θ_d rows, φ_d = 90°, n = +z, tangent +x.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SliceGrid {
    /// θ_h columns.
    pub width: u32,
    /// θ_d rows.
    pub height: u32,
    /// θ_h = x·π/2 (`true`) or x²·π/2, MERL's spacing (`false`).
    pub linear: bool,
}

impl SliceGrid {
    /// Texels in the grid.
    pub fn texels(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }
}

/// One `(μ, α)` point of an importance-sampled table integral ([`crate::table::albedo`]
/// states the method): its sampling constants, computed in f64 on the host and rounded
/// once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImportancePoint {
    /// The view direction `v` (unit, n = +z).
    pub v: [f32; 3],
    /// `G1(v)` (GGX's visible-normal density).
    pub g1: f32,
    /// GGX: the stretched view's hemisphere frame `t1`, `t2`, `v_h` and `s = (1 + v_h.z)/2`.
    pub frame: [[f32; 3]; 3],
    /// See `frame`.
    pub s: f32,
    /// The roughness α.
    pub alpha: f32,
    /// Index into the job's material table.
    pub material: u32,
}

/// An importance-sampled table integral for
/// [`crate::backend::GeneratedDirections::importance_sums`].
#[derive(Debug, Clone, Copy)]
pub struct ImportanceJob<'a> {
    /// GGX by its visible normals (`true`) or Beckmann by `D cos_h`.
    pub ggx: bool,
    /// The points.
    pub points: &'a [ImportancePoint],
    /// The materials the points index (F = 1 Cook–Torrance).
    pub materials: &'a [Material],
    /// Hammersley points per `(μ, α)` point.
    pub samples: u32,
}
