//! `vkbrdf table <kind>`: slices, albedo, DFG, MERL exports and previews of materials,
//! evaluated on the chosen backend (library: `vkbrdf::table`).

use super::backend_choice::{self, BackendArgs};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;
use vkbrdf::material::{DistributionKind, Geometry, Material};
use vkbrdf::stream::shard::Shard;
use vkbrdf::table::albedo::Sampler;
use vkbrdf::table::albedo::{self, AlbedoJob, Lobe, Microfacet};
use vkbrdf::table::dfg::{self, Axes, DfgJob, Layout, LutStyle, RoughnessAxis, Sampling};
use vkbrdf::table::preview::{self, PreviewJob};
use vkbrdf::table::shard::PartSpec;
use vkbrdf::table::slice::{self, SliceJob, Spacing};
use vkbrdf::table::{merl, Grid, Runner};

/// Arguments of `vkbrdf table`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Every table evaluates f through the chosen backend (--backend auto|vulkan|cpu|reference),
writes its file
atomically (a failed or interrupted run leaves the previous file and no partial one; a
symlink is written through; several outputs appear together or not at all; a FIFO, a
device or `-` is written directly after success, atomicity being a promise for regular
files; an output that is an input is refused before any work), and records its provenance (material,
convention, parameterisation, texel centres, samples, backend, vkbrdf version) in the
EXR header. Texel centres: column i <-> x = (i + 0.5)/W, row j <-> y = (j + 0.5)/H.

Examples:
  vkbrdf table slice --material gold --output gold-slice.exr --terms
  vkbrdf table albedo --geometry smith-correlated --output E.exr --average Eavg.exr
  vkbrdf table dfg --output dfg.exr
  vkbrdf table merl --materials m.toml --material brushed --output brushed.binary
  vkbrdf table preview --material copper --sphere copper.png --polar copper-lobe.png")]
pub struct Args {
    /// Which table.
    #[command(subcommand)]
    pub kind: Kind,
}

/// The table kinds.
#[derive(clap::Subcommand, Debug)]
pub enum Kind {
    /// f over half/difference angles (θ_h, θ_d) at φ_d = 90° (Rusinkiewicz 1998), RGB EXR.
    Slice(SliceArgs),
    /// Directional albedo E(μ = cos_o, α) of Cook–Torrance with F = 1, channel Y.
    Albedo(AlbedoArgs),
    /// Split-sum DFG (Karis 2013): R = A (scale), G = B (bias), E = F0·A + B under Schlick.
    Dfg(DfgArgs),
    /// Export a material as a MERL binary (90×90×180 half/difference bins, f64).
    Merl(MerlArgs),
    /// A lit-sphere PNG and a polar plot of the lobe in the plane of incidence.
    Preview(PreviewArgs),
    /// A spectral material's Fresnel reflectance (sRGB, D65) against θ beside its RGB
    /// reductions (Mitsuba's, Filament's), with the differences and ΔE*ab; table and plot.
    Spectral(SpectralArgs),
}

/// Arguments of `vkbrdf table spectral`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
For θ from 0 to 90°, the Fresnel reflectance F(λ, cos θ) of the material's measured index,
reduced to linear sRGB under D65 by the CIE 1931 quadrature (FORMULAS.md §9), beside the
two common RGB forms of the same material: Mitsuba 3's (n and k each reduced to sRGB with
equal-energy weighting, then the exact Fresnel) and Filament's (F0 reduced under D65, then
Schlick). Each RGB form's per-channel difference from the spectral colour and its ΔE*ab
(CIELAB, D65 white) follow. Computed on the host in f64 (no engine: only F depends on λ).

Examples:
  vkbrdf table spectral --material gold-spectral
  vkbrdf table spectral --material copper-spectral --output copper.md --plot copper.svg
  vkbrdf table spectral -m m.toml --material my-metal --step 1")]
pub struct SpectralArgs {
    #[command(flatten)]
    material: MaterialArgs,
    /// Angle step in degrees.
    #[arg(long, default_value_t = 5.0, value_name = "DEG")]
    step: f64,
    /// Write the table (Markdown) here instead of standard output.
    #[arg(long, short = 'o', value_name = "TABLE.md")]
    output: Option<PathBuf>,
    /// Also draw the plot (SVG).
    #[arg(long, value_name = "PLOT.svg")]
    plot: Option<PathBuf>,
}

/// `vkbrdf table spectral`: no engine, so it runs before a backend is opened.
fn spectral_table(a: &SpectralArgs) -> anyhow::Result<ExitCode> {
    let inputs: Vec<&std::path::Path> = a.material.materials.as_deref().into_iter().collect();
    let outputs: Vec<&std::path::Path> = a
        .output
        .iter()
        .chain(&a.plot)
        .map(PathBuf::as_path)
        .collect();
    vkbrdf::atomic::check_outputs(&outputs, &inputs)?;
    let material = a.material.load()?;
    let rows = vkbrdf::table::spectral::reflectance(&material, a.step)?;
    let text = vkbrdf::table::spectral::markdown(&material, &rows);
    if let Some(path) = &a.plot {
        // plotters writes the file itself: draw into a temporary one beside it, then rename.
        let tmp = path.with_extension("svg.partial");
        vkbrdf::table::spectral::plot(&tmp, &material, &rows)?;
        anyhow::Context::with_context(std::fs::rename(&tmp, path), || {
            format!("writing {}", path.display())
        })?;
    }
    match &a.output {
        Some(path) => {
            vkbrdf::atomic::write(path, |w| std::io::Write::write_all(w, text.as_bytes()))?
        }
        None => outln!("{text}"),
    }
    Ok(ExitCode::SUCCESS)
}

/// Which material: a name in a materials file, or a preset when no file is given.
#[derive(clap::Args, Debug)]
pub struct MaterialArgs {
    /// Materials file (TOML); without it, NAME is one of the presets (`vkbrdf materials`).
    #[arg(long, short = 'm', value_name = "M.toml")]
    pub materials: Option<PathBuf>,
    /// The material's name.
    #[arg(long, value_name = "NAME")]
    pub material: String,
}

/// Arguments of `vkbrdf table slice`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Columns: theta_h = x^2 * 90° (MERL's square-root spacing; --linear: x * 90°); rows:
theta_d = y * 90°; phi_d = 90°, phi_h = 0, n = +z, t = +x. Layer `brdf` holds R, G, B = f
in 1/sr; --terms adds layer `terms` with D, G, F.R, F.G, F.B, K. --png writes the same
texels as a picture (theta_h across, theta_d down from 0 at the top), pi * f in display
sRGB: a white Lambertian is white, brighter values are scaled to keep their hue. On Vulkan the kernel
makes the directions itself (nothing but the material is uploaded; up to 2^24 texels);
--backend cpu (the native CPU engine) and --backend reference (the f64 reference)
evaluate host-made directions.

Example:
  vkbrdf table slice --materials m.toml --material plastic --output plastic.exr --terms
  vkbrdf table slice --material gold --output gold.exr --png gold-slice.png")]
pub struct SliceArgs {
    #[command(flatten)]
    material: MaterialArgs,
    /// Output EXR.
    #[arg(long, short = 'o', value_name = "S.exr")]
    output: PathBuf,
    /// Table size WxH (or N for NxN).
    #[arg(long, value_name = "WxH", default_value = "90x90", value_parser = parse_grid,
          allow_negative_numbers = true)]
    size: Grid,
    /// θ_h linear in x instead of MERL's square-root spacing.
    #[arg(long)]
    linear: bool,
    /// Add the layer `terms` (D, G, F.R, F.G, F.B, K).
    #[arg(long)]
    terms: bool,
    /// Also write the slice as a PNG: pixel (i, j) = texel (i, j), showing π·f in display
    /// sRGB (a white Lambertian is white; brighter values keep their hue).
    #[arg(long, value_name = "S.png", conflicts_with = "shard")]
    png: Option<PathBuf>,
    /// Evaluate only band K of N of the θ_d rows (1-based, e.g. 2/8: rows [(K−1)H/N, KH/N)),
    /// writing it as a .npy part (OUTPUT must end in .npy) with its sidecar
    /// OUTPUT.shard.json; `vkbrdf merge -o S.exr PART…` writes the EXR.
    #[arg(long, value_name = "K/N")]
    shard: Option<Shard>,
    /// Write float16 instead of float32.
    #[arg(long)]
    half: bool,
    #[command(flatten)]
    backend: BackendArgs,
}

/// The model options of the integrated tables.
#[derive(clap::Args, Debug)]
pub struct ModelArgs {
    /// Microfacet distribution (the integrators importance-sample ggx and beckmann only).
    #[arg(long, default_value = "ggx", value_parser = distribution_parser())]
    distribution: DistributionKind,
    /// Geometric attenuation (smith-fast needs beckmann; schlick-smith uses k = α/2 with
    /// ggx, k = m·sqrt(2/π) with beckmann).
    #[arg(long, default_value = "smith-correlated", value_parser = geometry_parser())]
    geometry: Geometry,
    /// What the y axis holds: alpha (y = α) or perceptual roughness r (α = r², as UE4
    /// and Filament index their LUTs).
    #[arg(long, value_name = "AXIS", default_value = "alpha",
          value_parser = clap::builder::PossibleValuesParser::new(["alpha", "perceptual"]))]
    roughness_axis: String,
    /// Where texels sit: centres (x = (i + 0.5)/W) or endpoints (x = i/(W - 1), both 0
    /// and 1 included; the 0 ends hold the limits, evaluated at 2^-10).
    #[arg(long, value_name = "WHERE", default_value = "centres",
          value_parser = clap::builder::PossibleValuesParser::new(["centres", "endpoints"]))]
    sampling: String,
    /// Table size WxH (or N): x = μ = cos_o, y = roughness [default: 32x32; Filament's
    /// 128x128 with --lut-style filament].
    #[arg(long, value_name = "WxH", value_parser = parse_grid, allow_negative_numbers = true)]
    size: Option<Grid>,
    /// Quasi-Monte Carlo samples per texel, 1 to 2^26 [default: 65536, accuracy ≤ 1e-4
    /// (see --help); 1024 with --lut-style, the engines' count].
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          value_parser = super::ranges::integer::<u32>(1, 1 << 26))]
    samples: Option<u32>,
    /// Write float16 instead of float32.
    #[arg(long)]
    half: bool,
    /// Evaluate only band K of N of the roughness rows (1-based, e.g. 2/8: rows
    /// [(K−1)H/N, KH/N)), writing it as a .npy part (OUTPUT, and --average, must end in
    /// .npy) with its sidecar OUTPUT.shard.json; `vkbrdf merge -o T.exr PART…` writes the EXR.
    #[arg(long, value_name = "K/N")]
    shard: Option<Shard>,
    #[command(flatten)]
    backend: BackendArgs,
}

/// Arguments of `vkbrdf table albedo`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
E(mu, alpha) = integral of f cos_i over the hemisphere for modern Cook-Torrance with F = 1
(white, no diffuse). Integration: 65536 Hammersley points per texel, GGX sampled by its
visible normals (Heitz 2018), Beckmann by D cos_h; measured error <= 1e-4 absolute against
an independent quadrature for alpha >= 1/1024 and mu >= 1/64 (tests/tables.rs). --average writes
E_avg(alpha) = 2 * integral of E(mu) mu dmu (Kulla-Conty) as an H x 1 table (x = alpha).

Example:
  vkbrdf table albedo --distribution beckmann --geometry smith --size 64x64 \\
      --output E.exr --average Eavg.exr")]
pub struct AlbedoArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Output EXR (channel Y).
    #[arg(long, short = 'o', value_name = "E.exr")]
    output: PathBuf,
    /// Also write E_avg(α) as an H×1 EXR.
    #[arg(long, value_name = "EAVG.exr")]
    average: Option<PathBuf>,
}

/// Arguments of `vkbrdf table dfg`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
A = integral of f/F (1 - (1 - c)^5) cos_i, B = integral of f/F (1 - c)^5 cos_i, c = v.h,
so that E = F0 * A + B under Schlick's Fresnel; channel R = A, G = B; x = mu, y = alpha
(or r with --roughness-axis perceptual). Same integrator and accuracy as `table albedo`.

--lut-style ENGINE writes the engine's own LUT, with its published choices and its own
estimator (GGX sampled by D cos_h from the Hammersley points (k/N, radical inverse), as
its generator does, so the table matches the engine's texel for texel, its 1024-sample
noise included; give --samples for more):
  ue4       Karis 2013 `IntegrateBRDF`: x = NoV, y = Roughness (alpha = r^2), texel
            centres, schlick-smith (k = alpha/2), R = A, G = B, 1024 samples.
  filament  CubemapIBL::DFG, multiscatter layout: x = NoV at centres, row j <-> r =
            min(1, (H - j + 0.5)/H) (row 0 roughest, Filament's rows), smith-correlated,
            R = B, G = A + B (E = mix(R, G, F0)), 1024 samples, 128x128.
tests/lut_reference.py re-implements both generators; tests/lut_styles.rs holds the
tables to them within 1e-3 per texel.

Examples:
  vkbrdf table dfg --size 64x64 --output dfg.exr --half
  vkbrdf table dfg --lut-style ue4 --size 128x32 --output ue4-dfg.exr
  vkbrdf table dfg --roughness-axis perceptual --sampling endpoints --geometry schlick-smith \\
      --output dfg.exr")]
pub struct DfgArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// An engine's LUT conventions (axes, geometry, channels, samples, estimator).
    #[arg(long, value_name = "ENGINE",
          value_parser = clap::builder::PossibleValuesParser::new(["ue4", "filament"]),
          conflicts_with_all = ["distribution", "geometry", "roughness_axis", "sampling"])]
    lut_style: Option<String>,
    /// Output EXR (channels R = A, G = B).
    #[arg(long, short = 'o', value_name = "DFG.exr")]
    output: PathBuf,
}

/// Arguments of `vkbrdf table merl`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Layout (Matusik et al. 2003): int32 dims 90 90 180, then R, G, B blocks of 90*90*180
little-endian doubles; bin (i, j, k) at theta_h = (i/90)^2 * 90°, theta_d = j°, phi_d =
k * 1°, phi_h = 0; stored value = f / scale (1/1500, 1.15/1500, 1.66/1500); -1 where either
direction is below the horizon.

Example:
  vkbrdf table merl --material gold --output gold.binary")]
pub struct MerlArgs {
    #[command(flatten)]
    material: MaterialArgs,
    /// Output MERL binary.
    #[arg(long, short = 'o', value_name = "F.binary")]
    output: PathBuf,
    /// Evaluate only band K of N of the 90 θ_h bins (1-based, e.g. 2/8), writing it as a
    /// MERL binary of those bins (dimensions rows 90 180) with its sidecar
    /// OUTPUT.shard.json; `vkbrdf merge -o F.binary PART…` writes the whole file.
    #[arg(long, value_name = "K/N")]
    shard: Option<Shard>,
    #[command(flatten)]
    backend: BackendArgs,
}

/// Arguments of `vkbrdf table preview`.
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("pictures").required(true).multiple(true)))]
#[command(after_help = "\
The sphere: orthographic, lit by one directional light from the upper left (irradiance
pi * exposure), shown in display-referred sRGB: at exposure 1 a white Lambertian's peak is
1 = white (255), and a brighter pixel is scaled as a whole to keep its hue (a gold highlight
stays gold). The polar plot: f in the plane of incidence for light at --incidence degrees
(solid yellow), mirror direction dashed, radius scaled to the largest value (stated in
1/sr), one white curve or R, G, B; titled with the material and labelled with the view
angle.

Example:
  vkbrdf table preview --material shiny-plastic --sphere plastic.png \\
      --polar plastic-lobe.png --incidence 60")]
pub struct PreviewArgs {
    #[command(flatten)]
    material: MaterialArgs,
    /// Lit-sphere PNG (give --sphere, --polar or both).
    #[arg(long, value_name = "SPHERE.png", group = "pictures")]
    sphere: Option<PathBuf>,
    /// Polar-plot PNG (give --sphere, --polar or both).
    #[arg(long, value_name = "POLAR.png", group = "pictures")]
    polar: Option<PathBuf>,
    /// Sphere image size in pixels, 1 to 16384.
    #[arg(long, default_value_t = preview::DEFAULT_SPHERE_SIZE as u32,
          allow_negative_numbers = true,
          value_parser = super::ranges::integer::<u32>(1, 16384))]
    size: u32,
    /// Light angle from the normal for the polar plot, degrees in [0, 90).
    #[arg(long, value_name = "DEG", default_value_t = preview::DEFAULT_INCIDENCE_DEG,
          allow_negative_numbers = true,
          value_parser = super::ranges::real(0.0, 90.0, false, true))]
    incidence: f64,
    /// Exposure of the sphere before tone mapping, in (0, 10^6].
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true,
          value_parser = super::ranges::real(0.0, 1e6, true, false))]
    exposure: f64,
    #[command(flatten)]
    backend: BackendArgs,
}

/// `--distribution`: every name a materials file accepts (the integrators then refuse
/// those they cannot sample, with the reason).
fn distribution_parser() -> impl clap::builder::TypedValueParser<Value = DistributionKind> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(DistributionKind::ALL.map(DistributionKind::toml_name))
        .map(|s: String| DistributionKind::from_toml_name(&s).expect("one of the possible values"))
}

/// `--geometry`: every name a materials file accepts.
fn geometry_parser() -> impl clap::builder::TypedValueParser<Value = Geometry> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(Geometry::ALL.map(Geometry::toml_name))
        .map(|s: String| Geometry::from_toml_name(&s).expect("one of the possible values"))
}

fn parse_grid(s: &str) -> Result<Grid, String> {
    s.parse::<Grid>().map_err(|e| e.to_string())
}

impl ModelArgs {
    fn spec(&self) -> anyhow::Result<Microfacet> {
        Ok(Microfacet {
            lobe: Lobe::of(self.distribution)?,
            geometry: self.geometry,
        })
    }

    fn axes(&self) -> Axes {
        Axes {
            roughness: match self.roughness_axis.as_str() {
                "perceptual" => RoughnessAxis::Perceptual,
                _ => RoughnessAxis::Alpha,
            },
            sampling: match self.sampling.as_str() {
                "endpoints" => Sampling::Endpoints,
                _ => Sampling::Centres,
            },
        }
    }

    fn size(&self) -> Grid {
        self.size.unwrap_or(Grid {
            width: 32,
            height: 32,
        })
    }

    fn samples(&self) -> u32 {
        self.samples.unwrap_or(albedo::DEFAULT_SAMPLES)
    }
}

/// `WxH`, as `--size` spells it.
fn grid_name(g: Grid) -> String {
    format!("{}x{}", g.width, g.height)
}

impl ModelArgs {
    /// The part of `--shard` over the roughness rows of `grid`, recording `options` and
    /// the common ones (size, --half).
    fn part(
        &self,
        grid: Grid,
        options: impl FnOnce() -> Vec<(&'static str, String)>,
    ) -> anyhow::Result<Option<PartSpec>> {
        Ok(self.shard.map(|shard| {
            let mut map: std::collections::BTreeMap<String, String> = options()
                .into_iter()
                .map(|(k, v)| (k.to_string(), v))
                .collect();
            map.insert("size".into(), grid_name(grid));
            map.insert("half".into(), self.half.to_string());
            PartSpec {
                shard,
                total_rows: grid.height,
                options: map,
            }
        }))
    }
}

impl MaterialArgs {
    /// The options that name the material in a part's sidecar: its name, and the
    /// materials file's size and sampled hash (or the presets).
    fn options(&self) -> anyhow::Result<std::collections::BTreeMap<String, String>> {
        let mut map = std::collections::BTreeMap::new();
        map.insert("material".to_string(), self.material.clone());
        let source = match &self.materials {
            Some(path) => {
                let print = vkbrdf::stream::shard::fingerprint(path)?;
                format!("file of {} bytes, hash {}", print.size, print.hash)
            }
            None => "the presets".to_string(),
        };
        map.insert("materials".to_string(), source);
        Ok(map)
    }

    fn load(&self) -> anyhow::Result<Material> {
        Ok(vkbrdf::table::load_material(
            self.materials.as_deref(),
            &self.material,
        )?)
    }
}

/// A checked job of any kind.
enum Job {
    Slice(SliceJob, Option<PathBuf>, Option<PartSpec>),
    Albedo(AlbedoJob, Option<PartSpec>),
    Dfg(DfgJob, Option<PartSpec>),
    Merl(Material, PathBuf, Option<PartSpec>),
    Preview(PreviewJob),
}

/// Runs `vkbrdf table <kind>`: builds and checks the job (material, model, size, memory,
/// output paths) before opening the backend, then evaluates and writes.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    if let Kind::Spectral(a) = &args.kind {
        return spectral_table(a);
    }
    let t0 = Instant::now();
    let (job, backend_args, outputs) = prepare(&args.kind)?;
    let mut backend = backend_choice::open(backend_args)?;
    let name = backend.name();
    let mut runner = Runner::new(backend.as_mut())
        .with_progress(true)
        .with_cancel(super::common::cancel());
    match &job {
        Job::Slice(j, _, Some(part)) => slice::write_part(&mut runner, j, part)?,
        Job::Slice(j, png, None) => slice::write_with_png(&mut runner, j, png.as_deref())?,
        Job::Albedo(j, Some(part)) => albedo::write_part(&mut runner, j, part)?,
        Job::Albedo(j, None) => albedo::write(&mut runner, j)?,
        Job::Dfg(j, Some(part)) => dfg::write_part(&mut runner, j, part)?,
        Job::Dfg(j, None) => dfg::write(&mut runner, j)?,
        Job::Merl(m, path, Some(part)) => merl::write_part(&mut runner, m, path, part)?,
        Job::Merl(m, path, None) => merl::write(&mut runner, m, path)?,
        Job::Preview(j) => preview::write(&mut runner, j)?,
    }
    for w in runner.take_warnings() {
        eprintln!("warning: {w}");
    }
    let written: Vec<String> = outputs.iter().map(|p| p.display().to_string()).collect();
    eprintln!(
        "wrote {} ({} backend, {:.2} s)",
        written.join(", "),
        name,
        t0.elapsed().as_secs_f64()
    );
    Ok(ExitCode::SUCCESS)
}

/// The material a job evaluates, for the jobs that have one.
fn material_of(job: &Job) -> Option<&Material> {
    match job {
        Job::Slice(j, _, _) => Some(&j.material),
        Job::Merl(m, _, _) => Some(m),
        Job::Preview(j) => Some(&j.material),
        Job::Albedo(..) | Job::Dfg(..) => None,
    }
}

/// The checked job, its backend options and the files it will write.
fn prepare(kind: &Kind) -> anyhow::Result<(Job, &BackendArgs, Vec<PathBuf>)> {
    let (job, backend) = match kind {
        Kind::Spectral(_) => unreachable!("`run` answers `table spectral` before `prepare`"),
        Kind::Slice(a) => {
            let job = SliceJob {
                material: a.material.load()?,
                grid: a.size,
                spacing: if a.linear {
                    Spacing::Linear
                } else {
                    Spacing::Sqrt
                },
                terms: a.terms,
                half: a.half,
                output: a.output.clone(),
            };
            if let Some(p) = &a.png {
                vkbrdf::table::check_output(p)?;
            }
            let part = a
                .shard
                .map(|shard| {
                    let mut options = a.material.options()?;
                    options.insert("size".into(), grid_name(a.size));
                    options.insert("spacing".into(), format!("{:?}", job.spacing));
                    options.insert("terms".into(), a.terms.to_string());
                    options.insert("half".into(), a.half.to_string());
                    anyhow::Ok(PartSpec {
                        shard,
                        total_rows: a.size.height,
                        options,
                    })
                })
                .transpose()?;
            match &part {
                Some(part) => job.check_part(part)?,
                None => job.check()?,
            }
            (Job::Slice(job, a.png.clone(), part), &a.backend)
        }
        Kind::Albedo(a) => {
            let job = AlbedoJob {
                spec: a.model.spec()?,
                grid: a.model.size(),
                samples: a.model.samples(),
                axes: a.model.axes(),
                half: a.model.half,
                output: a.output.clone(),
                average: a.average.clone(),
            };
            let part = a.model.part(job.grid, || {
                vec![
                    ("model", format!("{:?}", job.spec)),
                    ("samples", job.samples.to_string()),
                    ("axes", format!("{:?}", job.axes)),
                ]
            })?;
            match &part {
                Some(part) => job.check_part(part)?,
                None => job.check()?,
            }
            (Job::Albedo(job, part), &a.model.backend)
        }
        Kind::Dfg(a) => {
            let style = a.lut_style.as_deref().map(|s| match s {
                "filament" => LutStyle::Filament,
                _ => LutStyle::Ue4,
            });
            let job = match style {
                None => DfgJob {
                    spec: a.model.spec()?,
                    grid: a.model.size(),
                    samples: a.model.samples(),
                    axes: a.model.axes(),
                    layout: Layout::ScaleBias,
                    sampler: Sampler::Visible,
                    style: None,
                    half: a.model.half,
                    output: a.output.clone(),
                },
                Some(style) => DfgJob {
                    spec: Microfacet {
                        lobe: Lobe::Ggx,
                        geometry: style.geometry(),
                    },
                    grid: a.model.size.or(style.size()).unwrap_or(a.model.size()),
                    samples: a.model.samples.unwrap_or(style.samples()),
                    axes: style.axes(),
                    layout: style.layout(),
                    sampler: Sampler::Engine,
                    style: Some(style),
                    half: a.model.half,
                    output: a.output.clone(),
                },
            };
            let part = a.model.part(job.grid, || {
                vec![
                    ("model", format!("{:?}", job.spec)),
                    ("samples", job.samples.to_string()),
                    ("axes", format!("{:?}", job.axes)),
                    ("layout", format!("{:?}", job.layout)),
                    ("sampler", format!("{:?}", job.sampler)),
                    ("lut-style", format!("{:?}", job.style)),
                ]
            })?;
            match &part {
                Some(part) => job.check_part(part)?,
                None => job.check()?,
            }
            (Job::Dfg(job, part), &a.model.backend)
        }
        Kind::Merl(a) => {
            let material = a.material.load()?;
            merl::check(&a.output)?;
            let part = a
                .shard
                .map(|shard| {
                    anyhow::Ok(PartSpec {
                        shard,
                        total_rows: merl::THETA_H_BINS,
                        options: a.material.options()?,
                    })
                })
                .transpose()?;
            (Job::Merl(material, a.output.clone(), part), &a.backend)
        }
        Kind::Preview(a) => {
            let job = PreviewJob {
                material: a.material.load()?,
                sphere: a.sphere.clone(),
                polar: a.polar.clone(),
                size: a.size as usize,
                incidence_deg: a.incidence,
                exposure: a.exposure,
            };
            job.check()?;
            (Job::Preview(job), &a.backend)
        }
    };
    let outputs = match &job {
        Job::Slice(j, png, _) => std::iter::once(j.output.clone())
            .chain(png.clone())
            .collect(),
        Job::Albedo(j, _) => std::iter::once(j.output.clone())
            .chain(j.average.clone())
            .collect(),
        Job::Dfg(j, _) => vec![j.output.clone()],
        Job::Merl(_, path, _) => vec![path.clone()],
        Job::Preview(j) => j.sphere.iter().chain(&j.polar).cloned().collect(),
    };
    // No output may be an input (the materials file, a measured material's MERL file) or
    // name the same file as another output.
    let (materials_file, material) = match kind {
        Kind::Slice(a) => (a.material.materials.as_deref(), material_of(&job)),
        Kind::Merl(a) => (a.material.materials.as_deref(), material_of(&job)),
        Kind::Preview(a) => (a.material.materials.as_deref(), material_of(&job)),
        Kind::Albedo(_) | Kind::Dfg(_) | Kind::Spectral(_) => (None, None),
    };
    let mut inputs: Vec<&std::path::Path> = materials_file.into_iter().collect();
    if let Some(vkbrdf::material::Model::Measured(d)) = material.map(|m| &m.model) {
        inputs.push(d.path.as_path());
    }
    // A part's sidecar is an output too.
    let sharded = match &job {
        Job::Slice(_, _, p) | Job::Albedo(_, p) | Job::Dfg(_, p) | Job::Merl(_, _, p) => {
            p.is_some()
        }
        Job::Preview(_) => false,
    };
    let sidecars: Vec<PathBuf> = if sharded {
        outputs
            .iter()
            .map(|p| vkbrdf::stream::shard::sidecar_path(p))
            .collect()
    } else {
        Vec::new()
    };
    let refs: Vec<&std::path::Path> = outputs
        .iter()
        .chain(&sidecars)
        .map(PathBuf::as_path)
        .collect();
    vkbrdf::atomic::check_outputs(&refs, &inputs)?;
    Ok((job, backend, outputs))
}
