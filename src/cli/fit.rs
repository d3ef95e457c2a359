//! `vkbrdf fit`: an analytic material fitted to a MERL binary or to tuples with measured
//! values (library: `vkbrdf::fit`; docs/FITTING.md).

use super::backend_choice::{self, BackendArgs};
use anyhow::Context;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use vkbrdf::fit::{self, data::FitData, losses::Loss, params::Param, params::Space, report};

/// Arguments of `vkbrdf fit`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Data: a MERL binary (--merl; each valid bin's directions from its half/difference
angles, weighted by the bin's own solid angle; negative bins masked), or tuples with
measured values (--tuples T.npy of shape (n, 6) local Lx Ly Lz Vx Vy Vz, or (n, 10)/(n, 13)
rows whose N is any normal; --values F.npy (n, 3) RGB f in 1/sr, a negative value marks an
invalid sample; --weights W.npy (n,) each sample's solid angle, else the samples are taken
to lie on a uniform angle grid and weighted by sin θ_i sin θ_o (L2) or sin θ_i (E1, E2,
relative RMS)). --max-theta DEG drops samples with θ_i or θ_o beyond DEG (grazing).

Model: the start material (--material NAME from --materials FILE, or a preset) with the
parameters --free names moved, the others kept: roughness (Beckmann, GGX, Gaussian,
Ward; bounds 1e-3..1), exponent (Phong, Blinn-Phong, RTR, the blinn distribution;
0..1e6), f0 (Schlick; 0..1), ior (a dielectric's one η 1..3, a conductor's n per
channel 0.01..10), extinction (a conductor's k per channel, 0..20), diffuse and specular
(albedos per channel, >= 0). --bound NAME=LO:HI narrows a parameter's bounds; a start
outside them is an error.

Search: for --loss l2 (Ngan et al. 2005, the default) and e1 (Löw et al. 2012) the
albedos and Schlick's F0 are solved exactly per channel (non-negative least squares)
inside every evaluation; for e2 and rrms they join the nonlinear parameters. The
nonlinear ones are searched by a bounded Nelder-Mead from --starts points (the start and
random ones); data beyond 2 x 65,536 samples is subsampled for that phase and the best
result polished on all of it. Every metric is reported whichever is minimised. Each loss
evaluation is one bulk evaluation on the engine (--backend; the kernel is compiled once).

Outputs (all optional, written together, atomically): --out-materials FIT.toml (a
materials file `vkbrdf eval` takes as is), --report FIT.md (metrics, parameters in the
engines' conventions: α, √α, Mitsuba alpha, F0 or η/k; the search), --residual R.exr
(relative residual (f - f_m)/max(f_m, 1e-3) per θ_h x θ_d cell of MERL's bins, averaged
over φ_d; R, G, B) and --residual-png R.png (their mean, blue = model too low, red = too
high, saturating at ±50 %). The metrics and parameters are also printed.

Ctrl-C: the one command whose partial result is a result. The first Ctrl-C (or SIGTERM)
stops the search at its next evaluation, writes the outputs for the best parameters found
so far (the report marks the fit as interrupted) and exits with 130; a second Ctrl-C
exits at once, writing nothing.

Examples:
  vkbrdf table merl --material gold --output gold.binary
  vkbrdf fit --merl gold.binary --material gold --free roughness,ior,extinction \\
      --out-materials fit.toml --report fit.md --residual-png residual.png
  vkbrdf fit --tuples t.npy --values f.npy --materials m.toml --material plastic \\
      --free roughness,diffuse,specular,f0 --loss e2")]
pub struct Args {
    /// A MERL binary to fit.
    #[arg(long, value_name = "FILE.binary", conflicts_with_all = ["tuples", "values"])]
    pub merl: Option<PathBuf>,
    /// Directions (.npy, (n, 6) local, or (n, 10)/(n, 13) rows); with --values.
    #[arg(long, value_name = "T.npy", requires = "values")]
    pub tuples: Option<PathBuf>,
    /// Measured f (.npy, (n, 3), 1/sr); negative marks an invalid sample.
    #[arg(long, value_name = "F.npy", requires = "tuples")]
    pub values: Option<PathBuf>,
    /// Each sample's solid-angle weight (.npy, (n,) or (n, 1)).
    #[arg(long, value_name = "W.npy", requires = "tuples")]
    pub weights: Option<PathBuf>,
    /// Materials file holding the start material; without it, --material is a preset.
    #[arg(long, short = 'm', value_name = "M.toml")]
    pub materials: Option<PathBuf>,
    /// The start material's name.
    #[arg(long, value_name = "NAME")]
    pub material: String,
    /// The parameters to fit, comma-separated (roughness, f0, diffuse, specular, ior,
    /// extinction, exponent).
    #[arg(long, value_name = "LIST", value_delimiter = ',', required = true)]
    pub free: Vec<String>,
    /// Narrower bounds for a parameter, NAME=LO:HI (repeatable).
    #[arg(long = "bound", value_name = "NAME=LO:HI")]
    pub bounds: Vec<String>,
    /// The loss minimised: l2 (Ngan), e1, e2 (Löw), rrms (relative RMS).
    #[arg(long, default_value = "l2")]
    pub loss: String,
    /// Starting points (the start material's, then random ones in the bounds).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u64).range(1..=1000))]
    pub starts: u64,
    /// Seed of the random starts.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Evaluations at most per start.
    #[arg(long, default_value_t = 1500, value_parser = clap::value_parser!(u64).range(1..))]
    pub max_evaluations: u64,
    /// Drop samples with θ_i or θ_o beyond this angle (degrees, grazing cut-off).
    #[arg(long, value_name = "DEG")]
    pub max_theta: Option<f64>,
    /// Name of the fitted material (default: the start's name + `-fit`).
    #[arg(long, value_name = "NAME")]
    pub name: Option<String>,
    /// Write the fitted material as a materials file.
    #[arg(long, value_name = "FIT.toml")]
    pub out_materials: Option<PathBuf>,
    /// Write the Markdown report.
    #[arg(long, value_name = "FIT.md")]
    pub report: Option<PathBuf>,
    /// Write the residual slice (EXR, R, G, B).
    #[arg(long, value_name = "R.exr")]
    pub residual: Option<PathBuf>,
    /// Write the residual slice as a picture (PNG).
    #[arg(long, value_name = "R.png")]
    pub residual_png: Option<PathBuf>,
    #[command(flatten)]
    pub backend: BackendArgs,
}

fn parse_bound(s: &str) -> anyhow::Result<(Param, f64, f64)> {
    let bad = || anyhow::anyhow!("--bound {s}: expected NAME=LO:HI, e.g. roughness=0.01:0.5");
    let (name, range) = s.split_once('=').ok_or_else(bad)?;
    let (lo, hi) = range.split_once(':').ok_or_else(bad)?;
    let num = |t: &str| {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|x| !x.is_nan())
            .ok_or_else(bad)
    };
    Ok((name.parse()?, num(lo)?, num(hi)?))
}

fn read_data(args: &Args) -> anyhow::Result<FitData> {
    let max_theta = match args.max_theta {
        Some(d) if !(d > 0.0 && d <= 90.0) => {
            anyhow::bail!("--max-theta {d}: give an angle in (0, 90] degrees")
        }
        d => d.map(f64::to_radians),
    };
    if let Some(path) = &args.merl {
        let table = vkbrdf::material::merl::read(path)?;
        return Ok(FitData::from_merl(&table, max_theta)?);
    }
    let (Some(t), Some(v)) = (&args.tuples, &args.values) else {
        anyhow::bail!("give the data: --merl FILE.binary, or --tuples T.npy --values F.npy");
    };
    let (tuples, tshape) = vkbrdf::batch::read_npy_f32(t)?;
    let (values, vshape) = vkbrdf::batch::read_npy_f32(v)?;
    if tshape.len() != 2 {
        anyhow::bail!(
            "{}: tuples must be 2-D (n, 6|10|13); shape {tshape:?}",
            t.display()
        );
    }
    if vshape.len() != 2 || vshape[1] != 3 {
        anyhow::bail!(
            "{}: values must be (n, 3) RGB; shape {vshape:?}",
            v.display()
        );
    }
    let weights = match &args.weights {
        Some(w) => {
            let (data, shape) = vkbrdf::batch::read_npy_f32(w)?;
            if !(shape.len() == 1 || (shape.len() == 2 && shape[1] == 1)) {
                anyhow::bail!(
                    "{}: weights must be (n,) or (n, 1); shape {shape:?}",
                    w.display()
                );
            }
            Some(data)
        }
        None => None,
    };
    Ok(FitData::from_tuples(
        &tuples,
        tshape[1] as usize,
        &values,
        weights.as_deref(),
        max_theta,
        t,
    )?)
}

/// Runs `vkbrdf fit`.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let cancel = super::common::cancel();
    let loss: Loss = args.loss.parse()?;
    let free: Vec<Param> = args
        .free
        .iter()
        .map(|s| s.parse())
        .collect::<Result<_, _>>()?;
    let bounds: Vec<_> = args
        .bounds
        .iter()
        .map(|s| parse_bound(s))
        .collect::<anyhow::Result<_>>()?;
    let start = vkbrdf::table::load_material(args.materials.as_deref(), &args.material)?;
    let space = Space::new(&start, &free, &bounds, loss.is_quadratic())?;
    let mut inputs: Vec<&Path> = [
        &args.merl,
        &args.tuples,
        &args.values,
        &args.weights,
        &args.materials,
    ]
    .into_iter()
    .flatten()
    .map(PathBuf::as_path)
    .collect();
    if let vkbrdf::material::Model::Measured(d) = &start.model {
        inputs.push(d.path.as_path());
    }
    let outputs: Vec<&Path> = [
        &args.out_materials,
        &args.report,
        &args.residual,
        &args.residual_png,
    ]
    .into_iter()
    .flatten()
    .map(PathBuf::as_path)
    .collect();
    vkbrdf::atomic::check_outputs(&outputs, &inputs)?;
    let data = read_data(args)?;
    eprintln!(
        "fit: {} samples ({} read, {} masked), {} nonlinear coordinate(s) [{}], loss {}",
        data.len(),
        data.read,
        data.masked,
        space.coords.len(),
        space
            .coords
            .iter()
            .map(|c| c.label())
            .collect::<Vec<_>>()
            .join(", "),
        loss.name()
    );
    let mut backend = backend_choice::open(&args.backend)?;
    let options = fit::Options {
        loss,
        starts: args.starts as usize,
        seed: args.seed,
        max_evaluations: args.max_evaluations,
        ..fit::Options::default()
    };
    // From here a Ctrl-C is the fit's to handle: it writes the best parameters so far.
    super::common::own_cancellation(true);
    let t0 = std::time::Instant::now();
    let mut last = 0.0;
    let mut result = fit::fit(
        &data,
        &space,
        &options,
        backend.as_mut(),
        &cancel,
        &mut |p| {
            let now = t0.elapsed().as_secs_f64();
            let status = format!(
                "{} start {}/{}: {} evaluations, best {} {:.6e}",
                p.phase,
                p.start.0 + 1,
                p.start.1,
                p.evaluations,
                loss.name(),
                p.best
            );
            super::common::set_status(status.clone());
            if now - last >= 1.0 {
                last = now;
                eprintln!("fit [{now:.1} s] {status}");
            }
        },
    )
    .with_context(|| format!("fitting {}", data.source.display()))?;
    result.material.name = args
        .name
        .clone()
        .unwrap_or_else(|| format!("{}-fit", start.name));
    print_summary(&result);
    write_outputs(args, &result, &data, &start)?;
    super::common::own_cancellation(false);
    if result.interrupted {
        eprintln!("fit: interrupted; wrote the best parameters found so far");
        return Ok(ExitCode::from(130));
    }
    Ok(ExitCode::SUCCESS)
}

fn print_summary(result: &fit::FitResult) {
    outln!("material {}", result.material.name);
    for (k, v) in report::conventions(&result.material) {
        outln!("  {k}: {v}");
    }
    for (name, v) in report::metric_lines(&result.metrics) {
        outln!("  {name}: {v:.6e}");
    }
    outln!(
        "  {} loss evaluations in {:.2} s ({:.1}/s; {:.1} M samples/s in the engine, {}){}",
        result.evaluations,
        result.seconds,
        result.evaluations as f64 / result.seconds.max(1e-9),
        result.sample_evaluations as f64 / result.engine_seconds.max(1e-9) / 1e6,
        result.backend,
        if result.interrupted {
            "; INTERRUPTED"
        } else {
            ""
        }
    );
}

fn write_outputs(
    args: &Args,
    result: &fit::FitResult,
    data: &FitData,
    start: &vkbrdf::material::Material,
) -> anyhow::Result<()> {
    // Written with a token of their own: after a Ctrl-C they are the result.
    let token = vkbrdf::cancel::Cancel::new();
    let mut staged = Vec::new();
    let text = |path: &Path, body: String| {
        vkbrdf::atomic::stage(path, &token, move |w| {
            use std::io::Write;
            w.write_all(body.as_bytes())
        })
    };
    if let Some(p) = &args.out_materials {
        staged.push(text(p, report::material_toml(&result.material)?)?);
    }
    if let Some(p) = &args.report {
        let command: Vec<String> = std::env::args().collect();
        staged.push(text(
            p,
            report::markdown(result, data, start, &command.join(" ")),
        )?);
    }
    let slice = report::residual_slice(data, &result.model);
    if let Some(p) = &args.residual {
        use vkbrdf::table::exr_out::{self, Channel, Layer, Provenance};
        let grid = vkbrdf::table::Grid::new(90, 90)?;
        let layer = Layer {
            name: "residual".into(),
            channels: ["R", "G", "B"]
                .iter()
                .zip(slice.iter())
                .map(|(n, v)| Channel {
                    name: (*n).into(),
                    values: v.clone(),
                })
                .collect(),
        };
        let provenance = Provenance {
            table: "fit residual".into(),
            material: result.material.name.clone(),
            convention: vkbrdf::table::convention_name(&result.material).into(),
            parameterisation: "relative residual (f - f_m)/max(f_m, 1e-3) per MERL theta_h bin (column, square-root spacing) x theta_d bin (row), weighted mean over phi_d; NaN: no sample".into(),
            samples: format!("{} samples of {}", data.len(), data.source.display()),
            backend: result.backend.clone(),
        };
        staged.push(exr_out::stage(p, grid, vec![layer], &provenance, false, &token)?.0);
    }
    if let Some(p) = &args.residual_png {
        let canvas = report::residual_png(&slice, 0.5);
        let meta = vec![
            (
                "vkbrdf.table",
                "fit residual (blue: model low, red: model high, +-50 %)".to_string(),
            ),
            ("vkbrdf.material", result.material.name.clone()),
        ];
        staged.push(vkbrdf::table::preview::stage_png(
            p, &canvas, &meta, &token,
        )?);
    }
    vkbrdf::atomic::commit(staged)?;
    Ok(())
}
