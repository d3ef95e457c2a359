//! What a chunk reads ([`Source`]), what a unit of work writes ([`Work`]) and where its
//! tuples went ([`Tally`]).

use crate::batch::columns::{Column, ColumnBatch};
use crate::batch::{Batch, LocalBatch, LocalLayout, Tuple, COLUMNS_LOCAL};
use crate::cpu::slice_tuples::SliceTuples;

/// Where the tuples of the last evaluation went.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Tally {
    /// Tuples of material groups that run in the lanes.
    pub lanes: u64,
    /// Of those, tuples re-evaluated by the reference (invalid, below the horizon, grazing,
    /// or an output the lanes cannot vouch for).
    pub rescued: u64,
    /// Tuples of material groups that run on the reference.
    pub reference: u64,
    /// Of `lanes`, tuples their block's f32 frame could not serve, gathered into blocks of
    /// the f64 frame or of the general f32 frame (`cpu::kernel::Params::defer_slow`).
    pub deferred: u64,
    /// Of `lanes`, tuples read and evaluated on the register path
    /// (`cpu::register`; their deferred and rescued lanes are counted above too).
    pub registers: u64,
}

impl Tally {
    pub(crate) fn add(&mut self, o: &Tally) {
        self.lanes += o.lanes;
        self.rescued += o.rescued;
        self.reference += o.reference;
        self.deferred += o.deferred;
        self.registers += o.registers;
    }
}

/// What the engine reads: ordinary rows, or the local-frame form.
#[derive(Clone, Copy)]
pub(crate) enum Source<'a> {
    Rows(&'a Batch<'a>),
    Local(&'a LocalBatch),
    /// A half/difference slice whose tuples the workers make block by block.
    Slice(&'a SliceTuples),
    /// A batch given as columns, read in place.
    Columns(&'a ColumnBatch<'a>),
}

impl Source<'_> {
    pub(crate) fn len(&self) -> usize {
        match self {
            Source::Rows(b) => b.len(),
            Source::Local(b) => b.len(),
            Source::Slice(s) => s.len(),
            Source::Columns(b) => b.len(),
        }
    }

    pub(crate) fn material(&self, i: usize) -> usize {
        match self {
            Source::Rows(b) => b.material(i),
            Source::Local(b) => b.material(),
            Source::Slice(_) => 0,
            Source::Columns(b) => b.material(i),
        }
    }

    pub(crate) fn tuple(&self, i: usize) -> Tuple {
        match self {
            Source::Rows(b) => b.tuple(i),
            Source::Local(b) => b.tuple(i),
            Source::Slice(s) => s.tuple(i),
            Source::Columns(b) => b.tuple(i),
        }
    }

    /// The rows as they are held (row-major, [`Source::columns`] a row); empty for the
    /// forms that are not held as rows, which `run_chunk` reads block by block.
    pub(crate) fn data(&self) -> &[f32] {
        match self {
            Source::Rows(b) => b.as_slice(),
            Source::Local(b) if b.layout() == LocalLayout::Rows => b.as_slice(),
            Source::Local(_) | Source::Slice(_) | Source::Columns(_) => &[],
        }
    }

    /// The local form held as six columns.
    pub(crate) fn local_columns(&self) -> Option<&LocalBatch> {
        match self {
            Source::Local(b) if b.layout() == LocalLayout::Columns => Some(b),
            _ => None,
        }
    }

    pub(crate) fn columns(&self) -> usize {
        match self {
            Source::Rows(b) => b.columns(),
            Source::Local(_) => COLUMNS_LOCAL,
            // The columns its tuples would have as rows.
            Source::Slice(s) => s.columns(),
            Source::Columns(b) => b.columns(),
        }
    }

    /// Whether every row's N is (0, 0, 1) bit for bit, so that the groups with an f32 frame
    /// may run their N = +z variants (the same bits as the general frame there).
    pub(crate) fn normal_is_z(&self) -> bool {
        match self {
            Source::Local(_) => true,
            Source::Columns(b) => {
                matches!(b.directions()[2], Column::Every(n) if n.map(f32::to_bits) == [0.0f32, 0.0, 1.0].map(f32::to_bits))
            }
            Source::Rows(_) | Source::Slice(_) => false,
        }
    }
}

/// One unit of work: its outputs, from position `start` of the order its rows are read
/// in (the batch's, or a chunk's grouped order).
pub(crate) struct Work<'a> {
    /// The one material of its rows, or `None`: the chunk groups its rows itself.
    pub(crate) material: Option<usize>,
    /// Its first position in the order its rows are read in.
    pub(crate) start: usize,
    /// RGB outputs, 3 a row.
    pub(crate) brdf: &'a mut [f32],
    /// Term outputs, [`TERM_COLUMNS`](crate::backend::TERM_COLUMNS) a row, when asked for.
    pub(crate) terms: Option<&'a mut [f32]>,
}
