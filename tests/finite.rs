//! Finite in, finite out (issue 10, item 4; FORMULAS.md §1, "Overflow"): the three cases the
//! issue names, on every backend, against values derived by hand; the saturated count; and
//! the parse-time ranges of the parameters that have no meaningful float32 evaluation.

mod common;

use common::materials;

use std::f64::consts::PI;
use vkbrdf::backend::{Request, TERM_COLUMNS};
use vkbrdf::batch::{memory_source, Batch};
use vkbrdf::material::parse_materials;

/// Rows `L V N material` (10 columns).
fn batch(rows: &[[f32; 10]], materials: usize) -> Batch<'static> {
    Batch::new(rows.concat(), 10, materials, &memory_source()).expect("valid batch")
}

fn assert_close(got: f32, want: f64, rel: f64, what: &str) {
    assert!(
        ((got as f64) - want).abs() <= rel * want.abs(),
        "{what}: got {got:e}, want {want:e} (relative tolerance {rel:e})"
    );
}

fn all_finite(out: &vkbrdf::backend::Output, name: &str) {
    let terms = out.terms.as_deref().unwrap_or(&[]);
    for (i, x) in out.brdf.iter().chain(terms).enumerate() {
        assert!(x.is_finite(), "{name}: output value {i} is {x}");
    }
}

/// A conductor with extinction 1e10 (was NaN on Vulkan: 1/|η²|² overflowed float32). At
/// normal incidence, GGX m = 0.5: D = 1/(π m²), G = 1, K = 1/4 and
/// F = ((n−1)² + k²)/((n+1)² + k²) = 1e20/(4 + 1e20), so f = F/(4π m²) = F/π.
#[test]
fn conductor_with_extinction_1e10_is_finite_and_exact() {
    let m = materials(
        r#"
        [[material]]
        name = "k1e10"
        model = "cook-torrance"
        distribution = "ggx"
        roughness = 0.5
        geometry = "smith-correlated"
        fresnel = "conductor"
        ior = 1.0
        extinction = 1e10
        "#,
    );
    let f = 1e20 / (4.0 + 1e20);
    let want = f / (4.0 * PI * 0.25);
    // Normal incidence, then a tilted mirror pair and a grazing pair (compared across
    // backends below).
    let rows = [
        [0., 0., 1., 0., 0., 1., 0., 0., 1., 0.],
        [0.6, 0., 0.8, -0.6, 0., 0.8, 0., 0., 1., 0.],
        [1., 0., 1e-6, -0.3, 0.2, 1., 0., 0., 1., 0.],
    ];
    let b = batch(&rows, 1);
    let mut outputs = Vec::new();
    for mut backend in common::backends() {
        let name = backend.name();
        let out = backend
            .evaluate(&b, &m, &Request { terms: true })
            .expect("evaluates");
        all_finite(&out, &name);
        for c in 0..3 {
            assert_close(
                out.brdf[c],
                want,
                1e-5,
                &format!("{name}: f at normal incidence"),
            );
        }
        let terms = out.terms.as_deref().unwrap();
        assert_close(terms[2], f, 1e-6, &format!("{name}: F at normal incidence"));
        assert_eq!(out.counts.saturated, 0, "{name}");
        outputs.push((name, out.brdf));
    }
    // Every backend agrees with the first (the reference) off normal incidence too.
    let (ref_name, reference) = &outputs[0];
    for (name, brdf) in &outputs[1..] {
        for (i, (&x, &r)) in brdf.iter().zip(reference).enumerate() {
            assert_close(
                x,
                r as f64,
                1e-5,
                &format!("{name} vs {ref_name}, value {i}"),
            );
        }
    }
}

/// The gold preset (GGX m = 0.3, Smith height-correlated, modern K) at the exact mirror
/// configuration l = (−1, 0, c), v = (1, 0, c), n = +z (h = n, so cos_h = 1 and the Fresnel
/// cosine is c): D = 1/(π m²), 1 + Λ(l) + Λ(v) = √(1 + m² tan²) with tan² = (1 − c²)/c²,
/// K = 1/(4c²), so f = F/(4π m² c √(c² + m²(1 − c²))), and F = 1 − O(c) = 1 to f64
/// precision for c ≤ 1e-20. K = 1/(4c²) exceeds f32::MAX at all four cosines: saturated.
/// Was NaN on Vulkan and +inf for K on both backends.
#[test]
fn gold_at_a_grazing_mirror_is_exact_or_saturated() {
    let m = materials("[[material]]\nname = \"gold\"\npreset = \"gold\"\n");
    let cosines = [1e-20f32, 1e-30, 1e-38, 1e-45];
    let rows: Vec<[f32; 10]> = cosines
        .iter()
        .map(|&c| [-1., 0., c, 1., 0., c, 0., 0., 1., 0.])
        .collect();
    let b = batch(&rows, 1);
    let m_r: f64 = 0.3;
    for mut backend in common::backends() {
        let name = backend.name();
        let out = backend
            .evaluate(&b, &m, &Request { terms: true })
            .expect("evaluates");
        all_finite(&out, &name);
        let terms = out.terms.as_deref().unwrap();
        for (i, &c32) in cosines.iter().enumerate() {
            let c = f64::from(c32);
            let f = 1.0 / (4.0 * PI * m_r * m_r * c * (c * c + m_r * m_r * (1.0 - c * c)).sqrt());
            let what = format!("{name}: f at cos = {c32:e}");
            if f > f64::from(f32::MAX) {
                assert!(
                    out.brdf[3 * i..3 * i + 3].iter().all(|&x| x == f32::MAX),
                    "{what}: {:?} should be f32::MAX",
                    &out.brdf[3 * i..3 * i + 3]
                );
            } else {
                for ch in 0..3 {
                    assert_close(out.brdf[3 * i + ch], f, 1e-5, &what);
                }
            }
            let t = &terms[TERM_COLUMNS * i..TERM_COLUMNS * (i + 1)];
            assert_close(t[0], 1.0 / (PI * m_r * m_r), 1e-6, &format!("{name}: D"));
            assert_eq!(
                t[5],
                f32::MAX,
                "{name}: K = 1/(4c²) at c = {c32:e} saturates"
            );
        }
        assert_eq!(out.counts.saturated, 4, "{name}: every tuple's K saturates");
        // 1e-38 is the case where f is representable although K is not.
        assert!(
            out.brdf[6] < f32::MAX && out.brdf[6] > 2.9e38,
            "{name}: {}",
            out.brdf[6]
        );
        // The count does not depend on the request: without terms, the same tuples.
        let plain = backend
            .evaluate(&b, &m, &Request { terms: false })
            .expect("evaluates");
        assert_eq!(plain.counts, out.counts, "{name}: counts without terms");
        assert_eq!(plain.brdf, out.brdf, "{name}: BRDF without terms");
    }
}

/// Phong with exponent 1e40 (was NaN on Vulkan: e overflowed float32) is refused at parse
/// time with the supported range; at the bound, 1e18, the lobe at its exact peak is
/// (e + 2)/(2π) on every backend, and with specular 1e18 still representable (1.6e35).
#[test]
fn phong_exponent_is_bounded_and_finite_at_the_bound() {
    let err = parse_materials(
        "[[material]]\nname = \"p\"\nmodel = \"phong\"\nexponent = 1e40\n",
        "m.toml",
    )
    .expect_err("exponent 1e40 has no float32 evaluation");
    let msg = err.to_string();
    assert!(
        msg.contains("exponent") && msg.contains("[0, 1e18]") && msg.contains("1e40"),
        "{msg}"
    );
    let m = materials(
        r#"
        [[material]]
        name = "sharp"
        model = "phong"
        exponent = 1e18
        [[material]]
        name = "bright"
        model = "phong"
        exponent = 1e18
        specular = [1e18, 1, 0]
        "#,
    );
    let peak = (1e18 + 2.0) / (2.0 * PI);
    // Normal incidence and the mirror pair at 1e-30 from the horizon (r = v exactly).
    let rows = [
        [0., 0., 1., 0., 0., 1., 0., 0., 1., 0.],
        [0.8, 0., 1e-30, -0.8, 0., 1e-30, 0., 0., 1., 0.],
        [0., 0., 1., 0., 0., 1., 0., 0., 1., 1.],
    ];
    let b = batch(&rows, 2);
    for mut backend in common::backends() {
        let name = backend.name();
        let out = backend
            .evaluate(&b, &m, &Request { terms: true })
            .expect("evaluates");
        all_finite(&out, &name);
        for (i, x) in out.brdf[..6].iter().enumerate() {
            assert_close(*x, peak, 1e-6, &format!("{name}: lobe peak, value {i}"));
        }
        assert_close(
            out.brdf[6],
            1e18 * peak,
            1e-6,
            &format!("{name}: 1e18 × peak"),
        );
        assert_close(out.brdf[7], peak, 1e-6, &format!("{name}: green"));
        assert_eq!(out.brdf[8], 0.0, "{name}: blue (zero colour × finite lobe)");
        assert_eq!(out.counts.saturated, 0, "{name}");
    }
}

/// Every parameter outside its supported range is refused at parse time, naming the key
/// and the range.
#[test]
fn parameters_beyond_their_float32_range_are_refused_with_the_range() {
    let ct = "model = \"cook-torrance\"\ndistribution = \"ggx\"\ngeometry = \"smith\"";
    let cases = [
        (
            "model = \"ward\"\nroughness = 1e-8",
            "roughness",
            "[1e-7, 1e4]",
        ),
        (
            "model = \"ward\"\nroughness = [0.1, 2e4]",
            "roughness",
            "[1e-7, 1e4]",
        ),
        ("model = \"rtr\"\nexponent = 1e19", "exponent", "[0, 1e18]"),
        (
            &format!("{ct}\nroughness = 0.1\nfresnel = \"conductor\"\nior = 1\nextinction = 1e19"),
            "extinction",
            "[0, 1e18]",
        ),
        (
            &format!("{ct}\nroughness = 0.1\nfresnel = \"dielectric\"\nior = 1e-7"),
            "ior",
            "[1e-6, 1e18]",
        ),
        (
            &format!("{ct}\nroughness = 0.1\nfresnel = \"none\"\nspecular_weight = 1e19"),
            "specular_weight",
            "[0, 1e18]",
        ),
        (
            "model = \"lambert\"\ndiffuse = [1, 1e19, 1]",
            "diffuse",
            "[0, 1e18]",
        ),
    ];
    for (body, key, range) in cases {
        let text = format!("[[material]]\nname = \"x\"\n{body}\n");
        let msg = parse_materials(&text, "m.toml")
            .expect_err(body)
            .to_string();
        assert!(msg.contains(key) && msg.contains(range), "{body}: {msg}");
    }
}

/// Stress corpus rows at the smallest cosines: zero non-finite outputs and equal counts
/// (saturated included) on every backend.
#[test]
fn tiny_cosine_corpus_is_finite_with_equal_counts() {
    let mut reports = Vec::new();
    for mut backend in common::backends() {
        let r = vkbrdf::stress::run(backend.as_mut(), 60_000, 3, 1 << 15, &mut |_| {})
            .expect("stress run");
        assert_eq!(r.non_finite, 0, "{}", r.to_markdown(1e-5));
        assert_eq!(r.saturated.0, r.saturated.1, "{}", r.to_markdown(1e-5));
        assert!(
            r.saturated.1 > 100,
            "the corpus saturates outputs: {:?}",
            r.saturated
        );
        reports.push(r.saturated.0);
    }
    assert!(reports.windows(2).all(|w| w[0] == w[1]), "{reports:?}");
}

/// Blinn–Phong (the seed's `cos_h^e / (π cos_i)`) with l ⟂ v at cosines 1e-45 and 1e-38:
/// cos_h = (cos_i + cos_o)/|l + v| ≈ 7e-39 lies below float32's smallest normal number, so
/// an f32 lobe flushes to 0, yet the value is large. By hand, with |L| = |V| and l·v ≈ 0
/// (|l + v| = √2 to within 1e-83): f = (cos_i + cos_o)/(√2 π cos_i) = (1 + εv/εl)/(√2 π),
/// ε the z components (N = +z).
#[test]
fn blinn_phong_with_cos_h_below_the_smallest_normal_float_is_exact() {
    let m = materials(
        r#"
        [[material]]
        name = "bp"
        model = "blinn-phong"
        exponent = 1
        "#,
    );
    let (el, ev) = (1e-45f32, 1e-38f32);
    let rows = [[0.6, 0.8, el, -0.8, 0.6, ev, 0., 0., 1., 0.]];
    let len = |x: f32, y: f32, z: f32| {
        let (x, y, z) = (f64::from(x), f64::from(y), f64::from(z));
        (x * x + y * y + z * z).sqrt()
    };
    let cos_i = f64::from(el) / len(0.6, 0.8, el);
    let cos_o = f64::from(ev) / len(-0.8, 0.6, ev);
    let want = (cos_i + cos_o) / (2f64.sqrt() * PI * cos_i);
    assert!(want > 1e6, "the case is the large one: {want}");
    let b = batch(&rows, 1);
    for mut backend in common::backends() {
        let name = backend.name();
        let out = backend
            .evaluate(&b, &m, &Request { terms: true })
            .expect("evaluates");
        all_finite(&out, &name);
        for ch in 0..3 {
            assert_close(out.brdf[ch], want, 1e-5, &format!("{name}: f channel {ch}"));
        }
        assert_close(
            out.terms.as_ref().unwrap()[0],
            want,
            1e-5,
            &format!("{name}: D"),
        );
        assert_eq!(out.counts.saturated, 0, "{name}");
    }
}
