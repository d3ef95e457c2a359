//! Evaluation at wavelengths (FORMULAS.md §9), two ways:
//! - **triplets**: `⌈W/3⌉` RGB evaluations of the same tuples, each with the materials' forms
//!   at three of the wavelengths (a channel per wavelength:
//!   [`crate::material::spectral::SpectralForm`]). Every engine evaluates them with its own
//!   RGB code; the reference always takes this way (it is the judge), and so do HTSG and
//!   measured materials on every engine.
//! - **factored** (`spectral_eval/factored.rs`): one RGB evaluation of a basis material gives the
//!   λ-independent factors (D, G and K computed once per tuple), and F is formed per
//!   wavelength on the host. What the engines take wherever every material allows it.
//!
//! `--color` then reduces the `W` values of each tuple to CIE XYZ or linear sRGB by the CIE
//! quadrature, in f64, in the grid's order.

mod factored;

use crate::backend::{Backend, Output, Request};
use crate::batch::Batch;
use crate::error::{Error, Result};
use crate::material::spectral::spectral_form;
use crate::material::Material;
use crate::spectral::cie::{self, Illuminant};
use crate::spectral::Wavelengths;

/// What a colour reduction gives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Colour {
    /// CIE 1931 XYZ (Y = 1 for a white reflector).
    Xyz,
    /// Linear sRGB, unclamped (gold's red is above 1).
    Srgb,
}

/// A prepared spectral evaluation: the materials at each wavelength triplet.
#[derive(Debug, Clone)]
pub struct SpectralJob {
    wavelengths: Wavelengths,
    colour: Option<(Colour, Illuminant)>,
    /// `triplets[t]`: every material at wavelengths `3t, 3t+1, 3t+2` (the last repeated
    /// when `W` is not a multiple of 3).
    triplets: Vec<Vec<Material>>,
    factored: Option<factored::Factored>,
    /// Why material `i` has no spectral form, if it has none.
    unusable: Vec<Option<String>>,
}

impl SpectralJob {
    /// Prepares `materials` at `wavelengths`; with `colour`, the values are reduced (which
    /// needs the CIE grid 360:830:5). Errors name the material and wavelength.
    pub fn new(
        materials: &[Material],
        wavelengths: Wavelengths,
        colour: Option<(Colour, Illuminant)>,
    ) -> Result<SpectralJob> {
        if colour.is_some() && !wavelengths.is_cie_grid() {
            return Err(Error::Unsupported(format!(
                "--color integrates over the CIE 1931 tables' grid, 360:830:5 (95 wavelengths); these {} wavelengths are another grid (give --wavelengths 360:830:5, or leave out --color for the values themselves)",
                wavelengths.len()
            )));
        }
        // A material without a spectral form is an error only if a row uses it (a table
        // may hold RGB materials beside spectral ones): it stands in unchanged meanwhile.
        let mut unusable = vec![None; materials.len()];
        let forms: Vec<Option<crate::material::spectral::SpectralForm>> = materials
            .iter()
            .enumerate()
            .map(|(i, m)| match spectral_form(m) {
                Ok(f) => Some(f),
                Err(e) => {
                    unusable[i] = Some(e);
                    None
                }
            })
            .collect();
        let w = &wavelengths.0;
        let triplets = (0..w.len().div_ceil(3))
            .map(|t| {
                let nm = [0, 1, 2].map(|j| w[(3 * t + j).min(w.len() - 1)]);
                forms
                    .iter()
                    .zip(materials)
                    .enumerate()
                    .map(|(i, (f, m))| match f {
                        Some(f) => f.at(nm),
                        None if unusable[i].is_some() => Ok(m.clone()),
                        None => unreachable!("a form or its error"),
                    })
                    .collect::<std::result::Result<Vec<_>, String>>()
                    .map_err(Error::Unsupported)
            })
            .collect::<Result<Vec<_>>>()?;
        let factored = factored::Factored::new(&triplets, wavelengths.len());
        Ok(SpectralJob {
            wavelengths,
            colour,
            triplets,
            factored,
            unusable,
        })
    }

    /// Output columns per tuple: `W`, or 3 with a colour reduction.
    pub fn columns(&self) -> usize {
        if self.colour.is_some() {
            3
        } else {
            self.wavelengths.len()
        }
    }

    /// The wavelengths.
    pub fn wavelengths(&self) -> &Wavelengths {
        &self.wavelengths
    }

    /// The materials at each triplet (what the engines evaluate; for the judge).
    pub fn triplets(&self) -> &[Vec<Material>] {
        &self.triplets
    }

    /// Why the first material without a spectral form that rows `[0, n)` use has none, if
    /// any row uses one (checked before any evaluation).
    pub fn unusable_by(
        &self,
        n: usize,
        row: &(dyn Fn(usize) -> ([f32; 3], [f32; 3], usize) + Sync),
    ) -> Option<String> {
        if self.unusable.iter().all(Option::is_none) {
            return None;
        }
        (0..n).find_map(|r| self.unusable.get(row(r).2).cloned().flatten())
    }

    /// Whether an engine that is not the reference takes the factored way for this job.
    pub fn is_factored(&self) -> bool {
        self.factored.is_some()
    }

    /// Evaluates `n` tuples: `eval` evaluates them with a material table into an RGB
    /// output; `row(r)` gives row r's L, V and material (the factored way reads them);
    /// `out` receives `n × columns` values. `triplets` forces the triplet way (the
    /// reference's). The counts are the first evaluation's (invalid and below-horizon tuples
    /// do not depend on λ), with the largest saturated count of any.
    pub fn evaluate_with(
        &self,
        n: usize,
        triplets: bool,
        row: &(dyn Fn(usize) -> ([f32; 3], [f32; 3], usize) + Sync),
        mut eval: impl FnMut(&[Material], &mut Output) -> Result<()>,
        out: &mut Output,
    ) -> Result<()> {
        if let Some(why) = self.unusable_by(n, row) {
            return Err(Error::Unsupported(why));
        }
        if let (Some(f), false) = (&self.factored, triplets) {
            let mut part = Output::default();
            eval(&f.basis, &mut part)?;
            out.counts = part.counts;
            out.terms = None;
            out.brdf.clear();
            out.brdf.resize(n * self.columns(), 0.0);
            let weights = self.colour.map(|(_, illum)| cie::weights(illum));
            let colour = self.colour.map(|(c, _)| match c {
                Colour::Xyz => [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                Colour::Srgb => cie::srgb_matrices().1,
            });
            let colour = weights.as_ref().zip(colour).map(|(w, m)| (&w[..], m));
            f.combine(&part.brdf, row, colour, &mut out.brdf);
            return Ok(());
        }
        let w = self.wavelengths.len();
        let cols = self.columns();
        let mut part = Output::default();
        let mut acc = vec![0.0f64; if self.colour.is_some() { 3 * n } else { 0 }];
        let weights = self.colour.map(|(_, illum)| cie::weights(illum));
        out.brdf.clear();
        out.brdf.resize(n * cols, 0.0);
        out.terms = None;
        for (t, materials) in self.triplets.iter().enumerate() {
            eval(materials, &mut part)?;
            if t == 0 {
                out.counts = part.counts;
            } else {
                out.counts.saturated = out.counts.saturated.max(part.counts.saturated);
            }
            for j in 0..3 {
                let l = 3 * t + j;
                if l >= w {
                    break; // the last triplet's repeated wavelength
                }
                match &weights {
                    None => {
                        for r in 0..n {
                            out.brdf[r * cols + l] = part.brdf[r * 3 + j];
                        }
                    }
                    Some(wt) => {
                        let wl = wt[l];
                        for r in 0..n {
                            let v = part.brdf[r * 3 + j] as f64;
                            for c in 0..3 {
                                acc[r * 3 + c] += v * wl[c];
                            }
                        }
                    }
                }
            }
        }
        if let Some((colour, _)) = self.colour {
            for r in 0..n {
                let xyz = [acc[3 * r], acc[3 * r + 1], acc[3 * r + 2]];
                let v = match colour {
                    Colour::Xyz => xyz,
                    Colour::Srgb => cie::xyz_to_srgb(xyz),
                };
                for (o, x) in out.brdf[r * 3..r * 3 + 3].iter_mut().zip(v) {
                    *o = x as f32;
                }
            }
        }
        Ok(())
    }

    /// Evaluates `batch` (whose material column indexes the job's materials) on `backend`.
    pub fn evaluate(&self, backend: &mut dyn Backend, batch: &Batch) -> Result<Output> {
        let mut out = Output::default();
        let triplets = backend.is_reference();
        self.evaluate_with(
            batch.len(),
            triplets,
            &batch_rows(batch),
            |m, o| backend.evaluate_into(batch, m, &Request::default(), o),
            &mut out,
        )?;
        out.counts.tuples = batch.len() as u64;
        Ok(out)
    }
}

/// Row access for [`SpectralJob::evaluate_with`] over a batch of 10- or 13-column rows.
pub fn batch_rows<'a>(
    batch: &'a Batch,
) -> impl Fn(usize) -> ([f32; 3], [f32; 3], usize) + Sync + 'a {
    let (rows, cols) = (batch.as_slice(), batch.columns());
    move |r| {
        let x = &rows[r * cols..];
        ([x[0], x[1], x[2]], [x[3], x[4], x[5]], x[9] as usize)
    }
}

/// Row access over a local-frame batch (6 columns, one material).
pub fn local_rows<'a>(
    batch: &'a crate::batch::LocalBatch,
) -> impl Fn(usize) -> ([f32; 3], [f32; 3], usize) + Sync + 'a {
    let material = batch.material();
    move |r| {
        let x = batch.row(r);
        ([x[0], x[1], x[2]], [x[3], x[4], x[5]], material)
    }
}
