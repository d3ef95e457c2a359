//! Where a table's directions come from when an engine makes them itself
//! ([`crate::backend::GeneratedDirections`]): a half/difference grid, or the sampling plan
//! of an importance-sampled integral. Plain data, computed on the host.

use crate::material::Material;
use std::f64::consts::FRAC_PI_2;

/// `(l, v)` of half/difference angles (Rusinkiewicz 1998) with `φ_h = 0` and `n = +z`:
/// `h = R_y(θ_h) z`, `l = R_y(θ_h) · d(θ_d, φ_d)`, `v` = `l` reflected about `h`.
pub fn from_half_diff(theta_h: f64, theta_d: f64, phi_d: f64) -> ([f64; 3], [f64; 3]) {
    let (sh, ch) = theta_h.sin_cos();
    let (sd, cd) = theta_d.sin_cos();
    let d = [sd * phi_d.cos(), sd * phi_d.sin(), cd];
    let l = [d[0] * ch + d[2] * sh, d[1], -d[0] * sh + d[2] * ch];
    let h = [sh, 0.0, ch];
    let lh = l[0] * h[0] + l[2] * h[2];
    let v = std::array::from_fn(|i| 2.0 * lh * h[i] - l[i]);
    (l, v)
}

/// A half/difference slice grid (see [`crate::table::slice`]; [`SliceGrid::texel_directions`]
/// makes the directions): `width` θ_h columns × `height` θ_d rows, φ_d = 90°, n = +z,
/// tangent +x.
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

    /// `(l, v)` of texel `t` (row-major, θ_h fastest): column i at `x = (i + 0.5)/W`,
    /// `θ_h = x · π/2` (linear) or `x² · π/2`, row j at `θ_d = (j + 0.5)/H · π/2`, φ_d = 90°
    /// — the host's tuples of `table::slice` and the CPU engine's, value for value.
    pub fn texel_directions(&self, t: u64) -> ([f64; 3], [f64; 3]) {
        let (w, h) = (u64::from(self.width), u64::from(self.height));
        let centre = |i: u64, n: u64| (i as f64 + 0.5) / n as f64;
        let x = centre(t % w, w);
        let theta_h = if self.linear {
            x * FRAC_PI_2
        } else {
            x * x * FRAC_PI_2
        };
        from_half_diff(theta_h, centre(t / w, h) * FRAC_PI_2, FRAC_PI_2)
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
    /// `(μ, α)` unrounded: an engine that makes its samples in f64 (the CPU engine) builds
    /// the host's sampling constants from it, and so the host's samples.
    pub point: [f64; 2],
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

impl ImportanceJob<'_> {
    /// The samples per point, or the tables' error for a job without any.
    pub fn checked_samples(&self) -> crate::error::Result<u32> {
        match self.samples {
            0 => Err(crate::error::Error::Table(
                "--samples must be at least 1".into(),
            )),
            n => Ok(n),
        }
    }
}
