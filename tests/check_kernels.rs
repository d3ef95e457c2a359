//! `vkbrdf check` compiles its kernels up front (`Backend::prepare_kernels`, several at
//! once): the plans it gives must be the kernels its batches then use, or the preparation
//! is wasted and the compiles happen one at a time after all. A backend that records the
//! Vulkan engine's pipeline count at every evaluation shows that none is created once the
//! check's loop runs.

mod common;

use vkbrdf::backend::{Backend, KernelPlan, Output, Request};
use vkbrdf::batch::Batch;
use vkbrdf::check::{self, CheckOptions};
use vkbrdf::gpu::VulkanBackend;
use vkbrdf::material::Material;

/// The Vulkan engine, with its pipeline count recorded after the preparation and after
/// every evaluation.
struct Counting {
    inner: VulkanBackend,
    prepared: Option<u64>,
    at_evaluations: Vec<u64>,
}

impl Backend for Counting {
    fn name(&self) -> String {
        self.inner.name()
    }

    fn evaluate(
        &mut self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
    ) -> vkbrdf::Result<Output> {
        let out = self.inner.evaluate(batch, materials, request)?;
        self.at_evaluations.push(self.inner.pipelines_created());
        Ok(out)
    }

    fn share_kernels(&mut self, materials: &[Material]) {
        self.inner.share_kernels(materials);
    }

    fn prepare_kernels(&mut self, plans: &[KernelPlan<'_>]) -> vkbrdf::Result<()> {
        self.inner.prepare_kernels(plans)?;
        self.prepared = Some(self.inner.pipelines_created());
        Ok(())
    }
}

#[test]
fn a_check_compiles_every_kernel_before_its_first_batch() {
    let Some(inner) = common::vulkan() else {
        return;
    };
    let mut backend = Counting {
        inner,
        prepared: None,
        at_evaluations: Vec::new(),
    };
    // GGX's combinations: isotropic and anisotropic, every geometry, convention and
    // Fresnel term (two kernels), and few tuples each.
    let options = CheckOptions {
        tuples: 64,
        seed: 7,
        only: Some("ggx".into()),
    };
    let reports = check::run(&mut backend, &options, &mut |_| {}).unwrap();
    assert!(reports.len() > 20, "{} GGX combinations", reports.len());
    assert!(reports.iter().all(|r| r.pass()), "every combination passes");
    let prepared = backend.prepared.expect("the check prepared its kernels");
    assert!(prepared >= 2, "{prepared} pipelines prepared");
    // The kernels were made on several threads at once: the validation layer (with its
    // thread-safety checks) reports nothing.
    assert!(
        backend.inner.validation_enabled(),
        "the validation layer is not installed (apt-get install vulkan-validationlayers): this test needs it"
    );
    assert_eq!(
        backend.inner.validation_message_count(),
        0,
        "{:?}",
        backend.inner.validation_messages()
    );
    assert_eq!(backend.at_evaluations.len(), reports.len());
    assert!(
        backend.at_evaluations.iter().all(|&n| n == prepared),
        "pipelines created while the check ran (after each batch): {:?}, prepared {prepared}",
        backend.at_evaluations
    );
}
