//! The tables' directions made inside the engine ([`GeneratedDirections`]), as the Vulkan
//! kernel makes them on the device: a half/difference slice is evaluated texel block by
//! texel block on every core, each block's directions formed where it is evaluated, with
//! no tuple batch on the host. The directions are the host's
//! ([`SliceGrid::texel_directions`], rounded to f32 as the table's rows are), so the slice is
//! bit for bit the one its tuples give. The importance-sampled sums of the albedo and DFG
//! tables are made the same way ([`super::importance`]).

use super::chunk::Source;
use super::slice_tuples::SliceTuples;
use super::CpuEngine;
use crate::backend::{GeneratedDirections, Output, Request};
use crate::directions::{ImportanceJob, SliceGrid};
use crate::error::Result;
use crate::material::Material;

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
        let slice = SliceTuples::new(grid, material.is_anisotropic());
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
