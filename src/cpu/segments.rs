//! The conductor's segment tables (`terms::f::conductor::segments`) in AVX-512's
//! registers: a register of `c` to F's three channels by permutes (one a coefficient,
//! each selecting a lane's segment from a register of 16 entries), for the register path
//! and, a block at a time, for the lane loops — the same instructions on both, so a lane's
//! F is the same bits on either (and the lane form's, `f_lane_segments` with FMA).

use crate::terms::f::conductor::segments::{self, Segments, DEGREE, FIRST, SEGMENTS, SHIFT};
use crate::terms::math::Fused;
use crate::terms::real::Real;
#[cfg(target_arch = "x86_64")]
use core::arch::x86_64::{__m512, __m512i};

/// Lanes that take F from the segment tables: one f32 (the lane form), or a register of
/// the register path (`cpu::register`: AVX-512's permutes, [`f_register`]).
pub(super) trait SegmentLanes: Real {
    /// Whether a plan may hand these lanes tables (AVX-512's registers, and the lane form
    /// that gives their bits); elsewhere the caller compiles no branch for them.
    const TABLES: bool;

    /// F of the three channels of these lanes from `tables`.
    fn f_segments(c: Self, tables: &Segments) -> [Self; 3];
}

impl SegmentLanes for f32 {
    const TABLES: bool = true;

    #[inline(always)]
    fn f_segments(c: f32, tables: &Segments) -> [f32; 3] {
        segments::f_lane_segments::<Fused>(c, tables)
    }
}

/// F of the three channels of a register of 16 lanes from `tables`: each lane's segment
/// from c's bits (`segments::segment_of`, whose wrap below 1/16 is the permute's own four
/// index bits), its centre and coefficients by `vpermps`, Horner's rule with FMA, the
/// channels' steps interleaved. Plain loops and functions, no closures: LLVM left a
/// closure here out of line, outside AVX-512's features, and every permute became a call
/// (2× slower).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(super) fn f_register(
    simd: pulp::x86::V4,
    c: pulp::f32x16,
    tables: &Segments,
) -> [pulp::f32x16; 3] {
    let f = simd.avx512f;
    let c: __m512 = bytemuck::cast(c);
    let top = f._mm512_set1_epi32(SEGMENTS as i32 - 1);
    let above = f._mm512_sub_epi32(
        f._mm512_srli_epi32::<SHIFT>(f._mm512_castps_si512(c)),
        f._mm512_set1_epi32(FIRST),
    );
    let idx = f._mm512_min_epi32(above, top);
    let t = f._mm512_sub_ps(c, look(simd, idx, &tables.centre));
    let mut r = [t; 3];
    for ch in 0..3 {
        r[ch] = look(simd, idx, &tables.b[ch][DEGREE]);
    }
    for i in (0..DEGREE).rev() {
        for ch in 0..3 {
            r[ch] = f._mm512_fmadd_ps(r[ch], t, look(simd, idx, &tables.b[ch][i]));
        }
    }
    [
        bytemuck::cast(r[0]),
        bytemuck::cast(r[1]),
        bytemuck::cast(r[2]),
    ]
}

/// Each lane's entry of `table` at its index in `idx`.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn look(simd: pulp::x86::V4, idx: __m512i, table: &[f32; SEGMENTS]) -> __m512 {
    simd.avx512f
        ._mm512_permutexvar_ps(idx, bytemuck::cast(*table))
}

/// F of the three channels of a block's `N` lanes (their `c`) from `tables`: registers of
/// AVX-512 (a plan takes the tables only on that instruction set; `N` a multiple of 16),
/// else lane by lane with the lane form, the same bits.
#[inline(always)]
pub(super) fn f_block<const N: usize>(c: &[f32; N], tables: &Segments) -> [[f32; N]; 3] {
    let mut out = [[0.0; N]; 3];
    #[cfg(target_arch = "x86_64")]
    if let (0, Some(simd)) = (N % 16, pulp::x86::V4::try_new()) {
        for (j, c16) in c.chunks_exact(16).enumerate() {
            let c16: [f32; 16] = c16.try_into().expect("16 lanes");
            let f = f_register(simd, bytemuck::cast(c16), tables);
            for (out, f) in out.iter_mut().zip(f) {
                out[16 * j..16 * (j + 1)].copy_from_slice(&bytemuck::cast::<_, [f32; 16]>(f));
            }
        }
        return out;
    }
    for (k, &c) in c.iter().enumerate() {
        let f = segments::f_lane_segments::<Fused>(c, tables);
        for ch in 0..3 {
            out[ch][k] = f[ch];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terms::f::conductor::LaneConstants;

    const LANES: usize = 16;

    /// The permutes give the lane form's bits on every `c` a lane may bring (each segment's
    /// ends and centre, 1 and past it) and on those no lane reads (below 1/16, where the
    /// index wraps: finite, as the lane form's), where the CPU has AVX-512.
    #[test]
    fn the_register_form_is_the_lane_forms_bits() {
        let (ior, ext) = ([0.2, 0.92, 1.1], [3.9, 2.45, 2.14]);
        let tables = Segments::fit(&LaneConstants::new(ior, ext), ior, ext).unwrap();
        let mut cs: Vec<f32> = (0..=4096).map(|i| i as f32 / 4096.0 * 1.002).collect();
        cs.extend([
            1e-30,
            f32::MIN_POSITIVE,
            0.0625,
            0.0999,
            0.1,
            1.0,
            1.0 + f32::EPSILON,
        ]);
        cs.extend(tables.centre);
        let blocks = cs.chunks(LANES).map(|ch| {
            let mut c = [0.5f32; LANES];
            c[..ch.len()].copy_from_slice(ch);
            c
        });
        for c in blocks {
            let got = f_block(&c, &tables);
            for (k, &c) in c.iter().enumerate() {
                let want = segments::f_lane_segments::<Fused>(c, &tables);
                for ch in 0..3 {
                    assert_eq!(
                        got[ch][k].to_bits(),
                        want[ch].to_bits(),
                        "c = {c}, channel {ch}"
                    );
                }
            }
        }
    }
}
