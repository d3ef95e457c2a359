//! The bench's kernel-only timing (tuples resident in device-local memory, timestamp
//! queries): the resident path must compute what `evaluate` computes, cover the tuples it
//! says it timed, and clock with device timestamps where the queue has them.

mod common;

use vkbrdf::backend::{Backend, Request};
use vkbrdf::bench::scenarios;
use vkbrdf::features::FeatureSet;
use vkbrdf::gpu::KernelClock;

#[test]
fn resident_kernel_computes_what_evaluate_computes() {
    let Some(mut gpu) = common::vulkan() else {
        return;
    };
    // One single-material scenario and the mixed one (grouped by material on the device).
    for name in ["mitsuba-ggx", "mixed-8", "ward-aniso"] {
        let sc = scenarios::by_name(name).expect("scenario exists");
        let batch = scenarios::batch(&sc, 5000, 7);
        let want = gpu
            .evaluate(&batch, &sc.materials, &Request::default())
            .expect("evaluate");
        let t = gpu
            .kernel_timing(
                &batch,
                &sc.materials,
                &Request::default(),
                5000,
                2,
                FeatureSet::EMPTY,
            )
            .expect("kernel timing");
        assert_eq!(t.resident_tuples, 5000, "{name}");
        assert_eq!(t.dispatches, 1, "{name}");
        assert!(
            t.seconds > 0.0 && t.seconds.is_finite(),
            "{name}: {}",
            t.seconds
        );
        assert_eq!(t.brdf.len(), want.brdf.len(), "{name}");
        let differ = t
            .brdf
            .iter()
            .zip(&want.brdf)
            .filter(|(a, b)| a.to_bits() != b.to_bits())
            .count();
        assert_eq!(differ, 0, "{name}: resident outputs differ from evaluate's");
        // The backend's own buffers are bound again afterwards: evaluate still agrees.
        let again = gpu
            .evaluate(&batch, &sc.materials, &Request::default())
            .expect("evaluate after timing");
        assert_eq!(
            again.brdf, want.brdf,
            "{name}: evaluate after a resident timing"
        );
    }
    assert_clean(&gpu);
}

/// No validation-layer message (barriers, buffer usages, query resets) where the layer runs.
fn assert_clean(gpu: &vkbrdf::gpu::VulkanBackend) {
    assert_eq!(
        gpu.validation_message_count(),
        0,
        "{:?}",
        gpu.validation_messages()
    );
}

#[test]
fn repeated_dispatches_cover_the_requested_tuples() {
    let Some(mut gpu) = common::vulkan() else {
        return;
    };
    let sc = scenarios::by_name("lambert").expect("scenario exists");
    let batch = scenarios::batch(&sc, 4096, 1);
    let t = gpu
        .kernel_timing(
            &batch,
            &sc.materials,
            &Request::default(),
            40_000,
            1,
            FeatureSet::EMPTY,
        )
        .expect("kernel timing");
    assert_eq!(t.resident_tuples, 4096);
    assert_eq!(t.dispatches, 10, "40 000 tuples over 4096 resident rows");
    assert_eq!(t.bytes_per_tuple, 4 * (10 + 3));
    // lavapipe's queue has timestamps (timestampValidBits 64): the device clock is used.
    assert_eq!(t.clock, KernelClock::Timestamps);
    assert_clean(&gpu);
}

#[test]
fn copy_kernel_moves_the_row_and_three_floats() {
    let Some(mut gpu) = common::vulkan() else {
        return;
    };
    for cols in [10, 13] {
        let t = gpu
            .copy_timing(cols, 10_000, 30_000, 1)
            .expect("copy timing");
        assert_eq!(t.bytes_per_tuple, 4 * (cols + 3));
        assert_eq!(t.dispatches, 3);
        assert!(t.seconds > 0.0 && t.seconds.is_finite());
        assert!(
            t.brdf.is_empty(),
            "the copy kernel's output is not read back"
        );
    }
    // Wider rows fit fewer tuples into the same device limits.
    assert!(gpu.resident_capacity(10) >= gpu.resident_capacity(13));
    assert_clean(&gpu);
}
