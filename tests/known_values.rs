//! Hand-derived values for every model, distribution D, geometry term G, Fresnel term F and
//! convention K of FORMULAS.md, checked against the CPU reference (`reference::evaluate`)
//! to 1e-12 relative and, through `Backend::evaluate` with the terms output, against every
//! engine (the native CPU engine, the Vulkan kernel) under the conformance rule; plus the
//! rules of §1 (invalid tuples, the horizon) and the numeric guards of §2 and §4.
//!
//! Every expected value is derived here from the formula, with the numbers written out;
//! nothing calls the code under test to get an expectation. Materials are built from TOML
//! through `parse_materials`, so the parser is exercised too.
//!
//! Most checks use one geometry, `tilted()`: N = +z, L at 75° and V at 15° from N, both
//! toward +x in the xz-plane. Its half vector is at 45° (the average of the two angles) and
//! `c = v·h = cos 30°`. Everything is a closed form:
//!
//! | quantity | value |
//! |---|---|
//! | `cos_i = cos 75°` | `(√6 − √2)/4` |
//! | `cos_o = cos 15°` | `(√6 + √2)/4` |
//! | `cos_i cos_o` | `(6 − 2)/16 = 1/4` |
//! | `cos_h = cos 45°` | `√2/2`, so `cos⁴δ = 1/4`, `sin²δ = 1/2`, `tan²δ = 1`, `δ = π/4` |
//! | `c = cos 30°` | `√3/2` |
//! | `tan²θ_i = tan² 75°` | `(2 + √3)² = 7 + 4√3` |
//! | `tan²θ_o = tan² 15°` | `(2 − √3)² = 7 − 4√3` |
//!
//! The inputs are deliberately not unit length (L×3, V×0.5, N×2) so the normalisation is
//! exercised as well. The anisotropic checks add a tangent at 60° from +x in the tangent
//! plane (with a component along N that the evaluator must project out), giving
//! `t = (1/2, √3/2, 0)`, `b = n × t = (−√3/2, 1/2, 0)` and `h` in that frame
//! `(hx, hy, hz) = (√2/4, −√6/4, √2/2)`, so `(hx/hz)² = 1/4`, `(hy/hz)² = 3/4`.

mod common;

use std::f64::consts::PI;
use std::sync::{Mutex, OnceLock};
use vkbrdf::backend::{Backend, Request};
use vkbrdf::batch::{Batch, Tuple};
use vkbrdf::check::{allowed_error, f32_sensitivity};
use vkbrdf::material::{parse_materials, Material};
use vkbrdf::reference::{evaluate, Evaluation, Status};
use vkbrdf::terms::f::{conductor, dielectric};
use vkbrdf::vector::scale;

/// Relative tolerance of the hand-derived values: the inputs are f64 roundings of
/// irrational numbers and every formula here is well conditioned, so the reference should
/// be within a few dozen ulps.
const TOL: f64 = 1e-12;

fn sqrt(x: f64) -> f64 {
    x.sqrt()
}

// ---------------------------------------------------------------------------------------
// Set-up helpers

/// One material from the body of a `[[material]]` table, through the real parser.
fn material(body: &str) -> Material {
    let text = format!("[[material]]\nname = \"under-test\"\n{body}");
    match parse_materials(&text, "known_values.rs") {
        Ok(mut v) => v.remove(0),
        Err(e) => panic!("material does not parse: {e}\n{text}"),
    }
}

/// The inputs of one evaluation.
#[derive(Debug, Clone, Copy)]
struct Setup {
    name: &'static str,
    l: [f64; 3],
    v: [f64; 3],
    n: [f64; 3],
    t: Option<[f64; 3]>,
}

impl Setup {
    fn with_t(self, t: Option<[f64; 3]>) -> Setup {
        Setup { t, ..self }
    }
    fn eval(&self, m: &Material) -> Evaluation {
        evaluate(self.l, self.v, self.n, self.t, m)
    }
}

/// A direction at angle `theta` from +z toward +x (negative: toward −x).
fn in_xz(theta_deg: f64) -> [f64; 3] {
    let t = theta_deg.to_radians();
    [t.sin(), 0.0, t.cos()]
}

/// L at 75°, V at 15° (see the module docs), written with exact closed forms.
fn tilted() -> Setup {
    let (s2, s6) = (sqrt(2.0), sqrt(6.0));
    let (sin75, cos75) = ((s6 + s2) / 4.0, (s6 - s2) / 4.0);
    Setup {
        name: "tilted: L at 75°, V at 15°, N = +z (h at 45°, c = cos 30°)",
        l: scale([sin75, 0.0, cos75], 3.0),
        v: scale([cos75, 0.0, sin75], 0.5),
        n: [0.0, 0.0, 2.0],
        t: None,
    }
}

/// The tangent of the anisotropic checks: 60° from +x in the tangent plane, plus a
/// component along N, times 4.
fn tangent60() -> Option<[f64; 3]> {
    Some(scale([0.5, sqrt(3.0) / 2.0, 0.7], 4.0))
}

/// L at 60°, V = N: `cos_i = 1/2`, `cos_o = 1`, h at 30° (`cos_h = √3/2`, `tan²δ = 1/3`,
/// `cos⁴δ = 9/16`), `c = cos 30° = √3/2`, `l·v = 1/2`.
fn sixty_normal() -> Setup {
    Setup {
        name: "L at 60°, V = N = +z",
        l: [sqrt(3.0) / 2.0, 0.0, 0.5],
        v: [0.0, 0.0, 1.0],
        n: [0.0, 0.0, 1.0],
        t: None,
    }
}

/// What one evaluation should give.
#[derive(Debug, Clone, Copy)]
struct Want {
    brdf: [f64; 3],
    d: f64,
    g: f64,
    f: [f64; 3],
    k: f64,
}

/// The terms of a non-microfacet model: D = the lobe, G = F = K = 1.
fn lobe_model(diffuse: [f64; 3], specular: [f64; 3], lobe: f64) -> Want {
    Want {
        brdf: std::array::from_fn(|c| diffuse[c] / PI + specular[c] * lobe),
        d: lobe,
        g: 1.0,
        f: [1.0; 3],
        k: 1.0,
    }
}

/// A Cook–Torrance material with the default colours and weights (no diffuse, white
/// specular, s = 1): `f = D·G·F·K` per channel.
fn microfacet(d: f64, g: f64, f: [f64; 3], k: f64) -> Want {
    Want {
        brdf: f.map(|fc| d * g * fc * k),
        d,
        g,
        f,
        k,
    }
}

fn close(got: f64, want: f64, tol: f64) -> bool {
    if want == 0.0 {
        got == 0.0
    } else {
        (got - want).abs() <= tol * want.abs()
    }
}

/// Evaluates `body` at `setup` and compares every output with `want`.
fn check_with(label: &str, body: &str, setup: &Setup, want: &Want, tol: f64) {
    check_material(label, &material(body), body, setup, want, tol);
}

/// [`check_with`] for a material already built (`body` describes it in messages).
fn check_material(label: &str, m: &Material, body: &str, setup: &Setup, want: &Want, tol: f64) {
    let e = setup.eval(m);
    let ctx = || {
        format!(
            "[{label}] at {}: {setup:?}\nmaterial:\n{body}\ngot  {e:?}\nwant {want:?}",
            setup.name
        )
    };
    assert_eq!(e.status, Status::Valid, "{}", ctx());
    let columns = [
        ("brdf R", e.brdf[0], want.brdf[0]),
        ("brdf G", e.brdf[1], want.brdf[1]),
        ("brdf B", e.brdf[2], want.brdf[2]),
        ("D", e.d, want.d),
        ("G", e.g, want.g),
        ("F R", e.f[0], want.f[0]),
        ("F G", e.f[1], want.f[1]),
        ("F B", e.f[2], want.f[2]),
        ("K", e.k, want.k),
    ];
    for (name, got, expected) in columns {
        assert!(
            close(got, expected, tol),
            "{name}: got {got:e}, want {expected:e} (rel err {:.3e}, tol {tol:e})\n{}",
            ((got - expected) / expected).abs(),
            ctx()
        );
    }
    let nine = [
        want.brdf[0],
        want.brdf[1],
        want.brdf[2],
        want.d,
        want.g,
        want.f[0],
        want.f[1],
        want.f[2],
        want.k,
    ];
    engines_agree(label, m, setup, nine, &[0, 1, 2, 3, 4, 5, 6, 7, 8]);
}

/// Every engine (`common::backends()`: the native CPU engine and the Vulkan kernel beside
/// the reference), created once for the whole file.
fn engines() -> &'static Mutex<Vec<Box<dyn Backend + Send>>> {
    static ENGINES: OnceLock<Mutex<Vec<Box<dyn Backend + Send>>>> = OnceLock::new();
    ENGINES.get_or_init(|| {
        let mut v: Vec<Box<dyn Backend + Send>> = vec![Box::new(vkbrdf::cpu::CpuEngine::new())];
        if let Some(b) = common::vulkan() {
            v.push(Box::new(b));
        }
        Mutex::new(v)
    })
}

/// The same known value through every engine's `Backend::evaluate` with the terms output:
/// the setup's directions rounded to f32 (the engines' input), each of the nine outputs
/// within the conformance rule of `vkbrdf check` around the hand-derived value
/// (`1e-5 · max(|want|, 1e-6) + 4 · f32 sensitivity`; the sensitivity covers the move from
/// the f64 directions the value was derived for to their f32 roundings). Only the columns
/// in `which` are compared (all nine for a full check, G alone for `check_g`).
/// Setups with components outside f32's normal range (z = 1e-100 for the reference's
/// log-domain guards) have no f32 counterpart: only the reference sees them.
fn engines_agree(label: &str, m: &Material, setup: &Setup, want: [f64; 9], which: &[usize]) {
    let mut components = [setup.l, setup.v, setup.n, setup.t.unwrap_or([1.0; 3])]
        .into_iter()
        .flatten();
    if components.any(|x| {
        x != 0.0 && !(f64::from(f32::MIN_POSITIVE)..=f64::from(f32::MAX)).contains(&x.abs())
    }) {
        return;
    }
    let f = |a: [f64; 3]| a.map(|x| x as f32);
    let mut row = Vec::new();
    row.extend(f(setup.l));
    row.extend(f(setup.v));
    row.extend(f(setup.n));
    row.push(0.0);
    if let Some(t) = setup.t {
        row.extend(f(t));
    }
    let columns = row.len();
    let batch = Batch::new(row, columns, 1, std::path::Path::new("known_values.rs")).expect("row");
    let tuple: Tuple = batch.tuple(0);
    let sensitivity = f32_sensitivity(&tuple, m);
    let materials = [m.clone()];
    let mut engines = engines().lock().unwrap_or_else(|e| e.into_inner());
    for engine in engines.iter_mut() {
        let out = engine
            .evaluate(&batch, &materials, &Request { terms: true })
            .unwrap_or_else(|e| panic!("[{label}] {}: {e}", engine.name()));
        let terms = out.terms.as_ref().expect("terms asked for");
        let got: Vec<f64> = out
            .brdf
            .iter()
            .chain(terms)
            .map(|&x| f64::from(x))
            .collect();
        for &i in which {
            let allowed = allowed_error(want[i], sensitivity[i]);
            assert!(
                (got[i] - want[i]).abs() <= allowed,
                "[{label}] {} at {}: output {i} (brdf R G B, D G F_r F_g F_b K) is {:e}, the hand-derived value {:e}, allowed error {allowed:e}",
                engine.name(),
                setup.name,
                got[i],
                want[i]
            );
        }
    }
}

fn check(label: &str, body: &str, setup: &Setup, want: &Want) {
    check_with(label, body, setup, want, TOL);
}

/// Only the G column (for geometries whose other terms are not closed forms).
fn check_g(label: &str, body: &str, setup: &Setup, want_g: f64) {
    let m = material(body);
    let e = setup.eval(&m);
    assert!(
        e.status == Status::Valid && close(e.g, want_g, TOL),
        "[{label}] G: got {:e}, want {want_g:e}\nat {}: {setup:?}\nmaterial:\n{body}\ngot {e:?}",
        e.g,
        setup.name
    );
    let mut nine = [0.0; 9];
    nine[4] = want_g;
    engines_agree(label, &m, setup, nine, &[4]);
}

// ---------------------------------------------------------------------------------------
// Independent special functions: erf for Beckmann's Λ, and a real-arithmetic conductor
// Fresnel.

/// erf by its Maclaurin series `2/√π Σ (−1)ⁿ a^(2n+1)/(n!(2n+1))`, for a ≤ 1 (where no
/// term exceeds the first, so the alternating sum keeps its digits).
fn erf_series(a: f64) -> f64 {
    assert!(
        (0.0..=1.0).contains(&a),
        "erf_series is for a in [0, 1], got {a}"
    );
    let (mut power, mut sum) = (a, 0.0);
    for n in 0..200 {
        let term = power / f64::from(2 * n + 1);
        sum += term;
        if term.abs() < 1e-17 * sum.abs() {
            break;
        }
        power *= -a * a / f64::from(n + 1);
    }
    2.0 / sqrt(PI) * sum
}

/// Beckmann's Smith `Λ(a) = (erf(a) − 1)/2 + exp(−a²)/(2a√π)` (FORMULAS.md §3).
/// a ≤ 1: the series. a > 1: Laplace's continued fraction
/// `√π e^{a²} erfc(a) = 1/(a + T)`, `T = (1/2)/(a + 1/(a + (3/2)/(a + …)))`, which turns Λ
/// into `exp(−a²)/(2√π) · T/(a (a + T))` with no cancellation.
fn beckmann_lambda(a: f64) -> f64 {
    let g = (-a * a).exp() / (2.0 * a * sqrt(PI));
    if a <= 1.0 {
        (erf_series(a) - 1.0) / 2.0 + g
    } else {
        let mut t = 0.0;
        for n in (1..=20_000).rev() {
            t = (f64::from(n) / 2.0) / (a + t);
        }
        g * t / (a + t)
    }
}

/// GGX's Smith `Λ = (−1 + √(1 + m² tan²θ))/2`, given `x = m² tan²θ` (FORMULAS.md §3).
fn ggx_lambda(x: f64) -> f64 {
    (-1.0 + sqrt(1.0 + x)) / 2.0
}

/// FORMULAS.md §4's dielectric Fresnel, written exactly as printed there.
fn dielectric(c: f64, mu: f64) -> f64 {
    let g2 = mu * mu + c * c - 1.0;
    if g2 < 0.0 {
        return 1.0;
    }
    let g = sqrt(g2);
    let q = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    0.5 * ((g - c) / (g + c)).powi(2) * (1.0 + q * q)
}

/// Exact conductor Fresnel in real arithmetic (the a²/b² form: pbrt-v3 `FrConductor`,
/// after S. Lagarde, "Memo on Fresnel equations", 2013): an independent route to the same
/// quantity as FORMULAS.md §4's complex-η form.
fn conductor(c: f64, n: f64, k: f64) -> f64 {
    let (cos2, sin2) = (c * c, 1.0 - c * c);
    let t0 = n * n - k * k - sin2;
    let a2_plus_b2 = sqrt(t0 * t0 + 4.0 * n * n * k * k);
    let t1 = a2_plus_b2 + cos2;
    let a = sqrt(0.5 * (a2_plus_b2 + t0));
    let t2 = 2.0 * c * a;
    let rs = (t1 - t2) / (t1 + t2);
    let t3 = cos2 * a2_plus_b2 + sin2 * sin2;
    let t4 = t2 * sin2;
    let rp = rs * (t3 - t4) / (t3 + t4);
    0.5 * (rp + rs)
}

// ---------------------------------------------------------------------------------------
// Models (FORMULAS.md §6)

#[test]
fn lambert() {
    // c_diff/π; D = 0 (no lobe), G = F = K = 1.
    let diffuse = [0.2, 0.4, 0.6];
    check(
        "lambert",
        "model = \"lambert\"\ndiffuse = [0.2, 0.4, 0.6]",
        &tilted(),
        &lobe_model(diffuse, [1.0; 3], 0.0),
    );
}

#[test]
fn phong() {
    // L at 60°, V = N: r = 2 cos_i n − l is at −60°, r·v = cos 60° = 1/2.
    // e = 3: (e+2)/(2π) (r·v)^e = 5/(2π) · 1/8 = 5/(16π).
    let body = "model = \"phong\"\nexponent = 3\ndiffuse = 0.1\nspecular = [1.0, 0.5, 0.25]";
    let lobe = 5.0 / (16.0 * PI);
    check(
        "phong",
        body,
        &sixty_normal(),
        &lobe_model([0.1; 3], [1.0, 0.5, 0.25], lobe),
    );
    // L = V at 60°: r·v = 2 cos²60° − 1 = −1/2 < 0, so the lobe is max(0, ·)^e = 0.
    let same = Setup {
        name: "L = V at 60°",
        l: in_xz(60.0),
        v: in_xz(60.0),
        ..sixty_normal()
    };
    check(
        "phong, r·v < 0",
        body,
        &same,
        &lobe_model([0.1; 3], [1.0, 0.5, 0.25], 0.0),
    );
}

#[test]
fn blinn_phong() {
    // cos_h^e/(π cos_i), e = 4: (√2/2)⁴ / (π (√6 − √2)/4) = 1/(π (√6 − √2)).
    let lobe = 1.0 / (PI * (sqrt(6.0) - sqrt(2.0)));
    check(
        "blinn-phong",
        "model = \"blinn-phong\"\nexponent = 4\ndiffuse = [0.3, 0.2, 0.1]\nspecular = 0.5",
        &tilted(),
        &lobe_model([0.3, 0.2, 0.1], [0.5; 3], lobe),
    );
}

#[test]
fn rtr() {
    // (e+8)/(8π) cos_h^e, e = 4: 12/(8π) · 1/4 = 3/(8π).
    check(
        "rtr",
        "model = \"rtr\"\nexponent = 4\nspecular = [0.9, 0.6, 0.3]",
        &tilted(),
        &lobe_model([0.0; 3], [0.9, 0.6, 0.3], 3.0 / (8.0 * PI)),
    );
}

#[test]
fn ward_isotropic() {
    // exp(−tan²δ/m²)/(4π m² √(cos_i cos_o)), m = 1/2: e^{−4}/(4π · 1/4 · 1/2) = 2e^{−4}/π.
    check(
        "ward iso",
        "model = \"ward\"\nroughness = 0.5\ndiffuse = 0.25",
        &tilted(),
        &lobe_model([0.25; 3], [1.0; 3], 2.0 * (-4.0f64).exp() / PI),
    );
}

#[test]
fn ward_anisotropic() {
    // exp(−((hx/mx)² + (hy/my)²)/hz²)/(4π mx my √(cos_i cos_o)), (hx/hz)² = 1/4,
    // (hy/hz)² = 3/4. [mx, my] = [0.5, 1]: exponent −(1/4/0.25 + 3/4/1) = −1.75, and
    // 4π · 0.5 · 1 · 1/2 = π: e^{−1.75}/π. Swapped, [1, 0.5]: −(1/4 + 3) = −3.25.
    let s = tilted().with_t(tangent60());
    check(
        "ward aniso [0.5, 1]",
        "model = \"ward\"\nroughness = [0.5, 1.0]",
        &s,
        &lobe_model([0.0; 3], [1.0; 3], (-1.75f64).exp() / PI),
    );
    check(
        "ward aniso [1, 0.5]",
        "model = \"ward\"\nroughness = [1.0, 0.5]",
        &s,
        &lobe_model([0.0; 3], [1.0; 3], (-3.25f64).exp() / PI),
    );
}

#[test]
fn cook_torrance_full() {
    // Beckmann m = 0.5 (modern): D = e^{−1/m²}/(π m² cos⁴δ) = 16 e^{−4}/π; separable Smith
    // with a = 1/(m tan θ): a_i = 2/(2+√3) = 4 − 2√3, a_o = 2/(2−√3) = 4 + 2√3; dielectric
    // μ = 1.5 at c = √3/2 (g² = 9/4 + 3/4 − 1 = 2); K = 1/(4 cos_i cos_o) = 1.
    // f = d c_diff/π + s c_spec D G F K with d = 0.9, s = 0.1.
    let s3 = sqrt(3.0);
    let d = 16.0 * (-4.0f64).exp() / PI;
    let g =
        1.0 / ((1.0 + beckmann_lambda(4.0 + 2.0 * s3)) * (1.0 + beckmann_lambda(4.0 - 2.0 * s3)));
    // r = (g − c)/(g + c) = (2√2 − √3)/(2√2 + √3); q = (c(g+c) − 1)/(c(g−c) + 1) =
    // (√6/2 − 1/4)/(√6/2 + 1/4) = (2√6 − 1)/(2√6 + 1).
    let r = (2.0 * sqrt(2.0) - s3) / (2.0 * sqrt(2.0) + s3);
    let q = (2.0 * sqrt(6.0) - 1.0) / (2.0 * sqrt(6.0) + 1.0);
    let f = 0.5 * r * r * (1.0 + q * q);
    let (diffuse, specular) = ([0.5, 0.25, 0.125], [1.0, 0.5, 0.25]);
    let want = Want {
        brdf: std::array::from_fn(|c| 0.9 * diffuse[c] / PI + 0.1 * specular[c] * d * g * f),
        d,
        g,
        f: [f; 3],
        k: 1.0,
    };
    check(
        "cook-torrance with diffuse",
        r#"model = "cook-torrance"
distribution = "beckmann"
roughness = 0.5
geometry = "smith"
fresnel = "dielectric"
ior = 1.5
diffuse = [0.5, 0.25, 0.125]
specular = [1.0, 0.5, 0.25]
diffuse_weight = 0.9
specular_weight = 0.1"#,
        &tilted(),
        &want,
    );
}

#[test]
fn gold_preset() {
    // The gold preset: GGX α = 0.3, height-correlated Smith, conductor Fresnel with
    // (n, k) = (0.166, 3.15), (0.430, 2.46), (1.38, 1.92).
    // D = m²/(π cos⁴δ (m² + tan²δ)²) = 0.09/(π/4 · 1.09²); K = 1.
    let m2 = 0.09;
    let d = m2 / (PI / 4.0 * (m2 + 1.0) * (m2 + 1.0));
    let (t2i, t2o) = (7.0 + 4.0 * sqrt(3.0), 7.0 - 4.0 * sqrt(3.0));
    let g = 1.0 / (1.0 + ggx_lambda(m2 * t2o) + ggx_lambda(m2 * t2i));
    let c = sqrt(3.0) / 2.0;
    let f = [
        conductor(c, 0.166, 3.15),
        conductor(c, 0.430, 2.46),
        conductor(c, 1.38, 1.92),
    ];
    check(
        "preset gold",
        "preset = \"gold\"",
        &tilted(),
        &microfacet(d, g, f, 1.0),
    );
}

// ---------------------------------------------------------------------------------------
// Distributions D (FORMULAS.md §2), with G = F = 1

const CT_PLAIN: &str = "model = \"cook-torrance\"\ngeometry = \"none\"\nfresnel = \"none\"\n";

#[test]
fn d_gaussian() {
    // exp(−(δ/m)²), δ = π/4, m = 0.5: exp(−π²/4). In the seed convention K = 1/cos_o =
    // 4/(√6 + √2) = √6 − √2; in the modern one K = 1.
    let d = (-PI * PI / 4.0).exp();
    let body = format!("{CT_PLAIN}distribution = \"gaussian\"\nroughness = 0.5\n");
    check(
        "gaussian, seed",
        &format!("{body}convention = \"seed\""),
        &tilted(),
        &microfacet(d, 1.0, [1.0; 3], sqrt(6.0) - sqrt(2.0)),
    );
    check(
        "gaussian, modern",
        &body,
        &tilted(),
        &microfacet(d, 1.0, [1.0; 3], 1.0),
    );
}

#[test]
fn d_beckmann_each_convention() {
    // exp(−tan²δ/m²)/(k m² cos⁴δ), m = 0.5.
    // Tilted (tan²δ = 1, cos⁴δ = 1/4): e^{−4}/(k/16) = 16 e^{−4}/k.
    // sixty_normal (tan²δ = 1/3, cos⁴δ = 9/16): e^{−4/3}/(k · 1/4 · 9/16) = 64 e^{−4/3}/(9k).
    // K: tilted: seed √6 − √2, 1982 1/(π/4) = 4/π, modern 1;
    //    sixty_normal (cos_i = 1/2, cos_o = 1): seed 1, 1982 2/π, modern 1/2.
    let cases = [
        ("seed", 4.0, sqrt(6.0) - sqrt(2.0), 1.0),
        ("cook-torrance-1982", 1.0, 4.0 / PI, 2.0 / PI),
        ("modern", PI, 1.0, 0.5),
    ];
    for (convention, k_norm, k_tilted, k_sixty) in cases {
        let body = format!(
            "{CT_PLAIN}distribution = \"beckmann\"\nroughness = 0.5\nconvention = \"{convention}\""
        );
        let d_tilted = 16.0 * (-4.0f64).exp() / k_norm;
        let d_sixty = 64.0 * (-4.0f64 / 3.0).exp() / (9.0 * k_norm);
        check(
            &format!("beckmann, {convention}"),
            &body,
            &tilted(),
            &microfacet(d_tilted, 1.0, [1.0; 3], k_tilted),
        );
        check(
            &format!("beckmann, {convention}"),
            &body,
            &sixty_normal(),
            &microfacet(d_sixty, 1.0, [1.0; 3], k_sixty),
        );
    }
}

#[test]
fn d_ggx() {
    // m²/(π cos⁴δ (m² + tan²δ)²), m = 0.5: 0.25/(π/4 · 1.25²) = 1/(1.5625 π).
    check(
        "ggx",
        &format!("{CT_PLAIN}distribution = \"ggx\"\nroughness = 0.5"),
        &tilted(),
        &microfacet(1.0 / (1.5625 * PI), 1.0, [1.0; 3], 1.0),
    );
}

#[test]
fn d_blinn() {
    // (e+2)/(2π) cos_h^e, e = 4: 6/(2π) · 1/4 = 3/(4π). In cook-torrance-1982, K = 4/π.
    check(
        "blinn",
        &format!(
            "{CT_PLAIN}distribution = \"blinn\"\nexponent = 4\nconvention = \"cook-torrance-1982\""
        ),
        &tilted(),
        &microfacet(3.0 / (4.0 * PI), 1.0, [1.0; 3], 4.0 / PI),
    );
}

#[test]
fn d_charlie() {
    // (2 + 1/m)/(2π) sin_h^(1/m) with sin_h = sin 45° = 1/√2 on tilted. m = 1/2:
    // 4/(2π) · 1/2 = 1/π; m = 1/4: 6/(2π) · 1/4 = 3/(4π); m = 1: 3/(2π) · 1/√2.
    for (m, d) in [
        (0.5, 1.0 / PI),
        (0.25, 3.0 / (4.0 * PI)),
        (1.0, 3.0 / (2.0 * sqrt(2.0) * PI)),
    ] {
        check(
            &format!("charlie m = {m}"),
            &format!("{CT_PLAIN}distribution = \"charlie\"\nroughness = {m}"),
            &tilted(),
            &microfacet(d, 1.0, [1.0; 3], 1.0),
        );
    }
    // Valid under every convention: seed, K = 1/cos_o = 4/(√6 + √2) = √6 − √2.
    check(
        "charlie m = 0.5, seed",
        &format!("{CT_PLAIN}distribution = \"charlie\"\nroughness = 0.5\nconvention = \"seed\""),
        &tilted(),
        &microfacet(1.0 / PI, 1.0, [1.0; 3], sqrt(6.0) - sqrt(2.0)),
    );
    // L at 60°, V = N: h at 30°, sin_h = 1/2: m = 1/2 gives 4/(2π) · 1/4 = 1/(2π); K = 1/2.
    check(
        "charlie m = 0.5, V = N",
        &format!("{CT_PLAIN}distribution = \"charlie\"\nroughness = 0.5"),
        &sixty_normal(),
        &microfacet(1.0 / (2.0 * PI), 1.0, [1.0; 3], 0.5),
    );
    // With neubelt: D G K = (1/π) · 1/(2√6 − 1) (see g_neubelt), i.e. D times the
    // visibility 1/(4(cos_i + cos_o − cos_i cos_o)) of FORMULAS.md §3.
    check(
        "charlie m = 0.5 + neubelt",
        "model = \"cook-torrance\"\ndistribution = \"charlie\"\nroughness = 0.5\ngeometry = \"neubelt\"\nfresnel = \"none\"",
        &tilted(),
        &microfacet(1.0 / PI, 1.0 / (2.0 * sqrt(6.0) - 1.0), [1.0; 3], 1.0),
    );
    // h = n (L = V = N): sin_h = 0, so D = 0 (K = 1/4).
    let s = Setup {
        name: "L = V = N",
        l: [0.0, 0.0, 1.0],
        ..sixty_normal()
    };
    check(
        "charlie at h = n",
        &format!("{CT_PLAIN}distribution = \"charlie\"\nroughness = 0.5"),
        &s,
        &microfacet(0.0, 1.0, [1.0; 3], 0.25),
    );
}

#[test]
fn d_beckmann_anisotropic() {
    // exp(−((hx/mx)² + (hy/my)²)/hz²)/(π mx my hz⁴), [0.5, 1]: e^{−1.75}/(π/2 · 1/4)
    // = 8 e^{−1.75}/π. Swapped [1, 0.5]: 8 e^{−3.25}/π.
    let s = tilted().with_t(tangent60());
    for (r, arg) in [("[0.5, 1.0]", -1.75f64), ("[1.0, 0.5]", -3.25)] {
        check(
            &format!("aniso beckmann {r}"),
            &format!("{CT_PLAIN}distribution = \"beckmann\"\nroughness = {r}"),
            &s,
            &microfacet(8.0 * arg.exp() / PI, 1.0, [1.0; 3], 1.0),
        );
    }
}

#[test]
fn d_ggx_anisotropic() {
    // 1/(π mx my ((hx/mx)² + (hy/my)² + hz²)²) with hx² = 1/8, hy² = 3/8, hz² = 1/2.
    // [0.5, 1]: 0.5 + 0.375 + 0.5 = 1.375. [1, 0.5]: 0.125 + 1.5 + 0.5 = 2.125.
    let s = tilted().with_t(tangent60());
    for (r, sum) in [("[0.5, 1.0]", 1.375f64), ("[1.0, 0.5]", 2.125)] {
        check(
            &format!("aniso ggx {r}"),
            &format!("{CT_PLAIN}distribution = \"ggx\"\nroughness = {r}"),
            &s,
            &microfacet(1.0 / (PI * 0.5 * sum * sum), 1.0, [1.0; 3], 1.0),
        );
    }
}

// ---------------------------------------------------------------------------------------
// Geometry terms G (FORMULAS.md §3), with F = 1, modern K = 1

/// Beckmann m = 0.5 on `tilted`: D = 16 e^{−4}/π.
fn beckmann_half(geometry: &str) -> String {
    format!(
        "model = \"cook-torrance\"\ndistribution = \"beckmann\"\nroughness = 0.5\nfresnel = \"none\"\ngeometry = \"{geometry}\""
    )
}

/// GGX m = 0.5 on `tilted`: D = 1/(1.5625 π).
fn ggx_half(geometry: &str) -> String {
    format!(
        "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 0.5\nfresnel = \"none\"\ngeometry = \"{geometry}\""
    )
}

#[test]
fn g_none_and_v_cavity() {
    // V-cavity: min(1, 2 cos_h cos_o/c, 2 cos_h cos_i/c) with 2 cos_h/c = 2(√2/2)/(√3/2)
    // = 2√2/√3: masking 2√2/√3 · (√6+√2)/4 = (√12 + 2)/(2√3) = 1 + 1/√3 (> 1), shadowing
    // (√12 − 2)/(2√3) = 1 − 1/√3.
    let d = 16.0 * (-4.0f64).exp() / PI;
    check(
        "G none",
        &beckmann_half("none"),
        &tilted(),
        &microfacet(d, 1.0, [1.0; 3], 1.0),
    );
    check(
        "G cook-torrance",
        &beckmann_half("cook-torrance"),
        &tilted(),
        &microfacet(d, 1.0 - 1.0 / sqrt(3.0), [1.0; 3], 1.0),
    );
}

#[test]
fn g_smith_beckmann() {
    // a = 1/(m tan θ), m = 0.5: a_i = 4 − 2√3 ≈ 0.536, a_o = 4 + 2√3 ≈ 7.46.
    let d = 16.0 * (-4.0f64).exp() / PI;
    let s3 = sqrt(3.0);
    let (li, lo) = (
        beckmann_lambda(4.0 - 2.0 * s3),
        beckmann_lambda(4.0 + 2.0 * s3),
    );
    check(
        "G smith, beckmann",
        &beckmann_half("smith"),
        &tilted(),
        &microfacet(d, 1.0 / (1.0 + lo) / (1.0 + li), [1.0; 3], 1.0),
    );
    check(
        "G smith-correlated, beckmann",
        &beckmann_half("smith-correlated"),
        &tilted(),
        &microfacet(d, 1.0 / (1.0 + lo + li), [1.0; 3], 1.0),
    );
    // m = 1 on sixty_normal: V = N (tan θ_o = 0, Λ = 0), a_i = 1/tan 60° = 1/√3.
    let li = beckmann_lambda(1.0 / s3);
    let body = "model = \"cook-torrance\"\ndistribution = \"beckmann\"\nroughness = 1.0\nfresnel = \"none\"\ngeometry = \"smith\"";
    check_g(
        "G smith, beckmann, V = N",
        body,
        &sixty_normal(),
        1.0 / (1.0 + li),
    );
}

#[test]
fn g_smith_ggx() {
    // x = m² tan²θ: x_i = (7 + 4√3)/4, x_o = (7 − 4√3)/4; Λ = (−1 + √(1 + x))/2.
    let d = 1.0 / (1.5625 * PI);
    let s3 = sqrt(3.0);
    let li = ggx_lambda((7.0 + 4.0 * s3) / 4.0);
    let lo = ggx_lambda((7.0 - 4.0 * s3) / 4.0);
    check(
        "G smith, ggx",
        &ggx_half("smith"),
        &tilted(),
        &microfacet(d, 1.0 / (1.0 + lo) / (1.0 + li), [1.0; 3], 1.0),
    );
    check(
        "G smith-correlated, ggx",
        &ggx_half("smith-correlated"),
        &tilted(),
        &microfacet(d, 1.0 / (1.0 + lo + li), [1.0; 3], 1.0),
    );
}

/// Walter et al. 2007's fit as FORMULAS.md §3 prints it.
fn smith_fast_g1(a: f64) -> f64 {
    if a < 1.6 {
        (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    } else {
        1.0
    }
}

#[test]
fn g_smith_fast() {
    // Tilted, m = 0.5: a_i = 4 − 2√3 (< 1.6, the rational fit), a_o = 4 + 2√3 (≥ 1.6: 1).
    let d = 16.0 * (-4.0f64).exp() / PI;
    let s3 = sqrt(3.0);
    check(
        "G smith-fast",
        &beckmann_half("smith-fast"),
        &tilted(),
        &microfacet(d, smith_fast_g1(4.0 - 2.0 * s3), [1.0; 3], 1.0),
    );
    // Both in the rational branch: L at 60°, V at −45°, m = 1: a_i = 1/√3, a_o = 1/tan 45° = 1.
    let s = Setup {
        name: "L at 60°, V at −45°",
        l: in_xz(60.0),
        v: in_xz(-45.0),
        ..sixty_normal()
    };
    let body = "model = \"cook-torrance\"\ndistribution = \"beckmann\"\nroughness = 1.0\nfresnel = \"none\"\ngeometry = \"smith-fast\"";
    check_g(
        "G smith-fast, both fitted",
        body,
        &s,
        smith_fast_g1(1.0 / s3) * smith_fast_g1(1.0),
    );
}

#[test]
fn g_smith_anisotropic() {
    // Anisotropic Λ: m² tan²θ(w) → (mx² (w·t)² + my² (w·b)²)/(n·w)². For w in the xz-plane
    // at angle θ: w·t = sin θ/2, w·b = −(√3/2) sin θ, so the projected roughness is
    // (mx²/4 + 3 my²/4) tan²θ; [0.5, 1] gives 0.8125 tan²θ.
    let s3 = sqrt(3.0);
    let (xi, xo) = (0.8125 * (7.0 + 4.0 * s3), 0.8125 * (7.0 - 4.0 * s3));
    let d = 1.0 / (PI * 0.5 * 1.375 * 1.375); // d_ggx_anisotropic
    let g = 1.0 / (1.0 + ggx_lambda(xo) + ggx_lambda(xi));
    check(
        "aniso ggx, smith-correlated",
        "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = [0.5, 1.0]\nfresnel = \"none\"\ngeometry = \"smith-correlated\"",
        &tilted().with_t(tangent60()),
        &microfacet(d, g, [1.0; 3], 1.0),
    );
    // Beckmann: a = 1/√x.
    let d = 8.0 * (-1.75f64).exp() / PI; // d_beckmann_anisotropic
    let g = 1.0 / (1.0 + beckmann_lambda(1.0 / sqrt(xo))) / (1.0 + beckmann_lambda(1.0 / sqrt(xi)));
    check(
        "aniso beckmann, smith",
        "model = \"cook-torrance\"\ndistribution = \"beckmann\"\nroughness = [0.5, 1.0]\nfresnel = \"none\"\ngeometry = \"smith\"",
        &tilted().with_t(tangent60()),
        &microfacet(d, g, [1.0; 3], 1.0),
    );
}

#[test]
fn g_schlick_smith() {
    // G1(w) = cos_w/(cos_w + k(1 − cos_w)). With a = cos_i, b = cos_o on tilted, the product
    // is ab/((k + (1−k)a)(k + (1−k)b)) = (1/4)/(k² + k(1−k)(a+b) + (1−k)²/4), as
    // a + b = √6/2 and ab = 1/4.
    let s6 = sqrt(6.0);
    let g = |k: f64| 0.25 / (k * k + k * (1.0 - k) * s6 / 2.0 + (1.0 - k) * (1.0 - k) / 4.0);
    // GGX m = 0.5: k = m/2 = 1/4, G1 = 4c/(3c + 1), G = 16ab/(9ab + 3(a+b) + 1) = 16/(13 + 6√6).
    assert!((g(0.25) - 16.0 / (13.0 + 6.0 * s6)).abs() < 1e-15);
    check(
        "G schlick-smith, ggx",
        &ggx_half("schlick-smith"),
        &tilted(),
        &microfacet(1.0 / (1.5625 * PI), 16.0 / (13.0 + 6.0 * s6), [1.0; 3], 1.0),
    );
    // Beckmann m = 0.5: k = m √(2/π) = 1/√(2π).
    check(
        "G schlick-smith, beckmann",
        &beckmann_half("schlick-smith"),
        &tilted(),
        &microfacet(
            16.0 * (-4.0f64).exp() / PI,
            g(1.0 / sqrt(2.0 * PI)),
            [1.0; 3],
            1.0,
        ),
    );
    // GGX m = 4: k = 2 > 1 (where cos(1 − k) + k would cancel): G1 = c/(2 − c), G =
    // ab/((2 − a)(2 − b)) = (1/4)/(4 − 2(a+b) + ab) = 1/(17 − 4√6).
    check_g(
        "G schlick-smith, ggx, k = 2",
        "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 4.0\nfresnel = \"none\"\ngeometry = \"schlick-smith\"",
        &tilted(),
        1.0 / (17.0 - 4.0 * s6),
    );
    // L at 60°, V = N, GGX m = 1 (k = 1/2): G1(v) = 1, G1(l) = (1/2)/(1/2 + 1/4) = 2/3.
    check_g(
        "G schlick-smith, ggx, V = N",
        "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 1.0\nfresnel = \"none\"\ngeometry = \"schlick-smith\"",
        &sixty_normal(),
        2.0 / 3.0,
    );
}

#[test]
fn g_neubelt() {
    // ab/(a + b − ab) with a + b = √6/2, ab = 1/4 on tilted: (1/4)/((2√6 − 1)/4) = 1/(2√6 − 1).
    check(
        "G neubelt, ggx",
        &ggx_half("neubelt"),
        &tilted(),
        &microfacet(
            1.0 / (1.5625 * PI),
            1.0 / (2.0 * sqrt(6.0) - 1.0),
            [1.0; 3],
            1.0,
        ),
    );
    // L at 60°, V = N: (1/2)/(1/2 + 1 − 1/2) = 1/2.
    check_g(
        "G neubelt, gaussian, V = N",
        "model = \"cook-torrance\"\ndistribution = \"gaussian\"\nroughness = 0.5\nfresnel = \"none\"\ngeometry = \"neubelt\"",
        &sixty_normal(),
        0.5,
    );
}

// ---------------------------------------------------------------------------------------
// Fresnel F (FORMULAS.md §4), with GGX m = 0.5, G = 1, modern K = 1

fn ggx_fresnel(fresnel_lines: &str) -> String {
    format!(
        "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 0.5\ngeometry = \"none\"\n{fresnel_lines}"
    )
}

#[test]
fn f_each_kind() {
    let d = 1.0 / (1.5625 * PI);
    let c = sqrt(3.0) / 2.0;
    let s = tilted();
    check(
        "F none",
        &ggx_fresnel("fresnel = \"none\""),
        &s,
        &microfacet(d, 1.0, [1.0; 3], 1.0),
    );
    // Dielectric per channel: μ = 1.5 in closed form (see cook_torrance_full), the others
    // by the printed formula.
    let r = (2.0 * sqrt(2.0) - sqrt(3.0)) / (2.0 * sqrt(2.0) + sqrt(3.0));
    let q = (2.0 * sqrt(6.0) - 1.0) / (2.0 * sqrt(6.0) + 1.0);
    let f15 = 0.5 * r * r * (1.0 + q * q);
    check(
        "F dielectric",
        &ggx_fresnel("fresnel = \"dielectric\"\nior = [1.5, 1.33, 2.4]"),
        &s,
        &microfacet(d, 1.0, [f15, dielectric(c, 1.33), dielectric(c, 2.4)], 1.0),
    );
    // Conductor (silver), by the real-arithmetic a²/b² form.
    let (n, k) = ([0.052, 0.059, 0.040], [4.41, 3.32, 2.65]);
    check(
        "F conductor",
        &ggx_fresnel(
            "fresnel = \"conductor\"\nior = [0.052, 0.059, 0.040]\nextinction = [4.41, 3.32, 2.65]",
        ),
        &s,
        &microfacet(
            d,
            1.0,
            std::array::from_fn(|i| conductor(c, n[i], k[i])),
            1.0,
        ),
    );
    // Schlick: F0 + (1 − F0)(1 − c)⁵ with 1 − c = (2 − √3)/2.
    let w = ((2.0 - sqrt(3.0)) / 2.0).powi(5);
    let schlick = |f0: f64| f0 + (1.0 - f0) * w;
    check(
        "F schlick, f0",
        &ggx_fresnel("fresnel = \"schlick\"\nf0 = [0.04, 0.5, 0.9]"),
        &s,
        &microfacet(d, 1.0, [schlick(0.04), schlick(0.5), schlick(0.9)], 1.0),
    );
    // F0 from ior alone: ((n−1)/(n+1))², 1.5 → 0.25/6.25 = 0.04; 2.0 → 1/9; 1.2 → 1/121.
    check(
        "F schlick, ior",
        &ggx_fresnel("fresnel = \"schlick\"\nior = [1.5, 2.0, 1.2]"),
        &s,
        &microfacet(
            d,
            1.0,
            [schlick(0.04), schlick(1.0 / 9.0), schlick(1.0 / 121.0)],
            1.0,
        ),
    );
    // F0 from ior and extinction: ((n−1)² + k²)/((n+1)² + k²):
    // (0.2, 3): (0.64 + 9)/(1.44 + 9) = 9.64/10.44; (1, 1): 1/5; (2, 0.5): 1.25/9.25.
    check(
        "F schlick, ior + extinction",
        &ggx_fresnel("fresnel = \"schlick\"\nior = [0.2, 1.0, 2.0]\nextinction = [3.0, 1.0, 0.5]"),
        &s,
        &microfacet(
            d,
            1.0,
            [
                schlick(9.64 / 10.44),
                schlick(1.0 / 5.0),
                schlick(1.25 / 9.25),
            ],
            1.0,
        ),
    );
}

#[test]
fn f_dielectric_normal_incidence_is_four_percent() {
    // c = 1, μ = 1.5: g = 1.5, ((g−c)/(g+c))² = 0.04, q = (2.5 − 1)/(0.5 + 1) = 1:
    // F = ½ · 0.04 · 2 = 0.04 (the seed's misprinted denominator gives 0.2).
    let f = dielectric::f(1.0, 1.5);
    assert!(
        (f - 0.04).abs() <= 1e-15,
        "dielectric_f(c = 1, μ = 1.5) = {f:.17}, want 0.04"
    );
    // Through a material: L = V = N gives c = 1.
    let m = material(&ggx_fresnel("fresnel = \"dielectric\"\nior = 1.5"));
    let z = [0.0, 0.0, 1.0];
    let e = evaluate(z, z, z, None, &m);
    for (ch, &fc) in e.f.iter().enumerate() {
        assert!(
            (fc - 0.04).abs() <= 1e-15,
            "F channel {ch} at L = V = N, μ = 1.5: {fc:.17}, want 0.04 ({e:?})"
        );
    }
}

#[test]
fn f_tends_to_one_at_grazing() {
    // Dielectric: as c → 0, g → g0 = √(μ² − 1), ((g−c)/(g+c))² ≈ 1 − 4c/g0 and
    // q ≈ −(1 − c g0)/(1 + c g0), q² ≈ 1 − 4c g0, so F ≈ (1 − 4c/g0)(1 − 2c g0): the slope
    // (1 − F)/c must approach 4/g0 + 2 g0, and F(0) = 1.
    for mu in [1.1, 1.33, 1.5, 2.4, 4.0] {
        let g0 = sqrt(mu * mu - 1.0);
        let slope = 4.0 / g0 + 2.0 * g0;
        for c in [1e-5, 1e-7] {
            let f = dielectric::f(c, mu);
            let got = (1.0 - f) / c;
            assert!(
                (got - slope).abs() <= 1e-3 * slope,
                "dielectric_f(c = {c:e}, μ = {mu}) = {f:.17}: (1 − F)/c = {got}, want → {slope}"
            );
        }
        let f0 = dielectric::f(0.0, mu);
        assert!(
            (f0 - 1.0).abs() <= 1e-15,
            "dielectric_f(0, μ = {mu}) = {f0:.17}, want 1"
        );
    }
    // Conductor: F(c) → 1, compared with the real-arithmetic form at small c.
    for (n, k) in [
        (0.166, 3.15),
        (1.47, 7.79),
        (0.2, 0.5),
        (1.5, 0.0),
        (2.0, 1.0),
    ] {
        for c in [1e-3, 1e-6, 1e-9] {
            let f = conductor::f(c, n, k);
            let want = conductor(c, n, k);
            assert!(
                (f - want).abs() <= 1e-12 && (1.0 - f) <= 40.0 * c,
                "conductor_f(c = {c:e}, n = {n}, k = {k}) = {f:.17}, want {want:.17} → 1"
            );
        }
        let f0 = conductor::f(0.0, n, k);
        assert!(
            (f0 - 1.0).abs() <= 1e-15,
            "conductor_f(0, n = {n}, k = {k}) = {f0:.17}, want 1"
        );
    }
}

#[test]
fn f_conductor_without_extinction_is_dielectric() {
    for mu in [1.0, 1.0001, 1.2, 1.33, 1.5, 2.4, 4.0, 10.0] {
        // c in (0, 1]: at c = 0 with μ = 1 both forms are 0/0 (c > 0 whenever the tuple is
        // above the horizon).
        for i in 1..=20 {
            let c = f64::from(i) / 20.0;
            let (fc, fd) = (conductor::f(c, mu, 0.0), dielectric::f(c, mu));
            let want = dielectric(c, mu);
            assert!(
                (fc - fd).abs() <= 1e-12 * fd + 1e-15 && (fd - want).abs() <= 1e-12 * want + 1e-15,
                "c = {c}, μ = {mu}: conductor_f(k = 0) = {fc:e}, dielectric_f = {fd:e}, \
                 FORMULAS dielectric = {want:e}"
            );
        }
    }
}

#[test]
fn f_dielectric_total_internal_reflection() {
    // μ < 1: g² = μ² + c² − 1 < 0 for c < c_crit = √(1 − μ²): F = 1 exactly; above it F < 1.
    for mu in [1.0 / 1.5, 1.0 / 1.33, 0.5] {
        let c_crit = sqrt(1.0 - mu * mu);
        for frac in [0.0, 0.1, 0.5, 0.9, 0.999] {
            let c = frac * c_crit;
            let f = dielectric::f(c, mu);
            assert_eq!(
                f, 1.0,
                "dielectric_f(c = {c}, μ = {mu}), below c_crit = {c_crit}: {f}"
            );
        }
        for c in [c_crit + 0.01, (c_crit + 1.0) / 2.0, 1.0] {
            let (f, want) = (dielectric::f(c, mu), dielectric(c, mu));
            assert!(
                f < 1.0 && (f - want).abs() <= 1e-12 * want,
                "dielectric_f(c = {c}, μ = {mu}) = {f}, want {want} (< 1, above c_crit {c_crit})"
            );
        }
    }
    // Through a material: L at 80°, V at −80°: h = n, c = cos 80° ≈ 0.17 < c_crit ≈ 0.75.
    let s = Setup {
        name: "L at 80°, V at −80°",
        l: in_xz(80.0),
        v: in_xz(-80.0),
        ..sixty_normal()
    };
    let e = s.eval(&material(&ggx_fresnel(
        "fresnel = \"dielectric\"\nior = 0.6666666666666666",
    )));
    assert_eq!(e.f, [1.0; 3], "TIR through a material at {s:?}: {e:?}");
}

// ---------------------------------------------------------------------------------------
// Conventions K (FORMULAS.md §5) are checked in `d_beckmann_each_convention` (both
// geometries, all three) and `d_gaussian` / `d_blinn`; here every convention with a
// non-Beckmann D, where only K differs.

#[test]
fn k_each_convention() {
    let d = 1.0 / (1.5625 * PI); // GGX, m = 0.5, tilted
    for (convention, k) in [
        ("seed", sqrt(6.0) - sqrt(2.0)),
        ("cook-torrance-1982", 4.0 / PI),
        ("modern", 1.0),
    ] {
        check(
            &format!("K {convention}"),
            &format!(
                "{}\nconvention = \"{convention}\"",
                ggx_fresnel("fresnel = \"none\"")
            ),
            &tilted(),
            &microfacet(d, 1.0, [1.0; 3], k),
        );
    }
}

// ---------------------------------------------------------------------------------------
// Frame independence: rotating every input together changes nothing.

fn rotate(a: [f64; 3], axis: [f64; 3], angle: f64) -> [f64; 3] {
    // Rodrigues: a cos θ + (k × a) sin θ + k (k·a)(1 − cos θ).
    let (s, c) = angle.sin_cos();
    let kxa = [
        axis[1] * a[2] - axis[2] * a[1],
        axis[2] * a[0] - axis[0] * a[2],
        axis[0] * a[1] - axis[1] * a[0],
    ];
    let ka = axis[0] * a[0] + axis[1] * a[1] + axis[2] * a[2];
    std::array::from_fn(|i| a[i] * c + kxa[i] * s + axis[i] * ka * (1.0 - c))
}

#[test]
fn rotated_frame_gives_the_same_values() {
    let len = sqrt(14.0);
    let axis = [1.0 / len, 2.0 / len, 3.0 / len];
    let base = tilted().with_t(tangent60());
    let rot = |a: [f64; 3]| rotate(a, axis, 0.7);
    let rotated = Setup {
        name: "tilted, rotated 0.7 rad about (1, 2, 3)",
        l: rot(base.l),
        v: rot(base.v),
        n: rot(base.n),
        t: base.t.map(rot),
    };
    for body in [
        "preset = \"gold\"".to_string(),
        "preset = \"shiny-plastic\"".to_string(),
        "model = \"ward\"\nroughness = [0.5, 1.0]".to_string(),
        "model = \"rtr\"\nexponent = 7".to_string(),
        beckmann_half("cook-torrance"),
        "model = \"cook-torrance\"\ndistribution = \"beckmann\"\nroughness = [0.3, 0.6]\ngeometry = \"smith-correlated\"\nfresnel = \"schlick\"\nf0 = 0.04".to_string(),
    ] {
        let m = material(&body);
        let (a, b) = (base.eval(&m), rotated.eval(&m));
        let pairs = [
            a.brdf[0], b.brdf[0], a.brdf[1], b.brdf[1], a.brdf[2], b.brdf[2], a.d, b.d, a.g, b.g,
            a.f[0], b.f[0], a.k, b.k,
        ];
        for p in pairs.chunks(2) {
            assert!(
                a.status == Status::Valid && close(p[1], p[0], TOL),
                "material:\n{body}\nunrotated {a:?}\nrotated   {b:?}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// §1: invalid tuples and the horizon

fn assert_all_zero(e: &Evaluation, status: Status, ctx: &str) {
    assert_eq!(e.status, status, "{ctx}: {e:?}");
    assert!(
        e.brdf == [0.0; 3] && e.d == 0.0 && e.g == 0.0 && e.f == [0.0; 3] && e.k == 0.0,
        "{ctx}: outputs must all be 0: {e:?}"
    );
}

#[test]
fn invalid_directions() {
    let s = tilted();
    let bad: [[f64; 3]; 6] = [
        [0.0; 3],
        [f64::NAN, 0.0, 1.0],
        [0.0, f64::INFINITY, 1.0],
        [0.0, 0.0, f64::NEG_INFINITY],
        [f64::NAN; 3],
        [-0.0, 0.0, -0.0],
    ];
    for body in [
        "model = \"lambert\"\ndiffuse = 0.5".to_string(),
        beckmann_half("smith"),
        "model = \"ward\"\nroughness = [0.5, 1.0]".to_string(),
    ] {
        let m = material(&body);
        for x in bad {
            for (which, setup) in [
                ("L", Setup { l: x, ..s }),
                ("V", Setup { v: x, ..s }),
                ("N", Setup { n: x, ..s }),
            ] {
                let setup = setup.with_t(tangent60());
                assert_all_zero(
                    &setup.eval(&m),
                    Status::Invalid,
                    &format!("{which} = {x:?}, material:\n{body}"),
                );
            }
        }
        // The invalid test comes before the horizon test: zero L with V below the horizon.
        let e = Setup {
            l: [0.0; 3],
            v: [1.0, 0.0, -1.0],
            ..s
        }
        .with_t(tangent60())
        .eval(&m);
        assert_all_zero(
            &e,
            Status::Invalid,
            &format!("zero L, V below, material:\n{body}"),
        );
    }
}

#[test]
fn anisotropic_tangent_rules() {
    let s = tilted();
    let n = [0.0, 0.0, 1.0];
    for body in [
        "model = \"ward\"\nroughness = [0.5, 1.0]",
        "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = [0.5, 1.0]\ngeometry = \"smith\"\nfresnel = \"none\"",
        "model = \"cook-torrance\"\ndistribution = \"beckmann\"\nroughness = [0.5, 1.0]\ngeometry = \"none\"\nfresnel = \"none\"",
    ] {
        let m = material(body);
        // Missing, zero, non-finite, parallel (either sign, any length) or within 1e-12
        // of parallel (|T − n(n·T)| ≤ 1e-12 |T|): invalid.
        let bad = [
            None,
            Some([0.0; 3]),
            Some([f64::NAN, 1.0, 0.0]),
            Some([1.0, f64::INFINITY, 0.0]),
            Some(scale(n, 5.0)),
            Some(scale(n, -1e-3)),
            Some([1e-13, 0.0, 1.0]),
            Some([0.0, 3e-13, -3.0]),
        ];
        for t in bad {
            assert_all_zero(
                &s.with_t(t).eval(&m),
                Status::Invalid,
                &format!("T = {t:?}, N = {:?}, material:\n{body}", s.n),
            );
        }
        // Just outside the threshold (1e-11 of |T|) the tangent is usable.
        let e = s.with_t(Some([1e-11, 0.0, 1.0])).eval(&m);
        assert_eq!(e.status, Status::Valid, "T nearly along N (1e-11): {e:?}\n{body}");
        // Invalid before below-horizon: a missing tangent with L below the horizon.
        let e = Setup { l: [1.0, 0.0, -0.5], ..s }.eval(&m);
        assert_all_zero(&e, Status::Invalid, &format!("no T, L below, material:\n{body}"));
    }
}

#[test]
fn isotropic_materials_ignore_the_tangent() {
    let s = tilted();
    for body in [
        "model = \"ward\"\nroughness = 0.4".to_string(),
        beckmann_half("smith-correlated"),
        "preset = \"gold\"".to_string(),
        "model = \"blinn-phong\"\nexponent = 20".to_string(),
    ] {
        let m = material(&body);
        let reference = s.with_t(None).eval(&m);
        assert_eq!(reference.status, Status::Valid, "{body}");
        for t in [
            Some([0.0; 3]),
            Some([f64::NAN; 3]),
            Some([f64::INFINITY, 0.0, 0.0]),
            Some([0.0, 0.0, 1.0]),
            tangent60(),
        ] {
            let e = s.with_t(t).eval(&m);
            assert_eq!(e, reference, "isotropic material with T = {t:?}:\n{body}");
        }
    }
}

#[test]
fn below_horizon() {
    let z = [0.0, 0.0, 1.0];
    let up = in_xz(30.0);
    let cases = [
        ("cos_i = 0", [1.0, 0.0, 0.0], up),
        ("cos_o = 0", up, [0.0, -1.0, 0.0]),
        ("cos_i < 0", [0.3, 0.2, -0.5], up),
        ("cos_o < 0", up, [0.0, 0.0, -1.0]),
        ("both < 0", [0.0, 0.0, -1.0], [0.1, 0.0, -1.0]),
        ("L = −V", [0.6, 0.0, 0.8], [-0.6, 0.0, -0.8]),
    ];
    for body in [
        "model = \"lambert\"\ndiffuse = 0.5".to_string(),
        "model = \"blinn-phong\"\nexponent = 3".to_string(),
        beckmann_half("smith"),
        "preset = \"shiny-plastic\"".to_string(),
        "model = \"ward\"\nroughness = [0.5, 1.0]".to_string(),
    ] {
        let m = material(&body);
        for (name, l, v) in cases {
            let e = evaluate(l, v, z, Some([1.0, 0.0, 0.0]), &m);
            assert_all_zero(
                &e,
                Status::BelowHorizon,
                &format!("{name}: L = {l:?}, V = {v:?}, material:\n{body}"),
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// §2's guard: Beckmann at grazing cos_h

/// L = V = (1, 0, z) with N = +z: then h = l, `cos_h = cos_i = cos_o = z` exactly (for
/// z ≤ 1e-8, `1 + z²` rounds to 1), `sin²δ = |n × h|² = 1` and `c = 1`.
fn grazing(z: f64) -> Setup {
    Setup {
        name: "L = V = (1, 0, z), N = +z",
        l: [1.0, 0.0, z],
        v: [1.0, 0.0, z],
        n: [0.0, 0.0, 1.0],
        t: None,
    }
}

/// Checks Beckmann (modern, G = F = 1) at `grazing(z)` with roughness `m` against the
/// log-domain value `ln D = −tan²δ/m² − 4 ln cos δ − ln(π m²)`, `tan²δ = 1/z²`.
fn check_grazing_beckmann(z: f64, m: f64) {
    let body = format!(
        "model = \"cook-torrance\"\ndistribution = \"beckmann\"\nroughness = {m:e}\ngeometry = \"none\"\nfresnel = \"none\""
    );
    let terms = [
        -(1.0 / (z * z)) / (m * m),
        -4.0 * z.ln(),
        -(PI * m * m).ln(),
    ];
    let ln_d: f64 = terms.iter().sum();
    // ln K = −ln(4 cos_i cos_o) = −ln 4 − 2 ln z.
    let ln_k = -(4.0f64.ln()) - 2.0 * z.ln();
    let (d, k) = (ln_d.exp(), ln_k.exp());
    assert!(
        d.is_normal(),
        "pick z, m with a representable D (ln D = {ln_d})"
    );
    // The value is e^{ln D} with ln D the sum of terms of size up to ~2000: each carries an
    // absolute rounding of ≤ ε/2 per unit, a relative error of the same size in D.
    let size: f64 = terms.iter().map(|t| t.abs()).sum::<f64>() + ln_k.abs();
    let tol = TOL.max(4.0 * f64::EPSILON * size);
    // m up to 3.5e98 is beyond the parser's range (roughness ≤ 1e4: the float32 kernel cannot
    // hold m²), so the reference's f64 guard is exercised as an f64 caller would: the
    // material is parsed at m = 1 and its roughness set afterwards.
    let mut material = material(&body.replace(&format!("roughness = {m:e}"), "roughness = 1"));
    if let vkbrdf::material::Model::CookTorrance(ct) = &mut material.model {
        ct.distribution =
            vkbrdf::material::Distribution::Beckmann(vkbrdf::material::Roughness::Isotropic(m));
    }
    check_material(
        &format!("grazing beckmann, z = {z:e}, m = {m:e}"),
        &material,
        &body,
        &grazing(z),
        &Want {
            brdf: [(ln_d + ln_k).exp(); 3],
            d,
            g: 1.0,
            f: [1.0; 3],
            k,
        },
        tol,
    );
}

#[test]
fn beckmann_guard_log_domain() {
    // z = 1e-10, tan²δ/m² = 720: exp(−720) ≈ 1.2e-313 is subnormal while cos⁴ = 1e-40 is
    // fine; D = exp(−720 + 92.1 − 40.6) ≈ 5e-291.
    check_grazing_beckmann(1e-10, 1e10 / sqrt(720.0));
    // z = 1e-100, tan²δ/m² = 800: exp(−800) underflows to 0 and cos⁴ = 1e-400 to 0 (the
    // direct quotient is 0/0 = NaN), yet D = exp(−800 + 921.0 − 455.0) ≈ 9e-146.
    check_grazing_beckmann(1e-100, 1e100 / sqrt(800.0));
}

#[test]
fn beckmann_guard_true_underflow_is_zero() {
    // z = 1e-100, m = 1: tan²δ/m² = 1e200, D = exp(−1e200 + …) underflows: exactly 0, and
    // so is the BRDF (K = 1/(4e-200) = 2.5e199 is finite).
    for (z, m) in [(1e-100, 1.0), (1e-100, 0.3), (1e-10, 1e-3), (1e-3, 1e-3)] {
        let body = format!(
            "model = \"cook-torrance\"\ndistribution = \"beckmann\"\nroughness = {m:e}\ngeometry = \"smith\"\nfresnel = \"dielectric\"\nior = 1.5"
        );
        let e = grazing(z).eval(&material(&body));
        assert!(
            e.status == Status::Valid && e.d == 0.0 && e.brdf == [0.0; 3],
            "z = {z:e}, m = {m}: D and the BRDF must be exactly 0 (true value underflows): {e:?}"
        );
    }
    // Anisotropic Beckmann shares the guard.
    let body = "model = \"cook-torrance\"\ndistribution = \"beckmann\"\nroughness = [0.5, 1.0]\ngeometry = \"none\"\nfresnel = \"none\"";
    let e = grazing(1e-100)
        .with_t(Some([0.0, 1.0, 0.0]))
        .eval(&material(body));
    assert!(
        e.status == Status::Valid && e.d == 0.0 && e.brdf == [0.0; 3],
        "aniso beckmann at z = 1e-100: D and the BRDF must be 0: {e:?}"
    );
}

#[test]
fn grazing_product_is_never_nan() {
    // z = 1e-170: cos_i cos_o = 1e-340 underflows, so K = 1/(4 cos_i cos_o) = +∞, while D
    // (Beckmann, tan²δ = 1e340 → ∞) is exactly 0. The true BRDF is
    // exp(−4e340)/(π/4 · 1e-680) / 4e-340 = 0: it must come out 0, not 0·∞ = NaN
    // (FORMULAS.md §2: every form stays finite where its mathematical value is finite).
    let s = grazing(1e-170);
    for body in [
        "model = \"cook-torrance\"\ndistribution = \"beckmann\"\nroughness = 0.5\ngeometry = \"none\"\nfresnel = \"none\"",
        "model = \"cook-torrance\"\ndistribution = \"beckmann\"\nroughness = 0.5\ngeometry = \"smith\"\nfresnel = \"schlick\"\nf0 = 0.04",
    ] {
        let e = s.eval(&material(body));
        assert!(
            e.status == Status::Valid && e.brdf == [0.0; 3],
            "BRDF must be exactly 0 at {} with z = 1e-170 (true value underflows):\n\
             material:\n{body}\ngot {e:?}",
            s.name
        );
    }
    // The Gaussian with the V-cavity: G = 2 cos_h cos_i/c = 2e-340 underflows to 0 while
    // G·K = cos_h/(2 c cos_o) = 1/2, so f = D/2 = exp(−(δ/0.1)²)/2 with δ = atan2(1, 1e-170)
    // = π/2: exp(−25π²)/2 ≈ 3.5e-108. Required: finite, ≥ 0 and not above the true value
    // (FORMULAS.md asks finiteness here; 0, from G's underflow, is accepted).
    let body = "model = \"cook-torrance\"\ndistribution = \"gaussian\"\nroughness = 0.1\ngeometry = \"cook-torrance\"\nfresnel = \"none\"";
    let e = s.eval(&material(body));
    let want = (-25.0 * PI * PI).exp() / 2.0;
    assert!(
        e.status == Status::Valid
            && e.brdf.iter().all(|&x| x.is_finite() && (0.0..=want * (1.0 + TOL)).contains(&x)),
        "BRDF must be finite and in [0, {want:e}] at {} with z = 1e-170:\nmaterial:\n{body}\ngot {e:?}",
        s.name
    );
}

// ---------------------------------------------------------------------------------------
// Index-matched interfaces at grazing incidence (issue 10, item 6), on the reference and
// on every backend (Vulkan on lavapipe in CI).
//
// Geometry: N = +z, L = (1, 0, ε), V = (−1, 0, ε) in f32, ε ∈ {1e-4, 1e-8, 1e-12} (each
// the f32 number nearest to it, so the expectations use exactly what the backends read).
// An exact mirror configuration: l + v = (0, 0, 2ε)/|L|, so h = n, cos_h = 1, sin²δ = 0,
// and cos_i = cos_o = c = γ = ε/√(1 + ε²).
//
// Materials: Cook–Torrance, GGX m = 1/2 (D = m²/(π m⁴) = 1/(π m²) = 4/π at cos_h = 1),
// geometry none (G = 1), modern convention (K = 1/(4γ²)), diffuse 0.2 at weight 0.5, so
// f = 0.5·0.2/π + D·G·F·K = 0.1/π + (4/π)·F/(4γ²).
//
// - Conductor η = 1 + 0i: sin²θt = 1 − c², cos θt = c, so r∥ = (c − c)/(2c) = 0 and
//   r⊥ = 0: F = 0 exactly, and f = 0.1/π = 0.0318 (the old reference gave F = 1 at
//   ε = 1e-8 and f = 1/(π γ²)·… ≈ 2e5 here; the issue's 201,302).
// - Dielectric μ = 1: g² = c², g = c, F = ½·0²·(…) = 0 exactly; f = 0.1/π.
// - Conductor η = 1 + ik with k = 1e-13 at ε = 1e-4 (k ≪ c²): with g = η cos θt =
//   √(η² − 1 + c²) = c(1 + ik/c² + O(k²/c⁴)), r⊥ = (1 − η²)/(c + g)² and
//   r∥ = (η² − 1)((η² + 1)c² − 1)/(η² (ηc + cos θt)²) give |r⊥|² = k²/(4c⁴)·(1 + O(k²/c⁴)),
//   |r∥|² = k²(1 − 2c²)²/(4c⁴)·(1 + O(k²/c⁴)), so F = k²/(8c⁴)·(1 + (1 − 2c²)²) to a
//   relative 1e-10 (= (k/c²)²). F ≈ 2.5e-13: the old reference, which formed 1 − (1 − c²)/η²,
//   was 1e-3 off.
// - Conductor η = 1 + ik with k = 1e-6 at ε = 1e-8 and 1e-12 (c ≪ √k): to first order in
//   c/g, r⊥ = −1 + 2c/g and r∥ = −1 + 2η²c/g, so F = 1 − 2c·Re((1 + η²)/g); with
//   η² = 1 + 2ik − k² and g = √(2ik − k² + c²) = √k (1 + i)(1 + O(k) + O(c²/k)) this is
//   F = 1 − 2c/√k to an absolute 1e-9 (the dropped terms are O(c k^½) and O(c²/k)).

const GRAZING: [f32; 3] = [1e-4, 1e-8, 1e-12];

fn grazing_mirror(eps: f32) -> ([f32; 3], [f32; 3], [f32; 3]) {
    ([1.0, 0.0, eps], [-1.0, 0.0, eps], [0.0, 0.0, 1.0])
}

/// γ = ε/√(1 + ε²) of the f32 ε.
fn gamma(eps: f32) -> f64 {
    let e = eps as f64;
    e / (1.0 + e * e).sqrt()
}

fn index_matched_body(fresnel_lines: &str) -> String {
    format!(
        "model = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 0.5\ngeometry = \"none\"\n\
         {fresnel_lines}\ndiffuse = 0.2\ndiffuse_weight = 0.5"
    )
}

/// `(label, fresnel lines, ε, expected F, |F error| allowed on the reference)`.
fn index_matched_cases() -> Vec<(String, String, f32, f64, f64)> {
    let mut v = Vec::new();
    for eps in GRAZING {
        v.push((
            format!("conductor η = 1 + 0i, ε = {eps:e}"),
            "fresnel = \"conductor\"\nior = 1.0\nextinction = 0.0".to_string(),
            eps,
            0.0,
            0.0,
        ));
        v.push((
            format!("dielectric μ = 1, ε = {eps:e}"),
            "fresnel = \"dielectric\"\nior = 1.0".to_string(),
            eps,
            0.0,
            0.0,
        ));
    }
    let (k, eps) = (1e-13f64, 1e-4f32);
    let c = gamma(eps);
    let c2 = c * c;
    let f = k * k / (8.0 * c2 * c2) * (1.0 + (1.0 - 2.0 * c2).powi(2));
    v.push((
        format!("conductor η = 1 + {k:e}i, ε = {eps:e}"),
        format!("fresnel = \"conductor\"\nior = 1.0\nextinction = {k:e}"),
        eps,
        f,
        1e-8 * f,
    ));
    for eps in [1e-8f32, 1e-12] {
        let k = 1e-6f64;
        v.push((
            format!("conductor η = 1 + {k:e}i, ε = {eps:e}"),
            format!("fresnel = \"conductor\"\nior = 1.0\nextinction = {k:e}"),
            eps,
            1.0 - 2.0 * gamma(eps) / k.sqrt(),
            1e-9,
        ));
    }
    v
}

#[test]
fn index_matched_interfaces_at_grazing_incidence_on_the_reference() {
    for (label, fresnel_lines, eps, want_f, f_tol) in index_matched_cases() {
        let body = index_matched_body(&fresnel_lines);
        let m = material(&body);
        let (l, v, n) = grazing_mirror(eps);
        let w = |a: [f32; 3]| a.map(f64::from);
        let e = evaluate(w(l), w(v), w(n), None, &m);
        let g = gamma(eps);
        let (d, k) = (4.0 / PI, 1.0 / (4.0 * g * g));
        let want_brdf = 0.1 / PI + d * want_f * k;
        assert_eq!(e.status, Status::Valid, "[{label}] {e:?}");
        for (ch, &f) in e.f.iter().enumerate() {
            assert!(
                (f - want_f).abs() <= f_tol,
                "[{label}] F[{ch}] = {f:e}, want {want_f:e} ± {f_tol:e}"
            );
        }
        assert!(close(e.d, d, TOL), "[{label}] D = {:e}, want {d:e}", e.d);
        assert!(close(e.k, k, TOL), "[{label}] K = {:e}, want {k:e}", e.k);
        assert_eq!(e.g, 1.0, "[{label}]");
        // f's tolerance: the reference's own 1e-12 plus F's allowance carried through D·K.
        let f_abs = TOL * want_brdf + d * k * f_tol;
        for (ch, &b) in e.brdf.iter().enumerate() {
            assert!(
                (b - want_brdf).abs() <= f_abs,
                "[{label}] f[{ch}] = {b:e}, want {want_brdf:e} ± {f_abs:e}"
            );
        }
    }
}

#[test]
fn index_matched_interfaces_at_grazing_incidence_on_every_backend() {
    use vkbrdf::backend::Request;
    use vkbrdf::batch::{memory_source, Batch, COLUMNS_PLAIN};
    let cases = index_matched_cases();
    let materials: Vec<Material> = cases
        .iter()
        .map(|(_, lines, ..)| material(&index_matched_body(lines)))
        .collect();
    let mut data = Vec::new();
    for (i, (_, _, eps, ..)) in cases.iter().enumerate() {
        let (l, v, n) = grazing_mirror(*eps);
        data.extend_from_slice(&l);
        data.extend_from_slice(&v);
        data.extend_from_slice(&n);
        data.push(i as f32);
    }
    let batch =
        Batch::new(data, COLUMNS_PLAIN, materials.len(), &memory_source()).expect("valid batch");
    for mut backend in common::backends() {
        let out = backend
            .evaluate(&batch, &materials, &Request { terms: true })
            .expect("evaluates");
        let terms = out.terms.expect("terms requested");
        for (i, (label, _, eps, want_f, _)) in cases.iter().enumerate() {
            let g = gamma(*eps);
            let (d, k) = (4.0 / PI, 1.0 / (4.0 * g * g));
            let want_brdf = 0.1 / PI + d * want_f * k;
            // The f32 outputs, judged as the stress test does: relative 1e-5 above an
            // absolute floor of 1e-6 (F of 2.5e-13 is compared absolutely).
            let ok =
                |got: f32, want: f64| ((got as f64) - want).abs() <= 1e-5 * want.abs().max(1e-6);
            let name = backend.name();
            for ch in 0..3 {
                let f = out.brdf[3 * i + ch];
                assert!(
                    ok(f, want_brdf),
                    "{name} [{label}] f[{ch}] = {f:e}, want {want_brdf:e}"
                );
                let fr = terms[6 * i + 2 + ch];
                assert!(
                    ok(fr, *want_f),
                    "{name} [{label}] F[{ch}] = {fr:e}, want {want_f:e}"
                );
            }
            assert!(
                ok(terms[6 * i], d),
                "{name} [{label}] D = {:e}",
                terms[6 * i]
            );
            assert!(
                ok(terms[6 * i + 5], k),
                "{name} [{label}] K = {:e}",
                terms[6 * i + 5]
            );
        }
    }
}
