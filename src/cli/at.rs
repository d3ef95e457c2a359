//! `vkbrdf at`: one material at a few directions given as angles — f and its terms, no
//! `.npy` to build.

use super::backend_choice::{self, BackendArgs, BackendKind};
use std::path::PathBuf;
use std::process::ExitCode;
use vkbrdf::backend::{Backend, Request, TERM_COLUMNS};
use vkbrdf::batch::Batch;
use vkbrdf::material::Material;

/// Arguments of `vkbrdf at`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Directions are in the local frame: N = +z, T = +x, azimuths φ measured from +x toward +y,
all angles in degrees. Each --dir is θ_i,φ_i,θ_o,φ_o (L at (θ_i, φ_i), V at (θ_o, φ_o));
each --rus is Rusinkiewicz's θ_h,θ_d,φ_d with φ_h = 0. Without either, a small default set
(normal incidence, 45° mirror, 45° back-scatter, 80° grazing mirror, a half/difference
pair). Printed per direction: f (RGB, 1/sr, no cosine) and the terms D, G, F (RGB), K;
for an HTSG material also ρ_dd and the mirror spike's weight ρ_s (FORMULAS.md §8);
--json prints the same as a JSON array.

MATERIAL is a preset (gold, glass, shiny-plastic, … — `vkbrdf materials` lists them) or,
with --materials FILE, the name of one of its [[material]] tables.

Evaluator: `at` runs the f64 reference unless --backend names another (cpu, vulkan, auto);
the `auto` default shown for --backend is that of the evaluating commands, not this one.

Examples:
  vkbrdf at gold
  vkbrdf at gold --dir 30,0,30,180 --dir 60,0,60,180
  vkbrdf at brushed --materials m.toml --rus 10,45,90 --json")]
pub struct Args {
    /// A preset name, or a material name in --materials.
    #[arg(value_name = "MATERIAL")]
    pub material: String,
    /// Materials file to look MATERIAL up in (TOML, [[material]] tables).
    #[arg(long, short = 'm', value_name = "M.toml")]
    pub materials: Option<PathBuf>,
    /// θ_i,φ_i,θ_o,φ_o in degrees (repeatable).
    #[arg(long = "dir", value_name = "TI,PI,TO,PO", value_parser = angles::<4>,
          allow_hyphen_values = true)]
    pub dirs: Vec<[f64; 4]>,
    /// θ_h,θ_d,φ_d in degrees, φ_h = 0 (repeatable).
    #[arg(long = "rus", value_name = "TH,TD,PD", value_parser = angles::<3>,
          allow_hyphen_values = true)]
    pub rus: Vec<[f64; 3]>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Evaluator: the f64 reference by default here (`reference`); `cpu`, `vulkan` and
    /// `auto` run an engine.
    #[command(flatten)]
    pub backend: BackendArgs,
}

/// `N` comma-separated finite angles in degrees.
fn angles<const N: usize>(s: &str) -> Result<[f64; N], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != N {
        return Err(format!(
            "expected {N} comma-separated angles in degrees, got {s:?}"
        ));
    }
    let mut out = [0.0; N];
    for (o, p) in out.iter_mut().zip(&parts) {
        *o = p
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite() && x.abs() <= 360.0)
            .ok_or_else(|| format!("{p:?} is not an angle in degrees within ±360"))?;
    }
    Ok(out)
}

/// The unit vector at polar angle `theta` and azimuth `phi` (degrees) about N = +z.
fn direction(theta: f64, phi: f64) -> [f64; 3] {
    let (st, ct) = theta.to_radians().sin_cos();
    let (sp, cp) = phi.to_radians().sin_cos();
    [st * cp, st * sp, ct]
}

/// One requested direction pair: its label and (l, v).
struct Query {
    label: String,
    l: [f64; 3],
    v: [f64; 3],
}

fn queries(args: &Args) -> Vec<Query> {
    let mut dirs = args.dirs.clone();
    let mut rus = args.rus.clone();
    if dirs.is_empty() && rus.is_empty() {
        dirs = vec![
            [0.0, 0.0, 0.0, 0.0],
            [45.0, 0.0, 45.0, 180.0],
            [45.0, 0.0, 45.0, 0.0],
            [80.0, 0.0, 80.0, 180.0],
        ];
        rus = vec![[10.0, 45.0, 90.0]];
    }
    let mut out: Vec<Query> = dirs
        .iter()
        .map(|&[ti, pi, to, po]| Query {
            label: format!("θi {ti} φi {pi} θo {to} φo {po}"),
            l: direction(ti, pi),
            v: direction(to, po),
        })
        .collect();
    out.extend(rus.iter().map(|&[th, td, pd]| {
        let (l, v) =
            vkbrdf::table::slice::from_half_diff(th.to_radians(), td.to_radians(), pd.to_radians());
        Query {
            label: format!("θh {th} θd {td} φd {pd}"),
            l,
            v,
        }
    }));
    out
}

fn find_material(args: &Args) -> anyhow::Result<Material> {
    if let Some(file) = &args.materials {
        let all = vkbrdf::material::load_materials(file)?;
        return all
            .iter()
            .find(|m| m.name == args.material)
            .cloned()
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "{} has no material named {:?}; it has: {}",
                    file.display(),
                    args.material,
                    all.iter()
                        .map(|m| m.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            });
    }
    match vkbrdf::material::presets::preset(&args.material) {
        Some(m) => Ok(m?),
        None => anyhow::bail!(
            "no preset named {:?} (the presets: {}); for your own material pass --materials FILE",
            args.material,
            vkbrdf::material::presets::NAMES.join(", ")
        ),
    }
}

/// Runs `vkbrdf at`.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let material = find_material(args)?;
    let qs = queries(args);
    let tangent = material.is_anisotropic();
    let mut rows = Vec::new();
    for q in &qs {
        rows.extend(q.l.iter().chain(&q.v).map(|&x| x as f32));
        rows.extend_from_slice(&[0.0, 0.0, 1.0, 0.0]);
        if tangent {
            rows.extend_from_slice(&[1.0, 0.0, 0.0]);
        }
    }
    let columns = if tangent { 13 } else { 10 };
    let batch = Batch::new(rows, columns, 1, &vkbrdf::batch::memory_source())?;
    let mut backend: Box<dyn Backend> = match args.backend.backend {
        None | Some(BackendKind::Reference) => Box::new(vkbrdf::reference::CpuReference::new()),
        Some(BackendKind::Cpu | BackendKind::Vulkan | BackendKind::Auto) => {
            backend_choice::open(&args.backend)?
        }
    };
    let out = backend.evaluate(
        &batch,
        std::slice::from_ref(&material),
        &Request { terms: true },
    )?;
    let terms = out.terms.unwrap_or_default();
    // HTSG: ρ_dd (f less the uniform diffuse a/π) and the spike's weight ρ_s (FORMULAS.md
    // §8), the latter from the reference (it is not a BRDF value an engine returns).
    let htsg: Option<Vec<([f64; 3], [f64; 3])>> =
        matches!(material.model, vkbrdf::material::Model::Htsg(_)).then(|| {
            (0..qs.len())
                .map(|i| {
                    let rho_s = vkbrdf::reference::htsg_spike(&batch.tuple(i), &material)
                        .unwrap_or_default();
                    let f = &out.brdf[3 * i..3 * i + 3];
                    let rho_dd = std::array::from_fn(|c| {
                        if f[c] == 0.0 {
                            0.0
                        } else {
                            f64::from(f[c]) - material.diffuse[c] / std::f64::consts::PI
                        }
                    });
                    (rho_dd, rho_s)
                })
                .collect()
        });
    let spectral = spectral_rows(&material, &batch, backend.as_mut())?;
    if args.json {
        let items: Vec<serde_json::Value> = qs
            .iter()
            .enumerate()
            .map(|(i, q)| {
                let t = &terms[i * TERM_COLUMNS..(i + 1) * TERM_COLUMNS];
                let mut item = serde_json::json!({
                    "at": q.label, "l": q.l, "v": q.v,
                    "f": &out.brdf[3 * i..3 * i + 3],
                    "D": t[0], "G": t[1], "F": &t[2..5], "K": t[5],
                });
                if let Some(h) = &htsg {
                    item["rho_dd"] = serde_json::json!(h[i].0);
                    item["rho_s"] = serde_json::json!(h[i].1);
                }
                if let Some(sp) = &spectral {
                    item["spectral_srgb"] = serde_json::json!(sp[i][0]);
                    item["mitsuba"] = serde_json::json!(sp[i][1]);
                    item["filament"] = serde_json::json!(sp[i][2]);
                }
                item
            })
            .collect();
        let doc = serde_json::json!({
            "material": material.name, "engine": backend.name(), "results": items
        });
        outln!("{}", serde_json::to_string_pretty(&doc)?);
        return Ok(ExitCode::SUCCESS);
    }
    outln!(
        "{} on {} (N = +z, T = +x; f in 1/sr, no cosine)",
        material.name,
        backend.name()
    );
    outln!(
        "{:<30} {:>11} {:>11} {:>11} {:>11} {:>9} {:>9} {:>9} {:>9} {:>11}",
        "directions (degrees)",
        "f_r",
        "f_g",
        "f_b",
        "D",
        "G",
        "F_r",
        "F_g",
        "F_b",
        "K"
    );
    for (i, q) in qs.iter().enumerate() {
        let f = &out.brdf[3 * i..3 * i + 3];
        let t = &terms[i * TERM_COLUMNS..(i + 1) * TERM_COLUMNS];
        outln!(
            "{:<30} {:>11.5e} {:>11.5e} {:>11.5e} {:>11.5e} {:>9.5} {:>9.5} {:>9.5} {:>9.5} {:>11.5e}",
            q.label, f[0], f[1], f[2], t[0], t[1], t[2], t[3], t[4], t[5]
        );
    }
    if let Some(h) = &htsg {
        outln!(
            "\nHTSG (FORMULAS.md §8): f = ρ_dd + a/π; the mirror spike ρ_s δ(ω − ω_mirror)/cos_i is not in f"
        );
        outln!(
            "{:<30} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11}",
            "directions (degrees)",
            "ρ_dd r",
            "ρ_dd g",
            "ρ_dd b",
            "ρ_s r",
            "ρ_s g",
            "ρ_s b"
        );
        for (q, (dd, s)) in qs.iter().zip(h) {
            outln!(
                "{:<30} {:>11.5e} {:>11.5e} {:>11.5e} {:>11.5} {:>11.5} {:>11.5}",
                q.label,
                dd[0],
                dd[1],
                dd[2],
                s[0],
                s[1],
                s[2]
            );
        }
    }
    if let Some(sp) = &spectral {
        let own = material
            .spectral
            .as_ref()
            .map_or("", |s| s.reduction.name());
        outln!(
            "\nSpectral (FORMULAS.md §9): f over 360–830 nm reduced to linear sRGB under D65, beside the two RGB forms of the index (the material's own, above, is {own})"
        );
        outln!(
            "{:<30} {:>11} {:>11} {:>11} | {:>11} {:>11} {:>11} | {:>11} {:>11} {:>11}",
            "directions (degrees)",
            "spectral r",
            "g",
            "b",
            "mitsuba r",
            "g",
            "b",
            "filament r",
            "g",
            "b"
        );
        for (q, v) in qs.iter().zip(sp) {
            outln!(
                "{:<30} {:>11.5e} {:>11.5e} {:>11.5e} | {:>11.5e} {:>11.5e} {:>11.5e} | {:>11.5e} {:>11.5e} {:>11.5e}",
                q.label, v[0][0], v[0][1], v[0][2], v[1][0], v[1][1], v[1][2], v[2][0], v[2][1], v[2][2]
            );
        }
    }
    let c = out.counts;
    if c.below_horizon > 0 || c.invalid > 0 {
        outln!(
            "({} below the horizon, {} invalid: their values are 0)",
            c.below_horizon,
            c.invalid
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// For a spectral material: per query, f reduced to sRGB (D65) from the spectral evaluation,
/// and f with each RGB form of its index (Mitsuba's, Filament's), on the same engine.
fn spectral_rows(
    material: &vkbrdf::material::Material,
    batch: &Batch,
    backend: &mut dyn Backend,
) -> anyhow::Result<Option<Vec<[[f32; 3]; 3]>>> {
    use vkbrdf::material::{spectral::rgb_fresnel, Model};
    use vkbrdf::spectral::RgbReduction;
    let Some(s) = &material.spectral else {
        return Ok(None);
    };
    let Model::CookTorrance(ct) = &material.model else {
        return Ok(None); // htsg reads its index at its own wavelengths
    };
    let colour = Some((vkbrdf::spectral_eval::Colour::Srgb, Default::default()));
    let job = vkbrdf::spectral_eval::SpectralJob::new(
        std::slice::from_ref(material),
        vkbrdf::spectral::Wavelengths::cie(),
        colour,
    )?;
    let spectral = job.evaluate(backend, batch)?;
    let mut forms = Vec::new();
    for r in RgbReduction::ALL {
        let mut m = material.clone();
        let mut c = ct.clone();
        c.fresnel = rgb_fresnel(s.fresnel, &s.index, r).map_err(anyhow::Error::msg)?;
        m.model = Model::CookTorrance(c);
        m.spectral = None;
        forms.push(backend.evaluate(batch, std::slice::from_ref(&m), &Request::default())?);
    }
    let three = |v: &[f32], i: usize| [v[3 * i], v[3 * i + 1], v[3 * i + 2]];
    Ok(Some(
        (0..batch.len())
            .map(|i| {
                [
                    three(&spectral.brdf, i),
                    three(&forms[0].brdf, i),
                    three(&forms[1].brdf, i),
                ]
            })
            .collect(),
    ))
}
