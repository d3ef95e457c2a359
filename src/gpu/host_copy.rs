//! [`HostCopy`]: the evaluator's copies into and out of mapped memory, split over a few
//! threads on a GPU host. One thread's `memcpy` moves ~10 GB/s, a tuple is 40 bytes in and
//! 12 out, so one thread caps a stream near 200 M tuples/s while a PCIe 4/5 link carries
//! 25–50 GB/s (issue 31's target on the H200 class is 250 M/s end to end). On a CPU device
//! the kernel runs on the host's own cores, which extra copy threads would take from it,
//! so there it copies on the calling thread.

/// Pieces smaller than this are not worth a hand-off to another thread (a pool task costs
/// a few microseconds; 256 KiB take ~25 µs to copy).
const MIN_PIECE_BYTES: usize = 256 << 10;

/// See the module docs.
pub(crate) struct HostCopy {
    /// `None`: copy on the calling thread.
    pool: Option<rayon_core::ThreadPool>,
    threads: usize,
}

impl HostCopy {
    /// Copies split over `threads` pool threads (1 or 0: on the calling thread; a pool
    /// that fails to start falls back to that too).
    pub(crate) fn new(threads: usize) -> HostCopy {
        let pool = (threads > 1)
            .then(|| {
                rayon_core::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .thread_name(|i| format!("vkbrdf-copy-{i}"))
                    .build()
                    .ok()
            })
            .flatten();
        let threads = if pool.is_some() { threads } else { 1 };
        HostCopy { pool, threads }
    }

    /// Threads a copy is split over.
    pub(crate) fn threads(&self) -> usize {
        self.threads
    }

    /// `dst.copy_from_slice(src)`, in up to `threads` pieces of whole cache lines.
    ///
    /// # Panics
    /// If the lengths differ (as `copy_from_slice`).
    pub(crate) fn copy(&self, dst: &mut [u8], src: &[u8]) {
        assert_eq!(dst.len(), src.len(), "a copy between slices of one length");
        let pieces = (src.len() / MIN_PIECE_BYTES).min(self.threads);
        let Some(pool) = self.pool.as_ref().filter(|_| pieces > 1) else {
            dst.copy_from_slice(src);
            return;
        };
        let piece = src.len().div_ceil(pieces).next_multiple_of(64);
        pool.scope(|scope| {
            for (d, s) in dst.chunks_mut(piece).zip(src.chunks(piece)) {
                scope.spawn(move |_| d.copy_from_slice(s));
            }
        });
    }
}

/// The default copy threads on a device: 1 on a CPU device (see the module docs), else a
/// quarter of the host's cores, 1 to 4 (a reader, a writer and the engine thread run beside
/// them).
pub(crate) fn default_threads(cpu_device: bool) -> usize {
    if cpu_device {
        return 1;
    }
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    (cores / 4).clamp(1, 4)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_split_copy_equals_one_copy_at_every_length() {
        // Not periodic, so a piece copied to another place cannot match by chance.
        let src: Vec<u8> = (0..3 * MIN_PIECE_BYTES as u64 + 77)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
            .collect();
        for threads in [1, 2, 3, 4] {
            let copy = HostCopy::new(threads);
            for len in [
                0,
                1,
                63,
                MIN_PIECE_BYTES,
                2 * MIN_PIECE_BYTES + 1,
                src.len(),
            ] {
                let mut dst = vec![0u8; len];
                copy.copy(&mut dst, &src[..len]);
                assert!(dst == src[..len], "{threads} threads, {len} bytes");
            }
        }
    }
}
