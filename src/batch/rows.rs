//! A `.npy` batch read in chunks of rows, so that a batch larger than memory streams
//! through (`vkbrdf eval`): the header is read and checked once, then each chunk is read
//! straight into a float buffer (float64 files rounded to float32, as [`Batch::read_npy`]
//! does).

use super::mapped::Window;
use super::{
    npy_head, open_sized, Batch, LocalBatch, LocalLayout, COLUMNS_LOCAL, COLUMNS_PLAIN,
    COLUMNS_TANGENT,
};
use crate::error::{Error, Result};
use crate::material::Material;
use std::fs::File;
use std::io::BufReader;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

/// The element type of a streamed `.npy` file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Dtype {
    F4,
    F8,
}

/// A `.npy` batch of shape `(n, 10)` or `(n, 13)`, or the local-frame `(n, 6)`, read chunk
/// by chunk.
pub struct NpyRows {
    reader: BufReader<File>,
    rows: u64,
    columns: usize,
    dtype: Dtype,
    next_row: u64,
    end_row: u64,
    data_start: u64,
    /// Column by column in the file (NumPy's `order='F'`): each chunk is gathered from
    /// one read per column.
    fortran: bool,
    material_count: usize,
    source: PathBuf,
    bytes: Vec<u8>,
}

impl NpyRows {
    /// Opens `path` and checks its header: 2-D, C order, float32 or float64, 10 or 13
    /// columns or the local-frame 6 (read with [`NpyRows::next_local`]), and (for a regular file) as much data as the shape says.
    pub fn open(path: &Path, material_count: usize) -> Result<NpyRows> {
        let err = |message: String| Error::Batch {
            path: path.to_owned(),
            message,
        };
        // The rows are read with random access (chunks, shards, the sidecar's
        // fingerprint): a pipe, a device or standard input cannot be, so say so rather
        // than fail later with "Illegal seek".
        let not_seekable = path.as_os_str() == "-"
            || std::fs::metadata(path).is_ok_and(|m| {
                use std::os::unix::fs::FileTypeExt;
                let t = m.file_type();
                t.is_fifo() || t.is_char_device() || t.is_socket()
            });
        if not_seekable {
            return Err(err(
                "is standard input, a pipe or a device; the tuples are read from a regular file (random access for chunks and shards): save them to a file first (e.g. `cat > t.npy`)".into(),
            ));
        }
        let (mut reader, len) = open_sized(path)?;
        let head = npy_head(&mut reader, len, path)?;
        let data_start = head.len() as u64;
        let npy = npyz::NpyFile::new(std::io::Cursor::new(head))
            .map_err(|e| err(format!("not a valid .npy file: {e}")))?;
        let fortran = npy.order() == npyz::Order::Fortran;
        let dtype = match npy.dtype().descr().trim_matches(|c| c == '\'' || c == '"') {
            "<f4" => Dtype::F4,
            "<f8" => Dtype::F8,
            other => {
                return Err(err(format!(
                    "dtype {other} is not supported; use float32 ('<f4') or float64 ('<f8')"
                )))
            }
        };
        let shape = npy.shape().to_vec();
        if shape.len() != 2 {
            return Err(err(format!(
                "expected a 2-D array of shape (n, 10), (n, 13) or (n, 6), found shape {shape:?}"
            )));
        }
        let columns = shape[1] as usize;
        if columns != COLUMNS_PLAIN && columns != COLUMNS_TANGENT && columns != COLUMNS_LOCAL {
            return Err(err(format!(
                "expected 10 columns (Lx Ly Lz Vx Vy Vz Nx Ny Nz material), 13 (plus Tx Ty Tz) or 6 (Lx Ly Lz Vx Vy Vz in the local frame, N = +z, one material), found {columns}"
            )));
        }
        Ok(NpyRows {
            reader,
            rows: shape[0],
            columns,
            dtype,
            next_row: 0,
            end_row: shape[0],
            data_start,
            fortran,
            material_count,
            source: path.to_owned(),
            bytes: Vec::new(),
        })
    }

    /// Rows in the file.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// 10, 13 with tangents, or 6 for the local-frame form.
    pub fn columns(&self) -> usize {
        self.columns
    }

    /// Reads only rows `range` (within the file's) from now on: the part of a shard.
    pub fn restrict(&mut self, range: std::ops::Range<u64>) -> Result<()> {
        // Every read is positioned (`floats_at`): no seek.
        let range = range.start.min(self.rows)..range.end.min(self.rows);
        self.next_row = range.start;
        self.end_row = range.end.max(range.start);
        Ok(())
    }

    /// Bytes one row takes in the file.
    pub fn row_bytes(&self) -> usize {
        self.columns * if self.dtype == Dtype::F8 { 8 } else { 4 }
    }

    /// The next at most `max_rows` rows as a [`Batch`] (materials checked, row numbers in
    /// errors counted from the file's start) with the index of its first row; `None` at the
    /// end. A local-frame file (6 columns) is read with [`NpyRows::next_local`] instead.
    pub fn next_chunk(&mut self, max_rows: usize) -> Result<Option<(u64, Batch<'static>)>> {
        self.next_chunk_reusing(max_rows, Vec::new())
    }

    /// [`next_chunk`](Self::next_chunk) into `buffer`'s memory (a spent chunk's, from
    /// [`Batch::into_data`]): a streamed run then touches the same pages chunk after chunk
    /// instead of faulting in fresh ones.
    pub fn next_chunk_reusing(
        &mut self,
        max_rows: usize,
        buffer: Vec<f32>,
    ) -> Result<Option<(u64, Batch<'static>)>> {
        self.next(max_rows, |rows, at, n, bytes| {
            rows.batch_at(at, n, buffer, bytes)
        })
    }

    /// [`NpyRows::next_chunk`] for a local-frame file (6 columns): the rows as a
    /// [`LocalBatch`] of material `material` (checked by [`LocalBatch::new`]).
    pub fn next_local(
        &mut self,
        max_rows: usize,
        material: usize,
        materials: &[Material],
    ) -> Result<Option<(u64, LocalBatch)>> {
        self.next(max_rows, |rows, at, n, bytes| {
            rows.local_at(at, n, material, materials, Vec::new(), bytes)
        })
    }

    /// The next at most `max_rows` rows as `read` makes them from their first row, their
    /// count and the byte buffer reused between calls; the cursor moves past them once
    /// they are read. `None` at the end.
    fn next<T>(
        &mut self,
        max_rows: usize,
        read: impl FnOnce(&Self, u64, usize, &mut Vec<u8>) -> Result<T>,
    ) -> Result<Option<(u64, T)>> {
        let left = self.end_row - self.next_row;
        if left == 0 {
            return Ok(None);
        }
        let n = left.min(max_rows.max(1) as u64) as usize;
        let at = self.next_row;
        let mut bytes = std::mem::take(&mut self.bytes);
        let made = read(self, at, n, &mut bytes);
        self.bytes = bytes;
        let made = made?;
        self.next_row += n as u64;
        Ok(Some((at, made)))
    }

    /// Rows `at..at + n` of the file as floats into `data` (resized to `n` rows, row-major),
    /// by positioned reads, so that several threads may read their own rows at once (the
    /// streamed path's workers). float64 files and Fortran-order files go through `bytes`
    /// (reused between calls), converted and laid out as rows.
    pub fn floats_at(
        &self,
        at: u64,
        n: usize,
        data: &mut Vec<f32>,
        bytes: &mut Vec<u8>,
    ) -> Result<()> {
        let truncated = |e: std::io::Error| {
            Error::Batch {
            path: self.source.clone(),
            message: format!(
                "the data is shorter than the header's shape says (truncated file?), at row {at}: {e}"
            ),
        }
        };
        let file = self.reader.get_ref();
        let columns = self.columns;
        let width = if self.dtype == Dtype::F8 { 8 } else { 4 };
        data.resize(n * columns, 0.0);
        if self.fortran {
            // Column j's rows [at, at + n) lie together at data_start + (j·rows + at)·width.
            bytes.resize(n * width, 0);
            for j in 0..columns {
                let offset = self.data_start + (j as u64 * self.rows + at) * width as u64;
                file.read_exact_at(bytes, offset).map_err(truncated)?;
                let rows = data.iter_mut().skip(j).step_by(columns);
                match self.dtype {
                    Dtype::F4 => rows
                        .zip(bytes.chunks_exact(4))
                        .for_each(|(x, b)| *x = f32::from_le_bytes(b.try_into().expect("4 bytes"))),
                    Dtype::F8 => rows.zip(bytes.chunks_exact(8)).for_each(|(x, b)| {
                        *x = f64::from_le_bytes(b.try_into().expect("8 bytes")) as f32
                    }),
                }
            }
            return Ok(());
        }
        let offset = self.data_start + at * self.row_bytes() as u64;
        if self.dtype == Dtype::F4 {
            // float32 rows go straight into the batch's buffer: one copy from the page
            // cache instead of two (the bytes, then the floats).
            file.read_exact_at(bytemuck::cast_slice_mut(data), offset)
                .map_err(truncated)?;
            if cfg!(target_endian = "big") {
                for x in data.iter_mut() {
                    *x = f32::from_bits(u32::from_le(x.to_bits()));
                }
            }
        } else {
            bytes.resize(n * self.row_bytes(), 0);
            file.read_exact_at(bytes, offset).map_err(truncated)?;
            for (x, b) in data.iter_mut().zip(bytes.chunks_exact(8)) {
                *x = f64::from_le_bytes(b.try_into().expect("8 bytes")) as f32;
            }
        }
        Ok(())
    }

    /// Rows `at..at + n` as a checked [`Batch`] read where the page cache holds them (a
    /// mapped window, no copy), handed to `use_rows`; `None` where they cannot be (see
    /// [`NpyRows::window`]): read them with [`NpyRows::batch_at`]. A page that could not
    /// be read (the file shrank under the run, a disk error) fails with the row it holds,
    /// before any error of the rows' own: its values read as zeros.
    pub(crate) fn with_mapped<T>(
        &self,
        at: u64,
        n: usize,
        use_rows: impl FnOnce(&Batch<'_>) -> Result<T>,
    ) -> Option<Result<T>> {
        let window = self.window(at, n)?;
        Some(self.in_window(&window, at, use_rows))
    }

    /// [`NpyRows::next_chunk_reusing`], with the rows mapped where the page cache holds
    /// them ([`RowsChunk::Mapped`], no copy) where they can be; `check` runs on the rows
    /// after the material check, and a page lost under the mapping fails before either.
    pub(crate) fn next_in_place(
        &mut self,
        max_rows: usize,
        spare: Vec<f32>,
        check: impl FnOnce(&Batch<'_>, u64) -> Result<()>,
    ) -> Result<Option<(u64, RowsChunk)>> {
        self.next(max_rows, |rows, at, n, bytes| match rows.window(at, n) {
            Some(window) => {
                rows.in_window(&window, at, |b| check(b, at))?;
                Ok(RowsChunk::Mapped(MappedRows {
                    window,
                    columns: rows.columns,
                    first: at,
                    source: rows.source.clone(),
                }))
            }
            None => {
                let b = rows.batch_at(at, n, spare, bytes)?;
                check(&b, at)?;
                Ok(RowsChunk::Read(b))
            }
        })
    }

    /// Rows `at..at + n` mapped read-only; `None` where they cannot be: mapped reads not
    /// enabled ([`enable_mapped_reads`](super::enable_mapped_reads)) or not Linux, a
    /// float64 or Fortran-order file (converted as read), rows not 4-byte aligned, no
    /// window free or the kernel refused.
    fn window(&self, at: u64, n: usize) -> Option<Window> {
        if self.fortran || self.dtype != Dtype::F4 || cfg!(target_endian = "big") {
            return None;
        }
        let offset = self.data_start + at * self.row_bytes() as u64;
        // A float32 file's rows start 4-byte aligned (NumPy pads the header to 64 bytes).
        if !offset.is_multiple_of(4) {
            return None;
        }
        Window::new(self.reader.get_ref(), offset, n * self.row_bytes())
    }

    /// `use_rows` on `window`'s rows (from row `at`) as a checked batch; a lost page's
    /// error first.
    fn in_window<T>(
        &self,
        window: &Window,
        at: u64,
        use_rows: impl FnOnce(&Batch<'_>) -> Result<T>,
    ) -> Result<T> {
        let floats = bytemuck::cast_slice(window.bytes());
        let used = Batch::borrowed_at(floats, self.columns, self.material_count, &self.source, at)
            .and_then(|b| use_rows(&b));
        lost_page(window, at, self.row_bytes(), &self.source)?;
        used
    }

    /// Rows `at..at + n` as a checked [`Batch`] (as [`NpyRows::next_chunk`] makes it) in
    /// `buffer`'s memory; see [`NpyRows::floats_at`].
    pub fn batch_at(
        &self,
        at: u64,
        n: usize,
        mut buffer: Vec<f32>,
        bytes: &mut Vec<u8>,
    ) -> Result<Batch<'static>> {
        self.floats_at(at, n, &mut buffer, bytes)?;
        Batch::new_at(buffer, self.columns, self.material_count, &self.source, at)
    }

    /// Rows `at..at + n` of a local-frame file as a [`LocalBatch`] of material `material`
    /// (as [`NpyRows::next_local`] makes it); see [`NpyRows::floats_at`]. A float32 file in
    /// Fortran order is read as it lies, each column straight into the buffer, and held as
    /// columns ([`LocalLayout::Columns`]), which the CPU engine reads without a transpose.
    pub fn local_at(
        &self,
        at: u64,
        n: usize,
        material: usize,
        materials: &[Material],
        mut buffer: Vec<f32>,
        bytes: &mut Vec<u8>,
    ) -> Result<LocalBatch> {
        if !(self.fortran && self.dtype == Dtype::F4 && cfg!(target_endian = "little")) {
            self.floats_at(at, n, &mut buffer, bytes)?;
            return LocalBatch::new(buffer, material, materials, &self.source);
        }
        buffer.resize(n * COLUMNS_LOCAL, 0.0);
        let file = self.reader.get_ref();
        for (j, column) in buffer.chunks_exact_mut(n.max(1)).enumerate() {
            // Column j's rows [at, at + n) lie together at data_start + (j·rows + at)·4.
            let offset = self.data_start + (j as u64 * self.rows + at) * 4;
            file.read_exact_at(bytemuck::cast_slice_mut(column), offset)
                .map_err(|e| Error::Batch {
                    path: self.source.clone(),
                    message: format!(
                        "the data is shorter than the header's shape says (truncated file?), at row {at}: {e}"
                    ),
                })?;
        }
        LocalBatch::with_layout(
            buffer,
            LocalLayout::Columns,
            material,
            materials,
            &self.source,
        )
    }
}

/// A chunk of rows as [`NpyRows::next_in_place`] gives it.
pub(crate) enum RowsChunk {
    /// Where the page cache holds them, checked.
    Mapped(MappedRows),
    /// Copied into a buffer, checked.
    Read(Batch<'static>),
}

/// Rows of a float32 file mapped read-only and checked: a chunk the pipeline's reader
/// hands to the engine's thread, which reads it in place ([`MappedRows::batch`]); on Vulkan
/// the one copy is then the page cache's into the staging memory.
pub(crate) struct MappedRows {
    window: Window,
    columns: usize,
    first: u64,
    source: PathBuf,
}

impl MappedRows {
    /// The rows, as checked when they were mapped.
    pub(crate) fn batch(&self) -> Batch<'_> {
        Batch::checked_before(bytemuck::cast_slice(self.window.bytes()), self.columns)
    }

    /// Rows in the chunk.
    pub(crate) fn len(&self) -> usize {
        self.window.bytes().len() / (4 * self.columns)
    }

    /// The error of a page lost since the rows were mapped (the file shrank under the
    /// run): ask after every use of [`MappedRows::batch`], whose values read as zeros there.
    pub(crate) fn lost_page(&self) -> Result<()> {
        lost_page(&self.window, self.first, 4 * self.columns, &self.source)
    }
}

/// The error naming the first row of `window` (rows from `first`, `row_bytes` each) on a
/// page that could not be read, if one could not.
fn lost_page(window: &Window, first: u64, row_bytes: usize, source: &Path) -> Result<()> {
    match window.fault() {
        None => Ok(()),
        Some(offset) => Err(Error::Batch {
            path: source.to_owned(),
            message: format!(
                "row {} could not be read: the file shrank while it was read (truncated by another process?) or its disk failed",
                first + (offset / row_bytes) as u64
            ),
        }),
    }
}

#[cfg(test)]
#[cfg(target_os = "linux")] // mapped reads
mod tests {
    use super::*;

    /// `rows` rows of 10 columns written to `t.npy` in a fresh directory (kept alive by
    /// the returned guard), the material column from `material(row)`, the rest not zero.
    fn written(rows: u64, material: fn(u64) -> f32) -> (tempfile::TempDir, PathBuf, Vec<f32>) {
        assert!(crate::batch::enable_mapped_reads());
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.npy");
        let data: Vec<f32> = (0..rows * 10)
            .map(|i| match i % 10 {
                9 => material(i / 10),
                _ => 1.0 + (i % 7) as f32,
            })
            .collect();
        crate::batch::write_npy_f32(&path, &data, 10).unwrap();
        (dir, path, data)
    }

    /// Truncates `path` (`rows` rows of 40 bytes behind its header) `extra` bytes into
    /// row `row`; returns the first row on a page now past the end.
    fn cut_into_row(path: &Path, rows: u64, row: u64, extra: u64) -> u64 {
        let header = std::fs::metadata(path).unwrap().len() - rows * 40;
        let cut = header + row * 40 + extra;
        let file = std::fs::OpenOptions::new().write(true).open(path).unwrap();
        file.set_len(cut).unwrap();
        let page = crate::batch::mapped::page_size() as u64;
        (cut.next_multiple_of(page) - header) / 40
    }

    #[test]
    fn a_truncated_input_fails_with_the_first_row_it_lost() {
        let rows = 2000;
        let (_dir, path, data) = written(rows, |_| 0.0);
        let npy = NpyRows::open(&path, 1).unwrap();
        // The whole file in place: the rows as written, no error.
        let sum = npy
            .with_mapped(0, rows as usize, |b| Ok(b.as_slice().iter().sum::<f32>()))
            .expect("a float32 file maps")
            .unwrap();
        assert_eq!(sum, data.iter().sum::<f32>());
        // Cut the file inside row 1000's page: the rows of the pages after it are lost.
        let first_lost = cut_into_row(&path, rows, 1000, 8);
        let err = npy
            .with_mapped(0, rows as usize, |b| {
                // The rows' own error, which the lost page's must come before.
                Err::<(), _>(Error::Batch {
                    path: path.clone(),
                    message: format!("saw {} rows", b.len()),
                })
            })
            .expect("a float32 file maps")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(&format!("row {first_lost} could not be read"))
                && err.contains("t.npy")
                && err.contains("shrank"),
            "{err} (expected row {first_lost})"
        );
    }

    /// The pipeline's form: a chunk mapped and checked on one thread, read on another
    /// after the file shrank, reports the first row it lost when asked after the read.
    #[test]
    fn a_mapped_chunk_read_after_a_truncation_reports_its_first_lost_row() {
        let rows = 3000;
        let (_dir, path, data) = written(rows, |row| (row % 2) as f32);
        let mut npy = NpyRows::open(&path, 2).unwrap();
        npy.restrict(1000..rows).unwrap();
        let mut checked = 0;
        let (first, chunk) = npy
            .next_in_place(1500, Vec::new(), |b, at| {
                checked = b.len() as u64 + at;
                Ok(())
            })
            .unwrap()
            .expect("rows left");
        assert_eq!((first, checked), (1000, 2500));
        let RowsChunk::Mapped(m) = chunk else {
            panic!("a float32 file maps");
        };
        assert_eq!(m.len(), 1500);
        let kept = &data[10_000..25_000];
        assert!(m.batch().as_slice() == kept);
        assert!(m.lost_page().is_ok());
        let first_lost = cut_into_row(&path, rows, 2000, 0);
        let sum: f32 = m.batch().as_slice().iter().sum();
        assert!(sum < kept.iter().sum::<f32>(), "lost rows read as zeros");
        let err = m.lost_page().unwrap_err().to_string();
        assert!(
            err.contains(&format!("row {first_lost} could not be read")),
            "{err} (expected row {first_lost})"
        );
        // The next chunk starts past the end of the shrunk file: mapped, it reads only
        // zeros, and says so before any use.
        let next = npy.next_in_place(1500, Vec::new(), |_, _| Ok(()));
        let err = next.err().expect("rows past the end").to_string();
        assert!(err.contains("row 2500 could not be read"), "{err}");
    }
}
