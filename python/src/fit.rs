//! `vkbrdf.fit`: the library's fitter ([`vkbrdf::fit`]) on NumPy data or a MERL file,
//! returning the fitted material's TOML, its parameters and every metric.

use crate::errors::{raise, to_py};
use crate::{parse_backend, run_engine, Materials};
use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use vkbrdf::fit::data::FitData;
use vkbrdf::fit::losses::Loss;
use vkbrdf::fit::params::{self, Param, Space};
use vkbrdf::fit::{self as fitting, report};

/// The data of a fit: a MERL file, or C-contiguous float32 tuples and values.
fn data(
    py: Python<'_>,
    merl: Option<PathBuf>,
    tuples: Option<PyReadonlyArray2<'_, f32>>,
    values: Option<PyReadonlyArray2<'_, f32>>,
    max_theta: Option<f64>,
) -> PyResult<FitData> {
    let usage = |m: &str| raise(py, "UsageError", m.to_string());
    let max_theta = match max_theta {
        Some(d) if !(d > 0.0 && d <= 90.0) => {
            return Err(usage("max_theta: give an angle in (0, 90] degrees"))
        }
        d => d.map(f64::to_radians),
    };
    match (merl, tuples, values) {
        (Some(path), None, None) => {
            let table = vkbrdf::material::merl::read(&path).map_err(|e| to_py(py, e))?;
            FitData::from_merl(&table, max_theta).map_err(|e| to_py(py, e))
        }
        (None, Some(t), Some(v)) => {
            let slice = |a: &PyReadonlyArray2<'_, f32>, name: &str| -> PyResult<Vec<f32>> {
                a.as_slice().map(<[f32]>::to_vec).map_err(|e| {
                    raise(
                        py,
                        "BatchError",
                        format!("{name}: the array must be C-contiguous float32 ({e})"),
                    )
                })
            };
            if v.shape()[1] != 3 {
                return Err(raise(
                    py,
                    "BatchError",
                    format!("values: must be (n, 3) RGB; shape {:?}", v.shape()),
                ));
            }
            let (t_rows, v_rows) = (slice(&t, "tuples")?, slice(&v, "values")?);
            FitData::from_tuples(
                &t_rows,
                t.shape()[1],
                &v_rows,
                None,
                max_theta,
                Path::new("tuples"),
            )
            .map_err(|e| to_py(py, e))
        }
        _ => Err(usage(
            "give the data: merl=PATH, or tuples= (n, 6|10|13) and values= (n, 3)",
        )),
    }
}

/// Fits `free` of `materials[material]` to the data; returns a dict (see the stub).
#[pyfunction]
#[pyo3(signature = (materials, material, free, merl, tuples, values, loss, backend, starts, seed, max_theta))]
#[allow(clippy::too_many_arguments)]
pub fn fit<'py>(
    py: Python<'py>,
    materials: &Materials,
    material: &str,
    free: Vec<String>,
    merl: Option<PathBuf>,
    tuples: Option<PyReadonlyArray2<'py, f32>>,
    values: Option<PyReadonlyArray2<'py, f32>>,
    loss: &str,
    backend: &str,
    starts: usize,
    seed: u64,
    max_theta: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = parse_backend(py, backend)?;
    let loss: Loss = loss.parse().map_err(|e| to_py(py, e))?;
    let free: Vec<Param> = free
        .iter()
        .map(|s| s.parse())
        .collect::<vkbrdf::Result<_>>()
        .map_err(|e| to_py(py, e))?;
    let start = &materials.list[materials.index(py, material)?];
    let space = Space::new(start, &free, &[], loss.is_quadratic()).map_err(|e| to_py(py, e))?;
    let data = data(py, merl, tuples, values, max_theta)?;
    let options = fitting::Options {
        loss,
        starts: starts.max(1),
        seed,
        ..fitting::Options::default()
    };
    let result = run_engine(py, kind, |backend, cancel| {
        fitting::fit(&data, &space, &options, backend, cancel, &mut |_| {})
    })?;
    let toml = report::material_toml(&result.material).map_err(|e| to_py(py, e))?;
    let out = PyDict::new(py);
    out.set_item("toml", toml)?;
    let parameters = PyDict::new(py);
    for p in Param::ALL.into_iter().filter(|p| space.is_free(*p)) {
        parameters.set_item(p.name(), params::get(&result.material, p))?;
    }
    out.set_item("parameters", parameters)?;
    let m = result.metrics;
    let metrics = PyDict::new(py);
    for (name, value) in [
        ("l2", m.l2),
        ("l2_relative", m.l2_relative),
        ("e1", m.e1),
        ("e2", m.e2),
        ("rrms", m.rrms),
        ("energy", m.energy),
    ] {
        metrics.set_item(name, value)?;
    }
    out.set_item("metrics", metrics)?;
    out.set_item("loss", loss.name())?;
    out.set_item("evaluations", result.evaluations)?;
    out.set_item("seconds", result.seconds)?;
    out.set_item("backend", result.backend)?;
    out.set_item("samples", data.len())?;
    Ok(out)
}
