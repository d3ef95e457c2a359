//! Property tests (proptest) on **every backend** — the Vulkan kernel (lavapipe here) and,
//! through the same code, the f64 CPU reference — mirroring `tests/properties.rs`, which
//! checks the same physics on the reference alone:
//!
//! 1. finite, non-negative outputs (BRDF and every term) for random legal materials and
//!    random finite directions of any length in 1e-20 … 1e20; invalid and below-horizon
//!    tuples give exactly 0 and are counted as the reference counts them;
//! 2. agreement with the f64 reference, per value, under the conformance rule of
//!    `src/check.rs`: `1e-5 · max(|ref|, 1e-6) + 4 · f32 sensitivity`; on random tuples
//!    (structured ones with |cos| ≥ 1e-3 and half vectors aimed into the lobe, plus wild
//!    ones), and on grazing mirror tuples for GGX at m = 1, whose D is exactly 1/π;
//! 3. Helmholtz reciprocity `f(l, v) = f(v, l)` (BRDF and terms) for the reciprocal models;
//! 4. the white furnace: directional albedo `E(v) ≤ 1` for Cook–Torrance with F = 1 (mixed
//!    with a white Lambert lobe, weights summing to 1), and `E = 1` for Lambert of albedo 1;
//! 5. normalisation `∫ D(h) cos_h dω_h = 1` (π/k for the seed's and Cook & Torrance's
//!    Beckmann) read from the backend's D term output.
//!
//! **Why whole batches per case.** Creating a Vulkan backend and dispatching a kernel costs
//! far more than evaluating one tuple, and each new material shape compiles a kernel
//! variant. So one proptest case is a whole batch — a random material plus 64–192 random
//! direction tuples (1–3), or a quadrature grid of 10⁴–10⁵ directions (4, 5) — evaluated by
//! ONE `Backend::evaluate` call, and every row is checked. The backends are created once
//! per test (`common::backends()`), and each runs its own `TestRunner` over a modest number
//! of cases. Seeds are random per run, as in `tests/properties.rs`; a failure names the
//! backend and the failing row's exact f32 inputs and material, and `PROPTEST_RNG_SEED`
//! replays a run.

mod common;

use common::quadrature::for_each_half_vector;
use common::strategies::{direction, material_toml};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestCaseError, TestError, TestRunner};
use std::cell::{Cell, RefCell};
use std::f64::consts::{PI, TAU};
use std::time::Instant;
use vkbrdf::backend::{Backend, Output, Request, TERM_COLUMNS};
use vkbrdf::batch::{memory_source, Batch, Tuple, COLUMNS_PLAIN, COLUMNS_TANGENT};
use vkbrdf::check::{allowed_error, f32_sensitivity};
use vkbrdf::material::{parse_materials, Material};
use vkbrdf::reference::{evaluate_tuple, Evaluation, Status};
use vkbrdf::vector::{cross, dot, normalize_direct};

// ---------------------------------------------------------------------------------------
// Plumbing: backends, runners, batches

/// Parses one material from its TOML keys (everything after `name`).
fn material(body: &str) -> Material {
    let text = format!("[[material]]\nname = \"under-test\"\n{body}");
    match parse_materials(&text, "vulkan_properties.rs") {
        Ok(mut v) => v.remove(0),
        Err(e) => panic!("material does not parse: {e}\n{text}"),
    }
}

/// Runs `property` for `cases` random cases of `strategy` on every backend of
/// `common::backends()` (each backend created once, here, and shared by all its cases).
/// `property` returns a statistic of the case (e.g. the largest share of tolerance used);
/// its maximum over the cases is printed as `stat` with the run time. Panics naming the
/// backend and the failure.
fn for_every_backend<S>(
    test: &str,
    stat: &str,
    cases: u32,
    strategy: S,
    property: impl Fn(&mut dyn Backend, &S::Value) -> Result<f64, TestCaseError>,
) where
    S: Strategy,
{
    for backend in common::backends() {
        let name = backend.name();
        let start = Instant::now();
        let backend = RefCell::new(backend);
        let worst = Cell::new(0.0f64);
        let mut runner = TestRunner::new(Config {
            cases,
            // Never write regression files into the source tree; a failure prints its inputs.
            failure_persistence: None,
            // Every shrinking step is a whole evaluation: keep shrinking short. The failure
            // message already names the failing row.
            max_shrink_iters: 32,
            ..Config::default()
        });
        let result = runner.run(&strategy, |value| {
            let s = property(backend.borrow_mut().as_mut(), &value)?;
            worst.set(worst.get().max(s));
            Ok(())
        });
        match result {
            Ok(()) => println!(
                "{test} on {name}: {cases} cases in {:.2?}; {stat}: {:.3e}",
                start.elapsed(),
                worst.get()
            ),
            Err(TestError::Fail(reason, _)) => panic!("{test} fails on {name}:\n{reason}"),
            Err(TestError::Abort(reason)) => panic!("{test} aborted on {name}: {reason}"),
        }
    }
}

/// One tuple in f64: `(L, V, N, material index, T)`.
type Row = ([f64; 3], [f64; 3], [f64; 3], usize, [f64; 3]);

/// Builds a batch of rows `(L, V, N, material[, T])` from f64 values rounded to f32, as
/// every backend evaluates them; 13 columns when `tangents` (else T is dropped).
fn batch(rows: &[Row], tangents: bool, materials: usize) -> Batch<'static> {
    let columns = if tangents {
        COLUMNS_TANGENT
    } else {
        COLUMNS_PLAIN
    };
    let mut data = Vec::with_capacity(rows.len() * columns);
    for (l, v, n, m, t) in rows {
        data.extend(l.iter().chain(v).chain(n).map(|&x| x as f32));
        data.push(*m as f32);
        if tangents {
            data.extend(t.map(|x| x as f32));
        }
    }
    Batch::new(data, columns, materials, &memory_source()).expect("test batches are well formed")
}

/// Evaluates `batch` with terms in ONE call, failing the case on a backend error or a
/// wrongly sized output.
fn evaluate(
    backend: &mut dyn Backend,
    batch: &Batch,
    materials: &[Material],
) -> Result<Output, TestCaseError> {
    let out = backend
        .evaluate(batch, materials, &Request { terms: true })
        .map_err(|e| TestCaseError::fail(format!("evaluate failed: {e}")))?;
    prop_assert_eq!(out.brdf.len(), batch.len() * 3);
    prop_assert_eq!(
        out.terms.as_ref().map(Vec::len),
        Some(batch.len() * TERM_COLUMNS)
    );
    prop_assert_eq!(out.counts.tuples, batch.len() as u64);
    Ok(out)
}

/// The 9 values of `row`: BRDF r, g, b, then D, G, F_r, F_g, F_b, K (the terms layout of
/// `backend::Output`).
fn values(out: &Output, row: usize) -> [f64; 9] {
    let terms = out.terms.as_deref().expect("terms were requested");
    std::array::from_fn(|c| {
        f64::from(if c < 3 {
            out.brdf[row * 3 + c]
        } else {
            terms[row * TERM_COLUMNS + c - 3]
        })
    })
}

/// The reference's 9 values in the order of [`values`].
fn reference_values(e: &Evaluation) -> [f64; 9] {
    let t = e.terms();
    [
        e.brdf[0], e.brdf[1], e.brdf[2], t[0], t[1], t[2], t[3], t[4], t[5],
    ]
}

/// Names of the 9 columns of [`values`].
const COLUMNS: [&str; 9] = [
    "brdf_r", "brdf_g", "brdf_b", "D", "G", "F_r", "F_g", "F_b", "K",
];

/// A row's exact inputs and its material, for failure messages.
fn describe(t: &Tuple, body: &str) -> String {
    format!(
        "L = {:?}, V = {:?}, N = {:?}, T = {:?} (f32)\nmaterial:\n{body}",
        t.l, t.v, t.n, t.t
    )
}

/// Two unit vectors `(t, b)` completing the unit vector `n` to a right-handed frame.
fn tangent_frame(n: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let a = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let t = normalize_direct(cross(n, a));
    (t, cross(n, t))
}

/// `2 (v·h) h − v`: v reflected about h.
fn reflect(v: [f64; 3], h: [f64; 3]) -> [f64; 3] {
    let c = dot(v, h);
    std::array::from_fn(|k| 2.0 * c * h[k] - v[k])
}

// ---------------------------------------------------------------------------------------
// Random materials and tuples (properties 1–3)

/// Smallest |cos| between L or V and N in the structured rows (as `MIN_COS` in
/// `src/check.rs`): well clear of the horizon, where an f32 evaluator and the f64 reference
/// could classify a tuple differently. (The wild rows have no such bound; a cosine within
/// ~1e-7 of 0 has probability ~1e-7 per row.)
const MIN_COS: f64 = 1e-3;

/// A direction relative to N: `(cos θ, φ, log10 length)`. `cos θ` is uniform in
/// [MIN_COS, 1] (uniform in solid angle), log-uniform near grazing, or below the horizon.
fn polar() -> impl Strategy<Value = (f64, f64, f64)> {
    let cos = prop_oneof![
        4 => MIN_COS..1.0f64,
        2 => (-3.0..0.0f64).prop_map(|e| 10f64.powf(e)),
        1 => -1.0..-MIN_COS,
    ];
    (cos, 0.0..TAU, -20.0..20.0f64)
}

/// The recipe of one random tuple.
#[derive(Debug, Clone)]
struct RowRecipe {
    /// N, any orientation and length.
    n: [f64; 3],
    /// V relative to N.
    v: (f64, f64, f64),
    /// L relative to N (used when `aim` is `None` or lands too close to the horizon).
    l: (f64, f64, f64),
    /// `(log10 θ_h, φ_h)`: L is V reflected about a half vector θ_h from N, so that sharp
    /// lobes are sampled at their peak and shoulders, not only where they vanish.
    aim: Option<(f64, f64)>,
    /// T, any orientation and length.
    t: [f64; 3],
    /// When set, L and V are these directions as they are (any orientation and length, as
    /// in `tests/properties.rs`) instead of the structured ones above.
    wild: Option<([f64; 3], [f64; 3])>,
    /// 0–5 corrupts the tuple (see [`RowRecipe::inputs`]); anything else leaves it legal.
    corrupt: u8,
}

/// A random [`RowRecipe`]: one in five wild, else one in two aimed at a half vector
/// 1e-4 … 1.55 rad from N; about one in seven corrupted.
fn row_recipe() -> impl Strategy<Value = RowRecipe> {
    let aim = prop::option::of((-4.0..0.19f64, 0.0..TAU));
    let wild = prop::option::weighted(0.2, (direction(), direction()));
    (
        direction(),
        polar(),
        polar(),
        aim,
        direction(),
        wild,
        0u8..40,
    )
        .prop_map(|(n, v, l, aim, t, wild, corrupt)| RowRecipe {
            n,
            v,
            l,
            aim,
            t,
            wild,
            corrupt,
        })
}

impl RowRecipe {
    /// `(L, V, N, T)` in f64. Corruptions (invalid tuples, FORMULAS.md §1): 0: L = 0;
    /// 1: V has a NaN; 2: N has +∞; 3: L has −∞; 4: T = N (invalid for anisotropic
    /// materials only); 5: N = 0.
    fn inputs(&self) -> ([f64; 3], [f64; 3], [f64; 3], [f64; 3]) {
        let n = normalize_direct(self.n);
        let (t0, b0) = tangent_frame(n);
        let unit = |c: f64, phi: f64| -> [f64; 3] {
            let s = (1.0 - c * c).max(0.0).sqrt();
            std::array::from_fn(|k| s * (phi.cos() * t0[k] + phi.sin() * b0[k]) + c * n[k])
        };
        let scaled = |d: [f64; 3], p: f64| d.map(|x| x * 10f64.powf(p));
        let v = unit(self.v.0, self.v.1);
        let aimed = self.aim.and_then(|(a, phi)| {
            let h = unit(10f64.powf(a).cos(), phi);
            let l = reflect(v, h);
            (dot(v, h) > 0.0 && dot(l, n) >= MIN_COS).then_some(l)
        });
        let l = aimed.unwrap_or_else(|| unit(self.l.0, self.l.1));
        let (mut l, mut v) = self
            .wild
            .unwrap_or((scaled(l, self.l.2), scaled(v, self.v.2)));
        let (mut n, mut t) = (self.n, self.t);
        match self.corrupt {
            0 => l = [0.0; 3],
            1 => v[1] = f64::NAN,
            2 => n[2] = f64::INFINITY,
            3 => l[0] = f64::NEG_INFINITY,
            4 => t = n,
            5 => n = [0.0; 3],
            _ => {}
        }
        (l, v, n, t)
    }
}

/// One random case of properties 1–3: a material, whether the batch carries tangents
/// (anisotropic materials always do), and the tuples.
#[derive(Debug, Clone)]
struct RandomCase {
    /// The material's TOML keys.
    body: String,
    /// Tangent columns for an isotropic material too (they must be ignored).
    tangents: bool,
    /// The tuples.
    rows: Vec<RowRecipe>,
}

/// A random material with 64–192 random tuples.
fn random_case() -> impl Strategy<Value = RandomCase> {
    (
        material_toml(),
        any::<bool>(),
        prop::collection::vec(row_recipe(), 64..=192),
    )
        .prop_map(|(body, tangents, rows)| RandomCase {
            body,
            tangents,
            rows,
        })
}

impl RandomCase {
    /// The material table (one material) and the batch: the tuples `(L, V)` in rows
    /// `0..n`, then the same tuples swapped, `(V, L)`, in rows `n..2n`.
    fn build(&self) -> (Vec<Material>, Batch<'static>) {
        let m = material(&self.body);
        let tangents = self.tangents || m.is_anisotropic();
        let forward: Vec<_> = self.rows.iter().map(RowRecipe::inputs).collect();
        let rows: Vec<_> = forward
            .iter()
            .map(|&(l, v, n, t)| (l, v, n, 0, t))
            .chain(forward.iter().map(|&(l, v, n, t)| (v, l, n, 0, t)))
            .collect();
        (vec![m], batch(&rows, tangents, 1))
    }
}

/// Property 1 on one random case: every output finite and ≥ 0; exactly 0 for invalid and
/// below-horizon tuples, which are counted as the reference counts them. Returns the
/// largest output value (to show how far the values went).
fn check_finite(backend: &mut dyn Backend, case: &RandomCase) -> Result<f64, TestCaseError> {
    check_rows(backend, case, false)
}

/// Properties 1 and 2 on one random case: besides [`check_finite`], every value within the
/// conformance tolerance of the f64 reference. Returns the largest share of its tolerance
/// any value used.
fn check_agreement(backend: &mut dyn Backend, case: &RandomCase) -> Result<f64, TestCaseError> {
    check_rows(backend, case, true)
}

/// Checks every row of one random case: property 1, and property 2 when `agreement`.
/// Returns the largest share of tolerance used (`agreement`) or the largest output.
fn check_rows(
    backend: &mut dyn Backend,
    case: &RandomCase,
    agreement: bool,
) -> Result<f64, TestCaseError> {
    let (materials, batch) = case.build();
    let out = evaluate(backend, &batch, &materials)?;
    let (mut invalid, mut below, mut first_invalid) = (0u64, 0u64, None);
    let (mut most_used, mut largest) = (0.0f64, 0.0f64);
    for row in 0..batch.len() {
        let t = batch.tuple(row);
        let m = &materials[t.material];
        let e = evaluate_tuple(&t, m);
        let got = values(&out, row);
        largest = got.iter().fold(largest, |a, &b| a.max(b));
        // 1. Finite and non-negative, always; exactly 0 for invalid / below-horizon tuples.
        prop_assert!(
            got.iter().all(|x| x.is_finite() && *x >= 0.0),
            "row {row}: outputs must be finite and ≥ 0, got {got:?}\n{}",
            describe(&t, &case.body)
        );
        match e.status {
            Status::Valid => {}
            Status::Invalid => {
                invalid += 1;
                first_invalid.get_or_insert(row as u64);
            }
            Status::BelowHorizon => below += 1,
        }
        if e.status != Status::Valid {
            prop_assert!(
                got.iter().all(|&x| x == 0.0),
                "row {row}: {:?} tuple must give 0, got {got:?}\n{}",
                e.status,
                describe(&t, &case.body)
            );
            continue;
        }
        if !agreement {
            continue;
        }
        // 2. Within the conformance tolerance of the f64 reference, value by value.
        let want = reference_values(&e);
        let sensitivity = f32_sensitivity(&t, m);
        for c in 0..9 {
            let allowed = allowed_error(want[c], sensitivity[c]);
            let err = (got[c] - want[c]).abs();
            prop_assert!(
                err <= allowed,
                "row {row} column {}: got {:e}, reference {:e}, |error| {err:.3e} > allowed {allowed:.3e} \
                 (1e-5 × max(|ref|, 1e-6) + 4 × f32 sensitivity {:.3e})\n{}",
                COLUMNS[c],
                got[c],
                want[c],
                sensitivity[c],
                describe(&t, &case.body)
            );
            most_used = most_used.max(err / allowed);
        }
    }
    let c = out.counts;
    prop_assert!(
        (c.invalid, c.below_horizon, c.first_invalid) == (invalid, below, first_invalid),
        "counts (invalid, below horizon, first invalid) = {:?}, reference {:?}\nmaterial:\n{}",
        (c.invalid, c.below_horizon, c.first_invalid),
        (invalid, below, first_invalid),
        case.body
    );
    if agreement {
        Ok(most_used)
    } else {
        Ok(largest)
    }
}

/// Property 3 on one random case of a reciprocal material: row `i` (L, V) and row `n + i`
/// (V, L) agree in every column (BRDF and terms: D, G, F and K are all symmetric in l and v
/// for these models). Tolerance: the two values are f32 evaluations of the same exact
/// number (the reference is reciprocal to 1e-12, `tests/properties.rs`), each allowed the
/// conformance error of its own tuple, so they may differ by the sum of the two
/// allowances. Returns the largest share of that used.
fn check_reciprocity(backend: &mut dyn Backend, case: &RandomCase) -> Result<f64, TestCaseError> {
    let (materials, batch) = case.build();
    let m = &materials[0];
    prop_assert!(m.is_reciprocal());
    let out = evaluate(backend, &batch, &materials)?;
    let n = batch.len() / 2;
    let mut most_used = 0.0f64;
    for i in 0..n {
        let (ta, tb) = (batch.tuple(i), batch.tuple(n + i));
        let (ea, eb) = (evaluate_tuple(&ta, m), evaluate_tuple(&tb, m));
        let (a, b) = (values(&out, i), values(&out, n + i));
        prop_assert_eq!(
            ea.status,
            eb.status,
            "reference statuses differ\n{}",
            describe(&ta, &case.body)
        );
        if ea.status != Status::Valid {
            prop_assert!(a == b, "rows {i} / {}: {a:?} ≠ {b:?}", n + i);
            continue;
        }
        let (sa, sb) = (f32_sensitivity(&ta, m), f32_sensitivity(&tb, m));
        let (ra, rb) = (reference_values(&ea), reference_values(&eb));
        for c in 0..9 {
            let allowed = allowed_error(ra[c], sa[c]) + allowed_error(rb[c], sb[c]);
            let diff = (a[c] - b[c]).abs();
            prop_assert!(
                diff <= allowed,
                "f(l, v) ≠ f(v, l) in column {}: {:e} vs {:e} (|diff| {diff:.3e} > allowed {allowed:.3e})\n{}",
                COLUMNS[c],
                a[c],
                b[c],
                describe(&ta, &case.body)
            );
            most_used = most_used.max(diff / allowed);
        }
    }
    Ok(most_used)
}

/// Cases per backend for properties 1–2 and 3: each is one evaluation of 128–384 tuples
/// and often a new kernel variant (a compile on Vulkan).
const RANDOM_CASES: u32 = 48;

/// Property 1 on every backend: finite, non-negative outputs; zeros and counts for invalid
/// and below-horizon tuples.
#[test]
fn random_batches_give_finite_non_negative_outputs() {
    for_every_backend(
        "finite, non-negative outputs and counts",
        "largest output",
        RANDOM_CASES,
        random_case(),
        check_finite,
    );
}

/// Property 2 on every backend: every value within the conformance tolerance. On the
/// reference itself this is a plumbing test (its batch path, threads and f32 outputs
/// against its own per-tuple function); the engines' rows are the agreement test.
#[test]
fn random_batches_match_the_reference() {
    for_every_backend(
        "agreement with the f64 reference",
        "most tolerance used",
        RANDOM_CASES,
        random_case(),
        check_agreement,
    );
}

/// Property 3 on every backend: `f(l, v) = f(v, l)` for the reciprocal materials.
#[test]
fn reciprocal_materials_are_reciprocal() {
    let strategy = random_case().prop_filter("reciprocal materials only", |c| {
        material(&c.body).is_reciprocal()
    });
    for_every_backend(
        "reciprocity",
        "most tolerance used",
        RANDOM_CASES,
        strategy,
        check_reciprocity,
    );
}

/// A GGX material whose D is the constant 1/π: at m = 1, `m² / (π cos⁴ (m² + tan²)²)`
/// = `1 / (π (cos² + sin²)²)` = 1/π for every h (isotropic, and anisotropic `[1, 1]`).
const GGX_UNIT: [&str; 2] = [
    "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 1.0\ngeometry = \"none\"\nfresnel = \"none\"",
    "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = [1.0, 1.0]\ngeometry = \"none\"\nfresnel = \"none\"",
];

/// One frame of grazing mirror tuples: N (any orientation and length) and, per row,
/// `(log10 cos_o, φ, log10 |L|, log10 |V|)`.
type GrazingCase = ([f64; 3], Vec<(f64, f64, f64, f64)>);

/// Random frames with 64 grazing mirror tuples each: cos_o = cos_i in [MIN_COS, 0.1], L the
/// mirror image of V about N (so l ≈ −v in the tangent plane and |l + v| = 2 cos_o), with
/// random lengths so that L and V round to f32 differently.
fn grazing_case() -> impl Strategy<Value = GrazingCase> {
    let row = (
        MIN_COS.log10()..-1.0f64,
        0.0..TAU,
        -3.0..3.0f64,
        -3.0..3.0f64,
    );
    (direction(), prop::collection::vec(row, 64))
}

/// Property 2 where it is sharpest: D of [`GGX_UNIT`] must be 1/π to the conformance
/// tolerance for every tuple, and its f32 sensitivity is 0 (D does not depend on h), so the
/// rule is 1e-5 relative. Grazing mirror geometry (cos_i, cos_o ~ 1e-3, l ≈ −v) is where an
/// f32 kernel that derives `cos_h` and `sin2_h` inconsistently gets `sin² + cos² ≠ 1`.
/// Returns the largest relative error.
fn check_ggx_unit(
    backend: &mut dyn Backend,
    (n, rows): &GrazingCase,
) -> Result<f64, TestCaseError> {
    let materials: Vec<Material> = GGX_UNIT.iter().map(|b| material(b)).collect();
    let nn = normalize_direct(*n);
    let (t0, b0) = tangent_frame(nn);
    let mut tuples = Vec::new();
    for (i, &(c, phi, pl, pv)) in rows.iter().enumerate() {
        let c = 10f64.powf(c);
        let s = (1.0 - c * c).sqrt();
        let v: [f64; 3] =
            std::array::from_fn(|k| s * (phi.cos() * t0[k] + phi.sin() * b0[k]) + c * nn[k]);
        let l = reflect(v, nn);
        let scale = |d: [f64; 3], p: f64| d.map(|x| x * 10f64.powf(p));
        tuples.push((scale(l, pl), scale(v, pv), *n, i % 2, t0));
    }
    let batch = batch(&tuples, true, materials.len());
    let out = evaluate(backend, &batch, &materials)?;
    let mut worst = 0.0f64;
    for row in 0..batch.len() {
        let t = batch.tuple(row);
        let m = &materials[t.material];
        let e = evaluate_tuple(&t, m);
        prop_assert_eq!(e.status, Status::Valid);
        let d = values(&out, row)[3];
        let allowed = allowed_error(e.d, f32_sensitivity(&t, m)[3]);
        prop_assert!(
            (d - e.d).abs() <= allowed,
            "GGX at m = 1: D = {d:e}, want {:e} (= 1/π; relative error {:.3e}, allowed {:.3e})\n{}",
            e.d,
            (d - e.d).abs() / e.d,
            allowed / e.d,
            describe(&t, GGX_UNIT[t.material])
        );
        worst = worst.max((d - e.d).abs() / e.d);
    }
    Ok(worst)
}

/// Property 2 at grazing mirror geometry, where the exact D is known (1/π).
#[test]
fn ggx_d_is_constant_at_unit_roughness() {
    for_every_backend(
        "GGX D = 1/π at m = 1, grazing mirror geometry",
        "largest relative error",
        16,
        grazing_case(),
        check_ggx_unit,
    );
}

// ---------------------------------------------------------------------------------------
// Quadrature over half vectors (properties 4, 5), as in `tests/properties.rs`
//
// With slopes `(x̃, ỹ) = (mx r cos ψ, my r sin ψ)`, `h = normalize(x̃, ỹ, 1)` and `r = e^u`,
// `dω_h = cos³θ_h mx my r² du dψ`. In (u, ψ) a Beckmann or GGX lobe of any roughness is the
// same smooth bump near u = 0, decaying exponentially on both sides and periodic in ψ, so
// the trapezoid rule converges exponentially (see `tests/properties.rs`).

/// The normal of the quadrature frame.
const Z: [f64; 3] = [0.0, 0.0, 1.0];
/// The tangent of the quadrature frame (t = +x, b = +y).
const X: [f64; 3] = [1.0, 0.0, 0.0];

// ---------------------------------------------------------------------------------------
// 4. White furnace

/// One furnace case: a modern Cook–Torrance material with white F (`fresnel = "none"` or
/// Schlick with F0 = 1), mixed with a white Lambert lobe (`diffuse = 1`,
/// `diffuse_weight + specular_weight = 1`), and a view direction.
#[derive(Debug, Clone)]
struct FurnaceCase {
    /// `beckmann` or `ggx`.
    distribution: &'static str,
    /// `smith`, `smith-correlated` or `cook-torrance`.
    geometry: &'static str,
    /// `fresnel = "none"`, or Schlick with F0 = 1 (F ≡ 1 too, through another code path).
    schlick: bool,
    /// `(mx, my)`; isotropic when equal.
    roughness: (f64, f64),
    /// Weight of the white Lambert lobe (the specular weight is `1 − diffuse_weight`).
    diffuse_weight: f64,
    /// View polar angle (radians) and azimuth.
    view: (f64, f64),
}

/// Random furnace cases: moderate roughness (0.2–1, where the grid below is converged) and
/// views up to 80° from N.
fn furnace_case() -> impl Strategy<Value = FurnaceCase> {
    let roughness = prop_oneof![
        (0.2..1.0f64).prop_map(|m| (m, m)),
        (0.2..1.0f64, 0.2..1.0f64),
    ];
    let weight = prop_oneof![Just(0.0), 0.0..1.0f64];
    (
        prop::sample::select(vec!["beckmann", "ggx"]),
        prop::sample::select(vec!["smith", "smith-correlated", "cook-torrance"]),
        any::<bool>(),
        roughness,
        weight,
        (0.0..80f64.to_radians(), 0.0..TAU),
    )
        .prop_map(
            |(distribution, geometry, schlick, roughness, diffuse_weight, view)| FurnaceCase {
                distribution,
                geometry,
                schlick,
                roughness,
                diffuse_weight,
                view,
            },
        )
}

impl FurnaceCase {
    /// The material's TOML keys.
    fn body(&self) -> String {
        let (mx, my) = self.roughness;
        let roughness = if mx == my {
            format!("roughness = {mx:?}")
        } else {
            format!("roughness = [{mx:?}, {my:?}]")
        };
        let fresnel = if self.schlick {
            "fresnel = \"schlick\"\nf0 = 1.0"
        } else {
            "fresnel = \"none\""
        };
        format!(
            "model = \"cook-torrance\"\ndistribution = \"{}\"\n{roughness}\ngeometry = \"{}\"\n{fresnel}\n\
             diffuse = 1.0\ndiffuse_weight = {:?}\nspecular_weight = {:?}",
            self.distribution,
            self.geometry,
            self.diffuse_weight,
            1.0 - self.diffuse_weight
        )
    }
}

/// The furnace grid in u (over [−9, 7], slopes 1.2e-4 m … 1100 m) and ψ: twice the base grid
/// of `tests/properties.rs`. Measured on the reference over 540 configurations (beckmann /
/// ggx × smith / cook-torrance × roughness (0.2, 0.2), (0.2, 1), (1, 0.2), (0.5, 0.5),
/// (1, 1) × diffuse weight 0, ½, 1 × θ_v 0°, 60°, 80° × three azimuths): a grid twice as
/// fine moves E by at most 4.1e-4, and pure white Lambert integrates to 1 within 4.2e-4.
const FURNACE_GRID: (u32, u32) = (320, 192);

/// The furnace's quadrature tolerance (that of `tests/properties.rs`): the integrand has a
/// kink where l crosses the horizon, so the grid converges as O(step²).
const FURNACE_TOL: f64 = 1e-3;

/// (μ, φ) midpoint grid of the Lambert rows: `∫ μ dμ dφ` is exact on it (linear in μ).
const LAMBERT_GRID: (u32, u32) = (64, 128);

/// How far the backend's albedo may be from the reference's on the same f32 batch: every
/// value is within ~1e-5 relative of the reference where well conditioned (`src/check.rs`),
/// and E is a positively weighted sum, so its error is ≤ 1e-5 E plus the weight of the rare
/// ill-conditioned rows near grazing (whose values G drives to 0).
const FURNACE_AGREEMENT: f64 = 2e-5;

/// Property 4 on one case; returns |E_backend − E_reference| on the same batch.
fn check_furnace(backend: &mut dyn Backend, case: &FurnaceCase) -> Result<f64, TestCaseError> {
    let body = case.body();
    let materials = vec![
        material(&body),
        material("model = \"lambert\"\ndiffuse = 1.0"),
    ];
    let (theta, phi) = case.view;
    let v = [
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    ];
    // Rows of material 0 on the half-vector grid (l = reflect(v, h), dω_l = 4 (v·h) dω_h),
    // then rows of material 1 (Lambert) on the (μ, φ) grid; each with its weight w, so that
    // E = Σ f w (w includes cos_i).
    let mut rows = Vec::new();
    let mut weights = Vec::new();
    let u = (-9.0, 7.0, FURNACE_GRID.0);
    for_each_half_vector(case.roughness, u, FURNACE_GRID.1, |h, w| {
        let c = dot(v, h);
        if c > 0.0 {
            let l = reflect(v, h);
            rows.push((l, v, Z, 0, X));
            weights.push(l[2].max(0.0) * 4.0 * c * w);
        }
    });
    let specular_rows = rows.len();
    let (nm, np) = LAMBERT_GRID;
    let (dmu, dphi) = (1.0 / f64::from(nm), TAU / f64::from(np));
    for i in 0..nm {
        let mu = (f64::from(i) + 0.5) * dmu;
        let s = (1.0 - mu * mu).sqrt();
        for j in 0..np {
            let p = (f64::from(j) + 0.5) * dphi;
            rows.push(([s * p.cos(), s * p.sin(), mu], v, Z, 1, X));
            weights.push(mu * dmu * dphi);
        }
    }
    let batch = batch(&rows, true, materials.len());
    let out = evaluate(backend, &batch, &materials)?;
    // E per channel, on the backend and on the reference for the same f32 inputs.
    let (mut e, mut e_ref, mut lambert) = ([0.0f64; 3], [0.0f64; 3], [0.0f64; 3]);
    for (row, w) in weights.iter().enumerate() {
        let got = values(&out, row);
        let r = evaluate_tuple(&batch.tuple(row), &materials[batch.material(row)]);
        for c in 0..3 {
            if row < specular_rows {
                e[c] += got[c] * w;
                e_ref[c] += r.brdf[c] * w;
            } else {
                lambert[c] += got[c] * w;
            }
        }
    }
    let ctx = || format!("V = {v:?}, material:\n{body}");
    let mut worst = 0.0f64;
    for c in 0..3 {
        prop_assert!(
            e[c] <= 1.0 + FURNACE_TOL && e[c] > 0.2,
            "white furnace: E(v) = {:.6} in channel {c} (must be ≤ 1 + {FURNACE_TOL}); reference on \
             the same grid {:.6}; {}",
            e[c],
            e_ref[c],
            ctx()
        );
        prop_assert!(
            (e[c] - e_ref[c]).abs() <= FURNACE_AGREEMENT,
            "E(v) = {:.8} in channel {c}, reference on the same grid {:.8}: differ by more than \
             {FURNACE_AGREEMENT}; {}",
            e[c],
            e_ref[c],
            ctx()
        );
        prop_assert!(
            (lambert[c] - 1.0).abs() <= FURNACE_AGREEMENT,
            "Lambert albedo 1: E(v) = {:.8} in channel {c} (V = {v:?})",
            lambert[c]
        );
        worst = worst.max((e[c] - e_ref[c]).abs());
    }
    Ok(worst)
}

/// Property 4 on every backend: `E(v) ≤ 1` with F = 1, and `E = 1` for white Lambert.
#[test]
fn white_furnace() {
    for_every_backend(
        "white furnace",
        "max |E − E_reference|",
        24,
        furnace_case(),
        check_furnace,
    );
}

// ---------------------------------------------------------------------------------------
// 5. ∫ D cos_h dω_h

/// One normalisation case: a distribution with its parameter and convention.
#[derive(Debug, Clone)]
struct NormCase {
    /// The material's TOML keys (G = F = none).
    body: String,
    /// The grid's scale `(mx, my)` (the lobe's width).
    scale: (f64, f64),
    /// Whether ψ needs a fine grid (anisotropic).
    anisotropic: bool,
    /// The exact integral: 1, or π/k for the seed's (k = 4) and 1982 (k = 1) Beckmann.
    want: f64,
}

/// Random distributions: Beckmann / GGX isotropic (m 0.02 … 1.5, every convention),
/// anisotropic (modern, m 0.05 … 1 per axis), normalised Blinn (e 0 … 1e4) and Charlie
/// (m 0.01 … 1).
fn norm_case() -> impl Strategy<Value = NormCase> {
    let log = |lo: f64, hi: f64| (lo.ln()..hi.ln()).prop_map(f64::exp);
    let isotropic = (
        prop::sample::select(vec!["beckmann", "ggx"]),
        prop::sample::select(vec!["seed", "cook-torrance-1982", "modern"]),
        log(0.02, 1.5),
    )
        .prop_map(|(d, conv, m)| {
            let want = match (d, conv) {
                ("beckmann", "seed") => PI / 4.0,
                ("beckmann", "cook-torrance-1982") => PI,
                _ => 1.0,
            };
            (
                format!("distribution = \"{d}\"\nroughness = {m:?}\nconvention = \"{conv}\""),
                (m, m),
                false,
                want,
            )
        });
    let anisotropic = (
        prop::sample::select(vec!["beckmann", "ggx"]),
        log(0.05, 1.0),
        log(0.05, 1.0),
    )
        .prop_map(|(d, mx, my)| {
            (
                format!("distribution = \"{d}\"\nroughness = [{mx:?}, {my:?}]"),
                (mx, my),
                true,
                1.0,
            )
        });
    let blinn = (
        prop::sample::select(vec!["seed", "cook-torrance-1982", "modern"]),
        0.0..4.0f64,
    )
        .prop_map(|(conv, x)| {
            let e = 10f64.powf(x) - 1.0;
            let w = (2.0 / (e + 2.0)).sqrt();
            (
                format!("distribution = \"blinn\"\nexponent = {e:?}\nconvention = \"{conv}\""),
                (w, w),
                false,
                1.0,
            )
        });
    // Charlie (sheen), every convention (its normalisation does not depend on one); its
    // mass lies toward grazing h, which the grid reaches at scale 1.
    let charlie = (
        prop::sample::select(vec!["seed", "cook-torrance-1982", "modern"]),
        log(0.01, 1.0),
    )
        .prop_map(|(conv, m)| {
            (
                format!("distribution = \"charlie\"\nroughness = {m:?}\nconvention = \"{conv}\""),
                (1.0, 1.0),
                false,
                1.0,
            )
        });
    prop_oneof![2 => isotropic, 1 => anisotropic, 1 => blinn, 1 => charlie].prop_map(
        |(keys, scale, anisotropic, want)| NormCase {
            body: format!(
                "model = \"cook-torrance\"\n{keys}\ngeometry = \"none\"\nfresnel = \"none\""
            ),
            scale,
            anisotropic,
            want,
        },
    )
}

/// Tolerance of property 5, relative. The grid (u over [−20, 20] in 2000 steps) integrates
/// these lobes to ~1e-13 in f64 (`tests/properties.rs`); on the backend each D value is an
/// f32 evaluation within ~1e-5 relative of the reference at well-conditioned h (L = V = h,
/// so |l + v| = 2), and the rounding of each node h to f32 perturbs D by far less. A
/// positively weighted sum of such values is within 1e-5 relative: 5e-5 leaves a margin and
/// still catches any wrong constant or lost factor.
const NORM_TOL: f64 = 5e-5;

/// Property 5 on one case: `∫ D(h) cos_h dω_h` from the backend's D column with L = V = h
/// (so that the half vector is h itself, for every h of the upper hemisphere). Returns the
/// relative error.
fn check_normalisation(backend: &mut dyn Backend, case: &NormCase) -> Result<f64, TestCaseError> {
    let materials = vec![material(&case.body)];
    let psi_steps = if case.anisotropic { 64 } else { 4 };
    let mut rows = Vec::new();
    let mut weights = Vec::new();
    for_each_half_vector(case.scale, (-20.0, 20.0, 2000), psi_steps, |h, w| {
        rows.push((h, h, Z, 0, X));
        weights.push(h[2] * w);
    });
    let batch = batch(&rows, case.anisotropic, 1);
    let out = evaluate(backend, &batch, &materials)?;
    prop_assert_eq!(
        out.counts.invalid + out.counts.below_horizon,
        0,
        "every L = V = h is above the horizon"
    );
    let terms = out.terms.as_deref().expect("terms were requested");
    let integral: f64 = weights
        .iter()
        .enumerate()
        .map(|(row, w)| f64::from(terms[row * TERM_COLUMNS]) * w)
        .sum();
    let err = (integral - case.want).abs() / case.want;
    prop_assert!(
        err <= NORM_TOL,
        "∫ D cos_h dω = {integral:.9}, want {:.9} (relative error {err:.3e} > {NORM_TOL})\nmaterial:\n{}",
        case.want,
        case.body
    );
    Ok(err)
}

/// Property 5 on every backend: `∫ D cos_h dω_h = 1` (π/k for the unnormalised Beckmann).
#[test]
fn distributions_are_normalised() {
    for_every_backend(
        "∫ D cos_h dω_h",
        "largest relative error",
        24,
        norm_case(),
        check_normalisation,
    );
}
