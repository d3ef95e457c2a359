//! Whole blocks of rows into lanes: the local form's 16 rows of `Lx Ly Lz Vx Vy Vz` and the
//! 10-column rows' 16 rows of `L V N material` — portably through fixed-stride loops, and
//! with AVX-512 by two-source permutes.
//!
//! On AVX-512 LLVM compiled the portable stride-6 loops to 168 scalar `movss` a block (and,
//! reading the batch directly instead of a copy, to masked loads that miss the cache); the
//! permutes do the local form in 18 shuffles and 12 blends.

use super::kernel::{Inputs, LANES};
use crate::batch::{COLUMNS_LOCAL, COLUMNS_PLAIN};

/// Floats in one whole block of the local form.
pub const BLOCK: usize = LANES * COLUMNS_LOCAL;

/// Floats in one whole block of 10-column rows.
pub const BLOCK_PLAIN: usize = LANES * COLUMNS_PLAIN;

/// Floats in one whole block of a 3-float column (`x y z` a row, as an `(n, 3)` array).
pub const BLOCK_XYZ: usize = LANES * 3;

/// A way to transpose whole blocks.
pub trait Transpose: Copy {
    /// Columns 0–5 of `block` (16 rows of 6) into `inp.v[0..6]`.
    fn local(self, block: &[f32; BLOCK], inp: &mut Inputs);
    /// Columns 0–8 (L, V, N) of `block` (16 rows of 10) into `inp.v[0..9]`.
    fn plain(self, block: &[f32; BLOCK_PLAIN], inp: &mut Inputs);
    /// The 3 columns of `block` (16 rows of `x y z`) into `lanes`.
    fn xyz(self, block: &[f32; BLOCK_XYZ], lanes: &mut [[f32; LANES]; 3]);
    /// The other way: 3 lane arrays (a block's RGB) into 16 rows of 3.
    #[inline(always)]
    fn rgb(self, lanes: &[[f32; LANES]; 3], rows: &mut [f32; BLOCK_XYZ]) {
        untranspose(lanes, rows)
    }
}

/// `C` lane arrays into `LANES` rows of `C` columns, by fixed-size loops (the portable way
/// back; the block's terms take it on every instruction set).
#[inline(always)]
pub(super) fn untranspose<const C: usize>(cols: &[[f32; LANES]; C], rows: &mut [f32]) {
    let rows = &mut rows[..LANES * C];
    for k in 0..LANES {
        for c in 0..C {
            rows[k * C + c] = cols[c][k];
        }
    }
}

/// Columns `0..K` of `LANES` rows of `C` columns into lanes, by fixed-stride loops.
#[inline(always)]
fn loops<const C: usize, const K: usize>(rows: &[f32], lanes: &mut [[f32; LANES]]) {
    for (c, col) in lanes[..K].iter_mut().enumerate() {
        for (k, x) in col.iter_mut().enumerate() {
            *x = rows[k * C + c];
        }
    }
}

/// The portable transpose: fixed-stride loops the compiler turns into shuffles where it can.
#[derive(Clone, Copy)]
pub struct Portable;

impl Transpose for Portable {
    #[inline(always)]
    fn local(self, block: &[f32; BLOCK], inp: &mut Inputs) {
        // Through a copy of the block that the compiler cannot see through: the stride-6
        // transpose straight from the batch compiled to masked loads which, missing the
        // cache, cost twice the whole tuple.
        let block: [f32; BLOCK] = std::hint::black_box(*block);
        loops::<COLUMNS_LOCAL, COLUMNS_LOCAL>(&block, &mut inp.v)
    }

    #[inline(always)]
    fn plain(self, block: &[f32; BLOCK_PLAIN], inp: &mut Inputs) {
        loops::<COLUMNS_PLAIN, 9>(block, &mut inp.v)
    }

    #[inline(always)]
    fn xyz(self, block: &[f32; BLOCK_XYZ], lanes: &mut [[f32; LANES]; 3]) {
        loops::<3, 3>(block, lanes)
    }
}

/// Register pairs a block of up to 10 columns spans (32 floats a pair).
const PAIRS: usize = 5;

/// Permute indices and blend masks for rows of `cols` columns: column `c`'s lane `k` is
/// flat element `cols·k + c`, in register pair `p = flat/32`; pair p's two-source permute
/// takes index `flat − 32p` (clamped where the lane lies in another pair), and the lanes at
/// or past flat index 32p take pair p's result (`masks[c][p]`, p ≥ 1).
#[derive(Clone, Copy)]
struct Tables {
    indices: [[[i32; LANES]; PAIRS]; COLUMNS_PLAIN],
    masks: [[u16; PAIRS]; COLUMNS_PLAIN],
}

const fn tables(cols: usize) -> Tables {
    let mut t = Tables {
        indices: [[[0; LANES]; PAIRS]; COLUMNS_PLAIN],
        masks: [[0; PAIRS]; COLUMNS_PLAIN],
    };
    let mut c = 0;
    while c < cols {
        let mut p = 0;
        while p < PAIRS {
            let mut k = 0;
            while k < LANES {
                let flat = cols * k + c;
                let i = flat as i32 - 32 * p as i32;
                t.indices[c][p][k] = if i < 0 {
                    0
                } else if i > 31 {
                    31
                } else {
                    i
                };
                if flat >= 32 * p {
                    t.masks[c][p] |= 1 << k;
                }
                k += 1;
            }
            p += 1;
        }
        c += 1;
    }
    t
}

#[cfg(target_arch = "x86_64")]
const LOCAL: Tables = tables(COLUMNS_LOCAL);
#[cfg(target_arch = "x86_64")]
const PLAIN: Tables = tables(COLUMNS_PLAIN);
#[cfg(target_arch = "x86_64")]
const XYZ: Tables = tables(3);

/// Columns `0..K` of `LANES` rows of `C` columns (at most 10) by permutes; an odd `C`'s
/// last pair has a zero register for its second.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn permutes<const C: usize, const K: usize>(
    simd: pulp::x86::V4,
    rows: &[f32],
    t: &Tables,
    lanes: &mut [[f32; LANES]],
) {
    let cols = columns::<C, K>(simd, rows, t);
    for (lane, col) in lanes.iter_mut().zip(cols) {
        *lane = bytemuck::cast(col);
    }
}

/// [`permutes`]' columns as registers (the register path's read, [`avx512::local_columns`]).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn columns<const C: usize, const K: usize>(
    simd: pulp::x86::V4,
    rows: &[f32],
    t: &Tables,
) -> [core::arch::x86_64::__m512; K] {
    use core::arch::x86_64::{__m512, __m512i};
    let f = simd.avx512f;
    // Whole-register loads (bytemuck's casts: pulp's x86-v4 makes __m512 Pod).
    let mut r = [bytemuck::cast::<[f32; LANES], __m512>([0.0; LANES]); 2 * PAIRS];
    for (i, reg) in r.iter_mut().enumerate().take(C) {
        let a: [f32; LANES] = rows[i * LANES..(i + 1) * LANES]
            .try_into()
            .expect("a whole register");
        *reg = bytemuck::cast(a);
    }
    // A plain loop, no closure: LLVM left `array::from_fn`'s closure out of line on the
    // register path, and every permute in it became a call (3.6x slower).
    let mut cols = [r[0]; K];
    for (c, col) in cols.iter_mut().enumerate() {
        let idx0: __m512i = bytemuck::cast(t.indices[c][0]);
        *col = f._mm512_permutex2var_ps(r[0], idx0, r[1]);
        for p in 1..C.div_ceil(2) {
            let idx: __m512i = bytemuck::cast(t.indices[c][p]);
            let q = f._mm512_permutex2var_ps(r[2 * p], idx, r[2 * p + 1]);
            *col = f._mm512_mask_blend_ps(t.masks[c][p], *col, q);
        }
    }
    cols
}

/// AVX-512's register-path transposes: the local form's 16 rows into 6 registers and 3
/// registers of RGB back into 16 rows, by two-source permutes.
#[cfg(target_arch = "x86_64")]
pub(super) mod avx512 {
    // By the crate's paths: the layering test reads `super` as the parent file.
    use crate::cpu::kernel::LANES;
    use crate::cpu::transpose::{columns, LOCAL, XYZ};
    use core::arch::x86_64::{__m512, __m512i};

    /// The local form's 6 columns of its 16 rows `block` (18 permutes, 12 blends).
    #[inline(always)]
    pub(crate) fn local_columns(simd: pulp::x86::V4, block: &[f32; 96]) -> [__m512; 6] {
        columns::<6, 6>(simd, block, &LOCAL)
    }

    /// The 3 columns of 16 rows `x y z` (an `(n, 3)` array's, the register path's read).
    #[inline(always)]
    pub(crate) fn xyz_columns(simd: pulp::x86::V4, block: &[f32; 48]) -> [__m512; 3] {
        columns::<3, 3>(simd, block, &XYZ)
    }

    /// For output register j (floats 16j … 16j + 15 of 16 rows of RGB), lane k: the
    /// source lane (the row, `(16j + k)/3`) in R's and G's pair (G's lanes from 16), in B,
    /// and which lanes come from B (`(16j + k) mod 3 = 2`).
    struct RgbTables {
        rg: [[i32; LANES]; 3],
        b: [[i32; LANES]; 3],
        from_b: [u16; 3],
    }

    const RGB: RgbTables = {
        let mut t = RgbTables {
            rg: [[0; LANES]; 3],
            b: [[0; LANES]; 3],
            from_b: [0; 3],
        };
        let mut j = 0;
        while j < 3 {
            let mut k = 0;
            while k < LANES {
                let flat = LANES * j + k;
                let (row, col) = ((flat / 3) as i32, flat % 3);
                match col {
                    0 => t.rg[j][k] = row,
                    1 => t.rg[j][k] = LANES as i32 + row,
                    _ => {
                        t.b[j][k] = row;
                        t.from_b[j] |= 1 << k;
                    }
                }
                k += 1;
            }
            j += 1;
        }
        t
    };

    /// 3 columns of 16 lanes (RGB) into 16 rows of 3 (6 permutes, 3 blends).
    #[inline(always)]
    pub(crate) fn rgb_rows(simd: pulp::x86::V4, rgb: [__m512; 3], rows: &mut [f32; 48]) {
        let f = simd.avx512f;
        let [r, g, b] = rgb;
        for j in 0..3 {
            let rg = f._mm512_permutex2var_ps(r, bytemuck::cast::<_, __m512i>(RGB.rg[j]), g);
            let bb = f._mm512_permutexvar_ps(bytemuck::cast::<_, __m512i>(RGB.b[j]), b);
            let out: [f32; LANES] = bytemuck::cast(f._mm512_mask_blend_ps(RGB.from_b[j], rg, bb));
            rows[LANES * j..LANES * (j + 1)].copy_from_slice(&out);
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl Transpose for pulp::x86::V4 {
    #[inline(always)]
    fn local(self, block: &[f32; BLOCK], inp: &mut Inputs) {
        permutes::<COLUMNS_LOCAL, COLUMNS_LOCAL>(self, block, &LOCAL, &mut inp.v)
    }

    #[inline(always)]
    fn plain(self, block: &[f32; BLOCK_PLAIN], inp: &mut Inputs) {
        permutes::<COLUMNS_PLAIN, 9>(self, block, &PLAIN, &mut inp.v)
    }

    #[inline(always)]
    fn xyz(self, block: &[f32; BLOCK_XYZ], lanes: &mut [[f32; LANES]; 3]) {
        permutes::<3, 3>(self, block, &XYZ, lanes)
    }
}

/// AVX2: 4 × 4 transposes inside each 128-bit half, rows `r` and `r + 4` of a group of 8
/// sharing a register (`vinsertf128` from memory), so that lane k is row k without a
/// cross-lane permute. LLVM made the portable stride-6 loops 192 scalar moves a block here
/// (12 an evaluation, a tenth of GGX's); this is 34 instructions per 8 rows.
#[cfg(target_arch = "x86_64")]
pub(super) mod avx2 {
    // By the crate's paths: the layering test reads `super` as the parent file.
    use crate::batch::{COLUMNS_LOCAL, COLUMNS_PLAIN};
    use crate::cpu::kernel::{Inputs, LANES};
    use crate::cpu::transpose::{Transpose, BLOCK, BLOCK_PLAIN, BLOCK_XYZ};
    use core::arch::x86_64::{__m128, __m256};

    /// `4` floats at `at` (row `r`) in the low half and at `at + 4 · cols` (row `r + 4`)
    /// in the high half.
    #[inline(always)]
    fn pair(simd: pulp::x86::V3, rows: &[f32], at: usize, cols: usize) -> __m256 {
        let q = |i: usize| -> __m128 {
            let a: &[f32; 4] = rows[i..i + 4].try_into().expect("4 floats");
            bytemuck::cast(*a)
        };
        simd.avx._mm256_set_m128(q(at + 4 * cols), q(at))
    }

    /// The 4 × 4 transpose of `r` inside each half: `out[j]`'s lane is `r[lane]`'s `j`.
    #[inline(always)]
    fn four(simd: pulp::x86::V3, r: [__m256; 4]) -> [__m256; 4] {
        let [x, y] = two::<false>(simd, r);
        let [z, w] = two::<true>(simd, r);
        [x, y, z, w]
    }

    /// Elements 0 and 1 of the 4 × 4 transpose (`HIGH`: 2 and 3, for a group whose other
    /// two columns are not wanted).
    #[inline(always)]
    fn two<const HIGH: bool>(simd: pulp::x86::V3, r: [__m256; 4]) -> [__m256; 2] {
        let un = [
            unpack::<HIGH>(simd, r[0], r[1]),
            unpack::<HIGH>(simd, r[2], r[3]),
        ];
        sort_pairs(simd, un)
    }

    /// `vunpcklps` (`HIGH`: `vunpckhps`) of `x` and `y`.
    #[inline(always)]
    fn unpack<const HIGH: bool>(simd: pulp::x86::V3, x: __m256, y: __m256) -> __m256 {
        if HIGH {
            simd.avx._mm256_unpackhi_ps(x, y)
        } else {
            simd.avx._mm256_unpacklo_ps(x, y)
        }
    }

    /// `[p0 q0 p1 q1]` of rows 0, 1 and of rows 2, 3 (an unpack's result) into the
    /// columns p and q.
    #[inline(always)]
    fn sort_pairs(simd: pulp::x86::V3, t: [__m256; 2]) -> [__m256; 2] {
        let a = simd.avx;
        [
            a._mm256_shuffle_ps::<0x44>(t[0], t[1]),
            a._mm256_shuffle_ps::<0xEE>(t[0], t[1]),
        ]
    }

    /// [`pair`] of rows `r0 + k` (and `r0 + k + 4`) from float `first` on, k = 0..4. (Not
    /// `array::from_fn`: LLVM stopped inlining it once the transposes had several callers,
    /// and out of line the intrinsics lose the instruction set and become calls.)
    #[inline(always)]
    fn quad(
        simd: pulp::x86::V3,
        rows: &[f32],
        r0: usize,
        cols: usize,
        first: usize,
    ) -> [__m256; 4] {
        let at = |k: usize| (r0 + k) * cols + first;
        [
            pair(simd, rows, at(0), cols),
            pair(simd, rows, at(1), cols),
            pair(simd, rows, at(2), cols),
            pair(simd, rows, at(3), cols),
        ]
    }

    #[inline(always)]
    fn put(v: &mut [f32; LANES], half: usize, x: __m256) {
        let a: [f32; 8] = bytemuck::cast(x);
        v[8 * half..8 * half + 8].copy_from_slice(&a);
    }

    /// `regs` — columns of 8 rows, the first 4 in the low halves — into lanes
    /// `8·half..8·half + 8` of `v[0..K]`.
    #[inline(always)]
    fn put_all<const K: usize>(v: &mut [[f32; LANES]], half: usize, regs: [__m256; K]) {
        for (c, x) in regs.into_iter().enumerate() {
            put(&mut v[c], half, x);
        }
    }

    /// The local form's 6 columns of rows `r0..r0 + 8`: Lx Ly Lz Vx from floats 0..4 of
    /// each row, Vy Vz from floats 2..6. (Functions, not closures: a closure LLVM leaves
    /// out of line takes the intrinsics with it, as calls.)
    #[inline(always)]
    fn local_rows(simd: pulp::x86::V3, block: &[f32], r0: usize) -> [__m256; 6] {
        const C: usize = COLUMNS_LOCAL;
        let [lx, ly, lz, vx] = four(simd, quad(simd, block, r0, C, 0));
        let [vy, vz] = two::<true>(simd, quad(simd, block, r0, C, 2));
        [lx, ly, lz, vx, vy, vz]
    }

    /// L, V and N of 10-column rows `r0..r0 + 8`: L and Vx from floats 0..4, Vy Vz Nx Ny
    /// from 4..8, Nz from 6..10.
    #[inline(always)]
    fn plain_rows(simd: pulp::x86::V3, block: &[f32], r0: usize) -> [__m256; 9] {
        const C: usize = COLUMNS_PLAIN;
        let [lx, ly, lz, vx] = four(simd, quad(simd, block, r0, C, 0));
        let [vy, vz, nx, ny] = four(simd, quad(simd, block, r0, C, 4));
        let [nz, _] = two::<true>(simd, quad(simd, block, r0, C, 6));
        [lx, ly, lz, vx, vy, vz, nx, ny, nz]
    }

    /// The 3 columns of `x y z` rows `r0..r0 + 8`: their 6 quarters q0..q5 as q0|q3, q1|q4,
    /// q2|q5 put rows k and k + 4 in the same place of each half, and 5 shuffles sort the
    /// columns out.
    #[inline(always)]
    fn xyz_rows(simd: pulp::x86::V3, block: &[f32], r0: usize) -> [__m256; 3] {
        let a = simd.avx;
        let rows = &block[3 * r0..3 * r0 + 24];
        let m03 = pair(simd, rows, 0, 3);
        let m14 = pair(simd, rows, 4, 3);
        let m25 = pair(simd, rows, 8, 3);
        let xy = a._mm256_shuffle_ps::<0x9E>(m14, m25);
        let yz = a._mm256_shuffle_ps::<0x49>(m03, m14);
        [
            a._mm256_shuffle_ps::<0x8C>(m03, xy),
            a._mm256_shuffle_ps::<0xD8>(yz, xy),
            a._mm256_shuffle_ps::<0xCD>(yz, m25),
        ]
    }

    impl Transpose for pulp::x86::V3 {
        #[inline(always)]
        fn local(self, block: &[f32; BLOCK], inp: &mut Inputs) {
            for half in 0..2 {
                put_all(&mut inp.v, half, local_rows(self, block, 8 * half));
            }
        }

        #[inline(always)]
        fn plain(self, block: &[f32; BLOCK_PLAIN], inp: &mut Inputs) {
            for half in 0..2 {
                put_all(&mut inp.v, half, plain_rows(self, block, 8 * half));
            }
        }

        #[inline(always)]
        fn xyz(self, block: &[f32; BLOCK_XYZ], lanes: &mut [[f32; LANES]; 3]) {
            for half in 0..2 {
                put_all(lanes, half, xyz_rows(self, block, 8 * half));
            }
        }

        #[inline(always)]
        fn rgb(self, lanes: &[[f32; LANES]; 3], rows: &mut [f32; BLOCK_XYZ]) {
            for half in 0..2 {
                let get = |c: usize| -> __m256 {
                    let v: [f32; 8] = lanes[c][8 * half..8 * half + 8]
                        .try_into()
                        .expect("8 lanes");
                    bytemuck::cast(v)
                };
                let out: &mut [f32; 24] = (&mut rows[24 * half..24 * half + 24])
                    .try_into()
                    .expect("8 rows of 3");
                rgb_rows(self, [get(0), get(1), get(2)], out);
            }
        }
    }

    /// The local form's 6 columns of its 8 rows `block` (the register path's read).
    #[inline(always)]
    pub(crate) fn local_columns(simd: pulp::x86::V3, block: &[f32; 48]) -> [__m256; 6] {
        local_rows(simd, block, 0)
    }

    /// The 3 columns of 8 rows `x y z` (an `(n, 3)` array's, the register path's read).
    #[inline(always)]
    pub(crate) fn xyz_columns(simd: pulp::x86::V3, block: &[f32; 24]) -> [__m256; 3] {
        xyz_rows(simd, block, 0)
    }

    /// 3 columns of 8 lanes (RGB) into 8 rows of 3.
    #[inline(always)]
    pub(crate) fn rgb_rows(simd: pulp::x86::V3, xyz: [__m256; 3], rows: &mut [f32; 24]) {
        let a = simd.avx;
        let [x, y, z] = xyz;
        // In each half, rows k..k+4 = x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3.
        let t0 = a._mm256_unpacklo_ps(x, y);
        let t1 = a._mm256_unpackhi_ps(x, y);
        let u = a._mm256_shuffle_ps::<0x50>(z, x); // z0 z0 x1 x1
        let v = a._mm256_shuffle_ps::<0x55>(y, z); // y1 y1 z1 z1
        let w1 = a._mm256_shuffle_ps::<0xFA>(z, x); // z2 z2 x3 x3
        let w2 = a._mm256_shuffle_ps::<0xFF>(y, z); // y3 y3 z3 z3
        let o = [
            a._mm256_shuffle_ps::<0x84>(t0, u),
            a._mm256_shuffle_ps::<0x48>(v, t1),
            a._mm256_shuffle_ps::<0x88>(w1, w2),
        ];
        // Low halves are rows 0..4, high halves rows 4..8.
        for (i, r) in o.into_iter().enumerate() {
            let lo: [f32; 4] = bytemuck::cast(a._mm256_castps256_ps128(r));
            let hi: [f32; 4] = bytemuck::cast(a._mm256_extractf128_ps::<1>(r));
            rows[4 * i..4 * i + 4].copy_from_slice(&lo);
            rows[12 + 4 * i..12 + 4 * i + 4].copy_from_slice(&hi);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every transpose this machine has puts row k's column c in lane k of column c, for
    /// the local form and for 10-column rows.
    #[test]
    fn every_transpose_puts_each_value_in_its_lane() {
        let check = |inp: &Inputs, cols: usize, k_cols: usize| {
            for c in 0..k_cols {
                for k in 0..LANES {
                    assert_eq!(
                        inp.v[c][k],
                        (k * cols + c) as f32,
                        "{cols} columns: column {c} lane {k}"
                    );
                }
            }
        };
        let xyz: [f32; BLOCK_XYZ] = std::array::from_fn(|i| i as f32);
        let check_xyz = |lanes: &[[f32; LANES]; 3]| {
            for c in 0..3 {
                for k in 0..LANES {
                    assert_eq!(lanes[c][k], (3 * k + c) as f32, "xyz: column {c} lane {k}");
                }
            }
        };
        let mut lanes = [[-1.0; LANES]; 3];
        Portable.xyz(&xyz, &mut lanes);
        check_xyz(&lanes);
        #[cfg(target_arch = "x86_64")]
        if let pulp::Arch::V4(v4) = pulp::Arch::new() {
            let mut lanes = [[-1.0; LANES]; 3];
            v4.xyz(&xyz, &mut lanes);
            check_xyz(&lanes);
        }
        let local: [f32; BLOCK] = std::array::from_fn(|i| i as f32);
        let plain: [f32; BLOCK_PLAIN] = std::array::from_fn(|i| i as f32);
        let fresh = || Inputs {
            v: [[-1.0; LANES]; 12],
        };
        let run = |t: &dyn Fn(&mut Inputs, bool)| {
            for (plain_rows, cols, k_cols) in [
                (false, COLUMNS_LOCAL, COLUMNS_LOCAL),
                (true, COLUMNS_PLAIN, 9),
            ] {
                let mut inp = fresh();
                t(&mut inp, plain_rows);
                check(&inp, cols, k_cols);
            }
        };
        run(&|inp, plain_rows| {
            if plain_rows {
                Portable.plain(&plain, inp)
            } else {
                Portable.local(&local, inp)
            }
        });
        #[cfg(target_arch = "x86_64")]
        if let pulp::Arch::V4(v4) = pulp::Arch::new() {
            run(&|inp, plain_rows| {
                if plain_rows {
                    v4.plain(&plain, inp)
                } else {
                    v4.local(&local, inp)
                }
            });
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = pulp::x86::V3::try_new() {
            run(&|inp, plain_rows| {
                if plain_rows {
                    v3.plain(&plain, inp)
                } else {
                    v3.local(&local, inp)
                }
            });
            let mut lanes = [[-1.0; LANES]; 3];
            v3.xyz(&xyz, &mut lanes);
            check_xyz(&lanes);
        }
    }

    /// Every way back puts lane k of column c at row k's column c.
    #[test]
    fn every_rgb_transpose_puts_each_lane_in_its_row() {
        let lanes: [[f32; LANES]; 3] =
            std::array::from_fn(|c| std::array::from_fn(|k| (3 * k + c) as f32));
        let want: [f32; BLOCK_XYZ] = std::array::from_fn(|i| i as f32);
        let mut rows = [-1.0; BLOCK_XYZ];
        Portable.rgb(&lanes, &mut rows);
        assert_eq!(rows, want, "portable");
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = pulp::x86::V3::try_new() {
            let mut rows = [-1.0; BLOCK_XYZ];
            v3.rgb(&lanes, &mut rows);
            assert_eq!(rows, want, "avx2");
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(v4) = pulp::x86::V4::try_new() {
            let mut rows = [-1.0; BLOCK_XYZ];
            let regs = lanes.map(bytemuck::cast);
            avx512::rgb_rows(v4, regs, &mut rows);
            assert_eq!(rows, want, "avx512 registers");
        }
    }

    /// The register path's AVX-512 read puts row k's column c in lane k of register c.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_avx512_register_read_puts_each_value_in_its_lane() {
        let Some(v4) = pulp::x86::V4::try_new() else {
            return;
        };
        let block: [f32; BLOCK] = std::array::from_fn(|i| i as f32);
        let cols = avx512::local_columns(v4, &block);
        for (c, col) in cols.into_iter().enumerate() {
            let lanes: [f32; LANES] = bytemuck::cast(col);
            let want: [f32; LANES] = std::array::from_fn(|k| (COLUMNS_LOCAL * k + c) as f32);
            assert_eq!(lanes, want, "column {c}");
        }
    }
}
