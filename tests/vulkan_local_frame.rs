//! The kernel's local f32 frame (glsl/frame64.glsl, `frame_scalars_local32`): GGX lanes
//! with N = +z evaluated from f32 l, v where D's certificate (`ggx_local_frame_ok`) holds,
//! the rest on the f64 frame. Tested where the certificate is hardest: h where D's slope is
//! steepest (tan θ_h = m/2, m, 2m), c from 0.02 (below `LOCAL32_MIN_C`) to 1, unnormalised
//! inputs, for the geometries and Fresnel terms that read c and the cosines.

mod common;

use vkbrdf::backend::{Backend, Output, Request};
use vkbrdf::batch::{memory_source, Batch};
use vkbrdf::gpu::VulkanOptions;
use vkbrdf::material::{parse_materials, Material};
use vkbrdf::reference::CpuReference;

/// The materials of the test: GGX at every roughness of `m_all`, with each G and F that
/// reads c or the cosines, `KINDS` materials a roughness.
const KINDS: [(&str, &str); 4] = [
    (
        "smith-correlated",
        "fresnel = \"conductor\"\nior = [0.2, 0.9, 1.5]\nextinction = [3.0, 2.4, 1.9]",
    ),
    ("smith", "fresnel = \"schlick\"\nf0 = [0.04, 0.5, 0.9]"),
    ("cook-torrance", "fresnel = \"none\""),
    ("schlick-smith", "fresnel = \"schlick\"\nf0 = 0.04"),
];

/// One frame's run: within the rule and the certificate's bound, and both frames taken.
fn check_frame(frame: &str, float64: bool, batch: &Batch, mats: &[Material], reference: &Output) {
    let request = Request { terms: true };
    let Some(mut gpu) = common::vulkan() else {
        return;
    };
    if gpu.float64_frame() != float64 {
        eprintln!("{frame}: not this device's frame, skipped");
        return;
    }
    let out = gpu.evaluate(batch, mats, &request).expect("vulkan");
    let worst = common::rule::assert_within_rule(frame, batch, mats, &out, reference);
    // The bound the certificate is built on (docs/VULKAN.md, "The local frames"): its
    // budget for D's turn plus 45u for the frame's other roundings and the f32 terms' own.
    let bound = 4e-6 + 45.0 * f64::from(f32::EPSILON) / 2.0;
    assert!(
        worst <= bound,
        "{frame}: largest relative error {worst:.2e} above {bound:.2e}"
    );
    // Both frames ran: without the local f32 frame some rows' bits change (the certified
    // lanes) and others' do not (c below LOCAL32_MIN_C, the steepest slopes).
    let mut without = common::vulkan_with(VulkanOptions {
        extra_defines: vec![("NO_LOCAL32_FRAME".into(), "1".into())],
        ..VulkanOptions::default()
    })
    .expect("the same device");
    let plain = without.evaluate(batch, mats, &request).expect("vulkan");
    let rows_differ = (0..batch.len())
        .filter(|&r| out.brdf[3 * r..3 * r + 3] != plain.brdf[3 * r..3 * r + 3])
        .count();
    assert!(
        rows_differ > batch.len() / 4 && rows_differ < batch.len(),
        "{frame}: {rows_differ} of {} rows changed without the local f32 frame",
        batch.len()
    );
    eprintln!(
        "{frame}: {} rows, largest relative error {worst:.2e} (bound {bound:.2e}); {rows_differ} changed without the local f32 frame",
        batch.len()
    );
}

/// One test in this file: it sets `VKBRDF_DISABLE_FLOAT64` for its second half (the f32
/// frame of devices without f64, whose local f32 frame forms the lengths as float-float
/// pairs), which no other test in the process may see.
#[test]
fn ggx_local_f32_frame_within_its_bound_where_ds_slope_is_steepest() {
    let m_all = [0.01, 0.05, 0.1, 0.3, 0.7, 1.5];
    let toml = common::steepest::materials_toml("ggx", &m_all, &KINDS);
    let mats = parse_materials(&toml, "ggx-local32").expect("materials");
    let batch = Batch::new(
        // c from 0.02, below `LOCAL32_MIN_C`.
        common::steepest::rows_z(common::steepest::ggx_pairs, 0.02, &m_all, KINDS.len()),
        10,
        mats.len(),
        &memory_source(),
    )
    .expect("batch");
    let reference = CpuReference::new()
        .evaluate(&batch, &mats, &Request { terms: true })
        .expect("reference");
    check_frame(
        "the float64 frame's device",
        true,
        &batch,
        &mats,
        &reference,
    );
    std::env::set_var("VKBRDF_DISABLE_FLOAT64", "1");
    check_frame(
        "the f32 frame (VKBRDF_DISABLE_FLOAT64=1)",
        false,
        &batch,
        &mats,
        &reference,
    );
    std::env::remove_var("VKBRDF_DISABLE_FLOAT64");
}
