//! The MERL binary format (Matusik, Pfister, Brand & McMillan 2003, "A data-driven
//! reflectance model"; FORMULAS.md §7): its layout, reading, and the lookup of a measured
//! material at arbitrary `(l, v, n)`. It lives with the materials because a measured
//! material *is* this data; exporting an analytic material to the format is a table
//! ([`crate::table::merl`]).
//!
//! Layout: three little-endian int32 dimensions `90, 90, 180` (θ_h, θ_d, φ_d), then the R,
//! G and B blocks of `90·90·180` little-endian f64, bin `(i, j, k)` at
//! `k + 180·(j + 90·i)`, sampled at `θ_h = (i/90)²·π/2`, `θ_d = j·(π/2)/90`,
//! `φ_d = k·π/180`, `φ_h = 0`; the stored value is `f / scale` ([`SCALES`]), and `−1`
//! where either direction is below the horizon.
//!
//! Lookup is MERL's own (`BRDFRead.cpp`): the half/difference angles of `(l, v)` in the
//! frame of `n`, bin indices by truncation (θ_h through the square root), `φ_d` folded into
//! `[0, π)` by reciprocity; negative (invalid or unmeasured) samples read as 0. One
//! deviation, documented at [`BIN_TOLERANCE`]: a point a hair below a bin's lower edge
//! counts as in that bin, so the bins' own sample points always find their bin.

use crate::error::{Error, Result};
use crate::vector::{cross, dot, normalize};
use std::f64::consts::{FRAC_PI_2, PI};
use std::io::Read;
use std::path::{Path, PathBuf};

/// θ_h bins.
pub const THETA_H_BINS: usize = 90;
/// θ_d bins.
pub const THETA_D_BINS: usize = 90;
/// φ_d bins over `[0, π)`.
pub const PHI_D_BINS: usize = 180;
/// Samples per colour channel, `90·90·180`.
pub const SAMPLES: usize = THETA_H_BINS * THETA_D_BINS * PHI_D_BINS;
/// Size of a MERL file: 12-byte header plus three blocks of f64.
pub const FILE_BYTES: usize = 12 + 3 * SAMPLES * 8;
/// MERL's R, G, B scales: a stored value times its scale is f in 1/sr.
pub const SCALES: [f64; 3] = [1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0];
/// Stored for samples with either direction below the horizon.
pub const INVALID: f64 = -1.0;

/// Bin tolerance, in bins: a coordinate within 1/1000 of a bin below its lower edge counts
/// as in that bin. MERL samples each bin at its lower edge, so without this the round-off
/// of computing angles from directions (1e-16 relative in f64; up to ~1e-4 bins for f32
/// directions near θ_h = 0, where the square root amplifies) would drop a bin's own sample
/// point into the bin below about half of the time.
pub const BIN_TOLERANCE: f64 = 1e-3;

/// The index of bin `(i, j, k)` within one colour block.
pub fn bin_index(i: usize, j: usize, k: usize) -> usize {
    k + PHI_D_BINS * (j + THETA_D_BINS * i)
}

/// `(θ_h, θ_d, φ_d)` of bin `(i, j, k)`'s sample point.
pub fn bin_angles(i: usize, j: usize, k: usize) -> (f64, f64, f64) {
    let x = i as f64 / THETA_H_BINS as f64;
    (
        x * x * FRAC_PI_2,
        j as f64 * FRAC_PI_2 / THETA_D_BINS as f64,
        k as f64 * PI / PHI_D_BINS as f64,
    )
}

/// How a measured material reads its table between the bins' sample points
/// (FORMULAS.md §7, "MERL lookup").
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum Lookup {
    /// MERL's own (`BRDFRead.cpp`): the bin's sample point, by truncation (the default).
    #[default]
    Nearest,
    /// Trilinear between the sample points around the point, in the bins' index
    /// coordinates (θ_h through the square root); φ_d wraps (π ≡ 0), θ_h and θ_d hold the
    /// last sample beyond index 89.
    Linear,
}

impl Lookup {
    /// `nearest` or `linear` (the materials-file value).
    pub fn toml_name(self) -> &'static str {
        match self {
            Lookup::Nearest => "nearest",
            Lookup::Linear => "linear",
        }
    }
}

/// A measured isotropic BRDF in MERL's tabulation.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredMerl {
    values: Vec<f64>,
    source: PathBuf,
}

/// Reads and validates a MERL binary: its dimensions must be 90 × 90 × 180 and its size
/// exactly [`FILE_BYTES`]; errors name the file.
pub fn read(path: &Path) -> Result<MeasuredMerl> {
    let io = |source| Error::Io {
        path: path.to_owned(),
        source,
    };
    let bad =
        |message: String| Error::Table(format!("{}: not a MERL BRDF: {message}", path.display()));
    // Before reading: a directory reads as a bare EISDIR, and a FIFO or a device would
    // block or never end.
    let meta = std::fs::metadata(path).map_err(io)?;
    if meta.is_dir() {
        return Err(bad("a directory, not a .binary file".into()));
    }
    if !meta.is_file() {
        return Err(bad(
            "not a regular file (a FIFO, socket or device); give the .binary file itself".into(),
        ));
    }
    let file = std::fs::File::open(path).map_err(io)?;
    read_from(file, path)
}

/// [`read`] from any reader; `source` names it in errors and becomes
/// [`MeasuredMerl::source`]. Reads at most one byte past [`FILE_BYTES`], and memory grows
/// only with the bytes actually read: a short stream costs no table's worth, an endless one
/// (`/dev/zero`, `/dev/urandom`) ends with an error instead of exhausting memory.
pub fn read_from(mut reader: impl Read, source: &Path) -> Result<MeasuredMerl> {
    let bad =
        |message: String| Error::Table(format!("{}: not a MERL BRDF: {message}", source.display()));
    let mut bytes = Vec::new();
    let mut read_up_to = |bytes: &mut Vec<u8>, n: usize| {
        reader
            .by_ref()
            .take(n as u64)
            .read_to_end(bytes)
            .map_err(|e| Error::Io {
                path: source.to_owned(),
                source: e,
            })
    };
    read_up_to(&mut bytes, 12)?;
    if bytes.len() < 12 {
        return Err(bad(format!(
            "{} bytes, shorter than the 12-byte header",
            bytes.len()
        )));
    }
    let dims: Vec<i32> = bytes[..12]
        .chunks_exact(4)
        .map(|b| i32::from_le_bytes(b.try_into().expect("4 bytes")))
        .collect();
    if dims != [90, 90, 180] {
        return Err(bad(format!(
            "dimensions {}x{}x{}, expected 90x90x180 (theta_h, theta_d, phi_d)",
            dims[0], dims[1], dims[2]
        )));
    }
    // One byte more than a table: enough to tell a padded file from an exact one.
    read_up_to(&mut bytes, FILE_BYTES + 1 - 12)?;
    if bytes.len() != FILE_BYTES {
        let size = if bytes.len() > FILE_BYTES {
            format!("more than {FILE_BYTES} bytes")
        } else {
            format!("{} bytes", bytes.len())
        };
        return Err(bad(format!(
            "{size}, expected {FILE_BYTES} (12-byte header + 3 x 90x90x180 doubles): truncated or padded"
        )));
    }
    let values = bytes[12..]
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
        .collect();
    Ok(MeasuredMerl {
        values,
        source: source.to_owned(),
    })
}

impl MeasuredMerl {
    /// A table from its stored values (R, G, B blocks of [`SAMPLES`], `f / scale` or
    /// negative), e.g. an analytic material exported in memory; `source` names it.
    pub fn from_values(values: Vec<f64>, source: &Path) -> Result<MeasuredMerl> {
        if values.len() != 3 * SAMPLES {
            return Err(Error::Table(format!(
                "{}: {} values given, a MERL table holds {}",
                source.display(),
                values.len(),
                3 * SAMPLES
            )));
        }
        Ok(MeasuredMerl {
            values,
            source: source.to_owned(),
        })
    }

    /// f (1/sr) of channel `c` at bin `(i, j, k)`: the stored value times its scale, 0 for
    /// a negative (invalid) sample. The table the kernel reads holds these, in f32.
    pub fn value(&self, c: usize, i: usize, j: usize, k: usize) -> f64 {
        self.stored(c, i, j, k).max(0.0) * SCALES[c]
    }

    /// Every [`MeasuredMerl::value`], R, G, B blocks in file order, rounded to f32.
    pub fn values_f32(&self) -> Vec<f32> {
        self.values
            .iter()
            .enumerate()
            .map(|(x, v)| (v.max(0.0) * SCALES[x / SAMPLES]) as f32)
            .collect()
    }

    /// The file it was read from.
    pub fn source(&self) -> &Path {
        &self.source
    }

    /// The stored value (`f / scale`, or negative) of channel `c` at bin `(i, j, k)`.
    pub fn stored(&self, c: usize, i: usize, j: usize, k: usize) -> f64 {
        self.values[c * SAMPLES + bin_index(i, j, k)]
    }

    /// f (RGB, 1/sr) at half/difference angles: the bin's stored value times its scale,
    /// 0 for negative (invalid) samples.
    pub fn lookup_half_diff(&self, theta_h: f64, theta_d: f64, phi_d: f64) -> [f64; 3] {
        let (i, j, k) = bin_of(theta_h, theta_d, phi_d);
        std::array::from_fn(|c| self.stored(c, i, j, k).max(0.0) * SCALES[c])
    }

    /// f (RGB, 1/sr) at half/difference angles by trilinear interpolation between the
    /// sample points ([`Lookup::Linear`]).
    pub fn linear_half_diff(&self, theta_h: f64, theta_d: f64, phi_d: f64) -> [f64; 3] {
        let ((i0, i1, wi), (j0, j1, wj), (k0, k1, wk)) = linear_corners(theta_h, theta_d, phi_d);
        std::array::from_fn(|c| {
            let at = |i, j, k| self.value(c, i, j, k);
            let along_k = |i, j| at(i, j, k0) * (1.0 - wk) + at(i, j, k1) * wk;
            let along_j = |i| along_k(i, j0) * (1.0 - wj) + along_k(i, j1) * wj;
            along_j(i0) * (1.0 - wi) + along_j(i1) * wi
        })
    }

    /// f (RGB, 1/sr) at half/difference angles by `mode`.
    pub fn lookup_half_diff_with(
        &self,
        mode: Lookup,
        theta_h: f64,
        theta_d: f64,
        phi_d: f64,
    ) -> [f64; 3] {
        match mode {
            Lookup::Nearest => self.lookup_half_diff(theta_h, theta_d, phi_d),
            Lookup::Linear => self.linear_half_diff(theta_h, theta_d, phi_d),
        }
    }

    /// f (RGB, 1/sr) at `(l, v, n)` (any lengths) by the standard nearest-bin lookup: 0
    /// for invalid vectors and below the horizon, as for analytic materials
    /// (FORMULAS.md §1).
    pub fn lookup(&self, l: [f64; 3], v: [f64; 3], n: [f64; 3]) -> [f64; 3] {
        self.lookup_with(Lookup::Nearest, l, v, n)
    }

    /// [`MeasuredMerl::lookup`] by `mode`.
    pub fn lookup_with(&self, mode: Lookup, l: [f64; 3], v: [f64; 3], n: [f64; 3]) -> [f64; 3] {
        match half_diff(l, v, n) {
            Some((th, td, pd)) => self.lookup_half_diff_with(mode, th, td, pd),
            None => [0.0; 3],
        }
    }
}

/// `(θ_h, θ_d, φ_d)` of `(l, v)` about `n` (Rusinkiewicz 1998, with `φ_h` undone), or
/// `None` for an invalid vector or a direction at or below the horizon. Angles come from
/// `atan2`, exact near 0 where `acos` loses half the digits.
pub fn half_diff(l: [f64; 3], v: [f64; 3], n: [f64; 3]) -> Option<(f64, f64, f64)> {
    let (l, v, n) = (normalize(l)?, normalize(v)?, normalize(n)?);
    if dot(n, l) <= 0.0 || dot(n, v) <= 0.0 {
        return None;
    }
    let h = normalize(std::array::from_fn(|i| l[i] + v[i]))?;
    let nxh = cross(n, h);
    let theta_h = dot(nxh, nxh).sqrt().atan2(dot(n, h));
    // b: the axis θ_h rotates about (n × h); any axis ⊥ n when h = n.
    let b = normalize(nxh)
        .or_else(|| normalize(cross(n, [1.0, 0.0, 0.0])))
        .or_else(|| normalize(cross(n, [0.0, 1.0, 0.0])))?;
    let t = cross(b, h);
    let d = [dot(l, t), dot(l, b), dot(l, h)];
    let theta_d = (d[0] * d[0] + d[1] * d[1]).sqrt().atan2(d[2]);
    Some((theta_h, theta_d, d[1].atan2(d[0])))
}

/// The continuous bin coordinates of `(θ_h, θ_d, φ_d)`: `(√(θ_h/(π/2))·90, θ_d/(π/2)·90,
/// (φ_d mod π)/π·180)`, sample points at the integers.
pub fn bin_coordinates(theta_h: f64, theta_d: f64, phi_d: f64) -> (f64, f64, f64) {
    (
        (theta_h.max(0.0) / FRAC_PI_2).sqrt() * THETA_H_BINS as f64,
        theta_d.max(0.0) / FRAC_PI_2 * THETA_D_BINS as f64,
        phi_d.rem_euclid(PI) / PI * PHI_D_BINS as f64,
    )
}

/// The corners and weights of [`Lookup::Linear`]: per axis `(lower, upper, weight of
/// upper)`; θ_h and θ_d clamp to their last sample (index 89), φ_d wraps (180 ≡ 0).
#[allow(clippy::type_complexity)]
pub fn linear_corners(
    theta_h: f64,
    theta_d: f64,
    phi_d: f64,
) -> (
    (usize, usize, f64),
    (usize, usize, f64),
    (usize, usize, f64),
) {
    let (x, y, z) = bin_coordinates(theta_h, theta_d, phi_d);
    let clamped = |x: f64, bins: usize| {
        let last = (bins - 1) as f64;
        let x = x.min(last);
        let lo = x.floor();
        let i = lo as usize;
        (i, (i + 1).min(bins - 1), x - lo)
    };
    let lo = z.floor();
    let k = lo as usize % PHI_D_BINS;
    (
        clamped(x, THETA_H_BINS),
        clamped(y, THETA_D_BINS),
        (k, (k + 1) % PHI_D_BINS, z - lo),
    )
}

/// The bin `(i, j, k)` holding `(θ_h, θ_d, φ_d)`: MERL's truncating lookup (θ_h index
/// `√(θ_h/(π/2))·90`, φ_d folded into `[0, π)`), clamped, with [`BIN_TOLERANCE`].
pub fn bin_of(theta_h: f64, theta_d: f64, phi_d: f64) -> (usize, usize, usize) {
    let index = |x: f64, bins: usize| ((x + BIN_TOLERANCE).floor().max(0.0) as usize).min(bins - 1);
    let i = if theta_h <= 0.0 {
        0
    } else {
        index(
            (theta_h / FRAC_PI_2).sqrt() * THETA_H_BINS as f64,
            THETA_H_BINS,
        )
    };
    let j = index(theta_d / FRAC_PI_2 * THETA_D_BINS as f64, THETA_D_BINS);
    // Reciprocity: swapping l and v maps φ_d to φ_d + π; a point within the tolerance
    // below π is bin 0's sample point (π ≡ 0).
    let phi = phi_d.rem_euclid(PI) / PI * PHI_D_BINS as f64;
    let k = (phi + BIN_TOLERANCE).floor().max(0.0) as usize % PHI_D_BINS;
    (i, j, k)
}
