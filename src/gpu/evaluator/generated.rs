//! Kernels that make their own directions: the half/difference slice of `vkbrdf table
//! slice`, computed from the invocation index and the push constants (`half_diff_row` in
//! `glsl/eval.comp`). Nothing is uploaded but the material: on lavapipe the tuple loads are
//! about half of the kernel's time, and end to end the host no longer builds and copies
//! 40 bytes per texel.

use super::*;
use crate::backend::SliceGrid;
use std::time::Instant;

/// Largest grid the generated-direction kernel takes: its texel index must be exact in
/// f32 (`half_diff_row` divides in f32: x86 has no vector integer division).
pub const MAX_GENERATED_TEXELS: u64 = 1 << 24;

/// The grid's push constants for the chunk of `len` texels from `first`.
fn push(grid: &SliceGrid, first: u32, len: u32) -> PushConstants {
    PushConstants {
        tuple_count: len,
        material_count: 1,
        first_row: first,
        grid_width: grid.width,
        grid_height: grid.height,
        spacing: u32::from(grid.linear),
    }
}

impl VulkanBackend {
    /// The features of the generated slice of `material`.
    fn slice_features(material: &Material, request: &Request) -> Result<FeatureSet> {
        let mut f = FeatureSet::of_material(material) | FeatureSet::GENERATED_SLICE;
        if f.contains(FeatureSet::MEASURED) {
            return Err(Error::Unsupported(
                "a measured (MERL) material has no Vulkan kernel; use --backend cpu".into(),
            ));
        }
        if material.is_anisotropic() {
            f |= FeatureSet::TANGENTS; // the generated tangent is +x
        }
        if request.terms {
            f |= FeatureSet::TERMS;
        }
        if material.precision == crate::precision::Precision::Fast {
            f |= FeatureSet::FAST_MATH;
        }
        Ok(f)
    }

    /// Checks that `grid` is non-empty and its texel indices fit the kernel's 32-bit rows.
    fn check_grid(grid: &SliceGrid) -> Result<usize> {
        let n = grid.texels();
        if grid.width == 0 || grid.height == 0 || n > MAX_GENERATED_TEXELS {
            return Err(Error::Unsupported(format!(
                "a {}x{} slice: the generated-direction kernel takes 1 to 2^24 texels",
                grid.width, grid.height
            )));
        }
        Ok(n as usize)
    }

    /// The half/difference slice `grid` of `material`, directions made on the device: the
    /// same values as evaluating [`crate::table::slice`]'s tuples (up to the f32 rounding
    /// of the directions, made here from f32 `sin`/`cos`), in the same row-major texel
    /// order. Streams in chunks like [`Backend::evaluate`].
    pub fn half_diff_slice(
        &mut self,
        material: &Material,
        grid: SliceGrid,
        request: &Request,
    ) -> Result<Output> {
        let n = Self::check_grid(&grid)?;
        let features = Self::slice_features(material, request)?;
        let terms = request.terms;
        let mut out = Output {
            brdf: vec![0.0; n * 3],
            terms: terms.then(|| vec![0.0; n * TERM_COLUMNS]),
            counts: Counts {
                tuples: n as u64,
                ..Counts::default()
            },
        };
        self.last_features = Some(features);
        let chunk = self.chunk_tuples(1)?;
        let pipeline = self.kernels.pipeline(features)?.raw();
        self.upload_materials(&gpu_materials(std::slice::from_ref(material)))?;
        let result = (|| {
            let chunks = n.div_ceil(chunk);
            for c in 0..chunks {
                let s = c % FRAMES_IN_FLIGHT;
                self.finish(s, &mut out)?;
                let (start, len) = (c * chunk, chunk.min(n - c * chunk));
                // One texel of input: the texel view must exist, the kernel reads none.
                self.prepare(s, 4, len * 3, if terms { len * TERM_COLUMNS } else { 0 })?;
                // SAFETY: the slot's previous chunk was finished above (fence waited).
                unsafe { self.slots[s].counts.write(0, &[GpuCounts::INITIAL]) };
                let pending = Pending {
                    brdf: start * 3..(start + len) * 3,
                    terms: terms.then(|| start * TERM_COLUMNS..(start + len) * TERM_COLUMNS),
                    first_row: start as u64,
                };
                let push = push(&grid, start as u32, len as u32);
                self.submit(s, pipeline, push, pending)?;
            }
            for k in 0..FRAMES_IN_FLIGHT {
                self.finish((chunks + k) % FRAMES_IN_FLIGHT, &mut out)?;
            }
            Ok::<(), Error>(())
        })();
        result.inspect_err(|_| self.recover())?;
        Ok(out)
    }

    /// Median seconds of the generated slice's dispatches alone (kernel only, no host
    /// copies), over `repeats` timed runs after a warm-up: the table-kernel figure of
    /// `vkbrdf bench`.
    pub fn half_diff_kernel_seconds(
        &mut self,
        material: &Material,
        grid: SliceGrid,
        repeats: usize,
    ) -> Result<f64> {
        let n = Self::check_grid(&grid)?;
        let features = Self::slice_features(material, &Request::default())?;
        let chunk = self.chunk_tuples(1)?;
        let pipeline = self.kernels.pipeline(features)?.raw();
        self.upload_materials(&gpu_materials(std::slice::from_ref(material)))?;
        let mut scratch = Output::default();
        let result = (|| {
            self.prepare(0, 4, chunk.min(n) * 3, 0)?;
            let mut secs = Vec::with_capacity(repeats + 1);
            for _ in 0..=repeats.max(1) {
                let t = Instant::now();
                let mut start = 0;
                while start < n {
                    let len = chunk.min(n - start);
                    // SAFETY: slot 0's previous dispatch was finished (fence waited) below.
                    unsafe { self.slots[0].counts.write(0, &[GpuCounts::INITIAL]) };
                    let pending = Pending {
                        brdf: 0..0,
                        terms: None,
                        first_row: start as u64,
                    };
                    self.submit(0, pipeline, push(&grid, start as u32, len as u32), pending)?;
                    self.finish(0, &mut scratch)?;
                    start += len;
                }
                secs.push(t.elapsed().as_secs_f64());
            }
            secs.remove(0); // the warm-up
            Ok(crate::bench::median(secs))
        })();
        result.inspect_err(|_| self.recover())
    }
}
