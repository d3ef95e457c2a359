//! `vkbrdf eval`: materials + tuples in, BRDF (and terms) out.

use super::backend_choice::{self, BackendArgs};
use anyhow::Context;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;
use vkbrdf::backend::{Request, TERM_COLUMNS};
use vkbrdf::batch::{self, Batch};
use vkbrdf::precision::{self, Precision};

/// Arguments of `vkbrdf eval`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Input: a float32 or float64 .npy array, C order, shape (n, 10) or (n, 13), columns
  Lx Ly Lz Vx Vy Vz Nx Ny Nz material [Tx Ty Tz]
(material = row index into the materials file's [[material]] tables, from 0; the tangent
columns are needed only by anisotropic materials).

Output: BRDF.npy, float32 (n, 3): RGB f in 1/sr (no cosine); TERMS.npy, float32 (n, 6):
D, G, F_r, F_g, F_b, K. Invalid tuples (zero or non-finite vectors, a bad tangent) and
tuples below the horizon give 0; both are counted.

Outputs never destroy data: an output that is an input (after links) or named twice is
refused before any work, as is a missing or read-only directory. Regular files are
written atomically (temporary file + rename; a symlink is written through, the link
kept): a failure, a full disk or Ctrl-C leaves the previous files intact, and BRDF and
TERMS appear both or neither. A FIFO, a device or `-` (standard output) is written
directly once the evaluation has succeeded (atomicity is a promise for regular files).

Example:
  vkbrdf generate --materials m.toml --tuples 1000000 --output t.npy
  vkbrdf eval --materials m.toml --input t.npy --output brdf.npy --terms terms.npy")]
pub struct Args {
    /// Materials file (TOML, [[material]] tables; see `vkbrdf materials --help`).
    #[arg(long, short = 'm', value_name = "M.toml")]
    pub materials: PathBuf,
    /// Tuples (.npy, shape (n, 10) or (n, 13)).
    #[arg(long, short = 'i', value_name = "T.npy")]
    pub input: PathBuf,
    /// Where to write the RGB BRDF values (.npy, float32 (n, 3)).
    #[arg(long, short = 'o', value_name = "BRDF.npy")]
    pub output: PathBuf,
    /// Also write the terms D, G, F_r, F_g, F_b, K (.npy, float32 (n, 6)).
    #[arg(long, value_name = "TERMS.npy")]
    pub terms: Option<PathBuf>,
    /// Fail (exit 1, no output written) if any tuple is invalid.
    #[arg(long)]
    pub strict: bool,
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

/// Runs `vkbrdf eval`.
pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let cancel = super::cancel();
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
    let outputs: Vec<&std::path::Path> = std::iter::once(args.output.as_path())
        .chain(args.terms.as_deref())
        .collect();
    vkbrdf::atomic::check_outputs(&outputs, &inputs)?;
    let t0 = Instant::now();
    let batch = Batch::read_npy(&args.input, materials.len())?;
    batch.check_tangents(&materials, &args.input)?;
    let read_s = t0.elapsed().as_secs_f64();
    let measured = materials
        .iter()
        .any(|m| matches!(m.model, vkbrdf::material::Model::Measured(_)));
    let mut backend = if measured && args.backend.backend.is_none() {
        eprintln!("note: measured (MERL) materials are evaluated by the CPU reference");
        let mut reference = Box::new(vkbrdf::reference::CpuReference::new());
        vkbrdf::backend::Backend::set_cancel(reference.as_mut(), cancel.clone());
        reference
    } else {
        backend_choice::open(&args.backend)?
    };
    let request = Request {
        terms: args.terms.is_some(),
    };
    let t1 = Instant::now();
    let out = backend.evaluate(&batch, &materials, &request)?;
    let eval_s = t1.elapsed().as_secs_f64();
    let c = out.counts;
    eprintln!(
        "{} tuples on {}: {} evaluated, {} invalid, {} below the horizon, {} saturated ({:.3} s read, {:.3} s evaluate, {:.1} M tuples/s)",
        c.tuples,
        backend.name(),
        c.tuples - c.invalid - c.below_horizon,
        c.invalid,
        c.below_horizon,
        c.saturated,
        read_s,
        eval_s,
        c.tuples as f64 / eval_s.max(1e-9) / 1e6
    );
    if args.strict && c.invalid > 0 {
        let e = vkbrdf::Error::InvalidTuples {
            invalid: c.invalid,
            total: c.tuples,
            first_row: c.first_invalid.unwrap_or(0),
        };
        eprintln!("error: {e} (--strict: nothing written)");
        return Ok(ExitCode::from(1));
    }
    // Both files are staged, then appear together: both or neither.
    let mut staged = vec![batch::stage_npy_f32(&args.output, &out.brdf, 3, &cancel)
        .with_context(|| "writing the BRDF values")?];
    if let (Some(path), Some(terms)) = (&args.terms, &out.terms) {
        staged.push(
            batch::stage_npy_f32(path, terms, TERM_COLUMNS, &cancel)
                .with_context(|| "writing the terms")?,
        );
    }
    vkbrdf::atomic::commit(staged).with_context(|| "writing the outputs")?;
    Ok(ExitCode::SUCCESS)
}
