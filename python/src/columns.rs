//! The broadcast form's native entry: `evaluate(l=, v=, n=, t=, material=)` given as
//! columns — each direction one vector for every row or one a row, the material one index
//! or one a row — evaluated as a [`ColumnBatch`]: the CPU engine reads the columns in
//! place, the other engines get rows gathered a chunk at a time. No `(n, 10)` array is
//! built (NumPy's building it first made the form a quarter of the row form's rate, issue
//! 31). Results, counts and errors are those of the same rows given as one array.

use crate::errors::{raise, to_py, TUPLES};
use crate::{engine_and_materials, refuse_invalid, rows, run_engine, Evaluated, Materials};
use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use std::path::Path;
use vkbrdf::backend::{Output, Request, TERM_COLUMNS};
use vkbrdf::batch::columns::ColumnBatch;

/// Evaluates the `count` rows the columns make (see the module docs): `l`, `v`, `n` and
/// `t` C-contiguous float32 `(k, 3)`, `m` float32 `(k,)`, each k 1 or `count`.
#[pyfunction]
#[pyo3(signature = (materials, count, l, v, n, t, m, backend, terms, precision, strict))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn evaluate_columns<'py>(
    py: Python<'py>,
    materials: &Materials,
    count: usize,
    l: PyReadonlyArray2<'py, f32>,
    v: PyReadonlyArray2<'py, f32>,
    n: PyReadonlyArray2<'py, f32>,
    t: Option<PyReadonlyArray2<'py, f32>>,
    m: PyReadonlyArray1<'py, f32>,
    backend: &str,
    terms: bool,
    precision: &str,
    strict: bool,
) -> PyResult<Evaluated<'py>> {
    let (kind, list) = engine_and_materials(py, materials, backend, precision)?;
    fn slice<'a>(
        py: Python<'_>,
        name: &str,
        a: &'a PyReadonlyArray2<'_, f32>,
    ) -> PyResult<&'a [f32]> {
        let s = a.as_slice().ok().filter(|_| a.shape()[1] == 3);
        s.ok_or_else(|| {
            raise(
                py,
                "BatchError",
                format!("{name}: internal: expected a C-contiguous float32 (k, 3) column"),
            )
        })
    }
    let directions = [
        slice(py, "l", &l)?,
        slice(py, "v", &v)?,
        slice(py, "n", &n)?,
    ];
    let tangent = t.as_ref().map(|t| slice(py, "t", t)).transpose()?;
    let m = m
        .as_slice()
        .map_err(|e| raise(py, "BatchError", format!("material: internal: {e}")))?;
    let batch = ColumnBatch::new(directions, tangent, m, count, &list, Path::new(TUPLES))
        .map_err(|e| to_py(py, e))?;
    let request = Request { terms };
    let out = run_engine(py, kind, |backend, _| {
        let mut out = Output::default();
        backend.evaluate_columns_into(&batch, &list, &request, &mut out)?;
        Ok(out)
    })?;
    let c = out.counts;
    refuse_invalid(py, strict, &c)?;
    let f = rows(py, out.brdf, count, 3)?;
    let t = match out.terms {
        Some(values) if terms => Some(rows(py, values, count, TERM_COLUMNS)?),
        _ => None,
    };
    Ok((
        f,
        t,
        (c.invalid, c.below_horizon, c.saturated, c.first_invalid),
        false,
    ))
}
