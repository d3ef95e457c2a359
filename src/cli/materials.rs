//! `vkbrdf materials`: list presets, or validate and list a materials file.

use std::path::PathBuf;
use std::process::ExitCode;
use vkbrdf::material::{self, Fresnel, Material, Model};

/// Arguments of `vkbrdf materials`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = r#"Materials files are TOML, one [[material]] table per material:

  [[material]]
  name = "brushed"            # required, unique
  preset = "aluminium"        # optional: start from a preset, then override keys
  model = "cook-torrance"     # lambert | phong | blinn-phong | rtr | ward | cook-torrance | merl
                              # | htsg
  convention = "modern"       # seed | cook-torrance-1982 | modern (default)
  distribution = "ggx"        # gaussian | beckmann | ggx | blinn | charlie (sheen, 0 < m <= 1)
  roughness = [0.1, 0.4]      # m > 0 (rms slope; GGX alpha), or [mx, my] (anisotropic)
  geometry = "smith-correlated" # none | cook-torrance | smith | smith-correlated | smith-fast
                              # | schlick-smith | neubelt
  fresnel = "conductor"       # none | dielectric | conductor | schlick
  ior = [1.47, 0.958, 0.618]  # number or RGB; or a spectrum: "au-johnson-christy",
                              # [[λ_nm, n, k], ...] rows or { file = "x.yml" } (docs/SPECTRAL.md)
  # rgb_reduction = "mitsuba" # a spectral ior's RGB form: mitsuba (default) | filament
  extinction = [7.79, 6.69, 5.47] # RGB k (conductor)
  # f0 = [0.9, 0.9, 0.9]      # schlick: F0, or give ior (+ extinction) instead
  # exponent = 50             # phong, blinn-phong, rtr, and distribution "blinn"
  diffuse = [0.0, 0.0, 0.0]   # c_diff (default black)
  specular = [1.0, 1.0, 1.0]  # c_spec (default white)
  specular_weight = 1.0       # s (default 1)
  diffuse_weight = 0.0        # d (default 0)
  precision = "exact"         # exact (default) | fast: Schlick for exact Fresnel,
                              # smith-fast for Smith-Beckmann (any analytic model)

  [[material]]
  name = "measured"
  model = "merl"              # measured data (every backend)
  file = "gold.binary"        # a MERL binary, relative to this file
  lookup = "nearest"          # nearest (default: MERL's own bin lookup) | linear

  [[material]]
  name = "wave-optical"
  model = "htsg"              # He, Torrance, Sillion & Greenberg 1991 (docs/HTSG.md)
  sigma0 = 0.0318             # rms height, µm, in [1e-4, 10]
  tau = 0.3                   # autocorrelation length, µm, in [1e-3, 100]; sigma0/tau in
                              # [1e-3, 10] (Beckmann m ≈ 2 sigma0/tau)
  ior = [1.3211, 0.88045, 0.59765]       # n per channel
  extinction = [7.41785, 6.1455, 5.2337] # k per channel (default 0: a dielectric)
  wavelengths = [645, 526, 444]          # nm per channel (the default)
  diffuse = 0.0               # uniform-diffuse albedo a: f = rho_dd + a/pi (the mirror
                              # spike's weight rho_s: `vkbrdf at`, `eval --spike`)

Keys a model does not read are errors, as are negative colours or weights, roughness <= 0,
smith* or schlick-smith with gaussian/blinn/charlie, smith-fast with anything but beckmann,
schlick-smith with anisotropic roughness, charlie with m > 1, conductor without extinction,
and anisotropic roughness outside ward and modern beckmann/ggx.

Examples:
  vkbrdf materials                      # the presets
  vkbrdf materials --file m.toml        # validate m.toml and list what it defines"#
)]
pub struct Args {
    /// Validate this materials file and list its materials instead of the presets.
    #[arg(long, short = 'f', value_name = "M.toml")]
    pub file: Option<PathBuf>,
}

/// Runs `vkbrdf materials`.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let list = match &args.file {
        Some(path) => material::load_materials(path)?,
        None => material::presets::all(),
    };
    outln!("{:<16} definition", "name");
    for m in &list {
        outln!("{:<16} {}", m.name, summary(m));
    }
    Ok(ExitCode::SUCCESS)
}

fn rgb(c: [f64; 3]) -> String {
    if c[0] == c[1] && c[1] == c[2] {
        format!("{}", c[0])
    } else {
        format!("[{}, {}, {}]", c[0], c[1], c[2])
    }
}

/// A one-line description of a material.
pub fn summary(m: &Material) -> String {
    let body = match &m.model {
        Model::Lambert => format!("lambert diffuse={}", rgb(m.diffuse)),
        Model::Phong { exponent } => format!("phong e={exponent}"),
        Model::BlinnPhong { exponent } => format!("blinn-phong e={exponent}"),
        Model::Rtr { exponent } => format!("rtr e={exponent}"),
        Model::Ward { roughness } => format!("ward {}", roughness.describe()),
        Model::Measured(m) => format!("merl {}", m.path.display()),
        Model::Htsg(p) => format!(
            "htsg sigma0={} µm tau={} µm (Beckmann m≈{:.3}), n={} k={}, λ={} nm, diffuse={}",
            p.sigma0,
            p.tau,
            vkbrdf::terms::htsg::beckmann_m(p),
            rgb(p.ior),
            rgb(p.extinction),
            rgb(p.wavelengths.map(|l| (l * 1000.0 * 1e6).round() / 1e6)),
            rgb(m.diffuse)
        ),
        Model::CookTorrance(ct) => {
            let d = ct.distribution.describe();
            let f = match ct.fresnel {
                Fresnel::None => "F=none".to_string(),
                Fresnel::Dielectric { ior } => format!("dielectric ior={}", rgb(ior)),
                Fresnel::Conductor { ior, extinction } => {
                    format!("conductor n={} k={}", rgb(ior), rgb(extinction))
                }
                Fresnel::Schlick { f0 } => format!("schlick f0={}", rgb(f0)),
            };
            format!(
                "cook-torrance ({}) {d}, G={}, {f}, s={} d={}",
                ct.convention.toml_name(),
                ct.geometry.toml_name(),
                ct.specular_weight,
                ct.diffuse_weight
            )
        }
    };
    let body = if m.precision == vkbrdf::precision::Precision::Fast {
        format!("{body}, precision=fast")
    } else {
        body
    };
    if matches!(
        m.model,
        Model::Lambert | Model::Measured(_) | Model::Htsg(_)
    ) {
        body
    } else if m.diffuse != [0.0; 3] || m.specular != [1.0; 3] {
        format!(
            "{body}, diffuse={}, specular={}",
            rgb(m.diffuse),
            rgb(m.specular)
        )
    } else {
        body
    }
}
