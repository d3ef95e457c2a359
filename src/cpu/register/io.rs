//! Each instruction set's reads, writes and conversions on the register path
//! ([`RegisterIo`]): AVX2's and AVX-512's, the engine's variants with FMA, both of which
//! have the path.

use crate::terms::f::conductor::segments::Segments;
use pulp::Simd;

/// An instruction set's register path: the width of a register and its own ways to read
/// the local form's rows into registers and write RGB back.
pub(crate) trait RegisterIo: Simd {
    /// Tuples a register.
    const WIDTH: usize = Self::F32_LANES;

    /// Whether an FMA reads a broadcast scalar from memory as an operand (AVX-512's
    /// `{1to16}`): a step's loop-invariant constants (the conductor's polynomial) are then
    /// better read where they are used than hoisted into registers, which spill. AVX2 has
    /// no such operand (a broadcast is an instruction of its own), and there the hoisted
    /// constants' spill slots fold into the FMAs instead.
    const BROADCAST_OPERANDS: bool;

    /// The 6 columns of [`Self::WIDTH`] rows of the local form.
    fn local_columns(self, rows: &[f32]) -> [Self::f32s; 6];

    /// The 3 columns of [`Self::WIDTH`] rows `x y z` (an `(n, 3)` array's).
    fn xyz_columns(self, rows: &[f32]) -> [Self::f32s; 3];

    /// 3 columns (RGB) into [`Self::WIDTH`] rows of 3.
    fn rgb_rows(self, rgb: [Self::f32s; 3], rows: &mut [f32]);

    /// The mask's lanes as bits (lane k is bit k).
    fn bits(self, m: Self::m32s) -> u32;

    /// A register's lanes exactly in f64: the low half's, the high half's.
    fn widen(self, x: Self::f32s) -> [Self::f64s; 2];

    /// Two halves of f64 lanes ([`Self::widen`]'s order) rounded to the nearest f32.
    fn narrow(self, w: [Self::f64s; 2]) -> Self::f32s;

    /// Whether a plan takes the conductor's segment tables on this instruction set (where
    /// a register of 16 entries is one permute): AVX-512's. AVX2's register path compiles
    /// no branch for them (the branch alone cost it 2.4–2.9 instructions an evaluation).
    const TABLES: bool;

    /// The conductor's F of three channels from the segment tables (`cpu::segments`).
    fn f_segments(self, c: Self::f32s, tables: &Segments) -> [Self::f32s; 3];
}

/// AVX2's reads and writes, 8 tuples a register: the transposes of `transpose::avx2`,
/// `vmovmskps`.
#[cfg(target_arch = "x86_64")]
impl RegisterIo for pulp::x86::V3 {
    const BROADCAST_OPERANDS: bool = false;
    const TABLES: bool = false;

    #[inline(always)]
    fn local_columns(self, rows: &[f32]) -> [Self::f32s; 6] {
        let rows: &[f32; 48] = rows[..48].try_into().expect("8 rows of 6");
        let [a, b, c, d, e, f] = crate::cpu::transpose::avx2::local_columns(self, rows);
        let r = bytemuck::cast;
        [r(a), r(b), r(c), r(d), r(e), r(f)]
    }

    #[inline(always)]
    fn xyz_columns(self, rows: &[f32]) -> [Self::f32s; 3] {
        let rows: &[f32; 24] = rows[..24].try_into().expect("8 rows of 3");
        let [x, y, z] = crate::cpu::transpose::avx2::xyz_columns(self, rows);
        let r = bytemuck::cast;
        [r(x), r(y), r(z)]
    }

    #[inline(always)]
    fn rgb_rows(self, rgb: [Self::f32s; 3], rows: &mut [f32]) {
        let rows: &mut [f32; 24] = (&mut rows[..24]).try_into().expect("8 rows of 3");
        let [x, y, z] = rgb;
        let r = bytemuck::cast;
        crate::cpu::transpose::avx2::rgb_rows(self, [r(x), r(y), r(z)], rows)
    }

    #[inline(always)]
    fn bits(self, m: Self::m32s) -> u32 {
        self.avx._mm256_movemask_ps(bytemuck::cast(m)) as u32
    }

    #[inline(always)]
    fn widen(self, x: Self::f32s) -> [Self::f64s; 2] {
        let x = bytemuck::cast(x);
        let lo = self.avx._mm256_cvtps_pd(self.avx._mm256_castps256_ps128(x));
        let hi = self
            .avx
            ._mm256_cvtps_pd(self.avx._mm256_extractf128_ps::<1>(x));
        [bytemuck::cast(lo), bytemuck::cast(hi)]
    }

    /// Lane by lane (a plan takes the tables only on AVX-512; the same bits).
    #[inline(always)]
    fn f_segments(self, c: Self::f32s, tables: &Segments) -> [Self::f32s; 3] {
        let c: [f32; 8] = bytemuck::cast(c);
        bytemuck::cast(crate::cpu::segments::f_block(&c, tables))
    }

    #[inline(always)]
    fn narrow(self, w: [Self::f64s; 2]) -> Self::f32s {
        let lo = self.avx._mm256_cvtpd_ps(bytemuck::cast(w[0]));
        let hi = self.avx._mm256_cvtpd_ps(bytemuck::cast(w[1]));
        bytemuck::cast(self.avx._mm256_set_m128(hi, lo))
    }
}

/// AVX-512's reads and writes, 16 tuples a register: the permutes of `transpose::avx512`,
/// the mask registers' bits as they are.
#[cfg(target_arch = "x86_64")]
impl RegisterIo for pulp::x86::V4 {
    const BROADCAST_OPERANDS: bool = true;
    const TABLES: bool = true;

    #[inline(always)]
    fn local_columns(self, rows: &[f32]) -> [Self::f32s; 6] {
        let rows: &[f32; 96] = rows[..96].try_into().expect("16 rows of 6");
        let [a, b, c, d, e, f] = crate::cpu::transpose::avx512::local_columns(self, rows);
        let r = bytemuck::cast;
        [r(a), r(b), r(c), r(d), r(e), r(f)]
    }

    #[inline(always)]
    fn xyz_columns(self, rows: &[f32]) -> [Self::f32s; 3] {
        let rows: &[f32; 48] = rows[..48].try_into().expect("16 rows of 3");
        let [x, y, z] = crate::cpu::transpose::avx512::xyz_columns(self, rows);
        let r = bytemuck::cast;
        [r(x), r(y), r(z)]
    }

    #[inline(always)]
    fn rgb_rows(self, rgb: [Self::f32s; 3], rows: &mut [f32]) {
        let rows: &mut [f32; 48] = (&mut rows[..48]).try_into().expect("16 rows of 3");
        let [x, y, z] = rgb;
        let r = bytemuck::cast;
        crate::cpu::transpose::avx512::rgb_rows(self, [r(x), r(y), r(z)], rows)
    }

    #[inline(always)]
    fn bits(self, m: Self::m32s) -> u32 {
        u32::from(m.0)
    }

    #[inline(always)]
    fn widen(self, x: Self::f32s) -> [Self::f64s; 2] {
        let x = bytemuck::cast(x);
        let f = self.avx512f;
        let lo = f._mm512_cvtps_pd(f._mm512_castps512_ps256(x));
        let hi = f._mm512_cvtps_pd(self.avx512dq._mm512_extractf32x8_ps::<1>(x));
        [bytemuck::cast(lo), bytemuck::cast(hi)]
    }

    #[inline(always)]
    fn f_segments(self, c: Self::f32s, tables: &Segments) -> [Self::f32s; 3] {
        crate::cpu::segments::f_register(self, c, tables)
    }

    #[inline(always)]
    fn narrow(self, w: [Self::f64s; 2]) -> Self::f32s {
        let f = self.avx512f;
        let lo = f._mm512_cvtpd_ps(bytemuck::cast(w[0]));
        let hi = f._mm512_cvtpd_ps(bytemuck::cast(w[1]));
        bytemuck::cast(
            self.avx512dq
                ._mm512_insertf32x8::<1>(f._mm512_castps256_ps512(lo), hi),
        )
    }
}
