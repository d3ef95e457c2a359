//! The broadcast form's native entry: `evaluate(l=, v=, n=, t=, material=)` given as
//! columns — each direction one vector for every row or one a row, the material one index
//! or one a row. The rows are gathered chunk by chunk into a buffer that stays in the
//! cache and evaluated there, so the form reads its 12 bytes a vector once and never
//! builds the whole `(n, 10)` array NumPy used to make first (a quarter of the row form's
//! rate, issue 31). Results, counts and errors are those of the same rows given as one
//! array: each chunk is checked and evaluated as rows `start..` of the batch.

use crate::errors::{raise, TUPLES};
use crate::{engine_and_materials, refuse_invalid, rows, run_engine, Evaluated, Materials};
use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use std::path::Path;
use vkbrdf::backend::{Counts, Output, Request, TERM_COLUMNS};
use vkbrdf::batch::{check_tangent_rows, Batch};

/// Rows gathered and evaluated at a time: 10 MiB of 10-column rows, in the last-level
/// cache while the engine reads them, and enough work a call that the engine's own
/// overhead is noise (2^14 and 2^16 measured no faster).
const CHUNK_ROWS: usize = 1 << 18;

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
    let mut columns = vec![
        slice(py, "l", &l)?,
        slice(py, "v", &v)?,
        slice(py, "n", &n)?,
    ];
    if let Some(t) = &t {
        columns.push(slice(py, "t", t)?);
    }
    let m = m
        .as_slice()
        .map_err(|e| raise(py, "BatchError", format!("material: internal: {e}")))?;
    if let Some(bad) = columns
        .iter()
        .map(|c| c.len() / 3)
        .chain([m.len()])
        .find(|&k| k != 1 && k != count)
    {
        return Err(raise(
            py,
            "BatchError",
            format!("internal: a column of {bad} rows for {count} rows"),
        ));
    }
    let width = if t.is_some() { 13 } else { 10 };
    let request = Request { terms };
    let source = Path::new(TUPLES);
    let (brdf, term_values, counts) = run_engine(py, kind, |backend, cancel| {
        let mut brdf = vec![0f32; 3 * count];
        let mut term_values = vec![0f32; if terms { TERM_COLUMNS * count } else { 0 }];
        let mut counts = Counts {
            tuples: count as u64,
            ..Counts::default()
        };
        let mut out = Output::default();
        let mut buffer = Vec::new();
        for start in (0..count).step_by(CHUNK_ROWS) {
            cancel.check()?;
            let end = (start + CHUNK_ROWS).min(count);
            gather(&columns, m, start..end, width, &mut buffer);
            let batch = Batch::new_at(
                std::mem::take(&mut buffer),
                width,
                list.len(),
                source,
                start as u64,
            )?;
            check_tangent_rows(batch.as_slice(), width, start as u64, &list, source)?;
            backend.evaluate_into(&batch, &list, &request, &mut out)?;
            copy_split(
                &mut brdf[3 * start..3 * end],
                &out.brdf[..3 * (end - start)],
            );
            if let Some(t) = out.terms.as_ref().filter(|_| terms) {
                copy_split(
                    &mut term_values[TERM_COLUMNS * start..TERM_COLUMNS * end],
                    &t[..TERM_COLUMNS * (end - start)],
                );
            }
            let mut c = out.counts;
            c.first_invalid = c.first_invalid.map(|r| r + start as u64);
            counts.absorb(&c);
            buffer = batch.into_data();
        }
        Ok((brdf, term_values, counts))
    })?;
    refuse_invalid(py, strict, &counts)?;
    let f = rows(py, brdf, count, 3)?;
    let t = if terms {
        Some(rows(py, term_values, count, TERM_COLUMNS)?)
    } else {
        None
    };
    let c = counts;
    Ok((
        f,
        t,
        (c.invalid, c.below_horizon, c.saturated, c.first_invalid),
        false,
    ))
}

/// The size of each part when `len` items are split one part a core, each at least
/// `min_part` items (below that a thread costs more than it saves): `len` itself when one
/// part. The core count is read once (on Linux it reads the cgroup's files).
fn part_size(len: usize, min_part: usize) -> usize {
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    let cores = *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    len.div_ceil(cores.min(len / min_part).max(1)).max(1)
}

/// `dst.copy_from_slice(src)` split over the cores: the result's pages are new, and
/// their first writes (page faults) are most of the copy's time.
fn copy_split(dst: &mut [f32], src: &[f32]) {
    let per_part = part_size(dst.len(), 16 << 10);
    if per_part >= dst.len() {
        dst.copy_from_slice(src);
        return;
    }
    std::thread::scope(|s| {
        for (d, c) in dst.chunks_mut(per_part).zip(src.chunks(per_part)) {
            s.spawn(move || d.copy_from_slice(c));
        }
    });
}

/// Rows `range` of the batch the columns make, into `buffer` (`width` floats a row: L, V,
/// N, the material, then T), split over the cores: the gather is the form's one pass the
/// row form does not have, and the engine's threads wait for it.
fn gather(
    columns: &[&[f32]],
    m: &[f32],
    range: std::ops::Range<usize>,
    width: usize,
    buffer: &mut Vec<f32>,
) {
    buffer.clear();
    buffer.resize(range.len() * width, 0.0);
    let rows_per_part = part_size(range.len(), 4096);
    if rows_per_part >= range.len() {
        gather_rows(columns, m, range, width, buffer);
        return;
    }
    std::thread::scope(|s| {
        for (i, piece) in buffer.chunks_mut(rows_per_part * width).enumerate() {
            let start = range.start + i * rows_per_part;
            let rows = start..start + piece.len() / width;
            s.spawn(move || gather_rows(columns, m, rows, width, piece));
        }
    });
}

/// [`gather`]'s work for rows `range` into `out` (their `width`-float rows). Column by
/// column (a pass each): faster here than one pass writing whole rows, whose indexing the
/// compiler does not vectorise.
fn gather_rows(
    columns: &[&[f32]],
    m: &[f32],
    range: std::ops::Range<usize>,
    width: usize,
    out: &mut [f32],
) {
    for (k, column) in columns.iter().enumerate() {
        let at = if k < 3 { 3 * k } else { 10 };
        let rows = out.chunks_exact_mut(width);
        if column.len() == 3 {
            rows.for_each(|r| r[at..at + 3].copy_from_slice(column));
        } else {
            let values = column[3 * range.start..3 * range.end].chunks_exact(3);
            rows.zip(values)
                .for_each(|(r, x)| r[at..at + 3].copy_from_slice(x));
        }
    }
    let rows = out.chunks_exact_mut(width);
    if m.len() == 1 {
        rows.for_each(|r| r[9] = m[0]);
    } else {
        rows.zip(&m[range]).for_each(|(r, &x)| r[9] = x);
    }
}
