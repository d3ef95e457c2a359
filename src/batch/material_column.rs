//! The material column's rule (FORMULAS.md §1: an integer index into the materials
//! table), in the forms the read stage runs on every row.

/// Whether [`material_index`] accepts `m`, in a form the compiler vectorises at the
/// baseline instruction set (a signed conversion, which SSE2 has for four lanes at once):
/// `as i32` saturates (NaN → 0, below −2^31 → `i32::MIN`, from 2^31 → `i32::MAX`, which
/// comes back as 2^31 and so has its own test), and the round trip gives `m` back exactly
/// when `m` is an integer in range.
#[inline]
pub(super) fn material_in_range(m: f32, count: usize) -> bool {
    let i = m as i32;
    (i as f32 == m) & (i >= 0) & (i != i32::MAX) & ((i as u64) < count as u64)
}

/// `m` (a row's material column) as an index below `count`: a non-negative integer, −0
/// counting as 0, below 2^31 − 1 (no table comes near). The read stage runs this on every
/// row, so no `trunc` call: see [`material_in_range`], which it agrees with.
#[inline]
pub(super) fn material_index(m: f32, count: usize) -> Option<usize> {
    material_in_range(m, count).then_some(m as usize)
}

/// Rows checked together by [`clean_rows`].
const BLOCK: usize = 16;

/// How many rows of `data` (row-major, `columns` a row, the material in column 9) lie
/// before the first block of [`BLOCK`] rows with a material [`material_in_range`] refuses:
/// a multiple of `BLOCK`, the whole blocks when every material passes. The read stage runs
/// it on every row; the caller finds the bad row itself from there.
pub(super) fn clean_rows(data: &[f32], columns: usize, count: usize) -> usize {
    #[cfg(target_arch = "x86_64")]
    if columns >= 10 && std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked on the line above) and the columns hold
        // column 9, which `clean_rows_avx2` requires.
        #[allow(unsafe_code)]
        return unsafe { clean_rows_avx2(data, columns, count) };
    }
    data.chunks_exact(columns * BLOCK)
        .take_while(|block| {
            let m: [f32; BLOCK] = std::array::from_fn(|k| block[k * columns + 9]);
            m.iter()
                .fold(true, |ok, &x| ok & material_in_range(x, count))
        })
        .count()
        * BLOCK
}

/// [`clean_rows`] by AVX2 gathers: the portable form loads the 16 materials of a block one
/// by one into vector lanes, which costs more than the test itself (docs/STREAMING.md has
/// the figures). AVX-512's 16-lane gather is slower than two of AVX2's on AMD's Zen 4, so
/// AVX2's serves both.
///
/// The same test as [`material_in_range`] in eight lanes: truncated to an integer (a value
/// out of `i32`'s range, NaN and the infinities become `i32::MIN`), which must convert
/// back to the value, be ≥ 0 and be below the count (capped at `i32::MAX`, which no float
/// converts to).
///
/// # Safety
/// The CPU must have AVX2, and `columns` must be at least 10.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
#[target_feature(enable = "avx2")]
unsafe fn clean_rows_avx2(data: &[f32], columns: usize, count: usize) -> usize {
    use std::arch::x86_64::*;
    let stride = columns as i32;
    let lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    let offsets = _mm256_mullo_epi32(lanes, _mm256_set1_epi32(stride));
    let limit = _mm256_set1_epi32(count.min(i32::MAX as usize) as i32);
    let minus_one = _mm256_set1_epi32(-1);
    let passes = |m: __m256| {
        let i = _mm256_cvttps_epi32(m);
        let exact = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_EQ_OQ>(_mm256_cvtepi32_ps(i), m));
        let in_range = _mm256_and_si256(
            _mm256_cmpgt_epi32(i, minus_one),
            _mm256_cmpgt_epi32(limit, i),
        );
        _mm256_and_si256(exact, in_range)
    };
    let mut clean = 0;
    for block in data.chunks_exact(columns * BLOCK) {
        let first = block[9..].as_ptr();
        // SAFETY: the block holds 16 rows of `columns` ≥ 10 values; the gathers read
        // the values at 9 + k·columns for k < 16 (k < 8 from `first`, 8 ≤ k < 16 from
        // `first` + 8·columns), each inside the block.
        let (a, b) = unsafe {
            (
                _mm256_i32gather_ps::<4>(first, offsets),
                _mm256_i32gather_ps::<4>(first.add(8 * columns), offsets),
            )
        };
        let all = _mm256_and_si256(passes(a), passes(b));
        if _mm256_movemask_ps(_mm256_castsi256_ps(all)) != 0xff {
            break;
        }
        clean += BLOCK;
    }
    clean
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The material column's rule at its edges: the integers below the count (and −0),
    /// nothing else — fractions, negatives, NaN, infinities, the count itself, and the
    /// values where the conversions saturate (±2^31, 2^32).
    #[test]
    fn a_material_index_is_a_nonnegative_integer_below_the_count() {
        for (m, count, want) in [
            (0.0, 1, Some(0)),
            (-0.0, 1, Some(0)),
            (2.0, 3, Some(2)),
            (3.0, 3, None),
            (0.5, 3, None),
            (2.999_999_8, 3, None),
            (-1.0, 3, None),
            (-0.25, 3, None),
            (f32::NAN, 3, None),
            (f32::INFINITY, 3, None),
            (f32::NEG_INFINITY, 3, None),
            (4_294_967_296.0, usize::MAX, None),
            (1e10, usize::MAX, None),
            (16_777_216.0, 16_777_217, Some(16_777_216)),
            (0.0, usize::MAX, Some(0)),
            (2_147_483_520.0, usize::MAX, Some(2_147_483_520)),
            (2_147_483_648.0, usize::MAX, None),
            (-2_147_483_648.0, usize::MAX, None),
        ] {
            assert_eq!(material_index(m, count), want, "m = {m}, count = {count}");
            assert_eq!(
                material_in_range(m, count),
                want.is_some(),
                "m = {m}, count = {count}"
            );
        }
    }

    /// The block test (AVX2's gathers where the CPU has them) finds the first block with a
    /// bad material at every row of a batch, for every edge value above, in rows of 10 and
    /// 13 columns, with the other columns holding values the test must not read (NaN).
    #[test]
    fn the_block_test_stops_at_the_first_block_with_a_bad_material() {
        let values = [
            0.0,
            -0.0,
            2.0,
            3.0,
            0.5,
            2.999_999_8,
            -1.0,
            -0.25,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            4_294_967_296.0,
            2_147_483_648.0,
            -2_147_483_648.0,
            2_147_483_520.0,
            16_777_216.0,
        ];
        for columns in [10, 13] {
            for count in [1, 3, 16_777_217, i32::MAX as usize, usize::MAX] {
                let rows = 5 * BLOCK + 3;
                let good = |r: usize| (r % count.min(3)) as f32;
                let mut data = vec![f32::NAN; rows * columns];
                for r in 0..rows {
                    data[r * columns + 9] = good(r);
                }
                assert_eq!(clean_rows(&data, columns, count), 5 * BLOCK);
                for &m in &values {
                    for bad in [0, 7, 8, 15, 16, 40, 5 * BLOCK - 1, 5 * BLOCK + 2] {
                        let mut d = data.clone();
                        d[bad * columns + 9] = m;
                        let want = if material_in_range(m, count) {
                            5 * BLOCK
                        } else {
                            (bad / BLOCK * BLOCK).min(5 * BLOCK)
                        };
                        assert_eq!(
                            clean_rows(&d, columns, count),
                            want,
                            "m = {m}, row {bad}, count {count}, {columns} columns"
                        );
                    }
                }
            }
        }
    }
}
