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
    (i as f32 == m) & (i >= 0) & (i != i32::MAX) & ((i as i64) < count as i64)
}

/// `m` (a row's material column) as an index below `count`: a non-negative integer, −0
/// counting as 0, below 2^31 − 1 (no table comes near). The read stage runs this on every
/// row, so no `trunc` call: see [`material_in_range`], which it agrees with.
#[inline]
pub(super) fn material_index(m: f32, count: usize) -> Option<usize> {
    material_in_range(m, count).then_some(m as usize)
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
}
