//! Conformance: every legal material combination, evaluated by a backend on seeded,
//! well-conditioned random tuples and compared with the f64 reference
//! ([`reference::evaluate_tuple`]) for the BRDF and every term. Shared by `vkbrdf check`
//! and `tests/conformance.rs`.
//!
//! **Combinations** ([`combinations`]): lambert, phong, blinn-phong, rtr; ward isotropic and
//! anisotropic; cook-torrance for every convention × distribution × geometry × fresnel that
//! FORMULAS.md allows: `smith*` only with beckmann/ggx, `smith-fast` with beckmann only,
//! anisotropic beckmann/ggx in the modern convention only. 198 in all. Each combination is
//! one batch over a table of [`MATERIALS_PER_COMBINATION`] materials with seeded random
//! parameters (one always at the sharpest lobe allowed: roughness 0.01 or exponent 20000).
//!
//! **Tuples** ([`generate`]): N, L, V (and T for anisotropic materials) with random non-unit
//! lengths (10^±2), `cos_i, cos_o ≥ 1e-3`; half with L, V uniform over the hemisphere, half
//! with the half vector drawn around N at the scale of the lobe (so the peak and its
//! shoulders, where values are large, are well covered); tangents at least 0.1 away from
//! parallel to N.
//!
//! **Metric**: per value, `|x − ref| / max(|ref|, FLOOR)` ([`crate::stats::relative_error`])
//! over the 9 columns (BRDF r, g, b; D, G, F_r, F_g, F_b, K); per combination the maximum,
//! the p99, and the worst tuple with its inputs. A combination passes when its maximum is
//! within [`tolerance`] and the invalid / below-horizon counts equal the reference's.

use crate::backend::{Backend, Request, TERM_COLUMNS};
use crate::batch::{Batch, Tuple, COLUMNS_PLAIN, COLUMNS_TANGENT};
use crate::error::Result;
use crate::material::{parse_materials, Material};
use crate::reference::{self, Status};
use crate::stats::{relative_error, ErrorStats};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use std::fmt;

/// Absolute floor of the relative error: below it an error counts as absolute. BRDF values
/// and D below 1e-6 sr⁻¹ (G, F, K below 1e-6) are far beneath anything visible, and a
/// value there can only be reached in an exponential tail whose relative error grows with
/// the exponent (see [`tolerance`]).
pub const FLOOR: f64 = 1e-6;

/// Materials (random parameter draws) per combination.
pub const MATERIALS_PER_COMBINATION: usize = 4;

/// Smallest roughness generated (rms slope, or radians for gaussian).
pub const MIN_ROUGHNESS: f64 = 0.01;

/// Largest exponent generated: the Blinn lobe of exponent `e` is about as wide as a
/// Beckmann lobe of `m = sqrt(2/(e+2))`, so 20000 matches [`MIN_ROUGHNESS`].
pub const MAX_EXPONENT: f64 = 20000.0;

/// Smallest `cos_i`, `cos_o` generated.
pub const MIN_COS: f64 = 1e-3;

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
    /// The tolerance it was held to.
    pub tolerance: f64,
    /// Whether the invalid / below-horizon counts and first invalid row equal the
    /// reference's.
    pub counts_match: bool,
    /// The worst value.
    pub worst: Option<WorstCase>,
}

impl CombinationReport {
    /// Within tolerance, with matching counts.
    pub fn pass(&self) -> bool {
        self.max_rel <= self.tolerance && self.counts_match
    }

    /// The header line of [`CombinationReport::row`].
    pub fn header() -> String {
        format!(
            "{:<52} {:>7} {:>11} {:>11} {:>9}  result",
            "combination", "tuples", "max rel", "p99 rel", "tolerance"
        )
    }

    /// One table line: combination, tuples, max and p99 relative error, tolerance, result.
    pub fn row(&self) -> String {
        let result = match (self.pass(), self.counts_match) {
            (true, _) => "pass",
            (false, false) => "FAIL (counts)",
            (false, true) => "FAIL",
        };
        format!(
            "{:<52} {:>7} {:>11.3e} {:>11.3e} {:>9.1e}  {result}",
            self.combination, self.tuples, self.max_rel, self.p99_rel, self.tolerance
        )
    }
}

/// The tolerance for a combination.
///
/// The kernel works in f32, and most of its error is the conditioning of the problem, not
/// the arithmetic: the f32 unit directions carry a rounding of u = 6e-8 each, so the half
/// vector's angle δ to N is off by ~u in absolute terms, tan²δ by ~2u·δ, and an exponential
/// lobe `exp(−tan²δ/m²)` by a relative `2u·δ/m²`. Over the part of the lobe above
/// [`FLOOR`] (δ up to ~5m) that is ~10u/m: 6e-5 at m = 0.01. Every combination is held to
/// the same tolerance, set from the measured worst case over all of them (see the README's
/// accuracy section and the `vkbrdf check` table).
pub fn tolerance(_combination: &Combination) -> f64 {
    TOLERANCE
}

/// The tolerance every combination is held to (see [`tolerance`]).
pub const TOLERANCE: f64 = 1e-5;

/// Options of a conformance run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CheckOptions {
    /// Tuples per combination.
    pub tuples: usize,
    /// Seed of the materials and tuples.
    pub seed: u64,
}

impl Default for CheckOptions {
    fn default() -> Self {
        CheckOptions {
            tuples: 2000,
            seed: 1,
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
    if shape.model != "lambert" {
        k.push(format!("specular = {}", rgb(rng, 0.2, 1.0)));
    }
    match shape.model {
        "phong" | "blinn-phong" | "rtr" => k.push(format!("exponent = {:.4}", exponent(rng, i))),
        "ward" => k.push(roughness_key(rng, i, shape.anisotropic)),
        "cook-torrance" => {
            k.push(format!("convention = \"{}\"", shape.convention));
            k.push(format!("distribution = \"{}\"", shape.distribution));
            match shape.distribution {
                "blinn" => k.push(format!("exponent = {:.4}", exponent(rng, i))),
                _ => k.push(roughness_key(rng, i, shape.anisotropic)),
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

/// The structural choices of one combination.
struct Shape {
    model: &'static str,
    convention: &'static str,
    distribution: &'static str,
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
                self.convention, self.distribution, self.geometry, self.fresnel
            ),
            m => format!("{m}{aniso}"),
        }
    }
}

fn shapes() -> Vec<Shape> {
    let plain = |model, anisotropic| Shape {
        model,
        convention: "",
        distribution: "",
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
    for convention in ["seed", "cook-torrance-1982", "modern"] {
        for distribution in ["gaussian", "beckmann", "ggx", "blinn"] {
            let geometries: &[&str] = match distribution {
                "beckmann" => &[
                    "none",
                    "cook-torrance",
                    "smith",
                    "smith-correlated",
                    "smith-fast",
                ],
                "ggx" => &["none", "cook-torrance", "smith", "smith-correlated"],
                _ => &["none", "cook-torrance"],
            };
            let anisotropy: &[bool] = match (distribution, convention) {
                ("beckmann" | "ggx", "modern") => &[false, true],
                _ => &[false],
            };
            for &anisotropic in anisotropy {
                for &geometry in geometries {
                    for fresnel in ["none", "dielectric", "conductor", "schlick"] {
                        v.push(Shape {
                            model: "cook-torrance",
                            convention,
                            distribution,
                            geometry,
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

/// Every legal combination (see the module docs), with materials drawn from `seed`.
/// The materials go through the TOML parser, so "legal" means what validation accepts.
pub fn combinations(seed: u64) -> Result<Vec<Combination>> {
    let mut out = Vec::new();
    for (ci, shape) in shapes().iter().enumerate() {
        let mut rng =
            Pcg64Mcg::seed_from_u64(seed ^ (ci as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let mut toml = String::new();
        for i in 0..MATERIALS_PER_COMBINATION {
            toml += &format!(
                "[[material]]\nname = \"{}#{i}\"\n{}\n\n",
                shape.name(),
                body(&mut rng, shape, i)
            );
        }
        let materials = parse_materials(&toml, &format!("combination `{}`", shape.name()))?;
        out.push(Combination {
            name: shape.name(),
            materials,
            anisotropic: shape.anisotropic,
        });
    }
    Ok(out)
}

fn unit(rng: &mut Pcg64Mcg) -> [f64; 3] {
    crate::sample::unit_vector(rng)
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalized(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    a.map(|x| x / l)
}

/// `x·t + y·b + z·n`.
fn local(t: [f64; 3], b: [f64; 3], n: [f64; 3], x: f64, y: f64, z: f64) -> [f64; 3] {
    std::array::from_fn(|k| x * t[k] + y * b[k] + z * n[k])
}

/// A direction of the hemisphere around n with `cos ≥ MIN_COS`, uniform in solid angle.
fn hemisphere(rng: &mut Pcg64Mcg, t: [f64; 3], b: [f64; 3], n: [f64; 3]) -> [f64; 3] {
    let z: f64 = rng.random_range(MIN_COS..1.0);
    let phi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let r = (1.0 - z * z).sqrt();
    local(t, b, n, r * phi.cos(), r * phi.sin(), z)
}

/// The angular width of a material's specular lobe (radians), used to aim half vectors.
fn lobe_width(m: &Material) -> f64 {
    use crate::material::{Distribution, Model};
    let from_exponent = |e: f64| (2.0 / (e + 2.0)).sqrt();
    match &m.model {
        Model::Lambert => 1.0,
        Model::Phong { exponent } | Model::BlinnPhong { exponent } | Model::Rtr { exponent } => {
            from_exponent(*exponent)
        }
        Model::Ward { roughness } => roughness.xy().0.max(roughness.xy().1),
        Model::CookTorrance(ct) => match ct.distribution {
            Distribution::Gaussian { m } => m,
            Distribution::Beckmann(r) | Distribution::Ggx(r) => r.xy().0.max(r.xy().1),
            Distribution::Blinn { exponent } => from_exponent(exponent),
        },
    }
}

/// `tuples` rows for `c` (material `i % MATERIALS_PER_COMBINATION` on row `i`), seeded.
pub fn generate(c: &Combination, tuples: usize, seed: u64) -> Result<Batch> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed.wrapping_add(0x5851_f42d_4c95_7f2d));
    let cols = if c.anisotropic {
        COLUMNS_TANGENT
    } else {
        COLUMNS_PLAIN
    };
    let mut data = Vec::with_capacity(tuples * cols);
    let scale = |rng: &mut Pcg64Mcg, v: [f64; 3]| {
        let s = 10f64.powf(rng.random_range(-2.0..2.0));
        v.map(|x| (x * s) as f32)
    };
    for i in 0..tuples {
        let mi = i % c.materials.len();
        let n = unit(&mut rng);
        let t0 = normalized(cross(
            n,
            if n[0].abs() < 0.9 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            },
        ));
        let b0 = cross(n, t0);
        let v = hemisphere(&mut rng, t0, b0, n);
        let l = if i % 2 == 0 {
            hemisphere(&mut rng, t0, b0, n)
        } else {
            // Aim h around n at the lobe's scale (Rayleigh-distributed angle) and reflect v
            // about it; keep it when it lands above the horizon, else fall back to uniform.
            let w = lobe_width(&c.materials[mi]).min(1.0);
            let mut l = None;
            for _ in 0..64 {
                let theta = 1.5 * w * (-2.0 * (1.0 - rng.random::<f64>()).ln()).sqrt();
                let phi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                if theta >= std::f64::consts::FRAC_PI_2 {
                    continue;
                }
                let h = local(
                    t0,
                    b0,
                    n,
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                );
                let vh = dot(v, h);
                let cand: [f64; 3] = std::array::from_fn(|k| 2.0 * vh * h[k] - v[k]);
                if vh > 0.0 && dot(cand, n) >= MIN_COS {
                    l = Some(cand);
                    break;
                }
            }
            l.unwrap_or_else(|| hemisphere(&mut rng, t0, b0, n))
        };
        data.extend(scale(&mut rng, l));
        data.extend(scale(&mut rng, v));
        data.extend(scale(&mut rng, n));
        data.push(mi as f32);
        if c.anisotropic {
            let t = loop {
                let t = unit(&mut rng);
                if dot(cross(n, t), cross(n, t)).sqrt() >= 0.1 {
                    break t;
                }
            };
            data.extend(scale(&mut rng, t));
        }
    }
    Batch::new(
        data,
        cols,
        c.materials.len(),
        &crate::batch::memory_source(),
    )
}

/// `Σ_j |f(x with input j scaled by 1 + u) − f(x)|` per column, u = 2⁻²⁴: the first-order
/// change of each output when every input component (L, V, N, T) is perturbed by one f32
/// rounding. An f32 evaluator that is exact up to rounding its inputs and intermediate
/// directions errs by a small multiple of this; it is large where the problem is
/// ill-conditioned (grazing mirror geometry, sharp lobes), and the tolerance scales with it.
pub fn input_rounding_sensitivity(t: &Tuple, m: &Material) -> [f64; 9] {
    const U: f64 = 1.0 / (1u64 << 24) as f64;
    let w = |a: [f32; 3]| a.map(f64::from);
    let x0 = [w(t.l), w(t.v), w(t.n), t.t.map(w).unwrap_or([0.0; 3])];
    let values = |e: &reference::Evaluation| {
        let terms = e.terms();
        [
            e.brdf[0], e.brdf[1], e.brdf[2], terms[0], terms[1], terms[2], terms[3], terms[4],
            terms[5],
        ]
    };
    let eval = |x: &[[f64; 3]; 4]| reference::evaluate(x[0], x[1], x[2], t.t.map(|_| x[3]), m);
    let base = values(&eval(&x0));
    let mut s = [0f64; 9];
    let vectors = if t.t.is_some() { 4 } else { 3 };
    for vi in 0..vectors {
        for k in 0..3 {
            let mut x = x0;
            x[vi][k] *= 1.0 + U;
            for (acc, (a, b)) in s.iter_mut().zip(values(&eval(&x)).iter().zip(base)) {
                *acc += (a - b).abs();
            }
        }
    }
    s
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
    let out = backend.evaluate(&batch, &c.materials, &Request { terms: true })?;
    let terms = out.terms.as_deref().unwrap_or(&[]);
    let mut all = ErrorStats::default();
    let mut ratio = ErrorStats::default();
    let mut column_max = [0f64; 9];
    let (mut invalid, mut below, mut first_invalid) = (0u64, 0u64, None);
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
            Status::Valid => {}
        }
        let sens = input_rounding_sensitivity(&tuple, material);
        let reference = e.terms();
        for col in 0..9 {
            let (x, r) = if col < 3 {
                (out.brdf[row * 3 + col], e.brdf[col])
            } else {
                (
                    terms
                        .get(row * TERM_COLUMNS + col - 3)
                        .copied()
                        .unwrap_or(f32::NAN),
                    reference[col - 3],
                )
            };
            let err = relative_error(f64::from(x), r, FLOOR);
            column_max[col] = column_max[col].max(err);
            all.add(err, (row * 9 + col) as u64);
            let abs = (f64::from(x) - r).abs();
            let q = if abs == 0.0 {
                0.0
            } else if !abs.is_finite() {
                f64::INFINITY
            } else {
                abs / (TOLERANCE * r.abs().max(FLOOR) + CONDITIONING_FACTOR * sens[col])
            };
            ratio.add(q, (row * 9 + col) as u64);
        }
    }
    if let Some(w) = ratio.worst {
        let (row, col) = (w as usize / 9, w as usize % 9);
        let t = batch.tuple(row);
        let m = &c.materials[t.material];
        let e = reference::evaluate_tuple(&t, m);
        let sens = input_rounding_sensitivity(&t, m);
        let vals = [
            e.brdf[0], e.brdf[1], e.brdf[2], e.d, e.g, e.f[0], e.f[1], e.f[2], e.k,
        ];
        let gpu: Vec<f32> = (0..9)
            .map(|k| {
                if k < 3 {
                    out.brdf[row * 3 + k]
                } else {
                    terms[row * 6 + k - 3]
                }
            })
            .collect();
        let w3 = |a: [f32; 3]| a.map(f64::from);
        let fr = crate::reference::frame::Frame::new(
            w3(t.l),
            w3(t.v),
            w3(t.n),
            t.t.map(w3),
            m.is_anisotropic(),
        )
        .unwrap();
        eprintln!("    ratio max {:.3} p99 {:.3} col {} gpu {:e} ref {:e} sens {:e} | cos_i {:.4e} cos_o {:.4e} cos_h {:.6e} c {:.6e} sin2h {:.4e}", ratio.max, ratio.p99(), COLUMNS[col], gpu[col], vals[col], sens[col], fr.cos_i, fr.cos_o, fr.cos_h, fr.c, fr.sin2_h);
        eprintln!(
            "      all cols rel: {:?}",
            (0..9)
                .map(|k| format!(
                    "{}:{:.1e}/{:.1e}",
                    COLUMNS[k],
                    (f64::from(gpu[k]) - vals[k]).abs() / vals[k].abs().max(FLOOR),
                    sens[k] / vals[k].abs().max(FLOOR)
                ))
                .collect::<Vec<_>>()
        );
    }
    let worst = all.worst.filter(|_| all.max > 0.0).map(|w| {
        let (row, col) = (w as usize / 9, w as usize % 9);
        let tuple = batch.tuple(row);
        let e = reference::evaluate_tuple(&tuple, &c.materials[tuple.material]);
        let (value, reference) = if col < 3 {
            (f64::from(out.brdf[row * 3 + col]), e.brdf[col])
        } else {
            (
                terms
                    .get(row * TERM_COLUMNS + col - 3)
                    .map_or(f64::NAN, |&x| f64::from(x)),
                e.terms()[col - 3],
            )
        };
        WorstCase {
            row,
            column: COLUMNS[col],
            value,
            reference,
            tuple,
            material: c.materials[tuple.material].clone(),
        }
    });
    let counts = out.counts;
    Ok(CombinationReport {
        combination: c.name.clone(),
        tuples: batch.len(),
        max_rel: all.max,
        p99_rel: all.p99(),
        column_max,
        tolerance: tolerance(c),
        counts_match: counts.invalid == invalid
            && counts.below_horizon == below
            && counts.first_invalid == first_invalid,
        worst,
    })
}

/// Multiple of the input-rounding sensitivity allowed on top of the relative tolerance.
pub const CONDITIONING_FACTOR: f64 = 1.0;

/// Checks every combination of [`combinations`] on `backend`, calling `progress` after each.
pub fn run(
    backend: &mut dyn Backend,
    options: &CheckOptions,
    progress: &mut dyn FnMut(&CombinationReport),
) -> Result<Vec<CombinationReport>> {
    let mut reports = Vec::new();
    for (i, c) in combinations(options.seed)?.iter().enumerate() {
        let r = check_combination(
            backend,
            c,
            options.tuples,
            options.seed.wrapping_add(i as u64),
        )?;
        progress(&r);
        reports.push(r);
    }
    Ok(reports)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::CpuReference;

    #[test]
    fn there_are_198_legal_combinations_and_all_parse() {
        let c = combinations(1).unwrap();
        assert_eq!(c.len(), 198);
        assert_eq!(c.iter().filter(|c| c.anisotropic).count(), 1 + 20 + 16);
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
