//! The conductor's F on AVX-512's lanes as 16 short polynomials in `c`, one a segment of
//! c's float bits, fitted per material as [`super::poly`]'s one long polynomial is
//! (Trefethen 2013, ch. 3–4 and 8), and looked up in registers: a lane's segment indexes
//! a register of 16 entries (one permute a coefficient), so that a channel takes
//! [`DEGREE`] multiply-adds where the polynomial takes 14.
//!
//! Why short polynomials suffice: F's nearest singularities are the poles where
//! `η c + cos θt = 0`, at `c² = 1/(η² + 1)` — for the metals the f32 lanes take, about 0.27
//! off the real axis near c = 0 — and a segment's interpolant converges at a rate set by
//! that distance over the segment's half-width. The segments are octaves of c split in
//! four (c's exponent and the top two bits of its mantissa), so the narrowest lie nearest
//! the poles: [1/16, 1/8) in steps of 1/64 up to [1/2, 1) in steps of 1/8. Degree 5
//! leaves a truncation of at most ~0.35u on every metal tried (degree 4: ~7u;
//! docs/CPU_ENGINE.md).
//!
//! `t = c − centre` is exact on a lane's own segment (Sterbenz: the centre and c share
//! the octave), so the bound is Horner's and the coefficients' roundings only.

use super::poly::{bound, fit_channel, FitCache};
use super::{LaneConstants, METAL_FORM_BUDGET};
use crate::terms::math::MulAdd;

/// Segments a table: the 16 entries of one AVX-512 register, which one permute selects
/// from.
pub const SEGMENTS: usize = 16;

/// Each segment's polynomial degree.
pub const DEGREE: usize = 5;

/// c's bits shifted right by this are its exponent and the top two bits of its
/// mantissa: four segments an octave.
pub const SHIFT: u32 = 21;

/// Segments an octave.
const PER_OCTAVE: usize = 4;

/// `c.to_bits() >> SHIFT` of the first segment's start, 1/16 (exponent 123, mantissa 0).
pub const FIRST: i32 = 123 << 2;

/// The last segment reaches past 1 to here: an f32 frame's `c` may exceed 1 by its own
/// few ulp (as [`super::poly`]'s interval does).
const TOP: f64 = 1.001875;

/// The lowest `c` whose F a lane reads from these tables (`cpu::kernel::FAST_MIN_C`: the
/// f32 frames' lanes; smaller c takes the f64 frame). The segments below it are fitted
/// but not bounded: no lane takes their values.
const LOWEST_C: f64 = 0.1;

/// Chebyshev points of each segment's interpolant.
const NODES: usize = 17;

/// A conductor's F per channel as a polynomial a segment, `Σ bᵢ tⁱ` in
/// `t = c − centre[s]` (coefficients `b[ch][i][s]`, rounded once to f32), and the bound
/// the tables were admitted under.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segments {
    /// Each segment's centre, exactly an f32.
    pub centre: [f32; SEGMENTS],
    /// The coefficients: channel, power of t, segment.
    pub b: [[[f32; SEGMENTS]; DEGREE + 1]; 3],
    /// The worst channel's and segment's error bound in units of u = 2⁻²⁴ relative to F
    /// (see [`Segments::fit`]).
    pub bound_u: f64,
}

/// The segment of `c`: its exponent and top two mantissa bits less the first segment's,
/// at most the last (c ≥ 1 takes the last); below 1/16 (lanes another frame takes) the
/// index wraps, as the permute's four index bits do, and the value is meaningless.
#[inline(always)]
pub fn segment_of(c: f32) -> usize {
    let s = ((c.to_bits() >> SHIFT) as i32 - FIRST).min(SEGMENTS as i32 - 1);
    s as usize & (SEGMENTS - 1)
}

/// Segment `s`'s start and width in c (octave `s / 4` from 1/16, quarters of it).
fn span(s: usize) -> (f64, f64) {
    let octave = (2.0f64).powi((s / PER_OCTAVE) as i32 - 4);
    let width = octave / PER_OCTAVE as f64;
    (octave + width * (s % PER_OCTAVE) as f64, width)
}

/// Segment `s`'s centre (exactly an f32: a multiple of its width's half inside its
/// octave) and the half-width its polynomial is fitted over: the segment's own, the last
/// one's reaching [`TOP`].
fn centre_and_half_width(s: usize) -> (f64, f64) {
    let (start, width) = span(s);
    let centre = start + width / 2.0;
    if s == SEGMENTS - 1 {
        (centre, TOP - centre)
    } else {
        (centre, width / 2.0)
    }
}

impl Segments {
    /// The tables of `η = ior + i·extinction`, when every channel's bound over every
    /// segment a lane may read (c from 0.1, `FAST_MIN_C`, to 1.001875) is within
    /// [`METAL_FORM_BUDGET`] and the material may take the metal form (`constants.metal`),
    /// else `None`. A segment's bound is [`super::poly`]'s: the truncation of its
    /// interpolant, Horner's running error with or without FMA, and the coefficients'
    /// rounding, relative to the least F on the segment; `t` is exact.
    pub fn fit(constants: &LaneConstants, ior: [f64; 3], extinction: [f64; 3]) -> Option<Segments> {
        if !constants.metal {
            return None;
        }
        let mut out = Segments {
            centre: [0.0; SEGMENTS],
            b: [[[0.0; SEGMENTS]; DEGREE + 1]; 3],
            bound_u: 0.0,
        };
        for s in 0..SEGMENTS {
            let (centre, half_width) = centre_and_half_width(s);
            out.centre[s] = centre as f32;
            let read = centre + half_width > LOWEST_C;
            for ch in 0..3 {
                let fit = fit_channel::<{ DEGREE + 1 }>(
                    centre,
                    half_width,
                    NODES,
                    ior[ch],
                    extinction[ch],
                );
                // A segment no lane reads may stay zeros (its fit is never taken).
                let (pow, truncation) = fit.or((!read).then_some(([0.0; DEGREE + 1], 0.0)))?;
                let rounded = pow.map(|x| x as f32);
                if read {
                    let bound_u = bound(&rounded.map(f64::from), truncation, half_width, 256);
                    if bound_u > METAL_FORM_BUDGET {
                        return None;
                    }
                    out.bound_u = out.bound_u.max(bound_u);
                }
                for (i, b) in rounded.into_iter().enumerate() {
                    out.b[ch][i][s] = b;
                }
            }
        }
        Some(out)
    }

    /// [`Segments::fit`] of `η = ior + i·extinction` (with its [`LaneConstants`]), once a
    /// process per η (a fit takes ~0.2 ms).
    pub fn fitted(ior: [f64; 3], extinction: [f64; 3]) -> Option<Segments> {
        static FITS: FitCache<Segments> = FitCache::new();
        FITS.get(ior, extinction, || {
            Segments::fit(&LaneConstants::new(ior, extinction), ior, extinction)
        })
    }
}

/// F of the three channels of one lane from the material's tables: its segment's centre
/// and coefficients, Horner's rule in `t = c − centre` (valid for `c` in [`FAST_MIN_C`, 1]:
/// the f32 frames' lanes; elsewhere finite or NaN and meaningless, and those lanes take
/// another frame). With FMA these are the bits of AVX-512's register form
/// (`cpu::segments`), which looks the same entries up by permutes.
///
/// [`FAST_MIN_C`]: crate::cpu::kernel::FAST_MIN_C
#[inline(always)]
pub fn f_lane_segments<A: MulAdd>(c: f32, tables: &Segments) -> [f32; 3] {
    let s = segment_of(c);
    let t = c - tables.centre[s];
    let mut r = [0.0f32; 3];
    for (r, b) in r.iter_mut().zip(&tables.b) {
        *r = b[DEGREE][s];
    }
    for i in (0..DEGREE).rev() {
        for (r, b) in r.iter_mut().zip(&tables.b) {
            *r = A::mul_add(*r, t, b[i][s]);
        }
    }
    r
}

#[cfg(test)]
mod tests {
    use super::super::poly::tests::{sweep, worst_u, METALS};
    use super::*;
    use crate::terms::math::{Fused, Rounded};

    /// Every `c` a lane may bring: a dense sweep from 0.1 to 1, each segment's first and
    /// last f32 and their neighbours across the boundary, and the f32 numbers just past 1.
    fn lane_cs() -> Vec<f32> {
        let mut cs = sweep();
        for s in 3..SEGMENTS {
            let start = span(s).0 as f32;
            let below = f32::from_bits(start.to_bits() - 1);
            cs.extend([start, below, f32::from_bits(start.to_bits() + 1)]);
        }
        let mut c = 1.0f32;
        for _ in 0..64 {
            cs.push(c);
            c = f32::from_bits(c.to_bits() + 1);
        }
        cs.push(0.1);
        cs
    }

    /// The largest relative error in u against the f64 F, on both MulAdd kinds.
    fn measured(t: &Segments, ior: [f64; 3], ext: [f64; 3]) -> f64 {
        worst_u(&lane_cs(), ior, ext, |c| {
            [f_lane_segments::<Fused>(c, t), f_lane_segments::<Rounded>(c, t)]
        })
    }

    #[test]
    fn segments_tile_the_octaves_and_c_finds_its_own() {
        assert_eq!(span(0), (0.0625, 0.0625 / 4.0));
        assert_eq!(span(SEGMENTS - 1), (0.875, 0.125));
        for s in 0..SEGMENTS - 1 {
            let (a, w) = span(s);
            assert_eq!(a + w, span(s + 1).0, "segment {s}");
            let (centre, _) = centre_and_half_width(s);
            assert_eq!(f64::from(centre as f32), centre, "segment {s}'s centre");
            // Its first f32, its last, and the centre all index it.
            let first = a as f32;
            let last = f32::from_bits((span(s + 1).0 as f32).to_bits() - 1);
            for c in [first, last, centre as f32] {
                assert_eq!(segment_of(c), s, "c = {c}");
            }
        }
        // 1 and just past it: the last segment, whose fit reaches TOP.
        for c in [1.0f32, 1.0 + f32::EPSILON, 1.0018] {
            assert_eq!(segment_of(c), SEGMENTS - 1);
        }
        assert!(centre_and_half_width(SEGMENTS - 1).0 + centre_and_half_width(SEGMENTS - 1).1 >= TOP);
    }

    /// Each metal admitted, inside its bound everywhere a lane may read, and the bound far
    /// inside the metal form's budget — and below the polynomial's, which is what GGX's
    /// certificate then spends (docs/CPU_ENGINE.md).
    #[test]
    fn metals_fit_inside_their_bound() {
        for (ior, ext) in METALS {
            let constants = LaneConstants::new(ior, ext);
            let t = Segments::fit(&constants, ior, ext)
                .unwrap_or_else(|| panic!("{ior:?} {ext:?} should fit"));
            let err = measured(&t, ior, ext);
            assert!(err <= t.bound_u, "{ior:?}: measured {err}u > bound {}u", t.bound_u);
            assert!(t.bound_u <= 8.0, "{ior:?}: bound {}u", t.bound_u);
            if let Some(p) = super::super::poly::Polynomial::fit(&constants, ior, ext) {
                assert!(t.bound_u < p.bound_u, "{ior:?}: {} ≥ {}", t.bound_u, p.bound_u);
            }
        }
    }

    /// The tables give the bits of the lane form (`f_lane_segments` is what the register
    /// form must reproduce) only on the lane's own segment: with one segment's centre
    /// moved, c on that segment is off by far more than the bound.
    #[test]
    fn a_wrong_centre_is_caught() {
        let (ior, ext) = METALS[0];
        let mut t = Segments::fit(&LaneConstants::new(ior, ext), ior, ext).unwrap();
        t.centre[10] = t.centre[11];
        assert!(measured(&t, ior, ext) > 100.0 * t.bound_u);
    }

    /// A material the metal form refuses gets no tables.
    #[test]
    fn a_dielectric_gets_no_tables() {
        let dielectric = LaneConstants::new([1.5; 3], [0.0; 3]);
        assert!(Segments::fit(&dielectric, [1.5; 3], [0.0; 3]).is_none());
    }
}
