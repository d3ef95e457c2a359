//! The accepted ranges of a material's numbers, as the parser checks them (each returns
//! the message for a value out of range), and how an error message shows a number.

/// A number as an error message shows it: 1e40, not forty-one digits.
pub(super) fn shown(x: f64) -> String {
    if x != 0.0 && !(1e-4..1e16).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

// The accepted ranges (FORMULAS.md §1, "Overflow": every accepted material gives a finite
// output, or its saturation, at every representable cosine). Each bound is where the
// float32 kernel can no longer carry the parameter or a product of two of them; the
// stress corpus (src/stress/corpus.rs) evaluates every bound.

/// Roughness in [1e-7, 1e4]. Below 1e-7 the lobe is narrower than the angular resolution
/// of float32 directions (~6e-8 rad), so no f32 input can resolve it; above 1e4,
/// `m² tan²θ` at the smallest cosine the float32 path takes (1e-15) leaves float32's range.
pub(super) fn roughness_range(x: f64) -> Option<&'static str> {
    (!(x.is_finite() && (1e-7..=1e4).contains(&x)))
        .then_some("must be a finite number > 0, in [1e-7, 1e4]")
}
/// Exponent in [0, 1e18]. A lobe `cos^e` is `exp(e ln cos)`, and at its peak `ln cos` is
/// known only to the f64 frame's resolution, `|δ sin²| ~ 1e-32`, which moves the lobe by
/// ~e·1e-32 relative: within the reference's 1e-12 up to 1e18 (the arbitrary-precision judge
/// found 3e-8 at 1e24), and by 1e38 it decides between the peak and 0 (the reference and
/// the kernel then disagree on which). Such a lobe is narrower (1/√e rad) than any
/// geometry f32 inputs can resolve.
pub(super) fn exponent_range(x: f64) -> Option<&'static str> {
    (!(x.is_finite() && (0.0..=1e18).contains(&x)))
        .then_some("must be a finite number ≥ 0, in [0, 1e18]")
}
/// IOR in [1e-6, 1e18]: `|η|²` (and `1/|η|²` for the conductor's `cos θ_t`) must stay
/// within float32's range in the kernel's Fresnel terms.
pub(super) fn ior_range(x: f64) -> Option<&'static str> {
    (!(x.is_finite() && (1e-6..=1e18).contains(&x)))
        .then_some("must be a finite number > 0, in [1e-6, 1e18]")
}
/// Extinction in [0, 1e18], for the same reason as [`ior_range`]; beyond it F is 1 to
/// every digit anyway.
pub(super) fn extinction_range(x: f64) -> Option<&'static str> {
    (!(x.is_finite() && (0.0..=1e18).contains(&x)))
        .then_some("must be a finite number ≥ 0, in [0, 1e18]")
}
/// Colours and weights in [0, 1e18]: the kernel multiplies a weight by a colour in float32
/// (`s · c_spec`, `d · c_diff / π`), and 1e18 · 1e18 stays below 3.4e38.
pub(super) fn colour_range(x: f64) -> Option<&'static str> {
    (!(x.is_finite() && (0.0..=1e18).contains(&x)))
        .then_some("must be a finite number ≥ 0, in [0, 1e18]")
}
pub(super) fn unit_interval(x: f64) -> Option<&'static str> {
    (!(x.is_finite() && (0.0..=1.0).contains(&x))).then_some("must be in [0, 1]")
}
