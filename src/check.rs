//! Conformance: every legal material combination, evaluated by a backend on seeded,
//! well-conditioned random tuples and compared with the f64 reference
//! ([`reference::evaluate_tuple`]) for the BRDF and every term. Shared by `vkbrdf check`
//! and `tests/conformance.rs`.
//!
//! **Combinations** ([`combinations`]): lambert, phong, blinn-phong, rtr; ward isotropic and
//! anisotropic; cook-torrance for every convention × distribution × anisotropy × geometry ×
//! fresnel that FORMULAS.md allows ([`crate::material::legality`] decides: `smith*` and
//! `schlick-smith` only with beckmann/ggx, `smith-fast` with beckmann only, anisotropic
//! beckmann/ggx in the modern convention only, `schlick-smith` isotropic); and `merl
//! nearest`, `merl linear`: measured materials over two analytic materials exported to MERL
//! in memory, read by each lookup. 317 in all; the CLI then runs 7 spectral rows
//! ([`spectral::run`]: the spectral presets at 95 wavelengths, FORMULAS.md §9). Each combination is
//! one batch over a table of [`MATERIALS_PER_COMBINATION`] materials with seeded random
//! parameters (one always at the sharpest lobe allowed: roughness 0.01 or exponent 20000).
//!
//! **Tuples** ([`generate`]): N, L, V (and T for anisotropic materials) with random non-unit
//! lengths (10^±2), `cos_i, cos_o ≥ 1e-3`; half with L, V uniform over the hemisphere, half
//! with the half vector drawn around N at the scale of the lobe (so the peak and its
//! shoulders, where values are large, are well covered); tangents at least 0.1 away from
//! parallel to N.
//!
//! **Metric**: per value, over the 9 columns (BRDF r, g, b; D, G, F_r, F_g, F_b, K), the
//! relative error `|x − ref| / max(|ref|, FLOOR)` ([`crate::stats::relative_error`]),
//! reported per combination as maximum and p99; and the share of the tolerance used,
//! `|x − ref| / allowed` (see [`tolerance`]: 1e-5 relative where the problem is well
//! conditioned in f32, more only where f32 inputs themselves cannot determine the value
//! better). A combination passes when every value is within its tolerance and the
//! invalid / below-horizon counts equal the reference's; the worst value (most tolerance
//! used) is reported with its inputs.

use crate::backend::{Backend, KernelPlan, Request, TERM_COLUMNS};
use crate::batch::{Batch, Tuple};
use crate::error::Result;
use crate::material::{
    legality, parse_materials, Convention, DistributionKind, FresnelKind, Geometry, Material,
};
use crate::reference::{self, Status};
mod rule;
pub mod spectral;
mod tuples;
use rule::columns_of;
pub use rule::{allowed_error, f32_sensitivity, CONDITIONING_FACTOR, FLOOR, RELATIVE_TOLERANCE};
pub use tuples::MIN_COS;

/// The materials whose spectral rows follow the combinations ([`spectral::run`]): every
/// spectral preset ([`crate::material::presets::SPECTRAL`]) and the RGB `shiny-plastic`
/// (its colours up-sampled, its dielectric a grey index).
pub fn spectral_materials() -> impl Iterator<Item = &'static str> + Clone {
    crate::material::presets::SPECTRAL
        .iter()
        .copied()
        .chain(["shiny-plastic"])
}

/// The row name of a spectral material in a report.
pub fn spectral_name(material: &str) -> String {
    format!("spectral {material} 360:830:5")
}

use crate::stats::{relative_error, ErrorStats};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use std::fmt;

/// Materials (random parameter draws) per combination.
pub const MATERIALS_PER_COMBINATION: usize = 4;

/// Smallest roughness generated (rms slope, or radians for gaussian).
pub const MIN_ROUGHNESS: f64 = 0.01;

/// Largest exponent generated: the Blinn lobe of exponent `e` is about as wide as a
/// Beckmann lobe of `m = sqrt(2/(e+2))`, so 20000 matches [`MIN_ROUGHNESS`].
pub const MAX_EXPONENT: f64 = 20000.0;

/// The column names, in comparison order.
pub const COLUMNS: [&str; 9] = [
    "brdf_r", "brdf_g", "brdf_b", "D", "G", "F_r", "F_g", "F_b", "K",
];

/// One combination: a label and a table of materials of that shape.
#[derive(Debug, Clone)]
pub struct Combination {
    /// E.g. `cook-torrance modern ggx-aniso smith conductor`.
    pub name: String,
    /// [`MATERIALS_PER_COMBINATION`] materials with seeded random parameters.
    pub materials: Vec<Material>,
    /// Whether the materials need tangents.
    pub anisotropic: bool,
}

/// The worst value of a combination, with everything needed to reproduce it.
#[derive(Debug, Clone)]
pub struct WorstCase {
    /// Row in the combination's batch.
    pub row: usize,
    /// Which column (one of [`COLUMNS`]).
    pub column: &'static str,
    /// The backend's value.
    pub value: f64,
    /// The reference's value.
    pub reference: f64,
    /// The error it was allowed ([`allowed_error`]).
    pub allowed: f64,
    /// The tuple (as stored: f32).
    pub tuple: Tuple,
    /// Its material.
    pub material: Material,
}

impl fmt::Display for WorstCase {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let t = &self.tuple;
        writeln!(
            f,
            "  worst: row {} column {}: got {:e}, reference {:e}",
            self.row, self.column, self.value, self.reference
        )?;
        writeln!(
            f,
            "    L = {:?}  V = {:?}  N = {:?}  T = {:?}",
            t.l, t.v, t.n, t.t
        )?;
        write!(f, "    material = {:?}", self.material)
    }
}

/// The result of one combination.
#[derive(Debug, Clone)]
pub struct CombinationReport {
    /// The combination's name.
    pub combination: String,
    /// Tuples evaluated.
    pub tuples: usize,
    /// Largest relative error over every value.
    pub max_rel: f64,
    /// 99th percentile of the relative error over every value.
    pub p99_rel: f64,
    /// Largest relative error per column ([`COLUMNS`] order).
    pub column_max: [f64; 9],
    /// Largest `|x − ref| / allowed` (≤ 1 passes; see [`tolerance`]).
    pub max_used: f64,
    /// Largest relative error among well-conditioned values: those whose sensitivity
    /// allowance is below the relative one (so the rule is at most 2e-5 relative).
    pub max_rel_well_conditioned: f64,
    /// Whether the invalid / below-horizon / saturated counts and first invalid row equal
    /// the reference's.
    pub counts_match: bool,
    /// Saturated tuples (an output beyond `f32::MAX`, FORMULAS.md §1) as counted by the
    /// backend and by the reference; part of `counts_match`.
    pub saturated: (u64, u64),
    /// The value that used the most of its tolerance.
    pub worst: Option<WorstCase>,
}

impl CombinationReport {
    /// Every value within its tolerance, and matching counts.
    pub fn pass(&self) -> bool {
        self.max_used <= 1.0 && self.counts_match
    }

    /// The header line of [`CombinationReport::row`].
    pub fn header() -> String {
        format!(
            "{:<54} {:>6} {:>10} {:>10} {:>9}  result",
            "combination", "tuples", "max rel", "p99 rel", "tol used"
        )
    }

    /// One table line: combination, tuples, max and p99 relative error, the largest share of
    /// its tolerance a value used, and the result.
    pub fn row(&self) -> String {
        let result = match (self.pass(), self.counts_match) {
            (true, _) => "pass",
            (false, false) => "FAIL (counts)",
            (false, true) => "FAIL",
        };
        format!(
            "{:<54} {:>6} {:>10.2e} {:>10.2e} {:>9.3}  {result}",
            self.combination, self.tuples, self.max_rel, self.p99_rel, self.max_used
        )
    }
}

/// The tolerance, FORMULAS.md §1's conformance rule, one for every engine, combination and
/// column: a value `x` with reference `r` passes when
///
/// `|x − r| ≤ RELATIVE_TOLERANCE · max(|r|, FLOOR) + CONDITIONING_FACTOR · S_in`,
///
/// where `S_in` is [`f32_sensitivity`]: how far the exact function moves when the given
/// float32 inputs L, V, N (and T) are rotated by one rounding. Where the problem is well
/// conditioned `S_in` is negligible and the rule is 1e-5 relative; where the inputs
/// themselves do not determine the value to 1e-5 (a sharp lobe near grazing mirror
/// geometry, where rounding L or V turns the half vector by ~u/|l + v| and the lobe
/// multiplies a change of δ by ~2δ/m²), no evaluator of those inputs can do better than a
/// small multiple of `S_in`.
pub fn tolerance() -> &'static str {
    "1e-5 × max(|ref|, 1e-6) + 4 × S_in (sensitivity to one rounding of the f32 inputs)"
}

/// Options of a conformance run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CheckOptions {
    /// Tuples per combination.
    pub tuples: usize,
    /// Seed of the materials and tuples.
    pub seed: u64,
    /// Only the combinations whose name contains this text (all when `None`). A
    /// combination gets the same materials and tuples whether or not others are filtered
    /// out.
    pub only: Option<String>,
}

impl Default for CheckOptions {
    fn default() -> Self {
        CheckOptions {
            tuples: 2000,
            seed: 1,
            only: None,
        }
    }
}

fn rgb(rng: &mut Pcg64Mcg, lo: f64, hi: f64) -> String {
    let c: Vec<String> = (0..3)
        .map(|_| format!("{:.6}", rng.random_range(lo..hi)))
        .collect();
    format!("[{}]", c.join(", "))
}

fn log_uniform(rng: &mut Pcg64Mcg, lo: f64, hi: f64) -> f64 {
    (rng.random_range(lo.ln()..hi.ln())).exp()
}

/// Roughness of material `i` of a combination: the sharpest allowed, a mild one, then
/// random (log-uniform in [MIN_ROUGHNESS, 1]).
fn roughness(rng: &mut Pcg64Mcg, i: usize) -> f64 {
    match i {
        0 => MIN_ROUGHNESS,
        1 => 0.5,
        _ => log_uniform(rng, MIN_ROUGHNESS, 1.0),
    }
}

/// Exponent of material `i`: the sharpest, a mild one, then log-uniform in [1, MAX], and
/// 0 for the last (the constant lobe, `pow(0, 0) = 1` at its edge).
fn exponent(rng: &mut Pcg64Mcg, i: usize) -> f64 {
    match i {
        0 => MAX_EXPONENT,
        1 => 10.0,
        i if i + 1 == MATERIALS_PER_COMBINATION => 0.0,
        _ => log_uniform(rng, 1.0, MAX_EXPONENT),
    }
}

/// The TOML keys of a roughness, isotropic or `[mx, my]`.
fn roughness_key(rng: &mut Pcg64Mcg, i: usize, aniso: bool) -> String {
    if aniso {
        let my = if i == 0 { 0.05 } else { roughness(rng, 2) };
        format!("roughness = [{:.6}, {:.6}]", roughness(rng, i), my)
    } else {
        format!("roughness = {:.6}", roughness(rng, i))
    }
}

/// One combination's TOML body for material `i` (keys after `name`).
fn body(rng: &mut Pcg64Mcg, shape: &Shape, i: usize) -> String {
    let mut k = vec![format!("model = \"{}\"", shape.model)];
    k.push(format!("diffuse = {}", rgb(rng, 0.0, 1.0)));
    if shape.model != "lambert" && shape.model != crate::terms::htsg::NAME {
        k.push(format!("specular = {}", rgb(rng, 0.2, 1.0)));
    }
    match shape.model {
        "phong" | "blinn-phong" | "rtr" => k.push(format!("exponent = {:.4}", exponent(rng, i))),
        "ward" => k.push(roughness_key(rng, i, shape.anisotropic)),
        "htsg" => k.extend(htsg_keys(rng, i)),
        "cook-torrance" => {
            k.push(format!("convention = \"{}\"", shape.convention));
            k.push(format!(
                "distribution = \"{}\"",
                shape.distribution.toml_name()
            ));
            if shape.distribution.takes_exponent() {
                k.push(format!("exponent = {:.4}", exponent(rng, i)));
            } else {
                k.push(roughness_key(rng, i, shape.anisotropic));
            }
            k.push(format!("geometry = \"{}\"", shape.geometry));
            k.push(format!("fresnel = \"{}\"", shape.fresnel));
            match shape.fresnel {
                // Below 1: total internal reflection and its boundary are covered too.
                "dielectric" => k.push(format!("ior = {}", rgb(rng, 0.5, 3.0))),
                "conductor" => {
                    k.push(format!("ior = {}", rgb(rng, 0.05, 3.0)));
                    k.push(format!("extinction = {}", rgb(rng, 0.0, 8.0)));
                }
                "schlick" if i == 1 => k.push(format!("ior = {}", rgb(rng, 1.0, 3.0))),
                "schlick" => k.push(format!("f0 = {}", rgb(rng, 0.0, 1.0))),
                _ => {}
            }
            k.push(format!(
                "diffuse_weight = {:.6}",
                rng.random_range(0.0..1.0)
            ));
            k.push(format!(
                "specular_weight = {:.6}",
                rng.random_range(0.1..1.0)
            ));
        }
        _ => {}
    }
    k.join("\n")
}

/// An HTSG material's keys (FORMULAS.md §8): the smoothest surface accepted with a long
/// correlation length (the sharpest lobe, g far below the switch), the bbm aluminium, a
/// rough one (σ0/τ = 0.5, the Beckmann-form side of g = 18.5), then log-uniform σ0/τ with a
/// dielectric (k = 0) among them; wavelengths across the accepted visible-to-infrared span.
fn htsg_keys(rng: &mut Pcg64Mcg, i: usize) -> Vec<String> {
    let (sigma0, tau) = match i {
        0 => (0.01, 10.0),
        1 => (0.0318, 0.3),
        2 => (0.5, 1.0),
        _ => {
            let tau = log_uniform(rng, 0.1, 10.0);
            (tau * log_uniform(rng, 1e-3, 2.0), tau)
        }
    };
    let mut k = vec![format!("sigma0 = {sigma0:.6e}"), format!("tau = {tau:.6e}")];
    if i == 1 {
        k.push("ior = [1.3211, 0.88045, 0.59765]".into());
        k.push("extinction = [7.41785, 6.1455, 5.2337]".into());
    } else {
        k.push(format!("ior = {}", rgb(rng, 0.2, 3.0)));
        if i != 3 {
            k.push(format!("extinction = {}", rgb(rng, 0.0, 8.0)));
        }
        k.push(format!("wavelengths = {}", rgb(rng, 300.0, 2000.0)));
    }
    k
}

/// The structural choices of one combination.
struct Shape {
    model: &'static str,
    convention: &'static str,
    distribution: DistributionKind,
    geometry: &'static str,
    fresnel: &'static str,
    anisotropic: bool,
}

impl Shape {
    fn name(&self) -> String {
        let aniso = if self.anisotropic { "-aniso" } else { "" };
        match self.model {
            "cook-torrance" => format!(
                "cook-torrance {} {}{aniso} {} {}",
                self.convention,
                self.distribution.toml_name(),
                self.geometry,
                self.fresnel
            ),
            m => format!("{m}{aniso}"),
        }
    }
}

fn shapes() -> Vec<Shape> {
    let plain = |model, anisotropic| Shape {
        model,
        convention: "",
        distribution: DistributionKind::Ggx,
        geometry: "",
        fresnel: "",
        anisotropic,
    };
    let mut v: Vec<Shape> = ["lambert", "phong", "blinn-phong", "rtr"]
        .into_iter()
        .map(|m| plain(m, false))
        .collect();
    v.push(plain("ward", false));
    v.push(plain("ward", true));
    v.push(plain(crate::terms::htsg::NAME, false));
    // Every combination the contract defines: the legality rules are material::legality's.
    for convention in Convention::ALL {
        for distribution in DistributionKind::ALL {
            for anisotropic in [false, true] {
                for geometry in Geometry::ALL {
                    if legality(convention, distribution, anisotropic, geometry).is_err() {
                        continue;
                    }
                    for fresnel in FresnelKind::ALL.map(FresnelKind::toml_name) {
                        v.push(Shape {
                            model: "cook-torrance",
                            convention: convention.toml_name(),
                            distribution,
                            geometry: geometry.toml_name(),
                            fresnel,
                            anisotropic,
                        });
                    }
                }
            }
        }
    }
    v
}

/// The analytic materials the measured combinations export to MERL (in memory, through
/// the reference): a glossy coloured conductor over a diffuse base, and a rough dielectric.
const MEASURED_SOURCES: &str = r#"
[[material]]
name = "glossy"
model = "cook-torrance"
distribution = "ggx"
roughness = 0.25
geometry = "smith-correlated"
fresnel = "schlick"
f0 = [0.95, 0.64, 0.27]
diffuse = [0.3, 0.2, 0.1]
diffuse_weight = 0.5

[[material]]
name = "rough"
model = "cook-torrance"
distribution = "beckmann"
roughness = 0.6
geometry = "smith"
fresnel = "dielectric"
ior = 1.5
diffuse = [0.1, 0.4, 0.2]
diffuse_weight = 0.8
"#;

/// The two MERL tables of the measured combinations, exported once per process.
fn measured_tables() -> Result<Vec<std::sync::Arc<crate::material::merl::MeasuredMerl>>> {
    use std::sync::{Arc, OnceLock};
    static TABLES: OnceLock<Vec<Arc<crate::material::merl::MeasuredMerl>>> = OnceLock::new();
    if let Some(t) = TABLES.get() {
        return Ok(t.clone());
    }
    let mut reference = reference::CpuReference::new();
    let mut runner = crate::table::Runner::new(&mut reference);
    let mut tables = Vec::new();
    for m in parse_materials(MEASURED_SOURCES, "the measured combinations' sources")? {
        let values = crate::table::merl::compute(&mut runner, &m)?;
        let source = std::path::PathBuf::from(format!("<{} exported to MERL>", m.name));
        tables.push(Arc::new(crate::material::merl::MeasuredMerl::from_values(
            values, &source,
        )?));
    }
    Ok(TABLES.get_or_init(|| tables).clone())
}

/// `merl nearest` and `merl linear`: [`MATERIALS_PER_COMBINATION`] measured materials over
/// the two exported tables (so a batch holds two), read by each lookup.
fn measured_combinations() -> Result<Vec<Combination>> {
    use crate::material::{merl::Lookup, Measured, Model};
    let tables = measured_tables()?;
    Ok([Lookup::Nearest, Lookup::Linear]
        .into_iter()
        .map(|lookup| {
            let name = format!("merl {}", lookup.toml_name());
            let materials = (0..MATERIALS_PER_COMBINATION)
                .map(|i| {
                    let data = tables[i % tables.len()].clone();
                    Material {
                        name: format!("{name}#{i}"),
                        model: Model::Measured(Measured {
                            path: data.source().to_owned(),
                            data,
                            lookup,
                        }),
                        diffuse: [0.0; 3],
                        specular: [1.0; 3],
                        precision: crate::material::precision::Precision::Exact,
                        spectral: None,
                    }
                })
                .collect();
            Combination {
                name,
                materials,
                anisotropic: false,
            }
        })
        .collect())
}

/// Every legal combination (see the module docs), with materials drawn from `seed`; the
/// analytic ones go through the TOML parser, so "legal" means what validation accepts. Last
/// come the two measured ones, `merl nearest` and `merl linear`.
pub fn combinations(seed: u64) -> Result<Vec<Combination>> {
    let mut out = Vec::new();
    for shape in shapes() {
        // Seeded by the name, not the position: adding a term leaves every other
        // combination's materials as they were.
        let mut rng = Pcg64Mcg::seed_from_u64(
            seed ^ fnv1a(&shape.name()).wrapping_mul(0x9e37_79b9_7f4a_7c15),
        );
        let mut toml = String::new();
        for i in 0..MATERIALS_PER_COMBINATION {
            toml += &format!(
                "[[material]]\nname = \"{}#{i}\"\n{}\n\n",
                shape.name(),
                body(&mut rng, &shape, i)
            );
        }
        let materials = parse_materials(&toml, &format!("combination `{}`", shape.name()))?;
        out.push(Combination {
            name: shape.name(),
            materials,
            anisotropic: shape.anisotropic,
        });
    }
    out.extend(measured_combinations()?);
    Ok(out)
}

/// FNV-1a of `s` (a stable hash: the standard library's may change between releases).
fn fnv1a(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// `tuples` rows for `c` (material `i % MATERIALS_PER_COMBINATION` on row `i`), seeded
/// (`check/tuples.rs`: where each term is hardest).
pub fn generate(c: &Combination, tuples: usize, seed: u64) -> Result<Batch<'static>> {
    tuples::rows(&c.materials, c.anisotropic, tuples, seed)
}

/// Evaluates combination `c` on `backend` with `tuples` tuples from `seed` and compares
/// every value with the f64 reference.
pub fn check_combination(
    backend: &mut dyn Backend,
    c: &Combination,
    tuples: usize,
    seed: u64,
) -> Result<CombinationReport> {
    let batch = generate(c, tuples, seed)?;
    let out = backend.evaluate(&batch, &c.materials, &CHECK_REQUEST)?;
    let terms = out.terms.as_deref().unwrap_or(&[]);
    let value = |row: usize, col: usize| -> f64 {
        let x = if col < 3 {
            out.brdf.get(row * 3 + col)
        } else {
            terms.get(row * TERM_COLUMNS + col - 3)
        };
        x.map_or(f64::NAN, |&x| f64::from(x))
    };
    let mut rel = ErrorStats::default();
    let mut used = ErrorStats::default();
    let mut column_max = [0f64; 9];
    let mut well_conditioned = 0f64;
    let (mut invalid, mut below, mut saturated, mut first_invalid) = (0u64, 0u64, 0u64, None);
    for row in 0..batch.len() {
        let tuple = batch.tuple(row);
        let material = &c.materials[tuple.material];
        let e = reference::evaluate_tuple(&tuple, material);
        match e.status {
            Status::Invalid => {
                invalid += 1;
                first_invalid.get_or_insert(row as u64);
            }
            Status::BelowHorizon => below += 1,
            Status::Valid => saturated += u64::from(e.saturated()),
        }
        let sensitivity = f32_sensitivity(&tuple, material);
        for (col, r) in columns_of(&e).into_iter().enumerate() {
            // The output the contract asks for: beyond f32::MAX, f32::MAX (FORMULAS.md §1).
            let r = r.min(f64::from(f32::MAX));
            let x = value(row, col);
            let err = relative_error(x, r, FLOOR);
            column_max[col] = column_max[col].max(err);
            rel.add(err, (row * 9 + col) as u64);
            let abs = if x == r {
                0.0
            } else if x.is_finite() {
                (x - r).abs()
            } else {
                f64::INFINITY
            };
            used.add(
                abs / allowed_error(r, sensitivity[col]),
                (row * 9 + col) as u64,
            );
            if CONDITIONING_FACTOR * sensitivity[col] < RELATIVE_TOLERANCE * r.abs().max(FLOOR) {
                well_conditioned = well_conditioned.max(err);
            }
        }
    }
    let worst = used.worst.filter(|_| used.max > 0.0).map(|w| {
        let (row, col) = (w as usize / 9, w as usize % 9);
        let tuple = batch.tuple(row);
        let material = c.materials[tuple.material].clone();
        let reference = columns_of(&reference::evaluate_tuple(&tuple, &material))[col];
        let allowed = allowed_error(reference, f32_sensitivity(&tuple, &material)[col]);
        WorstCase {
            row,
            column: COLUMNS[col],
            value: value(row, col),
            reference,
            allowed,
            tuple,
            material,
        }
    });
    let counts = out.counts;
    Ok(CombinationReport {
        combination: c.name.clone(),
        tuples: batch.len(),
        max_rel: rel.max,
        p99_rel: rel.p99(),
        column_max,
        max_used: used.max,
        max_rel_well_conditioned: well_conditioned,
        saturated: (counts.saturated, saturated),
        counts_match: counts.invalid == invalid
            && counts.below_horizon == below
            && counts.saturated == saturated
            && counts.first_invalid == first_invalid,
        worst,
    })
}

/// Checks every combination of [`combinations`] (or those `options.only` selects) on
/// `backend`, calling `progress` after each. A combination the backend does not support
/// ([`run_with_skips`]) is left out.
pub fn run(
    backend: &mut dyn Backend,
    options: &CheckOptions,
    progress: &mut dyn FnMut(&CombinationReport),
) -> Result<Vec<CombinationReport>> {
    Ok(run_with_skips(backend, options, progress)?.0)
}

/// The most tuples a combination may have (the CLI's `--tuples` range): bounds the
/// batch, the reference's outputs and the sensitivities allocated per combination.
pub const MAX_TUPLES: usize = 10_000_000;

/// What `check` asks of every batch: the BRDF and the terms, each judged.
const CHECK_REQUEST: Request = Request { terms: true };

/// A combination left out of a run, and why (the backend's message).
pub type Skipped = (String, String);

/// [`run`], also returning the combinations skipped and why: the measured ones on a backend
/// that refuses measured materials ([`crate::Error::Unsupported`], a Vulkan device without
/// f64). Any other error, and an unsupported analytic combination, stops the run.
pub fn run_with_skips(
    backend: &mut dyn Backend,
    options: &CheckOptions,
    progress: &mut dyn FnMut(&CombinationReport),
) -> Result<(Vec<CombinationReport>, Vec<Skipped>)> {
    if !(1..=MAX_TUPLES).contains(&options.tuples) {
        return Err(crate::Error::Unsupported(format!(
            "tuples: {} is out of range 1 to {MAX_TUPLES} per combination",
            options.tuples
        )));
    }
    let all = combinations(options.seed)?;
    if let Some(only) = options.only.as_deref() {
        if !all.iter().any(|c| c.name.contains(only))
            && !spectral_materials().any(|m| spectral_name(m).contains(only))
        {
            return Err(crate::Error::Unsupported(format!(
                "only {only:?} matches no combination (names look like `cook-torrance modern ggx-aniso smith conductor`)"
            )));
        }
    }
    let selected = |c: &Combination| options.only.as_deref().is_none_or(|o| c.name.contains(o));
    // One kernel per group of combinations ([`kernel_group`]): every kernel a check
    // compiles is compiled cold on a fresh machine, and 316 of them took minutes there.
    let mut groups: std::collections::HashMap<String, Vec<Material>> = Default::default();
    for c in all.iter().filter(|c| selected(c)) {
        groups
            .entry(kernel_group(c))
            .or_default()
            .extend(c.materials.iter().cloned());
    }
    // Every kernel the loop below will use, compiled up front and several at once
    // ([`Backend::prepare_kernels`]). Measured combinations are left to the loop: a device
    // may refuse them, which skips them there.
    let plans: Vec<KernelPlan> = all
        .iter()
        .filter(|c| selected(c) && options.tuples >= c.materials.len())
        .filter(|c| {
            !c.materials
                .iter()
                .any(|m| matches!(m.model, crate::material::Model::Measured(_)))
        })
        .map(|c| KernelPlan {
            materials: &c.materials,
            shared: &groups[&kernel_group(c)],
            tangents: c.anisotropic,
            request: CHECK_REQUEST,
        })
        .collect();
    backend.prepare_kernels(&plans)?;
    let mut reports = Vec::new();
    let mut skipped = Vec::new();
    for (i, c) in all.iter().enumerate() {
        if !selected(c) {
            continue;
        }
        backend.share_kernels(&groups[&kernel_group(c)]);
        let measured = c
            .materials
            .iter()
            .any(|m| matches!(m.model, crate::material::Model::Measured(_)));
        let r = match check_combination(
            backend,
            c,
            options.tuples,
            options.seed.wrapping_add(i as u64),
        ) {
            Err(crate::Error::Unsupported(why)) if measured => {
                skipped.push((c.name.clone(), why));
                continue;
            }
            r => r?,
        };
        progress(&r);
        reports.push(r);
    }
    backend.share_kernels(&[]);
    Ok((reports, skipped))
}

/// The combinations that share a kernel in [`run`]: a Cook–Torrance combination's
/// distribution and anisotropy (its geometries, conventions and Fresnel terms share one
/// kernel, as a material table mixing them would); the plain models by anisotropy; each
/// measured combination alone (a backend may refuse it). Each distribution keeps a kernel
/// of its own because its code differs most (the frames it may take, its Λ); 9 kernels in
/// all. llvmpipe compiles each kernel on its first dispatch, one at a time, so the count
/// is most of what a cold check pays (docs/VULKAN.md, "Kernels a check compiles").
fn kernel_group(c: &Combination) -> String {
    let m = &c.materials[0];
    match &m.model {
        crate::material::Model::CookTorrance(ct) => {
            format!("{} {}", ct.distribution.kind().toml_name(), c.anisotropic)
        }
        crate::material::Model::Measured(_) => c.name.clone(),
        _ => format!("plain {}", c.anisotropic),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::CpuReference;

    #[test]
    fn there_are_317_legal_combinations_and_all_parse() {
        // Per convention, G per distribution (isotropic): gaussian, blinn and charlie 3
        // (none, cook-torrance, neubelt); beckmann 7 (those, smith, smith-correlated,
        // smith-fast, schlick-smith); ggx 6 (no smith-fast). Modern adds anisotropic
        // beckmann 6 and ggx 5 (no schlick-smith). Times 4 Fresnel terms, plus 7 plain
        // (htsg among them), plus the 2 measured lookups.
        let c = combinations(1).unwrap();
        assert_eq!(c.len(), 7 + 4 * (2 * 22 + (22 + 11)) + 2);
        assert!(c.iter().any(|c| c.name == "merl nearest"));
        assert!(c.iter().any(|c| c.name == "merl linear"));
        assert_eq!(c.iter().filter(|c| c.anisotropic).count(), 1 + 4 * 11);
        let has = |name: &str| c.iter().any(|c| c.name == name);
        assert!(has("cook-torrance seed charlie neubelt none"));
        assert!(has("cook-torrance modern ggx schlick-smith conductor"));
        assert!(!has("cook-torrance modern charlie smith none"));
        assert!(!has("cook-torrance modern ggx-aniso schlick-smith none"));
        assert!(!c.iter().any(|c| c.name.contains("charlie-aniso")));
    }

    #[test]
    fn generated_tuples_are_well_conditioned() {
        for c in combinations(2).unwrap().iter().step_by(17) {
            let b = generate(c, 200, 3).unwrap();
            for i in 0..b.len() {
                let e = reference::evaluate_tuple(&b.tuple(i), &c.materials[b.material(i)]);
                assert_eq!(e.status, Status::Valid, "{} row {i}", c.name);
            }
        }
    }

    #[test]
    fn the_reference_passes_its_own_check() {
        let c = &combinations(4).unwrap()[100];
        let r = check_combination(&mut CpuReference::new(), c, 300, 5).unwrap();
        // The CPU backend rounds f64 to f32: relative error ≤ 2^-24, never above.
        assert!(r.max_rel <= 6e-8 && r.pass(), "{}", r.row());
    }
}
