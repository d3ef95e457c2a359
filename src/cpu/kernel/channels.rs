//! The BRDF's channels from D, G, F and K as a lane or a register forms them (FORMULAS.md
//! §5–§6), and the one test that sends an output the lanes cannot vouch for to the
//! reference — shared by the lane loops (`finish_lane`) and the register path.

use super::params::Params;
use crate::terms::math::MulAdd;
use crate::terms::real::Real;

/// Outputs above this go to the reference, which decides saturation (FORMULAS.md §1): an
/// f32 result this large may be a rounded value of an exact one above `f32::MAX`.
pub const OUTPUT_LIMIT: f32 = 1e37;

/// The BRDF's channels of a lane, or of a register of lanes (`cpu::register`), from D and
/// G as quotients, F of each channel (asked for once a channel after D·G·K, so that a
/// register path holds one channel's values at a time) and the cosines (FORMULAS.md
/// §5–§6): D·G·K over one division (the divider is what a block waits on); and whether an
/// output may be non-finite or above [`OUTPUT_LIMIT`] (the lane then goes to the
/// reference).
#[inline(always)]
pub(crate) fn brdf_of<A: MulAdd, T: Real>(
    p: &Params,
    d: (T, T),
    g: (T, T),
    f: impl FresnelOf<T>,
    cos_i: T,
    cos_o: T,
) -> ([T; 3], T::Mask) {
    let (dgk, size) = dgk_of(p, d, g, cos_i, cos_o);
    channels_of::<A, T>(p, dgk, size, f)
}

/// F of a lane's (or a register's) channels, formed when [`channels_of`] asks — a trait
/// with an inlined method rather than a closure, which LLVM left out of line on the
/// register path (and every intrinsic in it became a call).
pub(crate) trait FresnelOf<T> {
    /// F of channel `ch`.
    fn channel(&self, ch: usize) -> T;
}

impl<T: Copy> FresnelOf<T> for [T; 3] {
    #[inline(always)]
    fn channel(&self, ch: usize) -> T {
        self[ch]
    }
}

/// [`brdf_of`]'s first half: D·G·K and the sum of magnitudes its test starts from.
#[inline(always)]
pub(crate) fn dgk_of<T: Real>(p: &Params, d: (T, T), g: (T, T), cos_i: T, cos_o: T) -> (T, T) {
    // K (FORMULAS.md §5) as a quotient. Each denominator is ≥ 1e-20 and the product of
    // the three ≤ 1e24 on the lanes' cosines (≥ 1e-4), so the one division neither
    // overflows nor loses the quotient to underflow.
    let (kn, kd) = p.k.ratio(cos_i, cos_o);
    let dgk = (d.0 * g.0 * kn) / (d.1 * g.1 * kd);
    // One test for every output: a sum of magnitudes is NaN if any is, and above
    // OUTPUT_LIMIT if any is (a sum that only rounds up past it sends a lane to the
    // reference needlessly, never the other way) — 18 operations where a test a value
    // took 45. The quotients' parts stand for the terms (each term is finite when they
    // are), so the test, and with it the BRDF, is the same with and without terms. Every
    // part is ≥ 0 (or NaN) on the lanes the test decides — those whose frame passed its
    // tests, cosines ≥ GRAZING; the others go to the reference whatever it says — so the
    // sum of the values is the sum of their magnitudes, without an `abs` a value.
    (dgk, d.0 + d.1 + g.0 + g.1 + dgk)
}

/// [`brdf_of`]'s second half: the channels from D·G·K and F, and the test.
#[inline(always)]
pub(crate) fn channels_of<A: MulAdd, T: Real>(
    p: &Params,
    dgk: T,
    mut size: T,
    f: impl FresnelOf<T>,
) -> ([T; 3], T::Mask) {
    let mut brdf = [dgk; 3];
    for ch in 0..3 {
        let f = f.channel(ch);
        let b = A::mul_add(
            dgk.splat_as(p.spec[ch]),
            dgk * f,
            dgk.splat_as(p.diffuse[ch]),
        );
        brdf[ch] = b;
        // b and F are ≥ 0 (or NaN) on the lanes the test decides, as in `dgk_of` (F is a
        // reflectance; Schlick's may come out −1e-35 at c a rounding above 1, which moves
        // no test).
        size = size + (b + f);
    }
    // `≤` is false for NaN: one comparison catches both.
    (brdf, !size.le_scalar(OUTPUT_LIMIT))
}
