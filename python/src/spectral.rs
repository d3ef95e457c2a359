//! `vkbrdf.evaluate(..., wavelengths=, color=)`: the library's spectral evaluation
//! ([`vkbrdf::spectral_eval`], FORMULAS.md §9) on a NumPy tuple array read in place.

use crate::errors::{raise, to_py, TUPLES};
use crate::{
    borrowed_batch, parse_backend, parse_precision, refuse_invalid, rows, run_engine, Materials,
};
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use std::path::Path;
use vkbrdf::backend::Counts;
use vkbrdf::precision;

/// A spectral evaluation's values and counts.
type SpectralValues<'py> = (Bound<'py, PyArray2<f32>>, (u64, u64, u64, Option<u64>));

/// Evaluates a C-contiguous float32 tuple array at wavelengths (FORMULAS.md §9):
/// `(n, W)` values, or `(n, 3)` XYZ / linear sRGB with `color`.
#[pyfunction]
#[pyo3(signature = (materials, tuples, backend, wavelengths, color, illuminant, precision, strict))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn evaluate_spectral<'py>(
    py: Python<'py>,
    materials: &Materials,
    tuples: PyReadonlyArray2<'py, f32>,
    backend: &str,
    wavelengths: Option<&str>,
    color: Option<&str>,
    illuminant: &str,
    precision: &str,
    strict: bool,
) -> PyResult<SpectralValues<'py>> {
    use vkbrdf::spectral::cie::Illuminant;
    use vkbrdf::spectral_eval::{Colour, SpectralJob};
    let usage = |m: String| raise(py, "UsageError", m);
    let kind = parse_backend(py, backend)?;
    let list = precision::apply_all(&materials.list, parse_precision(py, precision)?);
    let illuminant = match illuminant {
        "d65" => Illuminant::D65,
        "e" => Illuminant::E,
        other => {
            return Err(usage(format!(
                "illuminant: `{other}`; expected `d65` or `e`"
            )))
        }
    };
    let colour = match color {
        None => None,
        Some("xyz") => Some((Colour::Xyz, illuminant)),
        Some("srgb") => Some((Colour::Srgb, illuminant)),
        Some(other) => return Err(usage(format!("color: `{other}`; expected `xyz` or `srgb`"))),
    };
    let wavelengths = match wavelengths {
        Some(w) => w
            .parse::<vkbrdf::spectral::Wavelengths>()
            .map_err(|e| usage(format!("wavelengths: {e}")))?,
        None => vkbrdf::spectral::Wavelengths::cie(),
    };
    // A material without a spectral form, data that does not cover a wavelength, or a
    // colour on another grid: each a request this table cannot answer.
    let job = SpectralJob::new(&list, wavelengths, colour).map_err(|e| usage(e.to_string()))?;
    let batch = borrowed_batch(py, &tuples, list.len())?;
    batch
        .check_tangents(&list, Path::new(TUPLES))
        .map_err(|e| to_py(py, e))?;
    if let Some(why) = job.unusable_by(batch.len(), &vkbrdf::spectral_eval::batch_rows(&batch)) {
        return Err(usage(why));
    }
    let out = run_engine(py, kind, |backend, _| job.evaluate(backend, &batch))?;
    let c: Counts = out.counts;
    refuse_invalid(py, strict, &c)?;
    let n = batch.len();
    Ok((
        rows(py, out.brdf, n, job.columns())?,
        (c.invalid, c.below_horizon, c.saturated, c.first_invalid),
    ))
}
