//! `vkbrdf eval`: materials + tuples in, BRDF (and terms) out.

use super::backend_choice::{self, BackendArgs};
use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;
use vkbrdf::precision::{self, Precision};
use vkbrdf::stream;

/// Arguments of `vkbrdf eval`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Input: a float32 or float64 .npy array, C order, shape (n, 10) or (n, 13), columns
  Lx Ly Lz Vx Vy Vz Nx Ny Nz material [Tx Ty Tz]
(material = row index into the materials file's [[material]] tables, from 0; the tangent
columns are needed only by anisotropic materials); or the local-frame form, shape (n, 6),
  Lx Ly Lz Vx Vy Vz
with N = +z and one material for every row (--material NAME|INDEX; may be left out when
the materials file defines one; not anisotropic). Each tuple means what the 10-column row
Lx Ly Lz Vx Vy Vz 0 0 1 material means, in 24 bytes instead of 40; `cpu` evaluates it as
it is, the other engines expand it to rows chunk by chunk.

Output: BRDF.npy, float32 (n, 3): RGB f in 1/sr (no cosine); with --wavelengths, (n, W):
f(λ) at each wavelength, or with --color (n, 3): XYZ or linear sRGB; TERMS.npy, float32 (n, 6):
D, G, F_r, F_g, F_b, K; for HTSG materials SPIKE.npy, float32 (n, 3): the mirror spike's
weight ρ_s per channel (a reflectance: the spike is ρ_s δ(ω − ω_mirror)/cos_i, not in f;
FORMULAS.md §8). Invalid tuples (zero or non-finite vectors, a bad tangent) and
tuples below the horizon give 0; both are counted.

Streaming: the input is read, evaluated and written in chunks, so host memory stays
within --max-memory (default 512MiB) plus the engine's own buffers whatever the batch's
size; the outputs need 12 bytes per tuple on disk (36 with --terms) beside the input.

Outputs never destroy data: an output that is an input (after links) or named twice is
refused before any work, as is a missing or read-only directory. Regular files are
written atomically (temporary file + rename; a symlink is written through, the link
kept): a failure, a full disk or Ctrl-C leaves the previous files intact, and BRDF and
TERMS appear both or neither. A FIFO, a device or `-` (standard output) is written
directly once the evaluation has succeeded (atomicity is a promise for regular files).

Shards: --shard K/N evaluates rows [(K-1)n/N, Kn/N) only and writes them as a part with a
sidecar (OUTPUT.shard.json: the range, the input's size and sampled hash, the engine, the
counts); `vkbrdf merge` joins the parts, bit-identical to one run. Run the N parts with
anything that runs N commands (docs/STREAMING.md: xargs, Slurm, Kubernetes).

Examples:
  vkbrdf generate --materials m.toml --tuples 1000000 --output t.npy
  vkbrdf eval --materials m.toml --input t.npy --output brdf.npy --terms terms.npy
  vkbrdf eval -m htsg.toml -i t.npy -o brdf.npy --spike spike.npy
  vkbrdf eval -m gold.toml -i t.npy -o spectra.npy --wavelengths 360:830:5
  vkbrdf eval -m gold.toml -i t.npy -o srgb.npy --color srgb   (gold.toml: preset = \"gold-spectral\")
  seq 1 4 | xargs -P 4 -I K vkbrdf eval -m m.toml -i t.npy -o part-K.npy --shard K/4
  vkbrdf merge -o brdf.npy part-1.npy part-2.npy part-3.npy part-4.npy")]
pub struct Args {
    /// Materials file (TOML, [[material]] tables; see `vkbrdf materials --help`).
    #[arg(long, short = 'm', value_name = "M.toml")]
    pub materials: PathBuf,
    /// Tuples (.npy, shape (n, 10) or (n, 13), or (n, 6) in the local frame).
    #[arg(long, short = 'i', value_name = "T.npy")]
    pub input: PathBuf,
    /// The material of a 6-column local-frame input, by name or index (only for that
    /// form: rows of 10 or 13 columns name their own).
    #[arg(long, value_name = "NAME|INDEX")]
    pub material: Option<String>,
    /// Where to write the RGB BRDF values (.npy, float32 (n, 3)).
    #[arg(long, short = 'o', value_name = "BRDF.npy")]
    pub output: PathBuf,
    /// Also write the terms D, G, F_r, F_g, F_b, K (.npy, float32 (n, 6)).
    #[arg(long, value_name = "TERMS.npy")]
    pub terms: Option<PathBuf>,
    /// Also write the mirror spike's weight ρ_s of HTSG materials (.npy, float32 (n, 3),
    /// FORMULAS.md §8; every material of the file must be htsg).
    #[arg(long, value_name = "SPIKE.npy")]
    pub spike: Option<PathBuf>,
    /// Evaluate at these wavelengths (nm) instead of in RGB: START:END:STEP (both ends
    /// included, e.g. 360:830:5) or a list (450,550,650). The output is then (n, W):
    /// f(λ) per tuple (FORMULAS.md §9). Materials need a spectral form: a spectral `ior`
    /// (`gold-spectral`, …) or no index at all (RGB colours are up-sampled).
    #[arg(long, value_name = "NM")]
    pub wavelengths: Option<vkbrdf::spectral::Wavelengths>,
    /// Reduce the spectral values to a colour, (n, 3): CIE 1931 XYZ or linear sRGB
    /// (unclamped), by the CIE quadrature on the 5 nm grid (needs --wavelengths 360:830:5,
    /// the default when --color is given alone).
    #[arg(long, value_enum, value_name = "SPACE")]
    pub color: Option<ColourArg>,
    /// The illuminant weighting --color: d65 (sRGB's white) or e (equal energy).
    #[arg(long, value_enum, default_value = "d65", requires = "color")]
    pub illuminant: IlluminantArg,
    /// Fail (exit 1, no output written) if any tuple is invalid.
    #[arg(long)]
    pub strict: bool,
    /// Evaluate only part K of N of the batch (1-based, e.g. 2/8: rows [(K−1)n/N, Kn/N)),
    /// writing that part and its sidecar OUTPUT.shard.json; join the parts with
    /// `vkbrdf merge`.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<vkbrdf::stream::shard::Shard>,
    /// Print the summary (counts, stage times, peak memory) as JSON on standard output.
    #[arg(long)]
    pub json: bool,
    /// Host memory for the chunks being read, evaluated and written: bytes, or with a
    /// suffix KiB, MiB, GiB (1 MiB to 1 TiB).
    #[arg(long, value_name = "BYTES", default_value = "512MiB",
          value_parser = super::ranges::bytes(1 << 20, 1 << 40),
          allow_negative_numbers = true)]
    pub max_memory: u64,
    /// `exact` (FORMULAS.md as written) or `fast` (Schlick for exact Fresnel, smith-fast
    /// for Smith–Beckmann; error measured by `vkbrdf bench`).
    #[arg(long, value_enum, default_value = "exact")]
    pub precision: PrecisionArg,
    #[command(flatten)]
    pub backend: BackendArgs,
}

/// `--precision` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PrecisionArg {
    /// The exact terms.
    Exact,
    /// Cheaper approximations (Schlick, smith-fast).
    Fast,
}

impl From<PrecisionArg> for Precision {
    fn from(p: PrecisionArg) -> Precision {
        match p {
            PrecisionArg::Exact => Precision::Exact,
            PrecisionArg::Fast => Precision::Fast,
        }
    }
}

/// `--color` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ColourArg {
    /// CIE 1931 XYZ.
    Xyz,
    /// Linear sRGB (unclamped).
    Srgb,
}

/// `--illuminant` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum IlluminantArg {
    /// CIE D65.
    D65,
    /// Equal energy.
    E,
}

/// The spectral job of `--wavelengths`/`--color`, if asked for.
fn spectral_job(
    args: &Args,
    materials: &[vkbrdf::material::Material],
) -> anyhow::Result<Option<vkbrdf::spectral_eval::SpectralJob>> {
    use vkbrdf::spectral::cie::Illuminant;
    use vkbrdf::spectral_eval::{Colour, SpectralJob};
    let colour = args.color.map(|c| {
        let c = match c {
            ColourArg::Xyz => Colour::Xyz,
            ColourArg::Srgb => Colour::Srgb,
        };
        let i = match args.illuminant {
            IlluminantArg::D65 => Illuminant::D65,
            IlluminantArg::E => Illuminant::E,
        };
        (c, i)
    });
    let wavelengths = match (&args.wavelengths, colour) {
        (None, None) => return Ok(None),
        (Some(w), _) => w.clone(),
        (None, Some(_)) => vkbrdf::spectral::Wavelengths::cie(),
    };
    if args.shard.is_some() {
        anyhow::bail!("--wavelengths/--color with --shard: merge joins RGB parts only; evaluate spectra unsharded (or split the input file)");
    }
    Ok(Some(SpectralJob::new(materials, wavelengths, colour)?))
}

/// Runs `vkbrdf eval`.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let cancel = super::common::cancel();
    let materials = precision::apply_all(
        &vkbrdf::material::load_materials(&args.materials)?,
        args.precision.into(),
    );
    // Every output is checked before any work: not an input (the measured materials'
    // MERL files included), not named twice, in a directory that accepts new files.
    let mut inputs = vec![args.materials.as_path(), args.input.as_path()];
    for m in &materials {
        if let vkbrdf::material::Model::Measured(d) = &m.model {
            inputs.push(d.path.as_path());
        }
    }
    let sidecar = args
        .shard
        .map(|_| vkbrdf::stream::shard::sidecar_path(&args.output));
    let outputs: Vec<&std::path::Path> = std::iter::once(args.output.as_path())
        .chain(args.terms.as_deref())
        .chain(args.spike.as_deref())
        .chain(sidecar.as_deref())
        .collect();
    vkbrdf::atomic::check_outputs(&outputs, &inputs)?;
    // Measured (MERL) materials run on every backend: the Vulkan kernel looks their
    // tables up on the device.
    let spectral = spectral_job(args, &materials)?;
    let mut backend = backend_choice::open(&args.backend)?;
    let job = stream::StreamJob {
        spectral: spectral.as_ref(),
        input: &args.input,
        material: args.material.as_deref(),
        materials: &materials,
        output: &args.output,
        terms: args.terms.as_deref(),
        spike: args.spike.as_deref(),
        max_memory: args.max_memory,
        strict: args.strict,
        shard: args.shard,
        materials_file: &args.materials,
    };
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template("eval [{bar:30}] {pos}/{len} tuples ({elapsed}, {eta} left)")
            .expect("valid template"),
    );
    let t0 = Instant::now();
    let summary = stream::evaluate(&job, backend.as_mut(), &cancel, |done, total| {
        bar.set_length(total);
        bar.set_position(done);
    })
    .with_context(|| format!("evaluating {}", args.input.display()))?;
    bar.finish_and_clear();
    let total_s = t0.elapsed().as_secs_f64();
    let c = summary.counts;
    eprintln!(
        "{} tuples on {}: {} evaluated, {} invalid, {} below the horizon, {} saturated; {} chunk(s) of {} rows, {:.3} s read, {:.3} s evaluate, {:.3} s write, {:.1} M tuples/s end to end{}",
        c.tuples,
        backend.name(),
        c.tuples - c.invalid - c.below_horizon,
        c.invalid,
        c.below_horizon,
        c.saturated,
        summary.chunks,
        summary.chunk_rows,
        summary.read_s,
        summary.eval_s,
        summary.write_s,
        c.tuples as f64 / total_s.max(1e-9) / 1e6,
        peak_memory().map_or(String::new(), |m| format!(", peak memory {m} MiB"))
    );
    if args.json {
        let doc = serde_json::json!({
            "tuples": c.tuples,
            "engine": backend.name(),
            "evaluated": c.tuples - c.invalid - c.below_horizon,
            "invalid": c.invalid,
            "first_invalid_row": c.first_invalid,
            "below_horizon": c.below_horizon,
            "saturated": c.saturated,
            "written": summary.written,
            "chunks": summary.chunks,
            "chunk_rows": summary.chunk_rows,
            "seconds": {"read": summary.read_s, "evaluate": summary.eval_s,
                        "write": summary.write_s, "total": total_s},
            "peak_memory_mib": peak_memory(),
            "shard": args.shard,
        });
        outln!("{}", serde_json::to_string_pretty(&doc)?);
    }
    if !summary.written {
        let e = vkbrdf::Error::InvalidTuples {
            invalid: c.invalid,
            total: c.tuples,
            first_row: c.first_invalid.unwrap_or(0),
        };
        eprintln!("error: {e} (--strict: nothing written)");
        return Ok(ExitCode::from(1));
    }
    Ok(ExitCode::SUCCESS)
}

/// Peak resident memory of this process in MiB (Linux: VmHWM), for the summary line.
fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024)
}
