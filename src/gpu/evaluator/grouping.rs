//! Mixed-material batches grouped by material (`BUCKETED` kernels): each chunk's rows are
//! uploaded in an order grouped by material and the outputs put back in place on readback.
//! llvmpipe runs a subgroup's lanes in SIMD, so a subgroup mixing models runs every
//! model's path; grouped, it runs one (mixed 8-material kernel 2.3× on lavapipe).

use crate::gpu::host_copy::HostCopy;
use crate::gpu::memory::Buffer;

/// The evaluation order of a chunk's `rows` (`cols` floats each, material index in column
/// 9, already validated against `material_count`): row indices grouped by material, in
/// row order within a material (a counting sort, O(rows + materials)).
pub(super) fn bucket_order(rows: &[f32], cols: usize, material_count: usize) -> Vec<u32> {
    let material = |r: &[f32]| (r[9] as usize).min(material_count.saturating_sub(1));
    let mut next = vec![0u32; material_count.max(1) + 1];
    for r in rows.chunks_exact(cols) {
        next[material(r) + 1] += 1;
    }
    for m in 1..next.len() {
        next[m] += next[m - 1];
    }
    let mut order = vec![0u32; rows.len() / cols];
    for (i, r) in rows.chunks_exact(cols).enumerate() {
        let slot = &mut next[material(r)];
        order[*slot as usize] = i as u32;
        *slot += 1;
    }
    order
}

/// `rows` (`cols` floats each) in the order `order`.
pub(super) fn gather_rows(rows: &[f32], cols: usize, order: &[u32]) -> Vec<f32> {
    let mut out = Vec::with_capacity(rows.len());
    for &i in order {
        let i = i as usize;
        out.extend_from_slice(&rows[i * cols..(i + 1) * cols]);
    }
    out
}

/// Reads `buffer`'s first `out.len()` floats into `out`, rows of `cols`, putting output row
/// i at row `order[i]` when the rows were uploaded in that order; in row order, `copy`
/// splits the copy over its threads.
///
/// # Safety
/// As [`Buffer::read`]: nothing writes the buffer meanwhile.
pub(super) unsafe fn read_in_place(
    buffer: &Buffer,
    out: &mut [f32],
    cols: usize,
    order: Option<&[u32]>,
    copy: &HostCopy,
) {
    match order {
        None => {
            let len = std::mem::size_of_val(out);
            // SAFETY: nothing writes `buffer` during the call (this function's own
            // contract, passed on unchanged); `Buffer::mapped` checks that `out` fits.
            let mapped = unsafe { buffer.mapped(len) };
            copy.copy(bytemuck::cast_slice_mut(out), mapped)
        }
        Some(order) => {
            let mut grouped = vec![0f32; out.len()];
            // SAFETY: as above; `grouped` has `out`'s length.
            unsafe { buffer.read(0, &mut grouped) };
            for (src, &dst) in grouped.chunks_exact(cols).zip(order) {
                let dst = dst as usize;
                out[dst * cols..(dst + 1) * cols].copy_from_slice(src);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_order_groups_by_material_keeps_row_order_and_is_a_permutation() {
        // 10 columns, material in column 9.
        let materials = [2, 0, 1, 0, 2, 2, 1, 0];
        let rows: Vec<f32> = materials
            .iter()
            .enumerate()
            .flat_map(|(i, &m)| {
                let mut r = [i as f32; 10];
                r[9] = m as f32;
                r
            })
            .collect();
        let order = bucket_order(&rows, 10, 3);
        assert_eq!(order, [1, 3, 7, 2, 6, 0, 4, 5]);
        let grouped = gather_rows(&rows, 10, &order);
        let firsts: Vec<f32> = grouped.chunks(10).map(|r| r[0]).collect();
        assert_eq!(firsts, [1.0, 3.0, 7.0, 2.0, 6.0, 0.0, 4.0, 5.0]);
    }
}
