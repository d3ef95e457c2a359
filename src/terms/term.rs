//! What every term says about itself, below the families that say it: [`Term`], and the
//! [`Illegal`] a legality rule returns.

/// An RGB triple (linear, per channel).
pub type Rgb = [f64; 3];

/// What the layers above need to know about one term, said once (in its family's list and
/// its file).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Term {
    /// The spelling in a materials file.
    pub toml_name: &'static str,
    /// The work the formula comes from, as the term's file and GLSL block cite it.
    pub citation: &'static str,
    /// The macro the kernel compares a material's code against and its value, the family
    /// enum's discriminant (the `GpuMaterial` slot is the family's: `kind.y` D, `kind.z` G,
    /// `kind.w` F and convention; `gpu::layout` injects every code into the GLSL).
    pub gpu_code: (&'static str, u32),
    /// The kernel feature that compiles the term's code: its bit in `FeatureSet` and its
    /// preprocessor name (`HAS_*`); `None` for a term with no code (`G = 1`, `F = 1`).
    pub feature: Option<(u32, &'static str)>,
}

/// A combination the contract does not define: the key to blame and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Illegal {
    /// The materials-file key the message is about (`roughness` or `geometry`).
    pub key: &'static str,
    /// What is wrong and what to use instead.
    pub message: String,
}
