//! The adversarial stress corpus (deterministic for a seed): extreme materials crossed with
//! the delicate geometric cases of FORMULAS.md §1 — grazing, normal incidence, the specular
//! peak, L = −V, backfacing, huge and tiny vectors, zero, NaN, Inf and denormal components,
//! tangents parallel to N.

use crate::batch::{Batch, COLUMNS_TANGENT};
use crate::material::{
    legality, parse_materials, Convention, DistributionKind, Geometry, Material,
};
use crate::sample::unit_vector;
use crate::vector::{axpy, dot, normalize_direct};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// The geometric case a stress tuple was built for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Case {
    /// Random directions with both cosines ≥ 0.1.
    WellConditioned,
    /// `cos_i` or `cos_o` in [1e-8, 1e-1] (log-uniform).
    Grazing,
    /// `L = V = N` exactly.
    NormalIncidence,
    /// `cos_h` within 1e-7 of 1 (log-uniform angle 1e-8 … 4e-4 from the peak).
    NearPeak,
    /// `L = −V` (always below the horizon on one side).
    Opposite,
    /// Both directions below the surface.
    Backfacing,
    /// Well-conditioned directions with lengths 1e-20 … 1e20.
    ExtremeLength,
    /// A zero vector, or NaN or ±Inf components: invalid by definition.
    NonFinite,
    /// Components that are f32 denormals (tiny but non-zero vectors).
    Denormal,
    /// A tangent exactly parallel to N (a power-of-two multiple of N).
    ParallelTangent,
    /// `cos_i` and/or `cos_o` down to the smallest positive float32 (FORMULAS.md §1,
    /// "Overflow"): log-uniform in [1.4e-45, 1e-8] or exactly 1e-20, 1e-30, 1e-38 or 1e-45
    /// (subnormal), N along an axis so that the cosine is the tiny component itself; half
    /// of them at the exact mirror configuration (h = n), where K overflows float32.
    TinyCosine,
}

/// Every case, in corpus order.
pub const CASES: [Case; 11] = [
    Case::WellConditioned,
    Case::Grazing,
    Case::NormalIncidence,
    Case::NearPeak,
    Case::Opposite,
    Case::Backfacing,
    Case::ExtremeLength,
    Case::NonFinite,
    Case::Denormal,
    Case::ParallelTangent,
    Case::TinyCosine,
];

/// The stress materials: every model and term, at the parameter extremes the issue names
/// (roughness 1e-4 … 10, anisotropy ratios to 1e4, exponents to 1e4, IOR 1, < 1 and 100,
/// extinction 50) and at the bounds the parser accepts (roughness 1e-7 and 1e4, exponent
/// 1e18, IOR 1e-6 and 1e18, extinction 1e10 and 1e18, colours and weights 0 and 1e18),
/// plus ordinary values so the extremes can be told apart.
pub fn materials() -> Vec<Material> {
    let mut toml = String::new();
    let mut add =
        |name: &str, body: &str| toml += &format!("[[material]]\nname = \"{name}\"\n{body}\n");
    add("lambert", "model = \"lambert\"\ndiffuse = [0.9, 0.5, 0.1]");
    for e in ["0", "1", "100", "10000", "1e18"] {
        add(
            &format!("phong-e{e}"),
            &format!("model = \"phong\"\nexponent = {e}\ndiffuse = 0.1"),
        );
        add(
            &format!("blinn-phong-e{e}"),
            &format!("model = \"blinn-phong\"\nexponent = {e}"),
        );
        add(
            &format!("rtr-e{e}"),
            &format!("model = \"rtr\"\nexponent = {e}"),
        );
    }
    for r in [
        "0.0001",
        "0.3",
        "10",
        "[0.0001, 1.0]",
        "[1.0, 0.0001]",
        "[0.05, 0.5]",
        "1e-7",
        "1e4",
        "[1e-7, 1e4]",
    ] {
        add(
            &format!("ward-{r}"),
            &format!("model = \"ward\"\nroughness = {r}"),
        );
    }
    let fresnels = [
        ("F-none", "fresnel = \"none\""),
        ("F-ior1", "fresnel = \"dielectric\"\nior = 1.0"),
        ("F-tir", "fresnel = \"dielectric\"\nior = 0.5"),
        ("F-glass", "fresnel = \"dielectric\"\nior = 1.5"),
        ("F-ior100", "fresnel = \"dielectric\"\nior = 100"),
        (
            "F-k50",
            "fresnel = \"conductor\"\nior = [0.2, 1.0, 5.0]\nextinction = [50, 3, 0]",
        ),
        (
            "F-cond-ior1",
            "fresnel = \"conductor\"\nior = 1.0\nextinction = 0",
        ),
        (
            "F-gold",
            "fresnel = \"conductor\"\nior = [0.166, 0.430, 1.38]\nextinction = [3.15, 2.46, 1.92]",
        ),
        ("F-schlick", "fresnel = \"schlick\"\nf0 = [0.04, 0.5, 1.0]"),
        (
            "F-k1e10",
            "fresnel = \"conductor\"\nior = 1.0\nextinction = 1e10",
        ),
        (
            "F-cond-bounds",
            "fresnel = \"conductor\"\nior = [1e-6, 1e18, 1e18]\nextinction = [1e18, 0, 1e18]",
        ),
        (
            "F-diel-bounds",
            "fresnel = \"dielectric\"\nior = [1e-6, 1e18, 1.0]",
        ),
    ];
    let conventions = ["modern", "seed", "cook-torrance-1982"];
    let mut k = 0;
    let mut ct = |dist: &str, param: &str, geoms: &[&str], aniso: bool| {
        for g in geoms {
            let (fname, f) = fresnels[k % fresnels.len()];
            let conv = if aniso {
                "modern"
            } else {
                conventions[k % conventions.len()]
            };
            k += 1;
            add(
                &format!("ct-{dist}-{param}-{g}-{fname}-{conv}").replace(['[', ']', ' ', ','], ""),
                &format!("model = \"cook-torrance\"\nconvention = \"{conv}\"\ndistribution = \"{dist}\"\n{param}\ngeometry = \"{g}\"\n{f}\ndiffuse = 0.2\ndiffuse_weight = 0.5"),
            );
        }
    };
    // Every geometry term the contract allows with each distribution (material::legality),
    // at every roughness bound the distribution accepts.
    let legal = |d: DistributionKind, aniso: bool| -> Vec<&'static str> {
        Geometry::ALL
            .into_iter()
            .filter(|&g| legality(Convention::Modern, d, aniso, g).is_ok())
            .map(Geometry::toml_name)
            .collect()
    };
    let rough = DistributionKind::ALL
        .into_iter()
        .filter(|d| !d.takes_exponent());
    for d in rough.clone() {
        let max = d.max_roughness().unwrap_or(f64::INFINITY);
        let mut rs: Vec<String> = ["1e-7", "0.0001", "0.01", "0.5", "10", "1e4"]
            .into_iter()
            .filter(|r| r.parse::<f64>().is_ok_and(|r| r <= max))
            .map(String::from)
            .collect();
        if max.is_finite() {
            rs.push(format!("{max:?}"));
        }
        for r in rs {
            ct(
                d.toml_name(),
                &format!("roughness = {r}"),
                &legal(d, false),
                false,
            );
        }
    }
    for d in rough.filter(|&d| legality(Convention::Modern, d, true, Geometry::None).is_ok()) {
        for r in [
            "[0.0001, 1.0]",
            "[1.0, 0.0001]",
            "[0.1, 0.4]",
            "[1e-7, 1e4]",
            "[1e4, 1e-7]",
        ] {
            ct(
                d.toml_name(),
                &format!("roughness = {r}"),
                &legal(d, true),
                true,
            );
        }
    }
    for e in ["0", "50", "10000", "1e18"] {
        let d = DistributionKind::Blinn;
        ct(
            d.toml_name(),
            &format!("exponent = {e}"),
            &legal(d, false),
            false,
        );
    }
    // Every fresnel at least once with an ordinary GGX lobe.
    for (i, (fname, f)) in fresnels.iter().enumerate() {
        let conv = conventions[i % 3];
        add(
            &format!("ct-ggx-0.3-{fname}-{conv}"),
            &format!("model = \"cook-torrance\"\nconvention = \"{conv}\"\ndistribution = \"ggx\"\nroughness = 0.3\ngeometry = \"smith-correlated\"\n{f}"),
        );
    }
    // Colours and weights at their bounds (1e18 and 0), on a sharp lobe.
    add(
        "ct-ggx-bright",
        "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 1e-7\ngeometry = \"smith\"\nfresnel = \"none\"\ndiffuse = 1e18\nspecular = [1e18, 0, 1]\ndiffuse_weight = 1e18\nspecular_weight = 1e18",
    );
    add(
        "phong-bright",
        "model = \"phong\"\nexponent = 1e18\ndiffuse = [1e18, 0, 1]\nspecular = [1e18, 0, 1]",
    );
    add(
        "ct-blinn-dim",
        "model = \"cook-torrance\"\nconvention = \"seed\"\ndistribution = \"blinn\"\nexponent = 1e18\ngeometry = \"none\"\nfresnel = \"none\"\nspecular_weight = 0",
    );
    toml += &htsg_materials();
    parse_materials(&toml, "stress corpus").expect("the stress materials are legal")
}

/// The HTSG materials of the corpus (FORMULAS.md §8), after [`materials`]'s others: every
/// eighth row is theirs ([`corpus_rows`]), so the other rows are the tuples they were
/// before HTSG joined.
fn htsg_materials() -> String {
    let mut toml = String::new();
    // HTSG (FORMULAS.md §8): σ0/τ at both bounds (1e-3, 10) and between, wavelengths from
    // the near UV to the infrared (0.2 … 5 µm), the parameters' bounds, a dielectric (k = 0),
    // and a surface whose green channel sits just above D's switch (g = 18.5 + 4e-4, far
    // beyond rounding: on the switch itself the value is ill-conditioned) at normal
    // incidence: σ0 = √g λ/(4π) makes g = (4πσ0/λ)² there (σ = σ0 at h = n, K = 0).
    let alu = "ior = [1.3211, 0.88045, 0.59765]\nextinction = [7.41785, 6.1455, 5.2337]";
    for (name, body) in [
        ("htsg-smooth", format!("sigma0 = 0.01\ntau = 10\nwavelengths = [300, 550, 2000]\n{alu}")),
        ("htsg-aluminium", format!("sigma0 = 0.0318\ntau = 0.3\n{alu}")),
        ("htsg-switch", format!("sigma0 = {}\ntau = 0.5\n{alu}", 18.5004f64.sqrt() * 0.526 / (4.0 * std::f64::consts::PI))),
        ("htsg-rough-dielectric", "sigma0 = 5\ntau = 0.5\nior = 1.5\nwavelengths = [300, 1000, 2000]\ndiffuse = 0.2".into()),
        ("htsg-bounds", "sigma0 = 1e-4\ntau = 1e-2\nior = [1e-6, 1, 1e18]\nextinction = [0, 1e18, 50]\nwavelengths = [200, 5000, 200]\ndiffuse = [1e18, 0, 1]".into()),
        ("htsg-roughest", format!("sigma0 = 10\ntau = 100\nwavelengths = [200, 526, 5000]\n{alu}")),
    ] {
        toml += &format!("[[material]]\nname = \"{name}\"\nmodel = \"htsg\"\n{body}\n");
    }
    toml
}

/// How many of [`materials`] are HTSG's (the last ones).
const HTSG_MATERIALS: usize = 6;

/// A random unit vector within the hemisphere of `n` with `n·w ≥ min_cos`.
fn hemisphere(rng: &mut Pcg64Mcg, n: [f64; 3], min_cos: f64) -> [f64; 3] {
    loop {
        let w = unit_vector(rng);
        if dot(w, n) >= min_cos {
            return w;
        }
        let r = reflect_through_plane(w, n);
        if dot(r, n) >= min_cos {
            return r;
        }
    }
}

fn reflect_through_plane(w: [f64; 3], n: [f64; 3]) -> [f64; 3] {
    axpy(-2.0 * dot(w, n), n, w)
}

/// A unit vector at angle `theta` from `n`, in a random azimuth.
fn at_angle(rng: &mut Pcg64Mcg, n: [f64; 3], theta: f64) -> [f64; 3] {
    let p = loop {
        let r = unit_vector(rng);
        let p = axpy(-dot(r, n), n, r);
        if dot(p, p) > 1e-6 {
            break normalize_direct(p);
        }
    };
    normalize_direct(axpy(theta.cos(), n, p.map(|x| x * theta.sin())))
}

fn log_uniform(rng: &mut Pcg64Mcg, lo: f64, hi: f64) -> f64 {
    10f64.powf(rng.random_range(lo.log10()..hi.log10()))
}

/// One tuple (13 columns, material in column 9) of the given case.
fn tuple(rng: &mut Pcg64Mcg, case: Case, material: usize) -> [f32; 13] {
    let mut n = unit_vector(rng);
    let mut t = unit_vector(rng);
    let (mut l, mut v) = (hemisphere(rng, n, 0.1), hemisphere(rng, n, 0.1));
    let mut scale = [1.0f64; 4];
    match case {
        Case::WellConditioned => {}
        Case::Grazing => {
            let c = log_uniform(rng, 1e-8, 1e-1);
            let w = at_angle(rng, n, c.acos());
            match rng.random_range(0..3) {
                0 => l = w,
                1 => v = w,
                _ => {
                    l = w;
                    let c2 = log_uniform(rng, 1e-8, 1e-1);
                    v = at_angle(rng, n, c2.acos());
                }
            }
        }
        Case::NormalIncidence => {
            l = n;
            v = n;
        }
        Case::NearPeak => {
            let delta = log_uniform(rng, 1e-8, 4e-4);
            let h = at_angle(rng, n, delta);
            v = hemisphere(rng, n, 0.2);
            l = axpy(2.0 * dot(v, h), h, v.map(|x| -x));
        }
        Case::Opposite => l = v.map(|x| -x),
        Case::Backfacing => {
            l = l.map(|x| -x);
            v = v.map(|x| -x);
        }
        Case::ExtremeLength => {
            for s in &mut scale {
                *s = log_uniform(rng, 1e-20, 1e20);
            }
        }
        Case::TinyCosine => {
            // N along +x, +y or +z: then n·w is the tiny component itself, exactly (a
            // rotated N would leave ~1e-8 of rounding error in every cosine).
            let axis = rng.random_range(0..3usize);
            let along = |tan: [f64; 2], c: f64| {
                let mut w = [0.0; 3];
                w[axis] = c;
                w[(axis + 1) % 3] = tan[0];
                w[(axis + 2) % 3] = tan[1];
                w
            };
            let tiny = |rng: &mut Pcg64Mcg| match rng.random_range(0..6) {
                0 => 1e-20,
                1 => 1e-30,
                2 => 1e-38,
                3 => 1e-45,
                _ => log_uniform(rng, 1.4e-45, 1e-8),
            };
            let phi = rng.random_range(0.0..std::f64::consts::TAU);
            let (s, c) = phi.sin_cos();
            let ci = tiny(rng);
            n = along([0.0, 0.0], 1.0);
            l = along([c, s], ci);
            v = match rng.random_range(0..4) {
                // The exact mirror configuration: h = n, c = v·h = cos_o.
                0 | 1 => along([-c, -s], ci),
                2 => along([-s, c], tiny(rng)),
                _ => hemisphere(rng, n, 0.1),
            };
            if rng.random_range(0..2) == 1 {
                std::mem::swap(&mut l, &mut v);
            }
        }
        Case::NonFinite | Case::Denormal | Case::ParallelTangent => {}
    }
    let mut row = [0f32; 13];
    for (k, w) in [l, v, n, t].iter().enumerate() {
        let idx = if k == 3 { 10 } else { 3 * k };
        for c in 0..3 {
            row[idx + c] = (w[c] * scale[k]) as f32;
        }
    }
    row[9] = material as f32;
    let vec_slot = rng.random_range(0..3usize) * 3;
    match case {
        Case::NonFinite => {
            let bad = [0.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY][rng.random_range(0..4)];
            if bad == 0.0 {
                row[vec_slot..vec_slot + 3].fill(0.0);
            } else {
                row[vec_slot + rng.random_range(0..3)] = bad;
            }
        }
        Case::Denormal => {
            // Scale one vector down into the f32 denormal range (components ~1e-39 … 1e-44).
            let s = log_uniform(rng, 1e-44, 1e-39);
            for c in 0..3 {
                row[vec_slot + c] = (row[vec_slot + c] as f64 * s) as f32;
            }
        }
        Case::ParallelTangent => {
            // An exact power-of-two multiple of N: parallel in f32 and in f64 alike.
            t = [row[6] as f64, row[7] as f64, row[8] as f64];
            let k = [2.0, -0.5, 4.0, 1.0][rng.random_range(0..4)];
            for c in 0..3 {
                row[10 + c] = (t[c] * k) as f32;
            }
        }
        _ => {}
    }
    row
}

/// The corpus: `n` tuples with tangents over [`materials`]. Every eighth row (`i % 8 == 7`,
/// k = i/8) uses HTSG material `k % 6` in case `CASES[(k / 6) % 11]`; the others are row
/// `j` of the rest (j counts them), material `j % M` in case `CASES[(j / M) % 11]`.
/// Returns the batch and each row's case.
pub fn corpus(n: usize, seed: u64) -> (Vec<Material>, Batch<'static>, Vec<Case>) {
    corpus_rows(0..n, seed)
}

/// Rows `range` of the corpus of seed `seed`: each row has its own RNG stream, so a chunk
/// is identical to the same rows of the whole corpus (long runs go chunk by chunk).
pub fn corpus_rows(
    range: std::ops::Range<usize>,
    seed: u64,
) -> (Vec<Material>, Batch<'static>, Vec<Case>) {
    let materials = materials();
    let m = materials.len() - HTSG_MATERIALS;
    let mut data = Vec::with_capacity(range.len() * COLUMNS_TANGENT);
    let mut cases = Vec::with_capacity(range.len());
    for i in range {
        // Every eighth row is an HTSG material's (its own sequence k, seeded apart); the
        // others are the rows j = 0, 1, 2, … of the other materials, as before HTSG.
        let (j, case, material) = if i % 8 == 7 {
            let k = i / 8;
            let case = CASES[(k / HTSG_MATERIALS) % CASES.len()];
            (k as u64 | 1 << 62, case, m + k % HTSG_MATERIALS)
        } else {
            let j = i / 8 * 7 + i % 8;
            (j as u64, CASES[(j / m) % CASES.len()], j % m)
        };
        let mut rng = Pcg64Mcg::seed_from_u64(seed ^ j.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        data.extend_from_slice(&tuple(&mut rng, case, material));
        cases.push(case);
    }
    let batch = Batch::new(
        data,
        COLUMNS_TANGENT,
        materials.len(),
        &crate::batch::memory_source(),
    )
    .expect("corpus rows are valid");
    (materials, batch, cases)
}
