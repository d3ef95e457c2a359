//! A 2-D table's size and the conventions every table file states (its texel centres, the
//! version in its provenance): below the writers, which all use them.

use crate::error::{Error, Result};

/// The version string stored in every table's provenance (`vkbrdf` crate version).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The texel-centre convention, as stored in EXR headers.
pub const TEXEL_CENTRES: &str = "column i <-> x = (i + 0.5)/W, row j <-> y = (j + 0.5)/H";

/// The coordinate of texel `i` of `n`: `(i + 0.5)/n`.
pub fn texel_centre(i: usize, n: usize) -> f64 {
    (i as f64 + 0.5) / n as f64
}

/// A 2-D table size, `W × H` texels (both ≥ 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Grid {
    /// Columns (x).
    pub width: usize,
    /// Rows (y).
    pub height: usize,
}

impl Grid {
    /// A grid of `width × height`, refusing an empty one and one beyond OpenEXR's
    /// `i32` coordinates.
    pub fn new(width: usize, height: usize) -> Result<Grid> {
        if width == 0 || height == 0 {
            return Err(Error::Table(format!(
                "table size {width}x{height} has no texels; give W and H of at least 1"
            )));
        }
        let limit = i32::MAX as usize / 2;
        if width > limit || height > limit {
            return Err(Error::Table(format!(
                "table size {width}x{height} exceeds OpenEXR's limit of {limit} texels per side"
            )));
        }
        Ok(Grid { width, height })
    }

    /// Number of texels, `W·H` (cannot overflow: both sides are below 2³⁰).
    pub fn texels(&self) -> usize {
        self.width * self.height
    }
}

impl std::str::FromStr for Grid {
    type Err = Error;

    /// Parses `WxH` (e.g. `32x32`), or `N` for `N×N`.
    fn from_str(s: &str) -> Result<Grid> {
        let bad = || {
            Error::Table(format!(
                "table size `{s}` is not of the form WxH (e.g. 32x32) or N"
            ))
        };
        let number = |t: &str| t.trim().parse::<usize>().map_err(|_| bad());
        match s.split_once(['x', 'X', '×']) {
            Some((w, h)) => Grid::new(number(w)?, number(h)?),
            None => {
                let n = number(s)?;
                Grid::new(n, n)
            }
        }
    }
}
