//! Kernels that make their own directions: the half/difference slice of `vkbrdf table
//! slice`, computed from the invocation index and the push constants (`half_diff_row` in
//! `glsl/generators.glsl`). Nothing is uploaded but the material: on lavapipe the tuple loads are
//! about half of the kernel's time, and end to end the host no longer builds and copies
//! 40 bytes per texel.

use super::state::{Pending, VulkanBackend, FRAMES_IN_FLIGHT};
use crate::backend::{Output, Request, TERM_COLUMNS};
use crate::directions::{ImportanceJob, SliceGrid};
use crate::error::{Error, Result};
use crate::features::FeatureSet;
use crate::gpu::layout::{gpu_materials, GpuCounts, PushConstants};
use crate::material::Material;
use crate::precision::Precision;
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
        if material.is_anisotropic() {
            f |= FeatureSet::TANGENTS; // the generated tangent is +x
        }
        if request.terms {
            f |= FeatureSet::TERMS;
        }
        if material.precision == Precision::Fast {
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
    /// order. Streams in chunks like [`Backend::evaluate`](crate::backend::Backend::evaluate).
    pub fn half_diff_slice(
        &mut self,
        material: &Material,
        grid: SliceGrid,
        request: &Request,
    ) -> Result<Output> {
        let n = Self::check_grid(&grid)?;
        let features = Self::slice_features(material, request)?;
        let terms = request.terms;
        let mut out = Output::zeroed(n, terms);
        self.last_features = Some(features);
        let chunk = self.chunk_tuples(1)?;
        self.upload_measured(std::slice::from_ref(material))?;
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
                // SAFETY: `finish(s, ..)` above waited on slot `s`'s fence (or found nothing
                // pending), so no dispatch uses its `counts` buffer while the host writes it.
                unsafe { self.slots[s].counts.write(0, &[GpuCounts::INITIAL]) };
                let pending = Pending {
                    brdf: start * 3..(start + len) * 3,
                    terms: terms.then(|| start * TERM_COLUMNS..(start + len) * TERM_COLUMNS),
                    order: None,
                    first_row: start as u64,
                };
                let push = push(&grid, start as u32, len as u32);
                self.submit(s, pipeline, push, pending, 1)?;
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
        self.upload_measured(std::slice::from_ref(material))?;
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
                    // SAFETY: slot 0 has no work in flight: before the first dispatch nothing was
                    // submitted since `prepare`, and each later one follows the `finish(0, ..)`
                    // below, which waited on slot 0's fence; the device does not touch `counts`.
                    unsafe { self.slots[0].counts.write(0, &[GpuCounts::INITIAL]) };
                    let pending = Pending {
                        brdf: 0..0,
                        terms: None,
                        order: None,
                        first_row: start as u64,
                    };
                    let push = push(&grid, start as u32, len as u32);
                    self.submit(0, pipeline, push, pending, 1)?;
                    self.finish(0, &mut scratch)?;
                    start += len;
                }
                secs.push(t.elapsed().as_secs_f64());
            }
            secs.remove(0); // the warm-up
            Ok(crate::stats::median(secs))
        })();
        result.inspect_err(|_| self.recover())
    }
}

/// Samples one invocation of the importance kernel sums (`SAMPLES_PER_BLOCK` in
/// glsl/integrators.glsl): enough work per invocation to hide its set-up, enough invocations
/// (1024 points × 256 blocks at 2¹⁶ samples) to fill a GPU.
pub const SAMPLES_PER_BLOCK: u32 = 256;

impl VulkanBackend {
    /// [`GeneratedDirections::importance_sums`](crate::backend::GeneratedDirections::importance_sums) on the device: one invocation per block of
    /// `SAMPLES_PER_BLOCK` (256) samples of one point, which makes its directions, evaluates f
    /// and sums in f32; the blocks are added here in f64.
    /// `progress` is called with the samples of each chunk as it finishes.
    pub fn importance_sums(
        &mut self,
        job: &ImportanceJob,
        progress: &mut dyn FnMut(u64),
    ) -> Result<Vec<[f64; 2]>> {
        let samples = job.checked_samples()?;
        let blocks = samples.div_ceil(SAMPLES_PER_BLOCK);
        let total = job.points.len() as u64 * u64::from(blocks);
        if total > MAX_GENERATED_TEXELS {
            return Err(Error::Unsupported(format!(
                "{} points x {blocks} blocks of samples: the importance kernel takes up to 2^24 blocks",
                job.points.len()
            )));
        }
        let mut features = job
            .materials
            .iter()
            .fold(FeatureSet::GENERATED_IMPORTANCE, |f, m| {
                f | FeatureSet::of_material(m)
            });
        if features.contains(FeatureSet::MEASURED) {
            return Err(Error::Unsupported(
                "a measured material has no importance-sampling kernel".into(),
            ));
        }
        if job.materials.iter().all(|m| m.precision == Precision::Fast) {
            features |= FeatureSet::FAST_MATH;
        }
        let input: Vec<f32> = job
            .points
            .iter()
            .flat_map(|p| {
                let [t1, t2, vh] = p.frame;
                [
                    p.v[0],
                    p.v[1],
                    p.v[2],
                    p.g1,
                    t1[0],
                    t1[1],
                    t1[2],
                    p.s,
                    t2[0],
                    t2[1],
                    t2[2],
                    p.alpha,
                    vh[0],
                    vh[1],
                    vh[2],
                    p.material as f32,
                ]
            })
            .collect();
        let n = total as usize;
        let chunk = self.chunk_tuples(job.materials.len())?;
        let pipeline = self.kernels.pipeline(features)?.raw();
        self.upload_materials(&gpu_materials(job.materials))?;
        self.last_features = Some(features);
        let mut out = Output {
            brdf: vec![0.0; n * 3],
            ..Output::default()
        };
        let result = (|| {
            let chunks = n.div_ceil(chunk);
            // Samples per chunk of `len` blocks, reported when the chunk is read back.
            let samples_of = |len: usize| len as u64 * u64::from(SAMPLES_PER_BLOCK);
            for c in 0..chunks {
                let s = c % FRAMES_IN_FLIGHT;
                if self.slots[s].pending.is_some() {
                    self.finish(s, &mut out)?;
                    progress(samples_of(chunk));
                }
                let (start, len) = (c * chunk, chunk.min(n - c * chunk));
                self.prepare(s, input.len(), len * 3, 0)?;
                // SAFETY: slot `s` has no work in flight: it was never submitted, or its previous
                // chunk was finished just above (its fence waited), so the device neither reads
                // `input` nor writes `counts` while the host writes them.
                unsafe {
                    let slot = &mut self.slots[s];
                    slot.input.as_mut().expect("prepared").write(0, &input);
                    slot.counts.write(0, &[GpuCounts::INITIAL]);
                }
                let pending = Pending {
                    brdf: start * 3..(start + len) * 3,
                    terms: None,
                    order: None,
                    first_row: start as u64,
                };
                let push = PushConstants {
                    tuple_count: len as u32,
                    material_count: job.materials.len() as u32,
                    first_row: start as u32,
                    grid_width: blocks,
                    grid_height: samples,
                    spacing: u32::from(!job.ggx),
                };
                // One block an invocation: the importance kernel's main takes one row.
                self.submit(s, pipeline, push, pending, 1)?;
            }
            for k in 0..FRAMES_IN_FLIGHT {
                let s = (chunks + k) % FRAMES_IN_FLIGHT;
                if self.slots[s].pending.is_some() {
                    self.finish(s, &mut out)?;
                    progress(samples_of(chunk.min(n)));
                }
            }
            Ok::<(), Error>(())
        })();
        result.inspect_err(|_| self.recover())?;
        let inv = 1.0 / f64::from(samples);
        Ok(out
            .brdf
            .chunks(3 * blocks as usize)
            .map(|point| {
                let (mut a, mut b) = (0.0f64, 0.0f64);
                for block in point.chunks(3) {
                    a += f64::from(block[0]);
                    b += f64::from(block[1]);
                }
                [a * inv, b * inv]
            })
            .collect())
    }
}

/// The kernel makes slice and importance-sample directions on the device.
impl crate::backend::GeneratedDirections for VulkanBackend {
    fn half_diff_slice(
        &mut self,
        material: &Material,
        grid: crate::directions::SliceGrid,
        request: &Request,
    ) -> Option<Result<Output>> {
        // Larger grids go through tuples (the caller builds them).
        (grid.texels() <= MAX_GENERATED_TEXELS)
            .then(|| VulkanBackend::half_diff_slice(self, material, grid, request))
    }

    fn importance_sums(
        &mut self,
        job: &crate::directions::ImportanceJob,
        progress: &mut dyn FnMut(u64),
    ) -> Option<Result<Vec<[f64; 2]>>> {
        // Beyond the kernel's 2^24 blocks the caller sends the samples as tuples.
        let blocks = u64::from(job.samples.div_ceil(SAMPLES_PER_BLOCK));
        (job.points.len() as u64 * blocks <= MAX_GENERATED_TEXELS)
            .then(|| VulkanBackend::importance_sums(self, job, progress))
    }
}
