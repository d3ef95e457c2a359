//! A half/difference slice's tuples, made on demand ([`SliceTuples`]): what the engine's
//! workers read block by block (`Source::Slice`) when the slice's directions are made in
//! the engine (`generated`). Below both.

use crate::batch::Tuple;
use crate::directions::SliceGrid;

/// The tuples of a half/difference slice, made on demand: texel `t` (row-major, θ_h
/// fastest) is the tuple `table::slice` builds for it.
#[derive(Debug, Clone, Copy)]
pub(super) struct SliceTuples {
    grid: SliceGrid,
    /// Whether the tuples carry the tables' tangent (+x): anisotropic materials.
    tangent: bool,
}

impl SliceTuples {
    /// The slice over `grid`, its tuples with the tables' tangent when `tangent`.
    pub(super) fn new(grid: SliceGrid, tangent: bool) -> SliceTuples {
        SliceTuples { grid, tangent }
    }

    /// Texels in the slice.
    pub(super) fn len(&self) -> usize {
        self.grid.texels() as usize
    }

    /// The columns its tuples have as rows (13 with the tangent, else 10).
    pub(super) fn columns(&self) -> usize {
        if self.tangent {
            crate::batch::COLUMNS_TANGENT
        } else {
            crate::batch::COLUMNS_PLAIN
        }
    }

    /// Texel `t`'s tuple (material 0).
    pub(super) fn tuple(&self, t: usize) -> Tuple {
        let (l, v) = self.grid.texel_directions(t as u64);
        let f = |a: [f64; 3]| a.map(|x| x as f32);
        Tuple {
            l: f(l),
            v: f(v),
            // The slice's frame (`SliceGrid`): n = +z, tangent +x.
            n: [0.0, 0.0, 1.0],
            material: 0,
            t: self.tangent.then_some([1.0, 0.0, 0.0]),
        }
    }
}
