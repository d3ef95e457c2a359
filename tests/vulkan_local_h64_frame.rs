//! The kernel's local frame for Beckmann (glsl/frame_local_h64.glsl,
//! `frame_scalars_local_h64`): Beckmann Cook–Torrance lanes with N = +z on a device with
//! f64, h in f64 and l, v in f32, with no certificate. Tested where Beckmann's D is
//! steepest (tan θ_h = m, 3m, 9m and either side of `exp`'s cut-off), c from 0.02 (below
//! `LOCAL32_MIN_C`) to 1, unnormalised inputs, for every geometry and the Fresnel terms
//! that read c and the cosines: within FORMULAS.md §1's rule, and the frame taken.

mod common;

use vkbrdf::backend::{Backend, Request};
use vkbrdf::batch::{memory_source, Batch};
use vkbrdf::gpu::VulkanOptions;
use vkbrdf::material::parse_materials;
use vkbrdf::reference::CpuReference;

/// The geometries and Fresnel terms of the test, each with Beckmann at every roughness.
const KINDS: [(&str, &str); 5] = [
    (
        "smith-fast",
        "fresnel = \"conductor\"\nior = [0.2, 0.9, 1.5]\nextinction = [3.0, 2.4, 1.9]",
    ),
    ("smith", "fresnel = \"schlick\"\nf0 = [0.04, 0.5, 0.9]"),
    ("cook-torrance", "fresnel = \"none\""),
    ("schlick-smith", "fresnel = \"schlick\"\nf0 = 0.04"),
    (
        "neubelt",
        "fresnel = \"conductor\"\nior = [0.27, 0.68, 1.2]\nextinction = [3.61, 2.63, 2.3]",
    ),
];

#[test]
fn beckmann_local_h64_frame_within_the_rule_where_ds_slope_is_steepest() {
    let Some(mut gpu) = common::vulkan() else {
        return;
    };
    if !gpu.float64_frame() {
        eprintln!("the device has no f64: the frame is not compiled, skipped");
        return;
    }
    let m_all = [0.01, 0.05, 0.1, 0.3, 0.7, 1.5];
    let toml = common::steepest::materials_toml("beckmann", &m_all, &KINDS);
    let mats = parse_materials(&toml, "beckmann-local-h64").expect("materials");
    // c from 0.02, below `LOCAL32_MIN_C`.
    let rows =
        common::steepest::rows_z(common::steepest::beckmann_pairs, 0.02, &m_all, KINDS.len());
    let batch = Batch::new(rows, 10, mats.len(), &memory_source()).expect("batch");
    let request = Request { terms: true };
    let reference = CpuReference::new()
        .evaluate(&batch, &mats, &request)
        .expect("reference");
    let out = gpu.evaluate(&batch, &mats, &request).expect("vulkan");
    let worst =
        common::rule::assert_within_rule("the local h64 frame", &batch, &mats, &out, &reference);
    // The frame ran: without it (the f64 local frame in every lane) some rows' bits change
    // — l and v are f32 products here — and others' do not (c below LOCAL32_MIN_C, and
    // D at exp's cut-off, 0 either way).
    let mut without = common::vulkan_with(VulkanOptions {
        extra_defines: vec![("NO_LOCAL_H64_FRAME".into(), "1".into())],
        ..VulkanOptions::default()
    })
    .expect("the same device");
    let plain = without.evaluate(&batch, &mats, &request).expect("vulkan");
    let worst_plain =
        common::rule::assert_within_rule("the f64 local frame", &batch, &mats, &plain, &reference);
    // As accurate as the f64 local frame (whose h it shares to ~1e-12): l and v in f32
    // add at most a few u to the cosines and sines, K and G (docs/VULKAN.md, "The local
    // frames"): 10u allowed beyond the f64 local frame's worst.
    let bound = worst_plain + 10.0 * f64::from(f32::EPSILON) / 2.0;
    assert!(
        worst <= bound,
        "largest relative error {worst:.2e}, the f64 local frame's {worst_plain:.2e}"
    );
    let rows_differ = (0..batch.len())
        .filter(|&r| out.brdf[3 * r..3 * r + 3] != plain.brdf[3 * r..3 * r + 3])
        .count();
    assert!(
        rows_differ > batch.len() / 10 && rows_differ < batch.len(),
        "{rows_differ} of {} rows changed without the local h64 frame",
        batch.len()
    );
    eprintln!(
        "{} rows, largest relative error {worst:.2e} (the f64 local frame's {worst_plain:.2e}); \
         {rows_differ} changed without the local h64 frame",
        batch.len()
    );
}
