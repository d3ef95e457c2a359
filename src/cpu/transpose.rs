//! The local form's whole blocks (16 rows of `Lx Ly Lz Vx Vy Vz`) into lanes: portably
//! through a copy and fixed-stride loops, and with AVX-512 by two-source permutes.
//!
//! On AVX-512 LLVM compiled the portable stride-6 loops to 168 scalar `movss` a block (and,
//! reading the batch directly instead of a copy, to masked loads that miss the cache); the
//! permutes do it in 18 shuffles and 12 blends.

use super::kernel::{Inputs, LANES};
use crate::batch::COLUMNS_LOCAL;

/// Floats in one whole block of the local form.
pub const BLOCK: usize = LANES * COLUMNS_LOCAL;

/// A way to transpose one whole block of the local form.
pub trait Local6: Copy {
    /// Columns 0–5 of `block` (16 rows of 6) into `inp.v[0..6]`.
    fn transpose6(self, block: &[f32; BLOCK], inp: &mut Inputs);
}

/// The portable transpose: fixed-stride loops over a copy of the block.
#[derive(Clone, Copy)]
pub struct Portable;

impl Local6 for Portable {
    #[inline(always)]
    fn transpose6(self, block: &[f32; BLOCK], inp: &mut Inputs) {
        // Through a copy of the block that the compiler cannot see through: the stride-6
        // transpose straight from the batch compiled to masked loads which, missing the
        // cache, cost twice the whole tuple.
        let block: [f32; BLOCK] = std::hint::black_box(*block);
        for (c, col) in inp.v[..COLUMNS_LOCAL].iter_mut().enumerate() {
            for (k, x) in col.iter_mut().enumerate() {
                *x = block[k * COLUMNS_LOCAL + c];
            }
        }
    }
}

/// Where column `c`'s lane `k` sits in the block: register `(6k + c)/16` of the six loaded,
/// so each column gathers from the register pairs (0, 1), (2, 3), (4, 5) by a two-source
/// permute (index `6k + c − 32p`, clamped where the lane comes from another pair) and two
/// blends (the lanes at or past flat index 32, then 64).
const fn permute_indices() -> [[[i32; LANES]; 3]; COLUMNS_LOCAL] {
    let mut t = [[[0i32; LANES]; 3]; COLUMNS_LOCAL];
    let mut c = 0;
    while c < COLUMNS_LOCAL {
        let mut p = 0;
        while p < 3 {
            let mut k = 0;
            while k < LANES {
                let i = (COLUMNS_LOCAL * k + c) as i32 - 32 * p as i32;
                t[c][p][k] = if i < 0 {
                    0
                } else if i > 31 {
                    31
                } else {
                    i
                };
                k += 1;
            }
            p += 1;
        }
        c += 1;
    }
    t
}

/// Lanes of column `c` whose element lies at flat index `lo` or beyond.
const fn blend_masks() -> [[u16; 2]; COLUMNS_LOCAL] {
    let mut t = [[0u16; 2]; COLUMNS_LOCAL];
    let mut c = 0;
    while c < COLUMNS_LOCAL {
        let mut k = 0;
        while k < LANES {
            let flat = COLUMNS_LOCAL * k + c;
            if flat >= 32 {
                t[c][0] |= 1 << k;
            }
            if flat >= 64 {
                t[c][1] |= 1 << k;
            }
            k += 1;
        }
        c += 1;
    }
    t
}

#[cfg(target_arch = "x86_64")]
const INDICES: [[[i32; LANES]; 3]; COLUMNS_LOCAL] = permute_indices();
#[cfg(target_arch = "x86_64")]
const MASKS: [[u16; 2]; COLUMNS_LOCAL] = blend_masks();

#[cfg(target_arch = "x86_64")]
impl Local6 for pulp::x86::V4 {
    #[inline(always)]
    fn transpose6(self, block: &[f32; BLOCK], inp: &mut Inputs) {
        use core::arch::x86_64::{__m512, __m512i};
        let f = self.avx512f;
        // Six whole-register loads (bytemuck's casts: pulp's x86-v4 makes __m512 Pod).
        let r: [__m512; 6] = bytemuck::cast(*block);
        for c in 0..COLUMNS_LOCAL {
            let idx = |p: usize| -> __m512i { bytemuck::cast(INDICES[c][p]) };
            let p0 = f._mm512_permutex2var_ps(r[0], idx(0), r[1]);
            let p1 = f._mm512_permutex2var_ps(r[2], idx(1), r[3]);
            let p2 = f._mm512_permutex2var_ps(r[4], idx(2), r[5]);
            let col = f._mm512_mask_blend_ps(MASKS[c][0], p0, p1);
            let col = f._mm512_mask_blend_ps(MASKS[c][1], col, p2);
            inp.v[c] = bytemuck::cast(col);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every transpose this machine has puts row k's column c in lane k of column c.
    #[test]
    fn every_transpose_puts_each_value_in_its_lane() {
        let block: [f32; BLOCK] = std::array::from_fn(|i| i as f32);
        let want = |c: usize, k: usize| (k * COLUMNS_LOCAL + c) as f32;
        let check = |inp: &Inputs| {
            for c in 0..COLUMNS_LOCAL {
                for k in 0..LANES {
                    assert_eq!(inp.v[c][k], want(c, k), "column {c} lane {k}");
                }
            }
        };
        let mut inp = Inputs {
            v: [[-1.0; LANES]; 9],
        };
        Portable.transpose6(&block, &mut inp);
        check(&inp);
        #[cfg(target_arch = "x86_64")]
        if let pulp::Arch::V4(v4) = pulp::Arch::new() {
            let mut inp = Inputs {
                v: [[-1.0; LANES]; 9],
            };
            v4.transpose6(&block, &mut inp);
            check(&inp);
        }
    }
}
