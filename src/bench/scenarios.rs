//! The benchmark scenarios: fixed materials and seeded inputs with N = +z and unit L, V
//! uniform over the upper hemisphere (the layout the peers read too).

use crate::batch::{Batch, LocalBatch, COLUMNS_LOCAL, COLUMNS_PLAIN, COLUMNS_TANGENT};
use crate::material::{parse_materials, Material};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// One benchmark scenario.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// Short name used in tables, JSON and plots.
    pub name: &'static str,
    /// The material table; rows cycle through it.
    pub materials: Vec<Material>,
    /// Whether the rows carry tangents (anisotropic materials).
    pub tangents: bool,
    /// The peer scenario (`beckmann` / `ggx` of benches/peers/peer.py) evaluating the same
    /// BRDF, if any.
    pub peer: Option<&'static str>,
}

const MITSUBA_METAL: &str =
    "ior = [0.2, 0.92, 1.1]\nextinction = [3.9, 2.45, 2.14]\nfresnel = \"conductor\"\n";

fn scenario(
    name: &'static str,
    toml: &str,
    tangents: bool,
    peer: Option<&'static str>,
) -> Scenario {
    let materials = parse_materials(toml, name).expect("benchmark materials are legal");
    Scenario {
        name,
        materials,
        tangents,
        peer,
    }
}

/// Every scenario: the six of the issue, GGX + Schlick (for the specialisation measurement), the two that match the Mitsuba peer exactly
/// (its `roughconductor`: Beckmann with Walter's rational G1 = our `smith-fast`, GGX with
/// separable Smith, exact conductor Fresnel).
pub fn all() -> Vec<Scenario> {
    let ct = |d: &str, r: f64, g: &str, f: &str| {
        format!("model = \"cook-torrance\"\ndistribution = \"{d}\"\nroughness = {r}\ngeometry = \"{g}\"\n{f}")
    };
    vec![
        scenario(
            "lambert",
            "[[material]]\nname = \"m\"\nmodel = \"lambert\"\ndiffuse = [0.8, 0.5, 0.2]\n",
            false,
            None,
        ),
        scenario(
            "blinn-phong",
            "[[material]]\nname = \"m\"\nmodel = \"blinn-phong\"\nexponent = 50\ndiffuse = 0.2\n",
            false,
            None,
        ),
        scenario(
            "beckmann-smith-dielectric",
            &format!(
                "[[material]]\nname = \"m\"\n{}",
                ct(
                    "beckmann",
                    0.3,
                    "smith",
                    "fresnel = \"dielectric\"\nior = 1.5\n"
                )
            ),
            false,
            None,
        ),
        scenario(
            "ggx-schlick",
            &format!(
                "[[material]]\nname = \"m\"\n{}",
                ct(
                    "ggx",
                    0.3,
                    "smith-correlated",
                    "fresnel = \"schlick\"\nf0 = [0.95, 0.64, 0.54]\n"
                )
            ),
            false,
            None,
        ),
        scenario(
            "ggx-smithcorr-conductor",
            &format!(
                "[[material]]\nname = \"m\"\n{}",
                ct("ggx", 0.3, "smith-correlated", MITSUBA_METAL)
            ),
            false,
            None,
        ),
        scenario(
            "ward-aniso",
            "[[material]]\nname = \"m\"\nmodel = \"ward\"\nroughness = [0.1, 0.4]\ndiffuse = 0.1\n",
            true,
            None,
        ),
        scenario("mixed-8", MIXED_8, true, None),
        scenario(
            "mitsuba-beckmann",
            &format!(
                "[[material]]\nname = \"m\"\n{}",
                ct("beckmann", 0.3, "smith-fast", MITSUBA_METAL)
            ),
            false,
            Some("beckmann"),
        ),
        scenario(
            "mitsuba-ggx",
            &format!(
                "[[material]]\nname = \"m\"\n{}",
                ct("ggx", 0.3, "smith", MITSUBA_METAL)
            ),
            false,
            Some("ggx"),
        ),
    ]
}

const MIXED_8: &str = r#"
[[material]]
name = "lambert"
model = "lambert"
diffuse = 0.5
[[material]]
name = "phong"
model = "phong"
exponent = 30
[[material]]
name = "rtr"
model = "rtr"
exponent = 20
[[material]]
name = "ward"
model = "ward"
roughness = [0.1, 0.4]
[[material]]
name = "gold"
preset = "gold"
[[material]]
name = "glass"
preset = "glass"
[[material]]
name = "plastic"
preset = "shiny-plastic"
[[material]]
name = "seed"
model = "cook-torrance"
convention = "seed"
distribution = "gaussian"
roughness = 0.2
geometry = "cook-torrance"
fresnel = "schlick"
f0 = 0.04
"#;

/// A scenario by name.
pub fn by_name(name: &str) -> Option<Scenario> {
    all().into_iter().find(|s| s.name == name)
}

/// `n` seeded tuples for `scenario`: N = +z, L and V unit and uniform (in solid angle) over
/// the upper hemisphere, rows cycling through the materials, T = +x when needed.
pub fn batch(scenario: &Scenario, n: usize, seed: u64) -> Batch<'static> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let cols = if scenario.tangents {
        COLUMNS_TANGENT
    } else {
        COLUMNS_PLAIN
    };
    let mut data = Vec::with_capacity(n * cols);
    let hemi = |rng: &mut Pcg64Mcg| {
        let z: f64 = rng.random_range(0.0..1.0);
        let phi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
        let r = (1.0 - z * z).sqrt();
        [(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32]
    };
    let m = scenario.materials.len();
    for i in 0..n {
        let l = hemi(&mut rng);
        let v = hemi(&mut rng);
        data.extend_from_slice(&l);
        data.extend_from_slice(&v);
        data.extend_from_slice(&[0.0, 0.0, 1.0, (i % m) as f32]);
        if scenario.tangents {
            data.extend_from_slice(&[1.0, 0.0, 0.0]);
        }
    }
    Batch::new(data, cols, m, &crate::batch::memory_source()).expect("benchmark batches are valid")
}

/// [`batch`]'s tuples in the local-frame form (`Lx Ly Lz Vx Vy Vz`, 24 bytes a tuple — what
/// the Mitsuba peer reads): `None` for a scenario of several materials or with tangents.
pub fn local_batch(scenario: &Scenario, n: usize, seed: u64) -> Option<LocalBatch> {
    if scenario.tangents || scenario.materials.len() != 1 {
        return None;
    }
    let rows = batch(scenario, n, seed);
    let mut data = Vec::with_capacity(n * COLUMNS_LOCAL);
    for r in rows.as_slice().chunks_exact(COLUMNS_PLAIN) {
        data.extend_from_slice(&r[..COLUMNS_LOCAL]);
    }
    Some(
        LocalBatch::new(data, 0, &scenario.materials, &crate::batch::memory_source())
            .expect("benchmark batches are valid"),
    )
}
