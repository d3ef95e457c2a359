//! The GPU data structures, mirrored field for field from `glsl/layout.glsl` (whose
//! `material.glsl` reads `GpuMaterial`'s packed slots by name), and the integer codes and
//! binding numbers the kernel reads, each said once (a term's code by its `Term` in
//! `terms`, the others here) and injected into the GLSL as macros
//! ([`shader_codes`], [`SHADER_BINDINGS`]).
//!
//! Every GPU struct is `#[repr(C)]` + [`Pod`] built only from `[f32; 4]` and `[u32; 4]`, so
//! its std430 layout equals its Rust layout with no padding rules to remember (a `vec3`
//! would be 16-byte aligned in std430 but 12 bytes in Rust). The sizes and offsets are
//! asserted at compile time below; `tests/conformance.rs` has a kernel copy every field
//! back (`gpu_material_layout_round_trips`).

use crate::material::{
    Convention, Distribution, Fresnel, FresnelKind, Geometry, Material, Model, Roughness, Term,
};
use bytemuck::{Pod, Zeroable};
use std::f64::consts::PI;
use std::mem::{offset_of, size_of};

/// `kind.x`: `lambert`.
pub const MODEL_LAMBERT: u32 = 0;
/// `kind.x`: `phong`.
pub const MODEL_PHONG: u32 = 1;
/// `kind.x`: `blinn-phong`.
pub const MODEL_BLINN_PHONG: u32 = 2;
/// `kind.x`: `rtr`.
pub const MODEL_RTR: u32 = 3;
/// `kind.x`: `ward`.
pub const MODEL_WARD: u32 = 4;
/// `kind.x`: `cook-torrance`.
pub const MODEL_COOK_TORRANCE: u32 = 5;
/// `kind.x`: measured (MERL); `kind.y` is the table's index in the batch's MERL buffer
/// ([`measured_tables`]), `kind.z` the lookup ([`LOOKUP_NEAREST`], [`LOOKUP_LINEAR`]).
pub const MODEL_MEASURED: u32 = 6;
/// `kind.x`: `htsg` (FORMULAS.md §8; its packing in [`gpu_material`], its code in
/// `glsl/htsg.glsl`).
pub const MODEL_HTSG: u32 = 7;
/// `kind.z` of a measured material: MERL's nearest-bin lookup.
pub const LOOKUP_NEAREST: u32 = 0;
/// `kind.z` of a measured material: trilinear between sample points.
pub const LOOKUP_LINEAR: u32 = 1;

/// `kind.y`: no distribution (not a microfacet model).
pub const DIST_NONE: u32 = 0;
/// `(kind.w >> 8) & 0xff`: no convention (not a microfacet model).
pub const CONV_NONE: u32 = 0;

// The terms' codes (DIST_* in `kind.y`, GEOM_* `kind.z`, FRESNEL_* `kind.w & 0xff`, CONV_*
// `(kind.w >> 8) & 0xff`) are said by each family's list in `terms` (`Term::gpu_code`, the enum's discriminant)
// and injected from there ([`shader_codes`]).
/// `kind.w` bit: the material has anisotropic roughness (needs the tangent frame).
pub const FLAG_ANISOTROPIC: u32 = 1 << 16;
/// `kind.w` bit: a conductor whose every channel is legal for F's metal form
/// (`terms::f::conductor::metal_form_legal`; `conductor_f_metal` in glsl/terms.glsl).
pub const FLAG_METAL_FORM: u32 = 1 << 17;

/// Descriptor binding of the tuple rows (read).
pub const BINDING_TUPLES: u32 = 0;
/// Descriptor binding of the material table (read).
pub const BINDING_MATERIALS: u32 = 1;
/// Descriptor binding of the `n × 3` BRDF output.
pub const BINDING_BRDF: u32 = 2;
/// Descriptor binding of the `n × 6` term output (declared only with `WRITE_TERMS`).
pub const BINDING_TERMS: u32 = 3;
/// Descriptor binding of the [`GpuCounts`] of a chunk.
pub const BINDING_COUNTS: u32 = 4;
/// Descriptor binding of the tuple input again, as a uniform texel buffer of RGBA32UI texels (the bits, read exactly)
/// over the same bytes as [`BINDING_TUPLES`] (the table kernels read their rows through it:
/// on lavapipe `texelFetch` of a vec4 is far cheaper than four scalar storage-buffer loads;
/// folded kernels read 4-word elements of [`BINDING_TUPLES`] instead, `glsl/input.glsl`).
pub const BINDING_TUPLE_TEXELS: u32 = 5;
/// Descriptor binding of a chunk's evaluation order (`BUCKETED` kernels): invocation `i`
/// evaluates chunk row `order[i]`, so that rows of one material run side by side.
pub const BINDING_ORDER: u32 = 6;
/// Descriptor binding of the batch's measured tables (`HAS_MEASURED` kernels): for each
/// table of [`measured_tables`], its R, G, B blocks of f in 1/sr (f32, MERL's bin order).
pub const BINDING_MERL: u32 = 7;
/// Number of descriptor bindings (all storage buffers but [`BINDING_TUPLE_TEXELS`]).
pub const BINDING_COUNT: u32 = 8;

/// The integer codes the GLSL compares against, injected as `#define NAME <value>u`: the
/// models', lookups' and flags' (here) and every term's (`terms`).
pub fn shader_codes() -> Vec<(&'static str, u32)> {
    let own = [
        ("MODEL_LAMBERT", MODEL_LAMBERT),
        ("MODEL_PHONG", MODEL_PHONG),
        ("MODEL_BLINN_PHONG", MODEL_BLINN_PHONG),
        ("MODEL_RTR", MODEL_RTR),
        ("MODEL_WARD", MODEL_WARD),
        ("MODEL_COOK_TORRANCE", MODEL_COOK_TORRANCE),
        ("MODEL_MEASURED", MODEL_MEASURED),
        ("MODEL_HTSG", MODEL_HTSG),
        ("LOOKUP_NEAREST", LOOKUP_NEAREST),
        ("LOOKUP_LINEAR", LOOKUP_LINEAR),
        ("DIST_NONE", DIST_NONE),
        ("CONV_NONE", CONV_NONE),
        ("FLAG_ANISOTROPIC", FLAG_ANISOTROPIC),
        ("FLAG_METAL_FORM", FLAG_METAL_FORM),
    ];
    own.into_iter()
        .chain(crate::terms::all_terms().map(|t| t.gpu_code))
        .collect()
}

/// The descriptor type of `binding` (said once, for the set layout, the pool and the writes).
pub fn descriptor_type(binding: u32) -> ash::vk::DescriptorType {
    if binding == BINDING_TUPLE_TEXELS {
        ash::vk::DescriptorType::UNIFORM_TEXEL_BUFFER
    } else {
        ash::vk::DescriptorType::STORAGE_BUFFER
    }
}

/// The descriptor bindings, injected as `#define BINDING_NAME <value>` (plain int: layout
/// qualifiers take an int).
pub const SHADER_BINDINGS: &[(&str, u32)] = &[
    ("BINDING_TUPLES", BINDING_TUPLES),
    ("BINDING_MATERIALS", BINDING_MATERIALS),
    ("BINDING_BRDF", BINDING_BRDF),
    ("BINDING_TERMS", BINDING_TERMS),
    ("BINDING_COUNTS", BINDING_COUNTS),
    ("BINDING_TUPLE_TEXELS", BINDING_TUPLE_TEXELS),
    ("BINDING_ORDER", BINDING_ORDER),
    ("BINDING_MERL", BINDING_MERL),
];

/// One material as the kernel reads it (`struct GpuMaterial` in `glsl/layout.glsl`; the
/// field comments there say what each component holds for each model).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// rgb: the diffuse term `d · c_diff / π` (d = 1 outside cook-torrance).
    pub diffuse: [f32; 4],
    /// rgb: `s · c_spec` (s = 1 outside cook-torrance).
    pub specular: [f32; 4],
    /// rgb: dielectric `μ² − 1` | conductor `n` | Schlick `F0`.
    pub fresnel0: [f32; 4],
    /// rgb: conductor `k`.
    pub fresnel1: [f32; 4],
    /// Roughness lobes: `1/mx², 1/my², mx², my²`; exponent lobes: `e` in x.
    pub lobe: [f32; 4],
    /// x: the lobe's normalisation constant.
    pub scale: [f32; 4],
    /// Model, distribution, geometry, fresnel | convention << 8 | flags.
    pub kind: [u32; 4],
}

/// The per-chunk counters the kernel accumulates (`buffer Counts` in `glsl/bindings.glsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuCounts {
    /// Invalid tuples in the chunk.
    pub invalid: u32,
    /// Below-horizon tuples in the chunk.
    pub below_horizon: u32,
    /// Chunk-relative row of the first invalid tuple, `u32::MAX` when none.
    pub first_invalid: u32,
    /// Saturated tuples in the chunk (an output clamped to `f32::MAX`, FORMULAS.md §1).
    pub saturated: u32,
}

impl GpuCounts {
    /// The value the host writes before each dispatch.
    pub const INITIAL: GpuCounts = GpuCounts {
        invalid: 0,
        below_horizon: 0,
        first_invalid: u32::MAX,
        saturated: 0,
    };
}

/// Push constants of the kernel (`uniform Params` in `glsl/bindings.glsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub struct PushConstants {
    /// Rows in the chunk.
    pub tuple_count: u32,
    /// Rows in the material table.
    pub material_count: u32,
    /// Global index of the chunk's first row (generated directions: the texel index).
    pub first_row: u32,
    /// Generated slice: grid width (θ_h columns). Importance sums: blocks per point.
    pub grid_width: u32,
    /// Generated slice: grid height (θ_d rows). Importance sums: samples per point.
    pub grid_height: u32,
    /// Generated slice: θ_h spacing, 0 = `x² π/2` (MERL), 1 = `x π/2`. Importance sums:
    /// the lobe, 0 = GGX, 1 = Beckmann.
    pub spacing: u32,
}

impl PushConstants {
    /// A dispatch over `tuple_count` rows read from the tuple buffer (no generated grid).
    /// `first_row` (the chunk's place in the batch) is truncated to 32 bits: only the
    /// generated-direction kernels read it, and their grids are checked to fit.
    pub fn rows(tuple_count: u32, material_count: u32, first_row: u32) -> PushConstants {
        PushConstants {
            tuple_count,
            material_count,
            first_row,
            ..PushConstants::zeroed()
        }
    }
}

// std430 == repr(C) for these types: sizes and offsets pinned at compile time.
const _: () = {
    assert!(size_of::<GpuMaterial>() == 112);
    assert!(offset_of!(GpuMaterial, diffuse) == 0);
    assert!(offset_of!(GpuMaterial, specular) == 16);
    assert!(offset_of!(GpuMaterial, fresnel0) == 32);
    assert!(offset_of!(GpuMaterial, fresnel1) == 48);
    assert!(offset_of!(GpuMaterial, lobe) == 64);
    assert!(offset_of!(GpuMaterial, scale) == 80);
    assert!(offset_of!(GpuMaterial, kind) == 96);
    assert!(size_of::<GpuCounts>() == 16);
    assert!(offset_of!(GpuCounts, below_horizon) == 4);
    assert!(offset_of!(GpuCounts, first_invalid) == 8);
    assert!(offset_of!(GpuCounts, saturated) == 12);
    assert!(size_of::<PushConstants>() == 24);
};

/// A term's kernel code (`terms`).
fn code(term: Term) -> u32 {
    term.gpu_code.1
}

fn v4(x: [f64; 3]) -> [f32; 4] {
    [x[0] as f32, x[1] as f32, x[2] as f32, 0.0]
}

/// `1/mx², 1/my², mx², my²` of a roughness (FORMULAS.md §2–§3), formed in f64.
fn roughness_lobe(r: Roughness) -> [f32; 4] {
    let (mx, my) = r.xy();
    [1.0 / (mx * mx), 1.0 / (my * my), mx * mx, my * my].map(|x| x as f32)
}

/// Beckmann's normalisation `k` per convention (FORMULAS.md §5).
fn beckmann_k(c: Convention) -> f64 {
    match c {
        Convention::Seed => 4.0,
        Convention::CookTorrance1982 => 1.0,
        Convention::Modern => PI,
    }
}

/// Converts one validated material into the kernel's table row, precomputing every
/// per-material constant in f64 (normalisations, `1/m²`, `μ² − 1`) so the kernel rounds
/// each only once.
pub fn gpu_material(m: &Material) -> GpuMaterial {
    let mut g = GpuMaterial::zeroed();
    let diffuse_over_pi = m.diffuse.map(|c| c / PI);
    g.diffuse = v4(diffuse_over_pi);
    g.specular = v4(m.specular);
    let exponent_lobe = |e: f64| [e as f32, 0.0, 0.0, 0.0];
    let scale = |s: f64| [s as f32, 0.0, 0.0, 0.0];
    match &m.model {
        Model::Lambert => {
            g.kind = [
                MODEL_LAMBERT,
                DIST_NONE,
                code(Geometry::None.term()),
                code(FresnelKind::None.term()),
            ]
        }
        // The table index (kind.y) is the batch's: set by `gpu_materials`.
        Model::Measured(d) => {
            let lookup = match d.lookup {
                crate::material::merl::Lookup::Nearest => LOOKUP_NEAREST,
                crate::material::merl::Lookup::Linear => LOOKUP_LINEAR,
            };
            g.kind = [MODEL_MEASURED, 0, lookup, code(FresnelKind::None.term())];
            g.diffuse = [0.0; 4];
        }
        // glsl/htsg.glsl reads: lobe.x = τ/(2σ0), lobe.y = σ0/τ; specular.rgb = T = 2πτ/λ per
        // channel; fresnel0/fresnel1/scale.yzw as the conductor's (n, k, n² − k² − 1, in
        // f64); diffuse = a/π. Every constant formed in f64 and rounded once.
        Model::Htsg(p) => {
            g.kind = [
                MODEL_HTSG,
                DIST_NONE,
                code(Geometry::None.term()),
                code(FresnelKind::Conductor.term()),
            ];
            g.lobe = [
                (p.tau / (2.0 * p.sigma0)) as f32,
                (p.sigma0 / p.tau) as f32,
                0.0,
                0.0,
            ];
            g.specular = v4(p.wavelengths.map(|l| 2.0 * PI * p.tau / l));
            g.fresnel0 = v4(p.ior);
            g.fresnel1 = v4(p.extinction);
            for ch in 0..3 {
                let (n, k) = (p.ior[ch], p.extinction[ch]);
                g.scale[ch + 1] = (n * n - k * k - 1.0) as f32;
            }
        }
        Model::Phong { exponent } => {
            g.kind[0] = MODEL_PHONG;
            g.lobe = exponent_lobe(*exponent);
            g.scale = scale((exponent + 2.0) / (2.0 * PI));
        }
        Model::BlinnPhong { exponent } => {
            g.kind[0] = MODEL_BLINN_PHONG;
            g.lobe = exponent_lobe(*exponent);
            g.scale = scale(1.0 / PI);
        }
        Model::Rtr { exponent } => {
            g.kind[0] = MODEL_RTR;
            g.lobe = exponent_lobe(*exponent);
            g.scale = scale((exponent + 8.0) / (8.0 * PI));
        }
        Model::Ward { roughness } => {
            let (mx, my) = roughness.xy();
            g.kind[0] = MODEL_WARD;
            g.lobe = roughness_lobe(*roughness);
            g.scale = scale(1.0 / (4.0 * PI * mx * my));
        }
        Model::CookTorrance(ct) => {
            g.kind[0] = MODEL_COOK_TORRANCE;
            g.diffuse = v4(diffuse_over_pi.map(|c| c * ct.diffuse_weight));
            g.specular = v4(m.specular.map(|c| c * ct.specular_weight));
            g.kind[1] = code(ct.distribution.kind().term());
            match ct.distribution {
                Distribution::Gaussian { m } => {
                    g.lobe = roughness_lobe(Roughness::Isotropic(m));
                    g.scale = scale(1.0);
                }
                Distribution::Beckmann(r) => {
                    let (mx, my) = r.xy();
                    g.lobe = roughness_lobe(r);
                    g.scale = scale(1.0 / (beckmann_k(ct.convention) * mx * my));
                }
                Distribution::Ggx(r) => {
                    let (mx, my) = r.xy();
                    g.lobe = roughness_lobe(r);
                    g.scale = scale(1.0 / (PI * mx * my));
                }
                Distribution::Blinn { exponent } => {
                    g.lobe = exponent_lobe(exponent);
                    g.scale = scale((exponent + 2.0) / (2.0 * PI));
                }
                Distribution::Charlie { m } => {
                    // lobe.x: the exponent 1/m; scale.x: (2 + 1/m)/(2π), both in f64.
                    g.lobe = exponent_lobe(1.0 / m);
                    g.scale = scale((2.0 + 1.0 / m) / (2.0 * PI));
                }
            }
            g.kind[2] = code(ct.geometry.term());
            if ct.geometry == Geometry::SchlickSmith {
                // Isotropic only (validated), so lobe.w (my², read by anisotropic
                // materials only) is free for k.
                let (ggx, r) = match ct.distribution {
                    Distribution::Ggx(r) => (true, r),
                    Distribution::Beckmann(r) => (false, r),
                    _ => unreachable!("schlick-smith needs beckmann/ggx (validated)"),
                };
                g.lobe[3] = crate::terms::g::schlick_smith::k(ggx, r.xy().0) as f32;
            }
            match ct.fresnel {
                Fresnel::None => {}
                Fresnel::Dielectric { ior } => {
                    // μ² − 1 in f64: in f32 it cancels for μ near 1, where F ~ (μ−1)². Its
                    // f32 rounding error goes in scale.yzw: with f64, the kernel forms
                    // g² = μ² − 1 + c² from both, which near the critical angle of total
                    // internal reflection (g² → 0) needs more than f32's 24 bits.
                    let mu2m1 = ior.map(|mu| mu * mu - 1.0);
                    g.fresnel0 = v4(mu2m1);
                    for (lo, hi) in g.scale[1..].iter_mut().zip(mu2m1) {
                        *lo = (hi - f64::from(hi as f32)) as f32;
                    }
                }
                Fresnel::Conductor { ior, extinction } => {
                    g.fresnel0 = v4(ior);
                    g.fresnel1 = v4(extinction);
                    // Re(η²) − 1 = n² − k² − 1 in f64: in f32, 1 − sin²θ_t/η² cancels for
                    // η near 1 at grazing c (F came out 1 instead of ~0 at c = 5e-5).
                    for ch in 0..3 {
                        let (n, k) = (ior[ch], extinction[ch]);
                        g.scale[ch + 1] = (n * n - k * k - 1.0) as f32;
                    }
                }
                Fresnel::Schlick { f0 } => {
                    g.fresnel0 = v4(f0);
                }
            }
            let fresnel = code(ct.fresnel.kind().term());
            let convention = code(ct.convention.term());
            g.kind[3] = fresnel | convention << 8;
            if let Fresnel::Conductor { ior, extinction } = ct.fresnel {
                let legal = |ch: usize| {
                    crate::terms::f::conductor::metal_form_legal(ior[ch], extinction[ch])
                };
                if (0..3).all(legal) {
                    g.kind[3] |= FLAG_METAL_FORM;
                }
            }
        }
    }
    if m.is_anisotropic() {
        g.kind[3] |= FLAG_ANISOTROPIC;
    }
    g
}

/// The kernel's material table for `materials` (same order, so batch indices carry over);
/// a measured material's `kind.y` is its table's index in [`measured_tables`].
pub fn gpu_materials(materials: &[Material]) -> Vec<GpuMaterial> {
    let tables = measured_tables(materials);
    materials
        .iter()
        .map(|m| {
            let mut g = gpu_material(m);
            if let Model::Measured(d) = &m.model {
                g.kind[1] = tables
                    .iter()
                    .position(|t| std::sync::Arc::ptr_eq(t, &d.data))
                    .expect("listed") as u32;
            }
            g
        })
        .collect()
}

/// The distinct MERL tables of `materials`, in order of first use (one upload each, however
/// many materials share a file).
pub fn measured_tables(
    materials: &[Material],
) -> Vec<std::sync::Arc<crate::material::merl::MeasuredMerl>> {
    let mut tables: Vec<std::sync::Arc<crate::material::merl::MeasuredMerl>> = Vec::new();
    for m in materials {
        if let Model::Measured(d) = &m.model {
            if !tables.iter().any(|t| std::sync::Arc::ptr_eq(t, &d.data)) {
                tables.push(d.data.clone());
            }
        }
    }
    tables
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::parse_materials;

    /// A metal takes F's metal form (`FLAG_METAL_FORM`); a conductor with one
    /// dielectric-like channel, or another Fresnel term, does not.
    #[test]
    fn only_legal_conductors_carry_the_metal_form_flag() {
        let m = |fresnel: &str| {
            let toml = format!(
                "[[material]]\nname = \"x\"\nmodel = \"cook-torrance\"\n\
                 distribution = \"ggx\"\nroughness = 0.3\ngeometry = \"smith\"\n{fresnel}"
            );
            gpu_material(&parse_materials(&toml, "test").unwrap()[0]).kind[3]
        };
        let metal =
            "fresnel = \"conductor\"\nior = [0.2, 0.92, 1.1]\nextinction = [3.9, 2.45, 2.14]\n";
        let mixed =
            "fresnel = \"conductor\"\nior = [0.2, 0.92, 1.5]\nextinction = [3.9, 2.45, 0.0]\n";
        assert_ne!(m(metal) & FLAG_METAL_FORM, 0);
        assert_eq!(m(mixed) & FLAG_METAL_FORM, 0);
        assert_eq!(m("fresnel = \"schlick\"\nf0 = 0.04\n") & FLAG_METAL_FORM, 0);
    }

    #[test]
    fn cook_torrance_constants_are_precomputed_in_f64() {
        let m = &parse_materials(
            r#"
            [[material]]
            name = "x"
            model = "cook-torrance"
            convention = "seed"
            distribution = "beckmann"
            roughness = 0.5
            geometry = "smith"
            fresnel = "dielectric"
            ior = 1.0001
            diffuse = 0.5
            diffuse_weight = 0.5
            specular_weight = 0.25
            "#,
            "test",
        )
        .unwrap()[0];
        let g = gpu_material(m);
        assert_eq!(
            g.kind,
            [
                MODEL_COOK_TORRANCE,
                2,          // DIST_BECKMANN
                2,          // GEOM_SMITH
                1 | 1 << 8  // FRESNEL_DIELECTRIC | CONV_SEED << 8
            ]
        );
        assert_eq!(g.scale[0], (1.0 / (4.0 * 0.25)) as f32);
        assert_eq!(g.lobe, [4.0, 4.0, 0.25, 0.25]);
        assert_eq!(g.fresnel0[0], (1.0001f64 * 1.0001 - 1.0) as f32);
        assert_eq!(g.diffuse[0], (0.25 / PI) as f32);
        assert_eq!(g.specular[0], 0.25);
    }
}
