//! The lanes' unit tests: every group without rescue on ordinary directions, the rescue
//! of grazing, invalid and below-horizon lanes, the local form's bits.

use super::*;
use crate::cpu::plan::Plan;
use crate::material::parse_materials;
use crate::reference::{evaluate, Status};

/// Every lanes-group on ordinary directions: no lane is rescued (so the lanes, not the
/// reference, made the numbers) and every output is within 3e-6 relative of the
/// reference (these tuples are well conditioned; the rule allows 1e-5 there).
#[test]
fn every_lanes_group_computes_without_rescue() {
    let dirs: [[f32; 9]; 4] = [
        [0.3, 0.2, 0.9, -0.2, 0.1, 0.8, 0.0, 0.0, 1.0],
        [0.7, -0.1, 0.3, -0.6, 0.2, 0.5, 0.0, 0.0, 2.0],
        [0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0],
        [0.5, 0.5, 0.2, 0.1, -0.6, 0.4, 0.1, 0.05, 1.0],
    ];
    let mut inp = Inputs::default();
    // A tangent for the anisotropic groups, across every lane's N.
    let tangent = [1.0f32, 0.2, 0.0];
    for k in 0..LANES {
        for j in 0..9 {
            inp.v[j][k] = dirs[k % 4][j];
        }
        for j in 0..3 {
            inp.v[9 + j][k] = tangent[j];
        }
    }
    // Every group the lanes take: each distribution with each geometry it is legal
    // with, each Fresnel term and convention, then the lobe models.
    let mut materials = Vec::new();
    for (d, param) in [
        ("ggx", "roughness = 0.3"),
        ("beckmann", "roughness = 0.3"),
        ("gaussian", "roughness = 0.3"),
        ("blinn", "exponent = 40"),
        ("charlie", "roughness = 0.4"),
    ] {
        let slope = d == "ggx" || d == "beckmann";
        for g in [
            "none",
            "cook-torrance",
            "smith",
            "smith-correlated",
            "smith-fast",
            "schlick-smith",
            "neubelt",
        ] {
            let smith = g.starts_with("smith") || g == "schlick-smith";
            if (smith && !slope) || (g == "smith-fast" && d != "beckmann") {
                continue;
            }
            for f in [
                "fresnel = \"none\"",
                "fresnel = \"schlick\"\nf0 = [0.04, 0.5, 0.9]",
                "fresnel = \"dielectric\"\nior = [1.5, 0.7, 2.4]",
                "fresnel = \"conductor\"\nior = [0.2, 0.9, 1.1]\nextinction = [3.9, 2.4, 0.0]",
            ] {
                for conv in ["modern", "seed", "cook-torrance-1982"] {
                    materials.push(format!(
                        "model = \"cook-torrance\"\ndistribution = \"{d}\"\n\
                         geometry = \"{g}\"\n{f}\n{param}\nconvention = \"{conv}\"\n\
                         diffuse_weight = 0.5\nspecular_weight = 0.7"
                    ));
                }
            }
        }
    }
    // Anisotropic roughness: modern convention only, no schlick-smith.
    for (d, g) in [
        ("ggx", "none"),
        ("ggx", "smith"),
        ("ggx", "smith-correlated"),
        ("ggx", "neubelt"),
        ("beckmann", "cook-torrance"),
        ("beckmann", "smith"),
        ("beckmann", "smith-fast"),
    ] {
        materials.push(format!(
            "model = \"cook-torrance\"\ndistribution = \"{d}\"\ngeometry = \"{g}\"\n\
             fresnel = \"conductor\"\nior = [0.2, 0.9, 1.1]\nextinction = [3.9, 2.4, 0.0]\n\
             roughness = [0.2, 0.45]"
        ));
    }
    for model in [
        "model = \"ward\"\nroughness = [0.15, 0.4]",
        "model = \"phong\"\nexponent = 30",
        "model = \"phong\"\nexponent = 0",
        "model = \"blinn-phong\"\nexponent = 50",
        "model = \"rtr\"\nexponent = 20",
        "model = \"ward\"\nroughness = 0.3",
    ] {
        materials.push(model.to_string());
    }
    // 2 rms-slope distributions × (6 geometries for GGX, 7 for Beckmann), 3 others × 3
    // geometries, each × 4 Fresnel × 3 conventions; 7 anisotropic groups; 6 lobes.
    assert_eq!(materials.len(), (6 + 7 + 3 * 3) * 4 * 3 + 7 + 6);
    for body in &materials {
        let toml = format!(
            "[[material]]\nname = \"x\"\n{body}\ndiffuse = [0.2, 0.3, 0.4]\n\
             specular = [0.9, 0.8, 0.7]\n"
        );
        let m = &parse_materials(&toml, "t").unwrap()[0];
        let plan = Plan::for_material(m).with_terms(true);
        assert!(plan.is_simd(), "{body} is not in the lanes");
        let mut out = Outputs::default();
        lambert_terms(&mut out);
        crate::cpu::block::<_, crate::terms::math::Rounded>(
            pulp::Scalar::new(),
            &plan,
            std::slice::from_ref(&inp),
            std::slice::from_mut(&mut out),
            false,
        );
        for k in 0..LANES {
            assert!(!out.rescue[k], "{body}: lane {k} rescued");
            let w = |a: usize| f64::from(dirs[k % 4][a]);
            let e = evaluate(
                [w(0), w(1), w(2)],
                [w(3), w(4), w(5)],
                [w(6), w(7), w(8)],
                Some(tangent.map(f64::from)),
                m,
            );
            assert_eq!(e.status, Status::Valid);
            let want = [
                e.brdf[0], e.brdf[1], e.brdf[2], e.d, e.g, e.f[0], e.f[1], e.f[2], e.k,
            ];
            let got = [
                out.brdf[0][k],
                out.brdf[1][k],
                out.brdf[2][k],
                out.terms[0][k],
                out.terms[1][k],
                out.terms[2][k],
                out.terms[3][k],
                out.terms[4][k],
                out.terms[5][k],
            ];
            for (i, (x, r)) in got.iter().zip(want).enumerate() {
                let err = (f64::from(*x) - r).abs() / r.abs().max(1e-6);
                // Roughness 0.3: the f32 frame (FAST_MIN_ROUGHNESS), whose few ulp in
                // the sines the Beckmann exponent multiplies by tan²/m²: 2.4e-6 at most
                // here (the f64 frame made 1.5e-6), well inside the rule's 1e-5 for
                // well-conditioned values.
                assert!(err < 3e-6, "{body}\nlane {k} col {i}: {x} vs {r}");
            }
        }
    }
}

#[test]
fn grazing_invalid_and_below_horizon_lanes_are_rescued() {
    let mut inp = Inputs::default();
    let rows: [[f32; 9]; 4] = [
        [1.0, 0.0, 1e-6, -0.2, 0.1, 0.8, 0.0, 0.0, 1.0], // cos_i ≈ 1e-6
        [0.3, 0.2, 0.9, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0],   // V = 0
        [0.3, 0.2, -0.9, -0.2, 0.1, 0.8, 0.0, 0.0, 1.0], // below the horizon
        [0.3, 0.2, 0.9, f32::INFINITY, 0.1, 0.8, 0.0, 0.0, 1.0],
    ];
    for k in 0..LANES {
        for j in 0..9 {
            inp.v[j][k] = rows[k % 4][j];
        }
    }
    let m = &parse_materials(
        "[[material]]\nname = \"x\"\nmodel = \"lambert\"\ndiffuse = [0.5, 0.5, 0.5]\n",
        "t",
    )
    .unwrap()[0];
    let mut out = Outputs::default();
    crate::cpu::block::<_, crate::terms::math::Rounded>(
        pulp::Scalar::new(),
        &Plan::for_material(m),
        std::slice::from_ref(&inp),
        std::slice::from_mut(&mut out),
        false,
    );
    assert!(out.rescue.iter().all(|&r| r));
}

/// The N = +z lanes (the local form) give the general lanes' bits when N = (0, 0, 1):
/// every group, on random, grazing, below-horizon and invalid directions.
#[test]
fn the_local_frame_lanes_give_the_general_bits() {
    let mut seed = 99u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    };
    let mut blocks = Vec::new();
    for b in 0..64 {
        let mut inp = Inputs::default();
        for k in 0..LANES {
            for j in 0..6 {
                inp.v[j][k] = rnd() * if b % 3 == 0 { 1e-3 } else { 1.0 };
            }
            match (b * LANES + k) % 13 {
                0 => inp.v[2][k] = 1e-6,
                1 => inp.v[5][k] = -inp.v[5][k].abs(),
                2 => inp.v[0][k] = f32::NAN,
                3 => inp.v[3..6].iter_mut().for_each(|c| c[k] = 0.0),
                4 => inp.v[1][k] = f32::INFINITY,
                5..=7 => {
                    // Near the specular peak, where |n × h|² is tiny.
                    let l = [inp.v[0][k], inp.v[1][k], inp.v[2][k].abs() + 0.1];
                    inp.v[0][k] = l[0];
                    inp.v[1][k] = l[1];
                    inp.v[2][k] = l[2];
                    inp.v[3][k] = -l[0] * (1.0 + 1e-3 * rnd());
                    inp.v[4][k] = -l[1] + 1e-4 * rnd();
                    inp.v[5][k] = l[2];
                }
                _ => {
                    inp.v[2][k] = inp.v[2][k].abs();
                    inp.v[5][k] = inp.v[5][k].abs();
                }
            }
            inp.v[8][k] = 1.0;
        }
        blocks.push(inp);
    }
    let mut groups = 0;
    for model in [
        "model = \"lambert\"".to_string(),
        "model = \"cook-torrance\"\nroughness = 0.02".to_string(),
        // The f32 frame (roughness ≥ FAST_MIN_ROUGHNESS) as well as the f64 one.
        "model = \"cook-torrance\"\nroughness = 0.3".to_string(),
    ] {
        for d in ["ggx", "beckmann"] {
            for g in [
                "none",
                "cook-torrance",
                "smith",
                "smith-correlated",
                "smith-fast",
            ] {
                for f in [
                    "fresnel = \"none\"",
                    "fresnel = \"schlick\"\nf0 = [0.04, 0.5, 0.9]",
                    "fresnel = \"dielectric\"\nior = [1.5, 0.7, 2.4]",
                    "fresnel = \"conductor\"\nior = [0.2, 0.9, 1.1]\nextinction = [3.9, 2.4, 0.0]",
                ] {
                    let extra = if model.contains("lambert") {
                        String::new()
                    } else {
                        format!("distribution = \"{d}\"\ngeometry = \"{g}\"\n{f}\n")
                    };
                    let toml = format!(
                        "[[material]]\nname = \"x\"\n{model}\n{extra}diffuse = [0.2, 0.3, 0.4]\n"
                    );
                    let Ok(ms) = parse_materials(&toml, "t") else {
                        continue; // smith-fast is Beckmann's only
                    };
                    let plan = Plan::for_material(&ms[0]).with_terms(true);
                    let bare = Plan::for_material(&ms[0]);
                    assert!(plan.is_simd(), "{toml}");
                    for inp in &blocks {
                        let run = |plan: &Plan, z: bool| {
                            let mut o = Outputs::default();
                            crate::cpu::block::<_, crate::terms::math::Rounded>(
                                pulp::Scalar::new(),
                                plan,
                                std::slice::from_ref(inp),
                                std::slice::from_mut(&mut o),
                                z,
                            );
                            o
                        };
                        // The general frame, the local form's, and the local form's without
                        // the terms (D·G·K is then formed without dividing them out: the
                        // BRDF and the rescue decisions must not change).
                        let (a, b, c) = (run(&plan, false), run(&plan, true), run(&bare, true));
                        assert_eq!(a.rescue, b.rescue, "{toml}");
                        assert_eq!(b.rescue, c.rescue, "{toml}");
                        for k in 0..LANES {
                            if a.rescue[k] {
                                continue; // the reference writes these lanes
                            }
                            for ch in 0..3 {
                                assert_eq!(
                                    a.brdf[ch][k].to_bits(),
                                    b.brdf[ch][k].to_bits(),
                                    "{toml}"
                                );
                                assert_eq!(
                                    b.brdf[ch][k].to_bits(),
                                    c.brdf[ch][k].to_bits(),
                                    "{toml}: the terms changed the BRDF"
                                );
                            }
                            for t in 0..TERM_COLUMNS {
                                assert_eq!(
                                    a.terms[t][k].to_bits(),
                                    b.terms[t][k].to_bits(),
                                    "{toml}"
                                );
                            }
                        }
                    }
                    groups += 1;
                }
            }
        }
    }
    assert!(groups > 40, "{groups}");
}

/// `bits` puts lane k's flag at bit k for every one of the 2^16 patterns of a block.
#[test]
fn bits_puts_each_lane_at_its_bit_for_every_pattern() {
    for pattern in 0u32..1 << LANES {
        let flags: [bool; LANES] = std::array::from_fn(|k| pattern >> k & 1 == 1);
        assert_eq!(bits(&flags), pattern, "{pattern:016b}");
    }
}
