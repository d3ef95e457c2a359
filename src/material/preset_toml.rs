//! The presets' TOML bodies and names (their sources: the `presets` module's notes):
//! below the parser, which reads a `preset = "..."` key with them, and [`super::presets`],
//! which parses them.

/// The names of all presets, in the order `vkbrdf materials` lists them.
pub const NAMES: &[&str] = &[
    "gold",
    "silver",
    "copper",
    "aluminium",
    "glass",
    "water",
    "shiny-plastic",
    "htsg-aluminium",
    "gold-spectral",
    "silver-spectral",
    "copper-spectral",
    "aluminium-spectral",
    "glass-spectral",
    "water-spectral",
];

/// The spectral forms of the presets (FORMULAS.md §9), each with a measured `ior`.
pub const SPECTRAL: &[&str] = &[
    "gold-spectral",
    "silver-spectral",
    "copper-spectral",
    "aluminium-spectral",
    "glass-spectral",
    "water-spectral",
];

/// The TOML body (keys without `name`) of a preset, or `None` for an unknown name.
pub fn body(name: &str) -> Option<String> {
    Some(match name {
        "gold" => {
            METAL_GGX_03.trim_end().to_owned()
                + "\nior = [0.166, 0.430, 1.38]\nextinction = [3.15, 2.46, 1.92]\n"
        }
        "silver" => {
            METAL_GGX_03.trim_end().to_owned()
                + "\nior = [0.052, 0.059, 0.040]\nextinction = [4.41, 3.32, 2.65]\n"
        }
        "copper" => {
            METAL_GGX_03.trim_end().to_owned()
                + "\nior = [0.214, 1.02, 1.24]\nextinction = [3.67, 2.58, 2.40]\n"
        }
        "aluminium" => {
            METAL_GGX_03.trim_end().to_owned()
                + "\nior = [1.47, 0.958, 0.618]\nextinction = [7.79, 6.69, 5.47]\n"
        }
        "glass" => DIELECTRIC.trim_end().to_owned() + "\nior = 1.5\n",
        "water" => DIELECTRIC.trim_end().to_owned() + "\nior = 1.33\n",
        "shiny-plastic" => SHINY_PLASTIC.to_owned(),
        "htsg-aluminium" => HTSG_ALUMINIUM.to_owned(),
        "gold-spectral" => METAL_GGX_03.trim_end().to_owned() + "\nior = \"au-johnson-christy\"\n",
        "silver-spectral" => {
            METAL_GGX_03.trim_end().to_owned() + "\nior = \"ag-johnson-christy\"\n"
        }
        "copper-spectral" => {
            METAL_GGX_03.trim_end().to_owned() + "\nior = \"cu-johnson-christy\"\n"
        }
        "aluminium-spectral" => METAL_GGX_03.trim_end().to_owned() + "\nior = \"al-rakic\"\n",
        "glass-spectral" => DIELECTRIC.trim_end().to_owned() + "\nior = \"sio2-malitson\"\n",
        "water-spectral" => DIELECTRIC.trim_end().to_owned() + "\nior = \"h2o-hale-querry\"\n",
        _ => return None,
    })
}

/// Metals: modern Cook–Torrance, GGX α = 0.3, height-correlated Smith, exact conductor
/// Fresnel; the colour comes from F, so `specular` stays white (FORMULAS.md §6).
const METAL_GGX_03: &str = r#"
model = "cook-torrance"
distribution = "ggx"
roughness = 0.3
geometry = "smith-correlated"
fresnel = "conductor"
"#;

/// Smooth dielectrics: GGX α = 0.1, exact dielectric Fresnel, no diffuse.
const DIELECTRIC: &str = r#"
model = "cook-torrance"
distribution = "ggx"
roughness = 0.1
geometry = "smith-correlated"
fresnel = "dielectric"
"#;

/// The seed's shiny plastic: `d = 0.9, s = 0.1` with a red diffuse base, Beckmann `m = 0.2`
/// ("m near 0.2 indicates a nearly smooth surface") and a dielectric coat of IOR 1.5.
const SHINY_PLASTIC: &str = r#"
model = "cook-torrance"
distribution = "beckmann"
roughness = 0.2
geometry = "smith"
fresnel = "dielectric"
ior = 1.5
diffuse = [0.8, 0.1, 0.1]
diffuse_weight = 0.9
specular_weight = 0.1
"#;

/// He–Torrance–Sillion–Greenberg (FORMULAS.md §8) with the bbm benchmark's aluminium-like
/// surface: σ0 = 0.0318 µm, τ = 0.3 µm, η at Westin's wavelengths 645, 526 and 444 nm.
const HTSG_ALUMINIUM: &str = r#"
model = "htsg"
sigma0 = 0.0318
tau = 0.3
ior = [1.3211, 0.88045, 0.59765]
extinction = [7.41785, 6.1455, 5.2337]
wavelengths = [645, 526, 444]
"#;
