//! Tuple batches: `n × 10` or `n × 13` float32 rows
//! `Lx Ly Lz Vx Vy Vz Nx Ny Nz material [Tx Ty Tz]` (FORMULAS.md §1), read from and written
//! to `.npy` with the `npyz` crate; and the local-frame form [`LocalBatch`], `n × 6` rows
//! `Lx Ly Lz Vx Vy Vz` with N = +z and one material for the whole batch.

pub mod columns;
mod local_material;
mod mapped;
mod material_column;
pub mod rows;

pub use local_material::{check_local_material, local_material};
pub use mapped::enable as enable_mapped_reads;
use material_column::material_index;

use crate::cancel::Cancel;
use crate::error::{Error, Result};
use crate::material::Material;
use std::borrow::Cow;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

/// Columns of a batch without tangents.
pub const COLUMNS_PLAIN: usize = 10;
/// Columns of a batch with tangents.
pub const COLUMNS_TANGENT: usize = 13;
/// Columns of a local-frame batch ([`LocalBatch`]): `Lx Ly Lz Vx Vy Vz`, N = +z.
pub const COLUMNS_LOCAL: usize = 6;

/// A validated batch of tuples, stored row-major as `f32`: owned (`Batch<'static>`, what
/// [`Batch::new`] and the readers make) or borrowed from the caller's buffer
/// ([`Batch::borrowed`]: a NumPy array evaluated without a copy).
///
/// Construction checks the shape and that every material value is an integer index into
/// the material table; direction problems (zero, NaN) are not batch errors but invalid
/// tuples, counted at evaluation (FORMULAS.md §1).
#[derive(Debug, Clone, PartialEq)]
pub struct Batch<'a> {
    data: Cow<'a, [f32]>,
    columns: usize,
}

/// One tuple of a batch, borrowed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tuple {
    /// Toward the light (any length).
    pub l: [f32; 3],
    /// Toward the viewer (any length).
    pub v: [f32; 3],
    /// Surface normal (any length).
    pub n: [f32; 3],
    /// Index into the material table.
    pub material: usize,
    /// Tangent, when the batch has 13 columns.
    pub t: Option<[f32; 3]>,
}

impl Batch<'static> {
    /// Wraps row-major data with `columns` (10 or 13) per row. `source` names the origin
    /// in errors; `material_count` is the size of the material table.
    pub fn new(
        data: Vec<f32>,
        columns: usize,
        material_count: usize,
        source: &Path,
    ) -> Result<Batch<'static>> {
        Batch::new_at(data, columns, material_count, source, 0)
    }

    /// [`Batch::new`] for rows `first_row..` of a larger batch (a streamed chunk): errors
    /// name rows counted from the batch's start.
    pub fn new_at(
        data: Vec<f32>,
        columns: usize,
        material_count: usize,
        source: &Path,
        first_row: u64,
    ) -> Result<Batch<'static>> {
        Batch::checked(Cow::Owned(data), columns, material_count, source, first_row)
    }
}

impl<'a> Batch<'a> {
    /// [`Batch::borrowed`] for rows `first_row..` of a larger batch (a mapped slice of a
    /// streamed file): errors name rows counted from the batch's start.
    pub(crate) fn borrowed_at(
        data: &'a [f32],
        columns: usize,
        material_count: usize,
        source: &Path,
        first_row: u64,
    ) -> Result<Batch<'a>> {
        Batch::checked(
            Cow::Borrowed(data),
            columns,
            material_count,
            source,
            first_row,
        )
    }

    /// Rows checked before (a mapped chunk the reader checked, handed to the engine's
    /// thread), wrapped without checking them again.
    pub(crate) fn checked_before(data: &'a [f32], columns: usize) -> Batch<'a> {
        Batch {
            data: Cow::Borrowed(data),
            columns,
        }
    }

    /// [`Batch::new`] on the caller's row-major data, without copying it (the Python
    /// binding evaluates a C-contiguous float32 array in place).
    pub fn borrowed(
        data: &'a [f32],
        columns: usize,
        material_count: usize,
        source: &Path,
    ) -> Result<Batch<'a>> {
        Batch::borrowed_at(data, columns, material_count, source, 0)
    }

    /// Whether the batch borrows its data ([`Batch::borrowed`]) rather than owning a copy.
    pub fn is_borrowed(&self) -> bool {
        matches!(self.data, Cow::Borrowed(_))
    }

    fn checked(
        data: Cow<'a, [f32]>,
        columns: usize,
        material_count: usize,
        source: &Path,
        first_row: u64,
    ) -> Result<Batch<'a>> {
        let err = |message: String| Error::Batch {
            path: source.to_owned(),
            message,
        };
        if columns != COLUMNS_PLAIN && columns != COLUMNS_TANGENT {
            return Err(err(format!(
                "expected 10 columns (Lx Ly Lz Vx Vy Vz Nx Ny Nz material) or 13 (plus Tx Ty Tz), found {columns}"
            )));
        }
        if !data.len().is_multiple_of(columns) {
            return Err(err(format!(
                "{} values do not make whole rows of {columns}",
                data.len()
            )));
        }
        let batch = Batch { data, columns };
        if let Some((row, value)) = batch.first_bad_material(material_count) {
            let row = first_row + row as u64;
            return Err(err(format!(
                "row {row}: material value {value} is not an integer index in 0..{material_count} (the materials file defines {material_count})"
            )));
        }
        Ok(batch)
    }

    /// The row-major data, for reuse (see [`rows::NpyRows::next_chunk_reusing`]).
    /// (A borrowed batch gives a copy.)
    pub fn into_data(self) -> Vec<f32> {
        self.data.into_owned()
    }

    fn first_bad_material(&self, material_count: usize) -> Option<(usize, f32)> {
        // Blocks of rows checked without a branch a row (the check was half the read
        // stage's time with one), then the rows from the first block with a bad one, one
        // by one.
        let columns = self.columns;
        let clean = material_column::clean_rows(&self.data, columns, material_count);
        self.data[clean * columns..]
            .chunks_exact(columns)
            .map(|row| row[9])
            .enumerate()
            .find(|&(_, m)| material_index(m, material_count).is_none())
            .map(|(i, m)| (clean + i, m))
    }

    /// Checks that every row whose material is anisotropic has a tangent: a batch without
    /// tangent columns whose rows reference an anisotropic material (roughness `[mx, my]`)
    /// is an [`Error::Batch`] naming the material, its first row and `source`, instead of
    /// rows that would all come back invalid (FORMULAS.md §1). One pass over the material
    /// column, none when the batch has tangents or no material is anisotropic; see
    /// [`check_tangent_rows`] for the same check chunk by chunk.
    pub fn check_tangents(&self, materials: &[Material], source: &Path) -> Result<()> {
        check_tangent_rows(&self.data, self.columns, 0, materials, source)
    }

    /// Number of tuples.
    pub fn len(&self) -> usize {
        self.data.len() / self.columns
    }

    /// Whether the batch holds no tuple.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// 10, or 13 with tangents.
    pub fn columns(&self) -> usize {
        self.columns
    }

    /// Whether rows carry a tangent.
    pub fn has_tangents(&self) -> bool {
        self.columns == COLUMNS_TANGENT
    }

    /// The raw row-major data.
    pub fn as_slice(&self) -> &[f32] {
        &self.data
    }

    /// The material index of row `i` (validated at construction).
    pub fn material(&self, i: usize) -> usize {
        self.data[i * self.columns + 9] as usize
    }

    /// Tuple `i`.
    pub fn tuple(&self, i: usize) -> Tuple {
        let r = &self.data[i * self.columns..(i + 1) * self.columns];
        Tuple {
            l: [r[0], r[1], r[2]],
            v: [r[3], r[4], r[5]],
            n: [r[6], r[7], r[8]],
            material: r[9] as usize,
            t: (self.columns == COLUMNS_TANGENT).then(|| [r[10], r[11], r[12]]),
        }
    }
}

impl Batch<'static> {
    /// Reads a batch from a `.npy` file: float32 or float64 (float64 is rounded to float32,
    /// the precision every backend evaluates from), C order, shape `(n, 10)` or `(n, 13)`.
    pub fn read_npy(path: &Path, material_count: usize) -> Result<Batch<'static>> {
        let (file, len) = open_sized(path)?;
        Batch::read_npy_from(file, len, material_count, path)
    }

    /// [`Batch::read_npy`] from any reader: `len` is the stream's total size when known (see
    /// [`read_npy_f32_from`]), `source` names it in errors.
    pub fn read_npy_from(
        reader: impl Read,
        len: Option<u64>,
        material_count: usize,
        source: &Path,
    ) -> Result<Batch<'static>> {
        let (data, shape) = read_npy_f32_from(reader, len, source)?;
        let err = |message: String| Error::Batch {
            path: source.to_owned(),
            message,
        };
        if shape.len() != 2 {
            return Err(err(format!(
                "expected a 2-D array of shape (n, 10) or (n, 13), found shape {shape:?}"
            )));
        }
        Batch::new(data, shape[1] as usize, material_count, source)
    }
}

/// A local-frame batch: `n` tuples `Lx Ly Lz Vx Vy Vz` in float32 in the surface's own
/// frame (N = +z, no tangent) and one material for every row — the input of users whose
/// directions are already local (a renderer's `wi`, `wo`), 24 bytes a tuple instead of 40.
/// Held as rows (`n × 6`, C order) or as six columns ([`LocalLayout`]).
///
/// Every tuple means the same as the 10-column row `Lx Ly Lz Vx Vy Vz 0 0 1 material`,
/// in either layout; engines that take rows expand it in chunks ([`LocalBatch::rows`]),
/// the CPU engine evaluates it as it is.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalBatch {
    data: Vec<f32>,
    material: usize,
    layout: LocalLayout,
}

/// How a [`LocalBatch`] holds its values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LocalLayout {
    /// `n` rows of 6 (`Lx Ly Lz Vx Vy Vz`): an `(n, 6)` array in C order.
    Rows,
    /// Six columns of `n`, `Lx` first: an `(n, 6)` array in Fortran order, or `wi`, `wo`
    /// as six arrays (what Mitsuba and Dr.Jit hold). The CPU engine's vector variants
    /// load them into registers as they are, with no transpose.
    Columns,
}

impl LocalBatch {
    /// Wraps row-major `n × 6` data evaluated with material `material` of a table of
    /// `materials`. Errors (naming `source`) when the data are not whole rows of 6, when
    /// `material` is not an index into the table, or when that material is anisotropic
    /// (it needs a tangent, which the local form does not carry).
    pub fn new(
        data: Vec<f32>,
        material: usize,
        materials: &[Material],
        source: &Path,
    ) -> Result<LocalBatch> {
        LocalBatch::with_layout(data, LocalLayout::Rows, material, materials, source)
    }

    /// As [`LocalBatch::new`], for data held in `layout`: with [`LocalLayout::Columns`],
    /// `data` is six columns of `n` one after another (`Lx` of every tuple, then `Ly`, …).
    pub fn with_layout(
        data: Vec<f32>,
        layout: LocalLayout,
        material: usize,
        materials: &[Material],
        source: &Path,
    ) -> Result<LocalBatch> {
        check_local_material(material, materials, source)?;
        if !data.len().is_multiple_of(COLUMNS_LOCAL) {
            let what = match layout {
                LocalLayout::Rows => "whole rows",
                LocalLayout::Columns => "six columns of equal length",
            };
            return Err(Error::Batch {
                path: source.to_owned(),
                message: format!(
                    "{} values do not make {what} of {COLUMNS_LOCAL} (Lx Ly Lz Vx Vy Vz)",
                    data.len()
                ),
            });
        }
        Ok(LocalBatch {
            data,
            material,
            layout,
        })
    }

    /// Number of tuples.
    pub fn len(&self) -> usize {
        self.data.len() / COLUMNS_LOCAL
    }

    /// Whether the batch holds no tuple.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// The material of every row.
    pub fn material(&self) -> usize {
        self.material
    }

    /// How the values are held.
    pub fn layout(&self) -> LocalLayout {
        self.layout
    }

    /// The raw data, in the batch's [`LocalLayout`].
    pub fn as_slice(&self) -> &[f32] {
        &self.data
    }

    /// The raw data, for reuse (as [`Batch::into_data`]).
    pub fn into_data(self) -> Vec<f32> {
        self.data
    }

    /// The same tuples held in `layout` (a copy).
    pub fn to_layout(&self, layout: LocalLayout) -> LocalBatch {
        let n = self.len();
        let data = match layout {
            LocalLayout::Rows => (0..n).flat_map(|i| self.row(i)).collect(),
            LocalLayout::Columns => {
                let mut data = vec![0.0; n * COLUMNS_LOCAL];
                for i in 0..n {
                    for (c, x) in self.row(i).into_iter().enumerate() {
                        data[c * n + i] = x;
                    }
                }
                data
            }
        };
        LocalBatch {
            data,
            material: self.material,
            layout,
        }
    }

    /// Tuple `i`'s six values `Lx Ly Lz Vx Vy Vz`, in either layout.
    #[inline]
    pub fn row(&self, i: usize) -> [f32; COLUMNS_LOCAL] {
        match self.layout {
            LocalLayout::Rows => self.data[i * COLUMNS_LOCAL..(i + 1) * COLUMNS_LOCAL]
                .try_into()
                .expect("a row of 6"),
            LocalLayout::Columns => {
                let n = self.len();
                std::array::from_fn(|c| self.data[c * n + i])
            }
        }
    }

    /// Column `c` (0–5: `Lx Ly Lz Vx Vy Vz`) of a batch held as columns; `None` for rows.
    pub fn column(&self, c: usize) -> Option<&[f32]> {
        let n = self.len();
        (self.layout == LocalLayout::Columns && c < COLUMNS_LOCAL)
            .then(|| &self.data[c * n..(c + 1) * n])
    }

    /// Tuple `i`, with N = (0, 0, 1).
    pub fn tuple(&self, i: usize) -> Tuple {
        let r = self.row(i);
        Tuple {
            l: [r[0], r[1], r[2]],
            v: [r[3], r[4], r[5]],
            n: [0.0, 0.0, 1.0],
            material: self.material,
            t: None,
        }
    }

    /// Rows `range` as an ordinary 10-column [`Batch`] (N = (0, 0, 1), the material column
    /// filled in), for engines that read rows.
    pub fn rows(&self, range: std::ops::Range<usize>) -> Batch<'static> {
        let mut data = Vec::with_capacity(range.len() * COLUMNS_PLAIN);
        let m = self.material as f32;
        for i in range {
            data.extend_from_slice(&self.row(i));
            data.extend_from_slice(&[0.0, 0.0, 1.0, m]);
        }
        Batch {
            data: data.into(),
            columns: COLUMNS_PLAIN,
        }
    }
}

/// [`Batch::check_tangents`] on part of a batch: `rows` (row-major, `columns` floats per
/// row) are batch rows `first_row..`, so a reader that streams a batch can check each chunk
/// as it arrives. Material values that are not an index into `materials` are left to
/// [`Batch::new`]'s check.
pub fn check_tangent_rows(
    rows: &[f32],
    columns: usize,
    first_row: u64,
    materials: &[Material],
    source: &Path,
) -> Result<()> {
    if columns != COLUMNS_PLAIN || !materials.iter().any(Material::is_anisotropic) {
        return Ok(());
    }
    let needs_tangent =
        |m: f32| material_index(m, materials.len()).is_some_and(|i| materials[i].is_anisotropic());
    let Some((row, m)) = rows
        .chunks_exact(columns)
        .map(|row| row[9])
        .enumerate()
        .find(|&(_, m)| needs_tangent(m))
    else {
        return Ok(());
    };
    Err(Error::Batch {
        path: source.to_owned(),
        message: format!(
            "row {}: material {} (`{}`) is anisotropic (roughness [mx, my]) and needs a tangent, but the batch has no tangent columns (shape (n, 10)); add Tx Ty Tz (shape (n, 13)), e.g. with `vkbrdf generate`, which adds them for such materials",
            first_row + row as u64,
            m as usize,
            materials[m as usize].name
        ),
    })
}

/// Opens `path` for reading, with its size when it is a regular file (a pipe's is unknown).
pub(crate) fn open_sized(path: &Path) -> Result<(BufReader<File>, Option<u64>)> {
    let file = File::open(path).map_err(|source| Error::Io {
        path: path.to_owned(),
        source,
    })?;
    let len = file
        .metadata()
        .ok()
        .filter(|m| m.is_file())
        .map(|m| m.len());
    Ok((BufReader::new(file), len))
}

/// Reads a C-order float32/float64 `.npy` file as `f32` with its shape.
pub fn read_npy_f32(path: &Path) -> Result<(Vec<f32>, Vec<u64>)> {
    let (file, len) = open_sized(path)?;
    read_npy_f32_from(file, len, path)
}

/// [`read_npy_f32`] from any reader; `source` names it in errors. `len`, the stream's total
/// size when known (a file's length), lets a header that claims more data than the stream
/// holds be rejected before any data is read; without it, memory still grows only with the
/// data actually read, never with what the header claims.
pub fn read_npy_f32_from(
    mut reader: impl Read,
    len: Option<u64>,
    source: &Path,
) -> Result<(Vec<f32>, Vec<u64>)> {
    let err = |message: String| Error::Batch {
        path: source.to_owned(),
        message,
    };
    let head = npy_head(&mut reader, len, source)?;
    let npy = npyz::NpyFile::new(std::io::Cursor::new(head).chain(reader))
        .map_err(|e| err(format!("not a valid .npy file: {e}")))?;
    let shape = npy.shape().to_vec();
    let fortran = npy.order() == npyz::Order::Fortran;
    if fortran && shape.len() > 2 {
        return Err(err(format!(
            "Fortran-order array of shape {shape:?}: only 1-D and 2-D arrays are read in Fortran order; save it in C order (numpy.ascontiguousarray)"
        )));
    }
    let dtype = npy
        .dtype()
        .descr()
        .trim_matches(|c| c == '\'' || c == '"')
        .to_string();
    let data: Vec<f32> = match dtype.as_str() {
        "<f4" => npy.into_vec::<f32>().map_err(|e| truncated(source, e))?,
        "<f8" => npy
            .into_vec::<f64>()
            .map_err(|e| truncated(source, e))?
            .into_iter()
            .map(|x| x as f32)
            .collect(),
        other => {
            return Err(err(format!(
                "dtype {other} is not supported; use float32 ('<f4') or float64 ('<f8')"
            )))
        }
    };
    if fortran && shape.len() == 2 {
        // Column by column in the file: rows are what every reader here expects.
        let (rows, columns) = (shape[0] as usize, shape[1] as usize);
        let mut c_order = vec![0f32; data.len()];
        for (j, column) in data.chunks_exact(rows.max(1)).enumerate().take(columns) {
            for (i, &x) in column.iter().enumerate() {
                c_order[i * columns + j] = x;
            }
        }
        return Ok((c_order, shape));
    }
    Ok((data, shape))
}

/// The magic, version, header length and header text of a `.npy` stream, read and checked
/// before npyz sees them (it is then handed these bytes followed by the rest of the
/// stream). Without these checks npyz allocates whatever header length the file states
/// (up to 4 GiB, before reading a byte of it), and multiplies the shape's dimensions
/// unchecked: a shape of `(2^63 + 2, 10)` would wrap to 20 values and read as 2 rows.
/// What is not understood here (no magic, an unknown version, a header that does not
/// parse) is left to npyz to report.
pub(crate) fn npy_head(reader: &mut impl Read, len: Option<u64>, source: &Path) -> Result<Vec<u8>> {
    let err = |message: String| Error::Batch {
        path: source.to_owned(),
        message,
    };
    let mut head = Vec::new();
    let mut read_up_to = |head: &mut Vec<u8>, n: u64| {
        reader
            .by_ref()
            .take(n)
            .read_to_end(head)
            .map_err(|e| Error::Io {
                path: source.to_owned(),
                source: e,
            })
    };
    read_up_to(&mut head, 8)?;
    if head.len() < 8 || &head[..6] != b"\x93NUMPY" {
        return Ok(head);
    }
    let size_bytes: usize = match head[6] {
        1 => 2,
        2 | 3 => 4,
        _ => return Ok(head),
    };
    read_up_to(&mut head, size_bytes as u64)?;
    if head.len() < 8 + size_bytes {
        return Ok(head);
    }
    let header_len = head[8..]
        .iter()
        .rev()
        .fold(0u64, |acc, &b| (acc << 8) | u64::from(b));
    let start = (8 + size_bytes) as u64;
    let short_header = |have: u64| {
        err(format!(
            "not a valid .npy file: the header is {header_len} bytes long by its own count, \
             but only {have} bytes follow (truncated file?)"
        ))
    };
    if let Some(len) = len {
        if start + header_len > len {
            return Err(short_header(len.saturating_sub(start)));
        }
    }
    read_up_to(&mut head, header_len)?;
    let have = head.len() as u64 - start;
    if have < header_len {
        return Err(short_header(have));
    }
    let text = &head[start as usize..];
    let depth = bracket_depth(text);
    if depth > MAX_HEADER_DEPTH {
        return Err(err(format!(
            "not a valid .npy file: the header nests brackets {depth} deep; a float array's \
             header nests {MAX_HEADER_DEPTH} at most"
        )));
    }
    if let Some((shape, item_size)) = npy_shape(text) {
        let nonzero = shape.iter().filter(|&&d| d != 0);
        let Some(count) = nonzero.copied().try_fold(1u64, u64::checked_mul) else {
            return Err(err(format!(
                "not a valid .npy file: shape {shape:?} holds more than 2^64 values"
            )));
        };
        let count = if shape.contains(&0) { 0 } else { count };
        if let (Some(len), Some(item_size)) = (len, item_size) {
            let needed = count
                .checked_mul(item_size)
                .and_then(|b| b.checked_add(start + header_len));
            if !matches!(needed, Some(needed) if needed <= len) {
                return Err(err(format!(
                    "the data is shorter than the header's shape says (truncated file?): \
                     shape {shape:?} needs {} bytes of data, the file holds {}",
                    count.saturating_mul(item_size),
                    len - start - header_len
                )));
            }
            // Bytes after the data are not part of any array: a file with them is not
            // what its header says (two arrays concatenated, a botched write).
            if let Some(needed) = needed.filter(|&n| n < len) {
                return Err(err(format!(
                    "{} bytes follow the data that the header's shape {shape:?} describes; \
                     a .npy file holds one array and nothing after it",
                    len - needed
                )));
            }
        }
    }
    Ok(head)
}

/// Deepest bracket nesting a `.npy` header may have: a float array's is the dict and the
/// shape tuple, 2; structured dtypes (not read here) need a little more. Without this
/// bound a header of a few dozen bytes stalls the header parser (`py_literal`, which
/// npyz uses too): it backtracks exponentially in the depth of unclosed brackets, about
/// a second at 16 `[` and minutes at 16 `{`.
const MAX_HEADER_DEPTH: usize = 4;

/// The deepest nesting of `(`, `[` and `{` in `text`, counting every bracket character,
/// inside string literals too (an overcount only refuses headers with brackets in
/// strings, which no float array's has; an undercount would let the stall through).
fn bracket_depth(text: &[u8]) -> usize {
    let (mut depth, mut deepest) = (0usize, 0usize);
    for &c in text {
        match c {
            b'(' | b'[' | b'{' => {
                depth += 1;
                deepest = deepest.max(depth);
            }
            b')' | b']' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    deepest
}

/// The shape in a `.npy` header's text, and the item size of the dtypes read here (`<f4`,
/// `<f8`); `None` where the text does not parse as npyz would parse it.
fn npy_shape(text: &[u8]) -> Option<(Vec<u64>, Option<u64>)> {
    use py_literal::Value;
    let text = text.strip_suffix(b"\n").unwrap_or(text);
    let Ok(Value::Dict(dict)) = std::str::from_utf8(text).ok()?.parse::<Value>() else {
        return None;
    };
    // The last of repeated keys, as npyz (which collects the pairs into a map) and Python
    // take it: checking the first let `'shape'` repeated slip an overflowing shape past.
    let get = |key: &str| {
        dict.iter()
            .rev()
            .find(|(k, _)| matches!(k, Value::String(s) if s == key))
            .map(|(_, v)| v)
    };
    let (Value::Tuple(dims) | Value::List(dims)) = get("shape")? else {
        return None;
    };
    let shape = dims
        .iter()
        .map(|d| match d {
            Value::Integer(i) => u64::try_from(i).ok(),
            _ => None,
        })
        .collect::<Option<Vec<u64>>>()?;
    let item_size = match get("descr") {
        Some(Value::String(s)) if s == "<f4" => Some(4),
        Some(Value::String(s)) if s == "<f8" => Some(8),
        _ => None,
    };
    Some((shape, item_size))
}

fn truncated(path: &Path, e: std::io::Error) -> Error {
    Error::Batch {
        path: path.to_owned(),
        message: format!("the data is shorter than the header's shape says (truncated file?): {e}"),
    }
}

/// Writes a 2-D float32 array `rows × cols` to `path` atomically: the data goes to a
/// temporary file in the same directory, which is renamed over `path` only when complete
/// (see [`crate::atomic`] for symlinks, FIFOs, devices and `-`).
pub fn write_npy_f32(path: &Path, data: &[f32], cols: usize) -> Result<()> {
    crate::atomic::commit(vec![stage_npy_f32(path, data, cols, &Cancel::new())?])
}

/// Stages a 2-D float32 `.npy` for [`crate::atomic::commit`] (several files that must
/// appear together), checking `cancel` as it writes.
pub fn stage_npy_f32(
    path: &Path,
    data: &[f32],
    cols: usize,
    cancel: &Cancel,
) -> Result<crate::atomic::Staged> {
    use npyz::WriterBuilder;
    let rows = (data.len() / cols.max(1)) as u64;
    crate::atomic::stage(path, cancel, |w| {
        let mut writer = npyz::WriteOptions::<f32>::new()
            .default_dtype()
            .shape(&[rows, cols as u64])
            .writer(w)
            .begin_nd()?;
        writer.extend(data.iter().copied())?;
        writer.finish()
    })
}

/// The header of a C-order float32 `.npy` of shape `(rows, columns)`, version 1.0, padded
/// so that the data starts at a multiple of 64 bytes (as NumPy writes it).
pub fn npy_header_f32(rows: u64, columns: usize) -> Vec<u8> {
    npy_header_f32_shape(&format!("{rows}, {columns}"))
}

/// The header of a C-order float32 `.npy` of shape `(shape)` (its comma-separated
/// dimensions), padded so that the data starts at a multiple of 64 bytes.
pub fn npy_header_f32_shape(shape: &str) -> Vec<u8> {
    let dict = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({shape}), }}");
    let unpadded = 10 + dict.len() + 1; // magic, version, length; the dict; '\n'
    let total = unpadded.div_ceil(64) * 64;
    let mut h = Vec::with_capacity(total);
    h.extend_from_slice(b"\x93NUMPY\x01\x00");
    h.extend_from_slice(&((total - 10) as u16).to_le_bytes());
    h.extend_from_slice(dict.as_bytes());
    h.resize(total - 1, b' ');
    h.push(b'\n');
    h
}

/// The path as a `PathBuf` for in-memory batches in errors.
pub fn memory_source() -> PathBuf {
    PathBuf::from("<memory>")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_borrowed_batch_reads_the_callers_rows_in_place_and_is_checked_alike() {
        let rows = vec![0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0];
        let b = Batch::borrowed(&rows, COLUMNS_PLAIN, 2, Path::new("tuples")).unwrap();
        assert!(b.is_borrowed());
        assert!(std::ptr::eq(b.as_slice(), rows.as_slice()));
        assert_eq!(b.tuple(0).material, 1);
        let owned = Batch::new(rows.clone(), COLUMNS_PLAIN, 2, Path::new("tuples")).unwrap();
        assert!(!owned.is_borrowed());
        assert_eq!(b, owned);
        // The same checks, the same messages, as an owned batch.
        let borrowed_err = Batch::borrowed(&rows, COLUMNS_PLAIN, 1, Path::new("tuples"))
            .unwrap_err()
            .to_string();
        let owned_err = Batch::new(rows.clone(), COLUMNS_PLAIN, 1, Path::new("tuples"))
            .unwrap_err()
            .to_string();
        assert_eq!(borrowed_err, owned_err);
        assert!(
            borrowed_err.contains("row 0: material value 1"),
            "{borrowed_err}"
        );
        let cols = Batch::borrowed(&rows[..9], 9, 2, Path::new("tuples")).unwrap_err();
        assert!(cols.to_string().contains("found 9"), "{cols}");
    }
}
