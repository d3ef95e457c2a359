//! The CPU engine's register path (`cpu::register`: the local form's GGX and Beckmann groups on AVX2 and AVX-512,
//! two registers of tuples at a time) against the lane loops it stands in for: the same
//! outputs bit for bit and the same counts, for every group it serves, on the tuples where
//! each term is hardest — D's steepest slope at every c down to the f32 frame's threshold,
//! the specular peak, normal incidence and retro-reflection, grazing cosines on either side
//! of the rescue threshold, c on either side of `FAST_MIN_C`, lengths at the frame's
//! limits, invalid and below-horizon tuples — and on uniform directions. The lane loops
//! are what the 10-column rows with N = (0, 0, 1) take, so the test compares the local
//! form, held as rows and as six columns, and `(n, 3)` columns of L and V with N given
//! once, with those rows on every instruction set (the register path runs on AVX2 and AVX-512;
//! the others must agree with their own rows as before).

mod common;

use vkbrdf::backend::{Backend, Output, Request};
use vkbrdf::batch::columns::ColumnBatch;
use vkbrdf::batch::{memory_source, Batch, LocalBatch, LocalLayout};
use vkbrdf::cpu::{CpuEngine, Isa};
use vkbrdf::material::{parse_materials, Material};

/// Unit vector of polar angle `theta` and azimuth `phi` about +z.
fn polar(theta: f64, phi: f64) -> [f64; 3] {
    [
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    ]
}

/// The local rows (`Lx Ly Lz Vx Vy Vz`) of the hard tuples for roughness `m`; `unit`: every
/// L and V of unit length and no invalid tuple, so that whole steps of the register path
/// take the frames' near-unit scales alone (other lengths in a step send it the way that
/// chooses lane by lane).
fn hard_rows(m: f64, unit: bool) -> Vec<f32> {
    let mut pairs: Vec<([f64; 3], [f64; 3])> = Vec::new();
    // D steepest in h (GGX: tan θ_h = m/2, m, 2m; Beckmann: out to its exp's cut-off),
    // c from 0.05 (below FAST_MIN_C) to 1.
    pairs.extend(common::steepest::ggx_pairs(m, 0.05));
    pairs.extend(common::steepest::beckmann_pairs(m, 0.05));
    // The specular peak: v the mirror of l turned by a fraction of m, at every elevation.
    for th in [0.0f64, 0.01, 0.3, 0.8, 1.2, 1.5, 1.565] {
        for d in [0.0f64, 1e-4, 0.02 * m, 0.3 * m, m] {
            let l = polar(th, 0.4);
            let v = polar(
                (th + d).min(std::f64::consts::FRAC_PI_2 - 1e-5),
                0.4 + std::f64::consts::PI,
            );
            pairs.push((l, v));
        }
    }
    // Normal incidence and retro-reflection.
    for th in [0.0f64, 0.5, 1.4, 1.5706] {
        pairs.push((polar(th, 1.0), polar(th, 1.0)));
    }
    // Grazing cosines either side of the rescue threshold (1e-4), for l and for v.
    for c in [0.99e-4f64, 1.01e-4, 1e-3, 0.02] {
        let th = c.acos();
        pairs.push((polar(th, 0.2), polar(0.6, 2.0)));
        pairs.push((polar(0.6, 2.0), polar(th, 0.2)));
    }
    // c = cos θ_d either side of FAST_MIN_C (0.1): l and v 2θ_d apart about h.
    for c in [0.0999f64, 0.1, 0.1001, 0.2] {
        let td = c.acos();
        for th_h in [0.05f64, 0.4] {
            let l = polar(th_h + td, 0.0);
            let v = polar(th_h - td, 0.0);
            if l[2] > 0.0 && v[2] > 0.0 {
                pairs.push((l, v));
            }
        }
    }
    // Uniform directions over the hemisphere (some below it).
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..2000 {
        let l = polar((rnd() * 1.0).acos(), 6.3 * rnd());
        let v = polar((rnd() * 1.02 - 0.02).acos(), 6.3 * rnd());
        pairs.push((l, v));
    }
    let mut rows = Vec::new();
    for (i, (l, v)) in pairs.into_iter().enumerate() {
        // Lengths other than 1, up to the frame's limits (|x|² in [1e-30, 1e30]) and past
        // them, on some tuples.
        let scale = match i % 13 {
            _ if unit => 1.0,
            3 => 3.7,
            5 => 1e-6,
            7 => 1e14,
            9 => 1e-16,
            // Squared lengths either side of the h64 frame's near-unit test (1 ± 2⁻¹²).
            11 => (1.0 + 0.99 / 4096.0f64).sqrt(),
            12 => (1.0 - 1.01 / 4096.0f64).sqrt(),
            _ => 1.0,
        };
        rows.extend(l.iter().map(|&x| (x * scale) as f32));
        rows.extend(v.iter().map(|&x| x as f32));
    }
    if unit {
        return rows;
    }
    // Invalid tuples: zero, NaN and infinite components.
    for bad in [[0.0f32; 3], [f32::NAN, 0.0, 1.0], [0.0, f32::INFINITY, 1.0]] {
        rows.extend_from_slice(&bad);
        rows.extend_from_slice(&[0.1, 0.2, 0.9]);
        rows.extend_from_slice(&[0.3, -0.1, 0.8]);
        rows.extend_from_slice(&bad);
    }
    rows
}

/// The same tuples as 10-column rows with N = (0, 0, 1).
fn as_rows(local: &[f32]) -> Batch<'static> {
    let mut rows = Vec::with_capacity(local.len() / 6 * 10);
    for r in local.chunks_exact(6) {
        rows.extend_from_slice(r);
        rows.extend_from_slice(&[0.0, 0.0, 1.0, 0.0]);
    }
    Batch::new(rows, 10, 1, &memory_source()).expect("rows")
}

/// GGX and Beckmann with every geometry and Fresnel term the register path serves (and
/// some it does not: a conductor with small n and k, which the metal form's rule refuses;
/// Beckmann's Smith forms), each convention, at roughness `m`.
fn materials(m: f64) -> Vec<(Material, bool)> {
    let mut out = Vec::new();
    let groups = [
        ("ggx", "none", true),
        ("ggx", "cook-torrance", true),
        ("ggx", "smith", true),
        ("ggx", "smith-correlated", true),
        ("beckmann", "none", true),
        ("beckmann", "cook-torrance", true),
        ("beckmann", "smith-fast", true),
        ("beckmann", "smith", false),
    ];
    for (d, g, g_served) in groups {
        for (f, f_served) in [
            ("fresnel = \"none\"", true),
            ("fresnel = \"schlick\"\nf0 = [0.04, 0.5, 0.95]", true),
            (
                "fresnel = \"conductor\"\nior = [0.27, 0.68, 1.22]\nextinction = [3.61, 2.63, 2.29]",
                true,
            ),
            (
                "fresnel = \"conductor\"\nior = [0.05, 0.9, 1.1]\nextinction = [0.02, 0.1, 0.0]",
                false,
            ),
        ] {
            for conv in ["modern", "seed", "cook-torrance-1982"] {
                let toml = format!(
                    "[[material]]\nname = \"m\"\nmodel = \"cook-torrance\"\n\
                     distribution = \"{d}\"\ngeometry = \"{g}\"\n{f}\nroughness = {m}\n\
                     convention = \"{conv}\"\ndiffuse_weight = 0.3\nspecular_weight = 0.9\n"
                );
                let mut mats = parse_materials(&toml, "test").expect("material");
                out.push((mats.remove(0), g_served && f_served));
            }
        }
    }
    out
}

#[test]
fn the_register_path_gives_the_lane_loops_bits_on_every_group_it_serves() {
    let registers = Isa::available_all()
        .iter()
        .any(|i| matches!(i, Isa::Avx2Fma | Isa::Avx512));
    let (mut deferred, mut rescued) = (0, 0);
    for (m, unit) in [0.075, 0.0751, 0.3, 1.0]
        .into_iter()
        .flat_map(|m| [(m, false), (m, true)])
    {
        let local = hard_rows(m, unit);
        let n = local.len() / 6;
        assert!(!n.is_multiple_of(16), "a tail that is not a whole step");
        let rows = as_rows(&local);
        for (mat, served) in materials(m) {
            let mats = vec![mat];
            let lb = LocalBatch::new(local.clone(), 0, &mats, &memory_source()).expect("local");
            // The same tuples held as six columns (read without a transpose), and as the
            // Python package's `(n, 3)` columns of L and V with N = +z given once.
            let planar = lb.to_layout(LocalLayout::Columns);
            let l: Vec<f32> = local
                .chunks_exact(6)
                .flat_map(|r| r[..3].to_vec())
                .collect();
            let v: Vec<f32> = local
                .chunks_exact(6)
                .flat_map(|r| r[3..].to_vec())
                .collect();
            let z = [0.0f32, 0.0, 1.0];
            let columns = ColumnBatch::new([&l, &v, &z], None, &[0.0], n, &mats, &memory_source())
                .expect("columns");
            // V given once for every row (a fixed viewer), L one a row.
            let v_once = [0.3f32, -0.2, 0.9];
            let fixed: Vec<f32> = l
                .chunks_exact(3)
                .flat_map(|x| [x[0], x[1], x[2], 0.3, -0.2, 0.9])
                .collect();
            let fixed_rows = as_rows(&fixed);
            let fixed_columns =
                ColumnBatch::new([&l, &v_once, &z], None, &[0.0], n, &mats, &memory_source())
                    .expect("columns");
            for isa in Isa::available_all() {
                let mut engine = CpuEngine::with_isa(1, isa);
                let request = Request { terms: false };
                let want = engine.evaluate(&fixed_rows, &mats, &request).expect("rows");
                let mut got = Output::default();
                engine
                    .evaluate_columns_into(&fixed_columns, &mats, &request, &mut got)
                    .expect("columns");
                let what = format!("{:?} m = {m}, {isa}, V given once", mats[0]);
                assert_eq!(got.counts, want.counts, "{what}");
                for (i, (a, b)) in got.brdf.iter().zip(&want.brdf).enumerate() {
                    assert_eq!(a.to_bits(), b.to_bits(), "{what}: row {}", i / 3);
                }
                let on_registers = matches!(isa, Isa::Avx2Fma | Isa::Avx512) && served;
                assert_eq!(
                    engine.last_tally().registers == n as u64,
                    on_registers,
                    "{what}"
                );
            }
            for (isa, form) in Isa::available_all()
                .into_iter()
                .flat_map(|isa| [(isa, 0), (isa, 1), (isa, 2)])
            {
                let mut engine = CpuEngine::with_isa(1, isa);
                for terms in [false, true] {
                    let request = Request { terms };
                    let want = engine.evaluate(&rows, &mats, &request).expect("rows");
                    let mut got = Output::default();
                    match form {
                        0 => engine.evaluate_local_into(&lb, &mats, &request, &mut got),
                        1 => engine.evaluate_local_into(&planar, &mats, &request, &mut got),
                        _ => engine.evaluate_columns_into(&columns, &mats, &request, &mut got),
                    }
                    .expect("evaluate");
                    let form = ["rows", "six columns", "(n, 3) columns"][form];
                    let what = format!("{:?} m = {m}, {isa}, {form}, terms {terms}", mats[0]);
                    assert_eq!(got.counts, want.counts, "{what}");
                    for (i, (a, b)) in got.brdf.iter().zip(&want.brdf).enumerate() {
                        assert_eq!(a.to_bits(), b.to_bits(), "{what}: row {}", i / 3);
                    }
                    assert_eq!(got.terms, want.terms, "{what}");
                    let tally = engine.last_tally();
                    // The register path takes exactly the local form's served groups
                    // without terms, on AVX2 and AVX-512.
                    let on_registers =
                        matches!(isa, Isa::Avx2Fma | Isa::Avx512) && served && !terms;
                    assert_eq!(tally.registers > 0, on_registers, "{what}: {tally:?}");
                    if on_registers {
                        assert_eq!(tally.registers, n as u64, "{what}");
                        deferred += tally.deferred;
                        rescued += tally.rescued;
                    }
                }
            }
        }
    }
    // The tuples reached the register path's f64-frame and reference hand-offs.
    if registers {
        assert!(
            deferred > 0 && rescued > 0,
            "{deferred} deferred, {rescued} rescued"
        );
    }
}
