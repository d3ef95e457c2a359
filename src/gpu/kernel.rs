//! The kernel: GLSL embedded in the binary, compiled by shaderc once per [`FeatureSet`],
//! and the compute pipelines, cached by FeatureSet.
//!
//! The FeatureSet's preprocessor names (`HAS_D_GGX`, `WRITE_TERMS`, …) are defined for the
//! compile, so code a batch does not use is not in the SPIR-V at all (the GLSL wraps every
//! model and term in `#if defined(...)`). The integer codes and binding numbers come from
//! [`super::layout`], the workgroup size from [`WORKGROUP_SIZE`] as specialization
//! constant 0: each is said once, in Rust.

use super::context::{Device, PhysicalInfo};
use super::disk_cache::{key_of, DiskCache};
use super::fold::Fold;
use super::layout::{descriptor_type, shader_codes, PushConstants, BINDING_COUNT, SHADER_BINDINGS};
use super::pipeline_cache::PipelineCache;
use super::vk_error::vk_error;
use crate::error::{Error, Result};
use crate::features::FeatureSet;
use ash::vk;
use std::collections::HashMap;
use std::sync::Arc;

/// Invocations per workgroup (specialization constant 0 of every kernel): a multiple of
/// every common subgroup size (8 on lavapipe, 32 NVIDIA, 64 AMD) and the most the Vulkan
/// specification guarantees (`maxComputeWorkGroupInvocations` ≥ 128). On lavapipe, where
/// each workgroup is a task with its own set-up, 128 ran folded kernels 2–6 % faster than
/// 64 (4M tuples; 256 and 1024 within 2 % of 128), docs/VULKAN.md.
pub const WORKGROUP_SIZE: u32 = 128;

/// Workgroups that cover `tuples` rows, `per_invocation` rows an invocation.
pub(crate) fn workgroups(tuples: u32, per_invocation: u32) -> u32 {
    tuples
        .div_ceil(per_invocation.max(1))
        .div_ceil(WORKGROUP_SIZE)
}

/// Materials one evaluator folds into pipelines at most (see [`fold_material_min_tuples`]):
/// the bench's scenarios and a few large batches, never a fit's thousands of parameter sets.
///
/// [`fold_material_min_tuples`]: super::VulkanOptions::fold_material_min_tuples
pub const FOLDED_MATERIALS_MAX: usize = 16;

/// The GLSL sources embedded in the binary, by the name `#include` uses.
pub const SOURCES: &[(&str, &str)] = &[
    ("eval.comp", include_str!("../../glsl/eval.comp")),
    ("layout.glsl", include_str!("../../glsl/layout.glsl")),
    ("math.glsl", include_str!("../../glsl/math.glsl")),
    ("ff.glsl", include_str!("../../glsl/ff.glsl")),
    ("terms.glsl", include_str!("../../glsl/terms.glsl")),
    (
        "f_poly_constants.glsl",
        include_str!("../../glsl/f_poly_constants.glsl"),
    ),
    ("models.glsl", include_str!("../../glsl/models.glsl")),
    ("htsg.glsl", include_str!("../../glsl/htsg.glsl")),
    ("evaluate.glsl", include_str!("../../glsl/evaluate.glsl")),
    ("measured.glsl", include_str!("../../glsl/measured.glsl")),
    ("material.glsl", include_str!("../../glsl/material.glsl")),
    ("bindings.glsl", include_str!("../../glsl/bindings.glsl")),
    ("input.glsl", include_str!("../../glsl/input.glsl")),
    (
        "generators.glsl",
        include_str!("../../glsl/generators.glsl"),
    ),
    ("frame.glsl", include_str!("../../glsl/frame.glsl")),
    (
        "frame_fields.glsl",
        include_str!("../../glsl/frame_fields.glsl"),
    ),
    ("frame64.glsl", include_str!("../../glsl/frame64.glsl")),
    ("frame32.glsl", include_str!("../../glsl/frame32.glsl")),
    (
        "frame_local32.glsl",
        include_str!("../../glsl/frame_local32.glsl"),
    ),
    (
        "frame_local_h64.glsl",
        include_str!("../../glsl/frame_local_h64.glsl"),
    ),
    (
        "integrators.glsl",
        include_str!("../../glsl/integrators.glsl"),
    ),
    ("counts.glsl", include_str!("../../glsl/counts.glsl")),
];

/// The disk cache's name for the SPIR-V of the kernel compiled with `defines` for `env`:
/// every embedded source, the definitions and the target, and this build's version.
fn spirv_key(defines: &[(String, String)], env: shaderc::EnvVersion) -> String {
    let mut parts: Vec<&[u8]> = vec![env!("CARGO_PKG_VERSION").as_bytes()];
    for (name, text) in SOURCES {
        parts.push(name.as_bytes());
        parts.push(text.as_bytes());
    }
    for (name, value) in defines {
        parts.push(name.as_bytes());
        parts.push(value.as_bytes());
    }
    let env = (env as u32).to_le_bytes();
    parts.push(&env);
    key_of(&parts)
}

/// The kernel's entry file in [`SOURCES`].
pub const KERNEL_FILE: &str = "eval.comp";

/// The Vulkan version to compile for: 1.1 (SPIR-V 1.3, subgroup operations) when the device
/// has it.
fn target(physical: &PhysicalInfo) -> shaderc::EnvVersion {
    if physical.properties.api_version >= vk::API_VERSION_1_1 {
        shaderc::EnvVersion::Vulkan1_1
    } else {
        shaderc::EnvVersion::Vulkan1_0
    }
}

/// Whether the kernel numbers its rows by subgroup (`ROW_FROM_SUBGROUP` in eval.comp): on a
/// CPU device (lavapipe), whose subgroups are full SIMD loops of `subgroup_size` lanes that
/// divide the workgroup, so that `gl_SubgroupID · gl_SubgroupSize + gl_SubgroupInvocationID`
/// numbers the workgroup's invocations once each. llvmpipe forms `gl_GlobalInvocationID`
/// from a remainder a lane (eight integer divisions a SIMD loop); GPUs keep it, which the
/// specification defines without any assumption about their subgroups.
fn row_from_subgroup(p: &PhysicalInfo, subgroups: bool) -> bool {
    subgroups
        && p.properties.device_type == vk::PhysicalDeviceType::CPU
        && p.subgroup_size
            .is_some_and(|s| s > 0 && WORKGROUP_SIZE.is_multiple_of(s))
}

/// The macros of the kernel for `features`: every feature name, every code and binding,
/// and `USE_SUBGROUP_ARITHMETIC` when the counts can be reduced across a subgroup.
pub fn kernel_defines(features: FeatureSet, subgroup_arithmetic: bool) -> Vec<(String, String)> {
    let mut d: Vec<(String, String)> = features
        .defines()
        .map(|n| (n.to_string(), "1".to_string()))
        .collect();
    d.extend(
        shader_codes()
            .iter()
            .map(|(n, v)| (n.to_string(), format!("{v}u"))),
    );
    d.extend(
        SHADER_BINDINGS
            .iter()
            .map(|(n, v)| (n.to_string(), v.to_string())),
    );
    if subgroup_arithmetic {
        d.push(("USE_SUBGROUP_ARITHMETIC".to_string(), "1".to_string()));
    }
    d
}

/// Compiles `main` of `files` (name, text) to SPIR-V words for Vulkan `env`, resolving
/// `#include "x"` against `files` only, so the binary needs no source tree. A compile error
/// is an [`Error::Shader`] whose text names the file and line (`terms.glsl:42: error: …`).
pub fn compile(
    files: &[(&str, &str)],
    main: &str,
    defines: &[(String, String)],
    env: shaderc::EnvVersion,
) -> Result<Vec<u32>> {
    let text = files
        .iter()
        .find(|(n, _)| *n == main)
        .map(|(_, t)| *t)
        .ok_or_else(|| Error::Shader(format!("{main}: no such embedded shader")))?;
    let compiler = shaderc::Compiler::new()
        .map_err(|e| Error::Shader(format!("cannot start the shaderc compiler: {e}")))?;
    let mut options = shaderc::CompileOptions::new()
        .map_err(|e| Error::Shader(format!("cannot create shaderc options: {e}")))?;
    options.set_target_env(shaderc::TargetEnv::Vulkan, env as u32);
    for (name, value) in defines {
        options.add_macro_definition(name, Some(value));
    }
    let names: Vec<String> = files.iter().map(|(n, _)| n.to_string()).collect();
    let owned: Vec<(String, String)> = files
        .iter()
        .map(|(n, t)| (n.to_string(), t.to_string()))
        .collect();
    options.set_include_callback(move |requested, _kind, from, _depth| {
        let wanted = requested.trim_start_matches("./");
        owned
            .iter()
            .find(|(n, _)| n == wanted)
            .map(|(n, t)| shaderc::ResolvedInclude {
                resolved_name: n.clone(),
                content: t.clone(),
            })
            .ok_or_else(|| {
                format!(
                    "{from}: #include \"{requested}\": not an embedded shader file (they are: {})",
                    names.join(", ")
                )
            })
    });
    let artifact = compiler
        .compile_into_spirv(
            text,
            shaderc::ShaderKind::Compute,
            main,
            "main",
            Some(&options),
        )
        .map_err(|e| match e {
            shaderc::Error::CompilationError(n, msg) => {
                Error::Shader(format!("{n} error(s):\n{}", msg.trim_end()))
            }
            other => Error::Shader(other.to_string()),
        })?;
    Ok(artifact.as_binary().to_vec())
}

/// Compiles the embedded kernel for `features` (no device needed: used by tests that
/// inspect what a FeatureSet compiles to).
pub fn compile_kernel(features: FeatureSet, subgroup_arithmetic: bool) -> Result<Vec<u32>> {
    let env = if subgroup_arithmetic {
        shaderc::EnvVersion::Vulkan1_1
    } else {
        shaderc::EnvVersion::Vulkan1_0
    };
    compile(
        SOURCES,
        KERNEL_FILE,
        &kernel_defines(features, subgroup_arithmetic),
        env,
    )
}

/// The `OpName` strings of a SPIR-V module (function, variable and type names; glslang
/// writes a function `f(float)` as `f(f1;`). `OpSource` text is not included, so a name
/// here means the code is really in the module.
pub fn spirv_names(words: &[u32]) -> Vec<String> {
    const OP_NAME: u32 = 5;
    let mut names = Vec::new();
    let mut i = 5; // header: magic, version, generator, bound, schema
    while i < words.len() {
        let count = (words[i] >> 16) as usize;
        let opcode = words[i] & 0xffff;
        if count == 0 || i + count > words.len() {
            break;
        }
        if opcode == OP_NAME && count >= 3 {
            let bytes: Vec<u8> = words[i + 2..i + count]
                .iter()
                .flat_map(|w| w.to_le_bytes())
                .collect();
            let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
            names.push(String::from_utf8_lossy(&bytes[..end]).into_owned());
        }
        i += count;
    }
    names
}

/// One compute pipeline.
pub(crate) struct Pipeline {
    raw: vk::Pipeline,
    device: Arc<Device>,
}

impl Pipeline {
    /// The handle.
    pub fn raw(&self) -> vk::Pipeline {
        self.raw
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        // SAFETY: owners drop pipelines only when no submitted work uses them (the evaluator
        // waits idle first); destroyed exactly once, before the layout (see Kernels::drop).
        unsafe { self.device.raw.destroy_pipeline(self.raw, None) };
    }
}

/// The descriptor-set and pipeline layouts every kernel shares, the pipelines made so far,
/// and what is kept across runs: the SPIR-V and the driver's pipeline cache
/// ([`super::disk_cache`]).
pub(crate) struct Kernels {
    cache: HashMap<FeatureSet, Pipeline>,
    /// The SPIR-V of each feature set compiled so far (the table kernel and, with one row
    /// an invocation, its folds share it).
    spirv: HashMap<FeatureSet, Arc<[u32]>>,
    /// The folded kernels' SPIR-V with `MULTI_ROW` ([`Kernels::compiled_folded`]).
    spirv_multi_row: HashMap<FeatureSet, Arc<[u32]>>,
    /// Pipelines with a material folded in ([`Kernels::folded`]), in order of creation: at
    /// most [`FOLDED_MATERIALS_MAX`], never evicted.
    folded: Vec<(FeatureSet, Fold, Pipeline)>,
    probes: HashMap<String, Pipeline>,
    layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    extra_defines: Vec<(String, String)>,
    disk: DiskCache,
    /// Pipelines created so far ([`Kernels::created`]).
    created: u64,
    /// Rows an invocation of a folded pipeline takes (`TUPLES_PER_INVOCATION`, 1–4; set by
    /// the evaluator from its option); table kernels 1.
    pub(crate) folded_per_invocation: u32,
    /// Declared after the pipelines' owners, so that it is written back after they are
    /// gone (`Drop` below clears them first in any case).
    pipeline_cache: PipelineCache,
    device: Arc<Device>,
}

impl Kernels {
    /// Creates the shared layouts: `BINDING_COUNT` bindings (storage buffers and the tuple
    /// texel buffer, see [`descriptor_type`]) and the push constants. `extra_defines` are
    /// added to every kernel's definitions (variant experiments).
    pub fn new(device: &Arc<Device>, extra_defines: Vec<(String, String)>) -> Result<Kernels> {
        // First: it cleans up after itself (RAII) if what follows fails.
        let disk = DiskCache::from_env();
        let pipeline_cache = PipelineCache::new(device, disk.clone())?;
        let bindings: Vec<vk::DescriptorSetLayoutBinding> = (0..BINDING_COUNT)
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(descriptor_type(b))
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
        // SAFETY: the device is live (`Arc<Device>`, also kept by `Kernels`); `info` points to
        // `bindings`, a local that outlives the call.
        let set_layout = unsafe { device.raw.create_descriptor_set_layout(&info, None) }
            .map_err(vk_error("vkCreateDescriptorSetLayout"))?;
        let mut kernels = Kernels {
            cache: HashMap::new(),
            spirv: HashMap::new(),
            spirv_multi_row: HashMap::new(),
            folded: Vec::new(),
            probes: HashMap::new(),
            layout: vk::PipelineLayout::null(),
            set_layout,
            extra_defines,
            disk,
            created: 0,
            folded_per_invocation: 1,
            pipeline_cache,
            device: Arc::clone(device),
        };
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .size(std::mem::size_of::<PushConstants>() as u32)];
        let set_layouts = [set_layout];
        let info = vk::PipelineLayoutCreateInfo::default()
            .set_layouts(&set_layouts)
            .push_constant_ranges(&ranges);
        // SAFETY: `set_layout` was created above on this device and is destroyed only in
        // `Kernels::drop`; `info` points to locals that outlive the call.
        kernels.layout = unsafe { device.raw.create_pipeline_layout(&info, None) }
            .map_err(vk_error("vkCreatePipelineLayout"))?;
        Ok(kernels)
    }

    /// The shared pipeline layout.
    pub fn layout(&self) -> vk::PipelineLayout {
        self.layout
    }

    /// The shared descriptor-set layout.
    pub fn set_layout(&self) -> vk::DescriptorSetLayout {
        self.set_layout
    }

    /// The pipeline for `features`, compiled on first use.
    pub fn pipeline(&mut self, features: FeatureSet) -> Result<&Pipeline> {
        if !self.cache.contains_key(&features) {
            let spirv = self.compiled(features)?;
            let pipeline = self.create(&spirv, None)?;
            self.cache.insert(features, pipeline);
        }
        Ok(&self.cache[&features])
    }

    /// The SPIR-V for `features`: kept from an earlier call, else from the disk cache, else
    /// compiled now (and stored there).
    fn compiled(&mut self, features: FeatureSet) -> Result<Arc<[u32]>> {
        if let Some(words) = self.spirv.get(&features) {
            return Ok(Arc::clone(words));
        }
        let words: Arc<[u32]> = self.spirv_source(features).words()?.into();
        self.spirv.insert(features, Arc::clone(&words));
        Ok(words)
    }

    /// The SPIR-V of a folded kernel for `features`: with several rows an invocation
    /// ([`Kernels::folded_per_invocation`] > 1), the kernel built with `MULTI_ROW` (its
    /// `main` takes `TUPLES_PER_INVOCATION` rows), else the table kernel's own.
    fn compiled_folded(&mut self, features: FeatureSet) -> Result<Arc<[u32]>> {
        if self.folded_per_invocation <= 1 {
            return self.compiled(features);
        }
        if let Some(words) = self.spirv_multi_row.get(&features) {
            return Ok(Arc::clone(words));
        }
        let mut source = self.spirv_source(features);
        source
            .defines
            .push(("MULTI_ROW".to_string(), "1".to_string()));
        let words: Arc<[u32]> = source.words()?.into();
        self.spirv_multi_row.insert(features, Arc::clone(&words));
        Ok(words)
    }

    /// What [`compiled`](Self::compiled) needs to make the SPIR-V of `features`, without
    /// `self`: for [`prepare`](Self::prepare)'s threads.
    fn spirv_source(&self, features: FeatureSet) -> SpirvSource {
        let p = &self.device.physical;
        let arithmetic =
            p.subgroup_arithmetic && target(p) as u32 >= shaderc::EnvVersion::Vulkan1_1 as u32;
        let mut defines = kernel_defines(features, arithmetic);
        if p.shader_float64 {
            defines.push(("HAS_FLOAT64".to_string(), "1".to_string()));
        }
        if row_from_subgroup(p, arithmetic) {
            defines.push(("ROW_FROM_SUBGROUP".to_string(), "1".to_string()));
        }
        // A CPU device's f64 square root and division are instructions (GPUs emulate both):
        // glsl/math.glsl's rsqrt64_once then takes them instead of an f32 estimate and a
        // Newton step (lavapipe, folded mitsuba-ggx +1.5–2 %).
        if p.shader_float64 && p.properties.device_type == vk::PhysicalDeviceType::CPU {
            defines.push(("F64_ROOTS".to_string(), "1".to_string()));
        }
        defines.extend(self.extra_defines.iter().cloned());
        SpirvSource {
            features,
            defines,
            target: target(p),
            disk: self.disk.clone(),
        }
    }

    /// Makes the pipelines of every feature set in `sets` that this evaluator has not made
    /// yet, several at once: one thread a core, each compiling a kernel (shaderc, then the
    /// driver's pipeline creation) from start to end: a `check` compiles 9 kernels, which a
    /// driver that compiles at pipeline creation (NVIDIA, AMD) would otherwise compile one
    /// after another (docs/VULKAN.md, "Kernels a check compiles"). Pipeline creation may run on several threads at once: the pipeline cache
    /// was created without `EXTERNALLY_SYNCHRONIZED`, so the driver synchronises it, and
    /// each thread has its own shaderc compiler. On an error the pipelines made are kept and
    /// the first failing set's error (in `sets`' order) is returned.
    pub fn prepare(&mut self, sets: &[FeatureSet]) -> Result<()> {
        let mut missing: Vec<FeatureSet> = Vec::new();
        for &f in sets {
            if !self.cache.contains_key(&f) && !missing.contains(&f) {
                missing.push(f);
            }
        }
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(missing.len());
        if threads <= 1 {
            return missing
                .iter()
                .try_for_each(|&f| self.pipeline(f).map(|_| ()));
        }
        let jobs: Vec<(SpirvSource, Option<Arc<[u32]>>)> = missing
            .iter()
            .map(|&f| (self.spirv_source(f), self.spirv.get(&f).cloned()))
            .collect();
        let (device, layout) = (Arc::clone(&self.device), self.layout);
        let cache = self.pipeline_cache.for_creation();
        let next = std::sync::atomic::AtomicUsize::new(0);
        let made: Vec<Vec<(usize, Made)>> = std::thread::scope(|s| {
            let workers: Vec<_> = (0..threads)
                .map(|_| {
                    s.spawn(|| {
                        let mut done = Vec::new();
                        loop {
                            let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                            let Some((source, kept)) = jobs.get(i) else {
                                return done;
                            };
                            let made = match kept {
                                Some(words) => Ok(Arc::clone(words)),
                                None => source.words().map(Arc::from),
                            }
                            .and_then(|words| {
                                let p = create_pipeline(&device, layout, cache, &words, None, 1)?;
                                Ok((words, p))
                            });
                            done.push((i, made));
                        }
                    })
                })
                .collect();
            workers
                .into_iter()
                .map(|w| w.join().expect("a kernel compile thread panicked"))
                .collect()
        });
        let mut made: Vec<(usize, Made)> = made.into_iter().flatten().collect();
        made.sort_by_key(|(i, _)| *i);
        let mut first_error = None;
        for (i, r) in made {
            match r {
                Ok((words, pipeline)) => {
                    self.spirv.insert(missing[i], words);
                    self.cache.insert(missing[i], pipeline);
                    self.created += 1;
                }
                Err(e) => {
                    first_error.get_or_insert(e);
                }
            }
        }
        first_error.map_or(Ok(()), Err)
    }

    /// How many pipelines this evaluator has created (every kernel, fold and probe).
    pub fn created(&self) -> u64 {
        self.created
    }

    /// The pipeline for `features` with a material folded in as specialization constants
    /// ([`Fold`]: `material_at` in `glsl/bindings.glsl`, and F's polynomial in
    /// `glsl/f_poly_constants.glsl`): the compiler then treats the material as a kernel
    /// written for it would, folding its constants and its terms' dispatch.
    /// `None` once this evaluator has folded [`FOLDED_MATERIALS_MAX`] materials: each fold
    /// is a compile, and a caller that changes the material from batch to batch (a fit)
    /// must not compile in a loop; it gets [`pipeline`](Self::pipeline)'s kernel instead.
    pub fn folded(&mut self, features: FeatureSet, fold: &Fold) -> Result<Option<vk::Pipeline>> {
        let found = self
            .folded
            .iter()
            .find(|(f, m, _)| *f == features && m == fold);
        if let Some((_, _, p)) = found {
            return Ok(Some(p.raw));
        }
        if self.folded.len() >= FOLDED_MATERIALS_MAX {
            return Ok(None);
        }
        let spirv = self.compiled_folded(features)?;
        let pipeline = self.create(&spirv, Some(fold))?;
        let raw = pipeline.raw;
        self.folded.push((features, *fold, pipeline));
        Ok(Some(raw))
    }

    /// The SPIR-V of the kernel for `features` (compiled on first use).
    pub fn spirv(&mut self, features: FeatureSet) -> Result<Vec<u32>> {
        Ok(self.compiled(features)?.to_vec())
    }

    /// A pipeline for a probe shader (`main.comp` in `source`, with the embedded files
    /// available to `#include`), cached by its text.
    pub fn probe(&mut self, source: &str) -> Result<&Pipeline> {
        if !self.probes.contains_key(source) {
            let mut files: Vec<(&str, &str)> = SOURCES.to_vec();
            files.push(("probe.comp", source));
            let p = &self.device.physical;
            let spirv = compile(
                &files,
                "probe.comp",
                &kernel_defines(FeatureSet::EMPTY, false),
                target(p),
            )?;
            let pipeline = self.create(&spirv, None)?;
            self.probes.insert(source.to_string(), pipeline);
        }
        Ok(&self.probes[source])
    }

    /// A pipeline from `spirv` ([`create_pipeline`]), counted.
    fn create(&mut self, spirv: &[u32], fold: Option<&Fold>) -> Result<Pipeline> {
        let cache = self.pipeline_cache.for_creation();
        let per_invocation = if fold.is_some() {
            self.folded_per_invocation
        } else {
            1
        };
        let p = create_pipeline(
            &self.device,
            self.layout,
            cache,
            spirv,
            fold,
            per_invocation,
        )?;
        self.created += 1;
        Ok(p)
    }
}

/// What [`Kernels::prepare`]'s threads make of one feature set: its SPIR-V and pipeline.
type Made = Result<(Arc<[u32]>, Pipeline)>;

/// Everything the SPIR-V of one kernel depends on: the kernel's definitions and target,
/// and the disk cache that may hold it already.
struct SpirvSource {
    features: FeatureSet,
    defines: Vec<(String, String)>,
    target: shaderc::EnvVersion,
    disk: DiskCache,
}

impl SpirvSource {
    /// The SPIR-V: from the disk cache, else compiled now (and stored there).
    fn words(&self) -> Result<Vec<u32>> {
        let key = spirv_key(&self.defines, self.target);
        if let Some(words) = self.disk.load_words("spirv", &key) {
            return Ok(words);
        }
        let words =
            compile(SOURCES, KERNEL_FILE, &self.defines, self.target).map_err(|e| match e {
                Error::Shader(m) => {
                    Error::Shader(format!("{m}\n(kernel for features {})", self.features))
                }
                e => e,
            })?;
        self.disk.store_words("spirv", &key, &words);
        Ok(words)
    }
}

/// The specialization constant of the rows an invocation takes.
const TUPLES_PER_INVOCATION_ID: u32 = 30;

/// A pipeline from `spirv` with the shared `layout`, through `pipeline_cache`: the workgroup
/// size as constant 0, with a fold MATERIAL_IS_CONSTANT (1), the material's 28 words (2-29,
/// in field order) and F's polynomial (31-76, [`Fold::f_poly_constants`]), and the rows an
/// invocation takes (30, `per_invocation`).
fn create_pipeline(
    device: &Arc<Device>,
    layout: vk::PipelineLayout,
    pipeline_cache: vk::PipelineCache,
    spirv: &[u32],
    fold: Option<&Fold>,
    per_invocation: u32,
) -> Result<Pipeline> {
    let d = &device.raw;
    let info = vk::ShaderModuleCreateInfo::default().code(spirv);
    // SAFETY: `spirv` is a complete module from shaderc; the device is live.
    let module =
        unsafe { d.create_shader_module(&info, None) }.map_err(vk_error("vkCreateShaderModule"))?;
    let mut data = WORKGROUP_SIZE.to_ne_bytes().to_vec();
    if let Some(f) = fold {
        data.extend_from_slice(&vk::TRUE.to_ne_bytes());
        data.extend_from_slice(bytemuck::bytes_of(&f.material));
    }
    // Constant i at offset 4 i: the data above is laid out in constant order.
    let mut entries: Vec<vk::SpecializationMapEntry> = (0..data.len() as u32 / 4)
        .map(|i| vk::SpecializationMapEntry {
            constant_id: i,
            offset: 4 * i,
            size: 4,
        })
        .collect();
    // TUPLES_PER_INVOCATION after them (a shader without the constant ignores the entry).
    entries.push(vk::SpecializationMapEntry {
        constant_id: TUPLES_PER_INVOCATION_ID,
        offset: data.len() as u32,
        size: 4,
    });
    data.extend_from_slice(&per_invocation.to_ne_bytes());
    for (constant_id, bits) in fold.map(Fold::f_poly_constants).unwrap_or_default() {
        entries.push(vk::SpecializationMapEntry {
            constant_id,
            offset: data.len() as u32,
            size: 4,
        });
        data.extend_from_slice(&bits.to_ne_bytes());
    }
    let specialization = vk::SpecializationInfo::default()
        .map_entries(&entries)
        .data(&data);
    let stage = vk::PipelineShaderStageCreateInfo::default()
        .stage(vk::ShaderStageFlags::COMPUTE)
        .module(module)
        .name(c"main")
        .specialization_info(&specialization);
    let infos = [vk::ComputePipelineCreateInfo::default()
        .stage(stage)
        .layout(layout)];
    // SAFETY: the module, layout and specialization data are live for the call. Other
    // threads may create pipelines through `pipeline_cache` at the same time
    // (`Kernels::prepare`): it was created without `EXTERNALLY_SYNCHRONIZED`, so the driver
    // synchronises access to it.
    let created = unsafe { d.create_compute_pipelines(pipeline_cache, &infos, None) };
    // SAFETY: the module is no longer needed once the pipeline exists (or failed).
    unsafe { d.destroy_shader_module(module, None) };
    let raw = created.map_err(|(_, r)| vk_error("vkCreateComputePipelines")(r))?[0];
    Ok(Pipeline {
        raw,
        device: Arc::clone(device),
    })
}

impl Drop for Kernels {
    fn drop(&mut self) {
        // Pipelines first (they were created with the layout), then the layouts.
        self.cache.clear();
        self.folded.clear();
        self.probes.clear();
        // SAFETY: no pipeline or pending work uses the layouts any more (the evaluator waits
        // idle before dropping); each is destroyed exactly once, in reverse creation order.
        unsafe {
            self.device.raw.destroy_pipeline_layout(self.layout, None);
            self.device
                .raw
                .destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_compile_error_names_file_and_line() {
        let files = [
            (
                "main.comp",
                "#version 450\n#include \"bad.glsl\"\nvoid main() {}\n",
            ),
            ("bad.glsl", "float f() {\n  return undefined_thing;\n}\n"),
        ];
        let err = compile(&files, "main.comp", &[], shaderc::EnvVersion::Vulkan1_0)
            .unwrap_err()
            .to_string();
        assert!(err.contains("bad.glsl:2"), "{err}");
    }

    #[test]
    fn a_missing_include_is_named() {
        let files = [(
            "main.comp",
            "#version 450\n#include \"nope.glsl\"\nvoid main() {}\n",
        )];
        let err = compile(&files, "main.comp", &[], shaderc::EnvVersion::Vulkan1_0)
            .unwrap_err()
            .to_string();
        assert!(err.contains("nope.glsl"), "{err}");
    }

    #[test]
    fn every_feature_set_of_one_feature_compiles() {
        for (f, _) in FeatureSet::all_named() {
            compile_kernel(f, true).unwrap_or_else(|e| panic!("{f}: {e}"));
        }
        compile_kernel(FeatureSet::all(), false).unwrap();
    }
}
