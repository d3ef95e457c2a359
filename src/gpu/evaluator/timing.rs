//! Kernel-only timing for `vkbrdf bench`: the tuples are uploaded once and stay resident;
//! only dispatch + fence wait is timed, so the figure excludes the host copies that the
//! end-to-end mode includes.

use super::*;
use std::time::Instant;

impl VulkanBackend {
    /// The kernel features for `batch` and `request`, widened by `forced` (the tangent
    /// layout and the terms output always follow the batch and the request).
    pub(super) fn features_with(
        batch: &Batch,
        materials: &[Material],
        request: &Request,
        forced: FeatureSet,
    ) -> FeatureSet {
        let mut features = FeatureSet::of_batch(batch, materials, request);
        for (f, _) in FeatureSet::ALL_NAMED {
            if forced.contains(*f) && *f != FeatureSet::TANGENTS && *f != FeatureSet::TERMS {
                features |= *f;
            }
        }
        features
    }

    /// Median seconds to evaluate `batch` with its data resident on the device (kernel
    /// only), over `repeats` timed runs after a warm-up. A batch larger than one chunk is
    /// timed as that many dispatches of the first chunk's (resident) tuples: the same work
    /// per tuple, without re-uploading.
    pub fn kernel_seconds(
        &mut self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
        repeats: usize,
    ) -> Result<f64> {
        self.kernel_seconds_with_features(batch, materials, request, repeats, FeatureSet::EMPTY)
    }

    /// [`kernel_seconds`](Self::kernel_seconds) with the kernel for `forced` ∪ what the
    /// batch needs (e.g. `FeatureSet::all()` for the all-features baseline).
    pub fn kernel_seconds_with_features(
        &mut self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
        repeats: usize,
        forced: FeatureSet,
    ) -> Result<f64> {
        let n = batch.len();
        if n == 0 {
            return Ok(0.0);
        }
        let features = self.grouping(Self::features_with(batch, materials, request, forced));
        let chunk = self.chunk_tuples(materials.len())?;
        let pipeline = self.kernels.pipeline(features)?.raw();
        self.upload_materials(&gpu_materials(materials))?;
        let (len, cols) = (n.min(chunk), batch.columns());
        let terms = features.contains(FeatureSet::TERMS);
        let result = (|| {
            // The grouping by material is done once, outside the timed loop: it is host
            // work, which the end-to-end timing includes.
            let rows = &batch.as_slice()[..len * cols];
            let bucketed = features.contains(FeatureSet::BUCKETED);
            self.load_chunk(0, rows, cols, materials.len(), bucketed, terms)?;
            let dispatches = n.div_ceil(len);
            let mut scratch = Output {
                brdf: Vec::new(),
                terms: None,
                counts: Counts::default(),
            };
            let mut secs = Vec::with_capacity(repeats + 1);
            for _ in 0..=repeats.max(1) {
                let t = Instant::now();
                for _ in 0..dispatches {
                    // SAFETY: slot 0 has no work in flight: before the first dispatch nothing was
                    // submitted since `prepare`, and each later one follows the `finish(0, ..)`
                    // below, which waited on slot 0's fence; the device does not touch `counts`.
                    unsafe { self.slots[0].counts.write(0, &[GpuCounts::INITIAL]) };
                    let pending = Pending {
                        brdf: 0..0,
                        terms: None,
                        order: None,
                        first_row: 0,
                    };
                    let push = PushConstants::rows(len as u32, materials.len() as u32, 0);
                    self.submit(0, pipeline, push, pending)?;
                    self.finish(0, &mut scratch)?;
                }
                secs.push(t.elapsed().as_secs_f64() * n as f64 / (dispatches * len) as f64);
            }
            secs.remove(0); // the warm-up
            Ok(crate::stats::median(secs))
        })();
        result.inspect_err(|_| self.recover())
    }
}
