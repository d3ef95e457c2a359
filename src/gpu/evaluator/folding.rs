//! Which pipeline a batch gets: for a batch of one material and at least
//! [`fold_material_min_tuples`] rows, the kernel with that material folded in as
//! specialization constants (`Kernels::folded`, docs/VULKAN.md), while the evaluator's
//! budget of folds lasts; else the one that reads the material table.
//!
//! [`fold_material_min_tuples`]: crate::gpu::VulkanOptions::fold_material_min_tuples

use super::VulkanBackend;
use crate::error::Result;
use crate::features::FeatureSet;
use crate::gpu::fold::Fold;
use crate::gpu::layout::GpuMaterial;
use crate::material::Material;
use ash::vk;

impl VulkanBackend {
    /// Sets [`fold_material_min_tuples`] (for measuring the folded kernel against the
    /// table-reading one) and returns the value it replaces.
    ///
    /// [`fold_material_min_tuples`]: crate::gpu::VulkanOptions::fold_material_min_tuples
    pub fn set_fold_material_min_tuples(&mut self, tuples: usize) -> usize {
        std::mem::replace(&mut self.options.fold_material_min_tuples, tuples)
    }

    /// Whether the last evaluation's kernel had the batch's one material folded in as
    /// specialization constants ([`fold_material_min_tuples`]).
    ///
    /// [`fold_material_min_tuples`]: crate::gpu::VulkanOptions::fold_material_min_tuples
    pub fn last_material_folded(&self) -> bool {
        self.last_folded
    }

    /// The pipeline for `features` and a batch of `tuples` rows over `materials`: with the
    /// material folded in ([`Kernels::folded`]) for a batch of one material and at least
    /// [`fold_material_min_tuples`] rows, while the evaluator's budget of folds lasts; else
    /// the table-reading one.
    ///
    /// [`Kernels::folded`]: crate::gpu::kernel::Kernels::folded
    /// [`fold_material_min_tuples`]: crate::gpu::VulkanOptions::fold_material_min_tuples
    pub(super) fn pipeline_for(
        &mut self,
        features: FeatureSet,
        (rows, materials): (&[GpuMaterial], &[Material]),
        tuples: usize,
    ) -> Result<vk::Pipeline> {
        self.last_folded = false;
        if let ([row], [material]) = (rows, materials) {
            if tuples >= self.options.fold_material_min_tuples {
                let fold = Fold::new(row, material);
                if let Some(p) = self.kernels.folded(features, &fold)? {
                    self.last_folded = true;
                    return Ok(p);
                }
            }
        }
        Ok(self.kernels.pipeline(features)?.raw())
    }

    /// Rows an invocation takes in the pipeline [`Self::pipeline_for`] chose last: the
    /// folded kernels' count ([`VulkanOptions::folded_tuples_per_invocation`]) when the
    /// material was folded in, else one.
    ///
    /// [`VulkanOptions::folded_tuples_per_invocation`]: crate::gpu::VulkanOptions::folded_tuples_per_invocation
    pub(super) fn rows_per_invocation(&self) -> u32 {
        if self.last_folded {
            self.folded_per_invocation
        } else {
            1
        }
    }
}
