//! `vkbrdf stress`: an adversarial corpus ([`corpus`]) evaluated on a backend and judged
//! against the f64 reference. The policy it checks (docs/STABILITY.md): finite
//! input gives finite output on every backend, invalid input gives 0 and is counted, and
//! the relative error per term, model and regime is measured, not guessed.

pub mod corpus;

use crate::backend::{Backend, Request, TERM_COLUMNS};
use crate::error::Result;
use crate::material::{Distribution, Fresnel, Material, Model, Roughness};
use crate::precision::Precision;
use crate::reference::{self, Status};
use crate::stats::{relative_error, ErrorStats};
use corpus::Case;
use std::collections::BTreeMap;

/// Absolute floor of the relative error: below 1e-6 (1/sr, or for G and F dimensionless)
/// errors count as absolute. f32 carries ~7 digits, so values under the floor are compared
/// at the floor's scale.
pub const ERROR_FLOOR: f64 = 1e-6;

/// The horizon test is decided in f32 on the GPU: a cosine within this distance of 0 may be
/// classified either way (f32 normalisation and the dot product carry ~2e-7 absolute error),
/// so a tuple the reference puts below the horizon with `min(cos_i, cos_o) > −HORIZON_EPS`
/// and a backend evaluates anyway is counted as ambiguous, not as a policy failure.
pub const HORIZON_EPS: f64 = 1e-6;

/// The error regimes of the report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Regime {
    /// Ordinary parameters and directions (including huge/tiny vector lengths).
    WellConditioned,
    /// A cosine in [1.4e-45, 0.1] (down to the smallest positive float32).
    Grazing,
    /// `cos_h` within 1e-7 of 1, and exact normal incidence.
    NearPeak,
    /// Roughness < 1e-3 or > 2, anisotropy ratio ≥ 100, or exponent ≥ 1000.
    ExtremeRoughness,
    /// IOR ≤ 1 or ≥ 50, or extinction ≥ 20.
    ExtremeIor,
}

impl Regime {
    /// The label used in reports.
    pub fn label(self) -> &'static str {
        match self {
            Regime::WellConditioned => "well-conditioned",
            Regime::Grazing => "grazing",
            Regime::NearPeak => "near-peak",
            Regime::ExtremeRoughness => "extreme roughness",
            Regime::ExtremeIor => "extreme IOR",
        }
    }
}

fn extreme_roughness(r: Roughness) -> bool {
    let (x, y) = r.xy();
    x.min(y) < 1e-3 || x.max(y) > 2.0 || x.max(y) / x.min(y) >= 100.0
}

/// The regime a valid tuple of material `m` built for `case` is judged in.
pub fn regime(m: &Material, case: Case) -> Regime {
    let rough = match &m.model {
        Model::Phong { exponent } | Model::BlinnPhong { exponent } | Model::Rtr { exponent } => {
            *exponent >= 1000.0
        }
        Model::Ward { roughness } => extreme_roughness(*roughness),
        Model::CookTorrance(ct) => match ct.distribution {
            Distribution::Gaussian { m } | Distribution::Charlie { m } => {
                extreme_roughness(Roughness::Isotropic(m))
            }
            Distribution::Beckmann(r) | Distribution::Ggx(r) => extreme_roughness(r),
            Distribution::Blinn { exponent } => exponent >= 1000.0,
        },
        Model::Lambert | Model::Measured(_) => false,
        // σ0/τ at the accepted bounds (1e-3: the sharpest diffraction lobe; 10).
        Model::Htsg(p) => !(2e-3..=5.0).contains(&(p.sigma0 / p.tau)),
    };
    let ior = match (&m.model, m.cook_torrance().map(|ct| ct.fresnel)) {
        // HTSG's η is the conductor's, with n near the parser's 1e-6 as extreme too.
        (Model::Htsg(p), _) => {
            p.ior.iter().any(|&n| n <= 1e-3 || n >= 50.0) || p.extinction.iter().any(|&k| k >= 20.0)
        }
        (_, f) => match f {
            Some(Fresnel::Dielectric { ior }) => ior.iter().any(|&n| n <= 1.0 || n >= 50.0),
            Some(Fresnel::Conductor { ior, extinction }) => {
                ior.iter().any(|&n| n >= 50.0)
                    || extinction.iter().any(|&k| k >= 20.0)
                    || (ior == [1.0; 3] && extinction == [0.0; 3])
            }
            _ => false,
        },
    };
    match case {
        _ if rough => Regime::ExtremeRoughness,
        _ if ior => Regime::ExtremeIor,
        Case::Grazing | Case::TinyCosine => Regime::Grazing,
        Case::NearPeak | Case::NormalIncidence => Regime::NearPeak,
        _ => Regime::WellConditioned,
    }
}

/// What a stress run found on one backend.
#[derive(Debug, Clone, Default)]
pub struct StressReport {
    /// Backend name.
    pub backend: String,
    /// Tuples evaluated.
    pub tuples: u64,
    /// Output values (BRDF or term) that were NaN or ±Inf.
    pub non_finite: u64,
    /// Invalid tuples as counted by the backend and by the reference.
    pub invalid: (u64, u64),
    /// Below-horizon tuples as counted by the backend and by the reference.
    pub below_horizon: (u64, u64),
    /// Saturated tuples (an output beyond `f32::MAX`, FORMULAS.md §1) as counted by the
    /// backend and by the reference (of the variant the backend evaluated).
    pub saturated: (u64, u64),
    /// Whether the backend evaluated the exact materials. Only then must the saturated
    /// counts agree: the fast variant's approximations (device exp/log, Schlick; measured,
    /// up to 1e-3 and more on the sharpest lobes) can move a value across f32::MAX.
    pub exact: bool,
    /// Invalid or below-horizon tuples (per the reference) with a non-zero output, beyond
    /// the f32 horizon ambiguity ([`HORIZON_EPS`]).
    pub nonzero_rejects: u64,
    /// Below-horizon tuples (per the reference) within [`HORIZON_EPS`] of the horizon that
    /// the backend evaluated.
    pub ambiguous_horizon: u64,
    /// Relative error per (quantity, regime); quantity is `f: MODEL`, `D`, `G`, `F` or `K`.
    pub errors: BTreeMap<(String, Regime), ErrorStats>,
    /// Rows (of the corpus) of the worst error per (quantity, regime), with their input.
    pub worst_rows: BTreeMap<(String, Regime), [f32; 13]>,
}

fn model_label(m: &Material) -> &'static str {
    match m.model {
        Model::Lambert => "f: lambert",
        Model::Measured(_) => "f: measured",
        Model::Phong { .. } => "f: phong",
        Model::BlinnPhong { .. } => "f: blinn-phong",
        Model::Rtr { .. } => "f: rtr",
        Model::Ward { .. } => "f: ward",
        Model::CookTorrance(_) => "f: cook-torrance",
        Model::Htsg(_) => "f: htsg",
    }
}

/// Runs `tuples` corpus tuples (seed `seed`) through `backend` in chunks of `chunk`,
/// calling `progress(done)` after each chunk.
pub fn run(
    backend: &mut dyn Backend,
    tuples: usize,
    seed: u64,
    chunk: usize,
    progress: &mut dyn FnMut(usize),
) -> Result<StressReport> {
    run_with(backend, Precision::Exact, tuples, seed, chunk, progress)
}

/// [`run`] with the backend evaluating the `precision` variant of each material, judged
/// against the reference of the exact material.
pub fn run_with(
    backend: &mut dyn Backend,
    precision: Precision,
    tuples: usize,
    seed: u64,
    chunk: usize,
    progress: &mut dyn FnMut(usize),
) -> Result<StressReport> {
    let backend_label = match precision {
        Precision::Exact => backend.name(),
        p => format!("{} ({})", backend.name(), p.label()),
    };
    let mut report = StressReport {
        backend: backend_label,
        exact: precision == Precision::Exact,
        ..StressReport::default()
    };
    let spectral = SpectralPass::new()?;
    let mut start = 0;
    while start < tuples {
        let end = (start + chunk.max(1)).min(tuples);
        let (materials, batch, cases) = corpus::corpus_rows(start..end, seed);
        if precision == Precision::Exact {
            spectral.run(backend, &batch, &cases, start, &mut report)?;
        }
        let variant = crate::precision::apply_all(&materials, precision);
        let out = backend.evaluate(&batch, &variant, &Request { terms: true })?;
        let terms = out.terms.as_deref().expect("terms were requested");
        report.tuples += batch.len() as u64;
        report.invalid.0 += out.counts.invalid;
        report.below_horizon.0 += out.counts.below_horizon;
        report.saturated.0 += out.counts.saturated;
        let judged = Judged {
            materials: &materials,
            variant: (precision != Precision::Exact).then_some(&variant[..]),
            cases: &cases,
        };
        let parts = judge(&batch, &judged, &out.brdf, terms, start);
        for p in parts {
            report.non_finite += p.non_finite;
            report.invalid.1 += p.invalid;
            report.below_horizon.1 += p.below;
            report.saturated.1 += p.saturated;
            report.nonzero_rejects += p.nonzero_rejects;
            report.ambiguous_horizon += p.ambiguous_horizon;
            for (key, stats) in p.errors {
                let entry = report.errors.entry(key.clone()).or_default();
                let before = entry.max;
                entry.merge(&stats);
                if entry.max > before || !report.worst_rows.contains_key(&key) {
                    if let Some(row) = stats.worst {
                        let local = row as usize - start;
                        let mut r = [0f32; 13];
                        r.copy_from_slice(&batch.as_slice()[local * 13..local * 13 + 13]);
                        report.worst_rows.insert(key, r);
                    }
                }
            }
        }
        start = end;
        progress(start);
    }
    Ok(report)
}

/// The spectral presets at seven wavelengths (FORMULAS.md §9) on every 16th corpus tuple
/// (its directions, a preset in turn for its material), through the backend's own spectral
/// way, judged against the reference's materials at the wavelengths: the rows
/// `f: spectral` of the report.
struct SpectralPass {
    job: crate::spectral_eval::SpectralJob,
}

/// Which corpus rows the spectral pass takes: one in [`SPECTRAL_EVERY`].
const SPECTRAL_EVERY: usize = 16;

impl SpectralPass {
    fn new() -> Result<SpectralPass> {
        let materials = crate::material::presets::SPECTRAL
            .iter()
            .map(|n| crate::material::presets::preset(n).expect("a preset name"))
            .collect::<std::result::Result<Vec<_>, _>>()?;
        let wavelengths = "380,450,520,590,660,730,800"
            .parse()
            .expect("a wavelength list");
        Ok(SpectralPass {
            job: crate::spectral_eval::SpectralJob::new(&materials, wavelengths, None)?,
        })
    }

    fn run(
        &self,
        backend: &mut dyn Backend,
        batch: &crate::batch::Batch,
        cases: &[Case],
        offset: usize,
        report: &mut StressReport,
    ) -> Result<()> {
        let presets = self.job.triplets()[0].len();
        let (mut data, mut rows) = (Vec::new(), Vec::new());
        for i in (SPECTRAL_EVERY / 2..batch.len()).step_by(SPECTRAL_EVERY) {
            let mut r = [0f32; 13];
            r.copy_from_slice(&batch.as_slice()[i * 13..i * 13 + 13]);
            r[9] = ((offset + i) / SPECTRAL_EVERY % presets) as f32;
            data.extend_from_slice(&r);
            rows.push(i);
        }
        if rows.is_empty() {
            return Ok(());
        }
        let sub = crate::batch::Batch::new(data, 13, presets, &crate::batch::memory_source())?;
        let out = self.job.evaluate(backend, &sub)?;
        let mut reference = reference::CpuReference::new();
        let w = self.job.wavelengths().len();
        for (t, mats) in self.job.triplets().iter().enumerate() {
            let r = reference.evaluate(&sub, mats, &Request::default())?;
            for (k, &i) in rows.iter().enumerate() {
                let tuple = sub.tuple(k);
                let m = &mats[tuple.material];
                if reference::evaluate_tuple(&tuple, m).status != Status::Valid {
                    continue; // judged, as every row, by the RGB pass
                }
                let key = ("f: spectral".to_string(), regime(m, cases[i]));
                let stats = report.errors.entry(key.clone()).or_default();
                let before = stats.max;
                for j in 0..3.min(w - 3 * t) {
                    let x = out.brdf[k * w + 3 * t + j];
                    report.non_finite += u64::from(!x.is_finite());
                    let want = f64::from(r.brdf[3 * k + j]);
                    stats.add(
                        relative_error(f64::from(x), want, ERROR_FLOOR),
                        (offset + i) as u64,
                    );
                }
                if stats.max > before {
                    let mut row = [0f32; 13];
                    row.copy_from_slice(&sub.as_slice()[k * 13..k * 13 + 13]);
                    report.worst_rows.insert(key, row);
                }
            }
        }
        Ok(())
    }
}

#[derive(Default)]
struct Part {
    non_finite: u64,
    invalid: u64,
    below: u64,
    saturated: u64,
    nonzero_rejects: u64,
    ambiguous_horizon: u64,
    errors: BTreeMap<(String, Regime), ErrorStats>,
}

/// What one chunk is judged against: the exact materials, the variant the backend
/// evaluated when it differs (its reference decides the saturated count), each row's case.
struct Judged<'a> {
    materials: &'a [Material],
    variant: Option<&'a [Material]>,
    cases: &'a [Case],
}

/// Compares one evaluated chunk with the reference, spread over the cores.
fn judge(
    batch: &crate::batch::Batch,
    judged: &Judged,
    brdf: &[f32],
    terms: &[f32],
    offset: usize,
) -> Vec<Part> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let per = batch.len().div_ceil(threads).max(1);
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..batch.len())
            .step_by(per)
            .map(|lo| {
                s.spawn(move || {
                    let mut p = Part::default();
                    for i in lo..(lo + per).min(batch.len()) {
                        let t = batch.tuple(i);
                        let m = &judged.materials[t.material];
                        let r = reference::evaluate_tuple(&t, m);
                        let saturated = match judged.variant {
                            None => r.saturated(),
                            Some(v) => reference::evaluate_tuple(&t, &v[t.material]).saturated(),
                        };
                        p.saturated += u64::from(r.status == Status::Valid && saturated);
                        let got_f = &brdf[3 * i..3 * i + 3];
                        let got_t = &terms[TERM_COLUMNS * i..TERM_COLUMNS * (i + 1)];
                        p.non_finite +=
                            got_f.iter().chain(got_t).filter(|x| !x.is_finite()).count() as u64;
                        if r.status != Status::Valid {
                            if r.status == Status::Invalid {
                                p.invalid += 1;
                            } else {
                                p.below += 1;
                            }
                            if got_f.iter().chain(got_t).any(|&x| x != 0.0) {
                                if r.status == Status::BelowHorizon
                                    && min_cosine(&t, m) > -HORIZON_EPS
                                {
                                    p.ambiguous_horizon += 1;
                                } else {
                                    p.nonzero_rejects += 1;
                                }
                            }
                            continue;
                        }
                        let regime = regime(m, judged.cases[i]);
                        let row = (offset + i) as u64;
                        let mut add = |q: &str, x: f32, want: f64| {
                            p.errors.entry((q.to_string(), regime)).or_default().add(
                                // Judged against the output the contract asks for:
                                // beyond f32::MAX, f32::MAX (FORMULAS.md §1).
                                relative_error(
                                    x as f64,
                                    want.min(f64::from(f32::MAX)),
                                    ERROR_FLOOR,
                                ),
                                row,
                            );
                        };
                        for (&x, want) in got_f.iter().zip(r.brdf) {
                            add(model_label(m), x, want);
                        }
                        let want = r.terms();
                        add("D", got_t[0], want[0]);
                        add("G", got_t[1], want[1]);
                        for c in 0..3 {
                            add("F", got_t[2 + c], want[2 + c]);
                        }
                        add("K", got_t[5], want[5]);
                    }
                    p
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("stress judge thread panicked"))
            .collect()
    })
}

/// `min(cos_i, cos_o)` of a valid tuple, from the reference's f64 frame.
fn min_cosine(t: &crate::batch::Tuple, m: &Material) -> f64 {
    let w = |a: [f32; 3]| a.map(f64::from);
    reference::frame::Frame::new(w(t.l), w(t.v), w(t.n), t.t.map(w), m.is_anisotropic())
        .map_or(f64::NAN, |f| f.cos_i.min(f.cos_o))
}

impl StressReport {
    /// Whether the policy holds: no non-finite output, the invalid and (for the exact
    /// materials) saturated counts agree, and no invalid or clearly-below-horizon tuple has
    /// a non-zero output.
    pub fn policy_holds(&self) -> bool {
        self.non_finite == 0
            && self.invalid.0 == self.invalid.1
            && (!self.exact || self.saturated.0 == self.saturated.1)
            && self.nonzero_rejects == 0
    }

    /// The report as Markdown: the policy summary and the error table.
    pub fn to_markdown(&self, target: f64) -> String {
        let mut s = format!(
            "### {}: {} stress tuples\n\n- non-finite outputs: **{}**\n- invalid tuples: {} (reference {})\n- below the horizon: {} (reference {})\n- saturated (an output beyond f32::MAX, stored as f32::MAX): {} (reference {})\n- invalid/below-horizon tuples with a non-zero output: {}\n- below-horizon tuples within {HORIZON_EPS:e} of the horizon evaluated anyway (f32 ambiguity): {}\n- policy (finite outputs, invalid and (exact precision) saturated counts agree, zero rejects): **{}**\n\n",
            self.backend,
            self.tuples,
            self.non_finite,
            self.invalid.0,
            self.invalid.1,
            self.below_horizon.0,
            self.below_horizon.1,
            self.saturated.0,
            self.saturated.1,
            self.nonzero_rejects,
            self.ambiguous_horizon,
            if self.policy_holds() { "holds" } else { "FAILS" }
        );
        s += &format!("Relative error against the f64 reference, `|x − ref| / max(|ref|, {ERROR_FLOOR:e})`:\n\n");
        s += &format!("| quantity | regime | values | max rel err | p99 rel err | ≤ {target:e} |\n|---|---|---:|---:|---:|:---:|\n");
        for ((q, regime), st) in &self.errors {
            s += &format!(
                "| {q} | {} | {} | {:.2e} | {:.2e} | {} |\n",
                regime.label(),
                st.count,
                st.max,
                st.p99(),
                if st.max <= target {
                    "yes"
                } else if st.p99() <= target {
                    "p99 only"
                } else {
                    "**no**"
                }
            );
        }
        let failing: Vec<_> = self
            .errors
            .iter()
            .filter(|(_, st)| st.max > target)
            .collect();
        if !failing.is_empty() {
            s += "\nWorst tuple per row over the target (`Lx Ly Lz Vx Vy Vz Nx Ny Nz material Tx Ty Tz`):\n\n";
            for (key, st) in failing {
                if let Some(row) = self.worst_rows.get(key) {
                    s += &format!(
                        "- {} / {} (row {}, rel err {:.2e}): `{:?}`\n",
                        key.0,
                        key.1.label(),
                        st.worst.unwrap_or(0),
                        st.max,
                        row
                    );
                }
            }
        }
        s
    }
}
