//! Quadrature over half vectors shared by `tests/properties.rs` (the reference) and
//! `tests/vulkan_properties.rs` (every backend).
//!
//! With slopes `(x̃, ỹ) = (mx r cos ψ, my r sin ψ)`, `h = normalize(x̃, ỹ, 1)` and
//! `r = e^u`, `dω_h = cos³θ_h mx my r² du dψ`. In (u, ψ) a Beckmann or GGX lobe of any
//! roughness is the same smooth bump near u = 0, decaying exponentially on both sides and
//! periodic in ψ, so the trapezoid rule converges exponentially.

use std::f64::consts::TAU;

/// A trapezoid grid in (u, ψ): `u_steps + 1` values over `[u_lo, u_hi]` (end weights ½),
/// `psi_steps` values of ψ (periodic). Calls `f(h, weight)` where `weight` is h's share
/// of solid angle.
pub fn for_each_half_vector(
    (mx, my): (f64, f64),
    (u_lo, u_hi, u_steps): (f64, f64, u32),
    psi_steps: u32,
    mut f: impl FnMut([f64; 3], f64),
) {
    let du = (u_hi - u_lo) / f64::from(u_steps);
    let dpsi = TAU / f64::from(psi_steps);
    for i in 0..=u_steps {
        let u = u_lo + du * f64::from(i);
        let end = if i == 0 || i == u_steps { 0.5 } else { 1.0 };
        let r = u.exp();
        for j in 0..psi_steps {
            let psi = dpsi * (f64::from(j) + 0.5);
            let (sx, sy) = (mx * r * psi.cos(), my * r * psi.sin());
            let len = (1.0 + sx * sx + sy * sy).sqrt();
            let h = [sx / len, sy / len, 1.0 / len];
            f(h, end * h[2].powi(3) * mx * my * r * r * du * dpsi);
        }
    }
}
