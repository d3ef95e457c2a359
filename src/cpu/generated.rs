//! The tables' directions made inside the engine ([`GeneratedDirections`]), as the Vulkan
//! kernel makes them on the device: a half/difference slice is evaluated texel block by
//! texel block on every core, each block's directions formed where it is evaluated, with
//! no tuple batch on the host. The directions are the host's
//! ([`SliceGrid::texel_directions`], rounded to f32 as the table's rows are), so the slice is
//! bit for bit the one its tuples give. The importance-sampled sums of the albedo and DFG
//! tables are made the same way ([`super::importance`]).

use super::{CpuEngine, Source};
use crate::backend::{GeneratedDirections, Output, Request};
use crate::batch::Tuple;
use crate::directions::{ImportanceJob, SliceGrid};
use crate::error::Result;
use crate::material::Material;

/// The tuples of a half/difference slice, made on demand: texel `t` (row-major, θ_h
/// fastest) is the tuple `table::slice` builds for it.
#[derive(Debug, Clone, Copy)]
pub(super) struct SliceTuples {
    grid: SliceGrid,
    /// Whether the tuples carry the tables' tangent (+x): anisotropic materials.
    tangent: bool,
}

impl SliceTuples {
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

impl GeneratedDirections for CpuEngine {
    fn half_diff_slice(
        &mut self,
        material: &Material,
        grid: SliceGrid,
        request: &Request,
    ) -> Option<Result<Output>> {
        // A slice too large to index on this platform takes the host path (which refuses
        // it with a clear error).
        usize::try_from(grid.texels()).ok()?;
        let slice = SliceTuples {
            grid,
            tangent: material.is_anisotropic(),
        };
        let mut out = Output::default();
        let run = self.run(
            Source::Slice(&slice),
            std::slice::from_ref(material),
            request,
            &mut out,
        );
        Some(run.map(|()| out))
    }

    fn importance_sums(
        &mut self,
        job: &ImportanceJob,
        progress: &mut dyn FnMut(u64),
    ) -> Option<Result<Vec<[f64; 2]>>> {
        Some(self.sum_importance(job, progress))
    }
}
