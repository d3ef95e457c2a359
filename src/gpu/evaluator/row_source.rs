//! What the chunk loop reads its rows from: a batch's rows in place, or a batch given as
//! columns, gathered into rows one chunk at a time while the device works on the chunks
//! before it (one call over the whole batch: calls of gathered parts drained the frames in
//! flight at every boundary, 0.91–0.93× the row form on lavapipe).

use crate::batch::columns::ColumnBatch;
use crate::batch::Batch;

/// See the module docs.
#[derive(Clone, Copy)]
pub(super) enum RowSource<'a> {
    /// Row-major rows, read in place.
    Rows(&'a Batch<'a>),
    /// Columns, gathered chunk by chunk.
    Columns(&'a ColumnBatch<'a>),
}

impl RowSource<'_> {
    /// Rows.
    pub(super) fn len(&self) -> usize {
        match self {
            RowSource::Rows(b) => b.len(),
            RowSource::Columns(b) => b.len(),
        }
    }

    /// Floats a row: 10, or 13 with tangents.
    pub(super) fn columns(&self) -> usize {
        match self {
            RowSource::Rows(b) => b.columns(),
            RowSource::Columns(b) => b.columns(),
        }
    }

    /// Rows `range` as row-major floats: the batch's own, or gathered into `scratch`
    /// (whose allocation is reused from chunk to chunk).
    pub(super) fn rows<'s>(
        &'s self,
        range: std::ops::Range<usize>,
        scratch: &'s mut Vec<f32>,
    ) -> &'s [f32] {
        match self {
            RowSource::Rows(b) => {
                let cols = b.columns();
                &b.as_slice()[range.start * cols..range.end * cols]
            }
            RowSource::Columns(b) => {
                *scratch = b.rows(range, std::mem::take(scratch)).into_data();
                scratch
            }
        }
    }
}
