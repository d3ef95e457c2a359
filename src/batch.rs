//! Tuple batches: `n × 10` or `n × 13` float32 rows
//! `Lx Ly Lz Vx Vy Vz Nx Ny Nz material [Tx Ty Tz]` (FORMULAS.md §1), read from and written
//! to `.npy` with the `npyz` crate.

use crate::cancel::Cancel;
use crate::error::{Error, Result};
use crate::material::Material;
use std::path::{Path, PathBuf};

/// Columns of a batch without tangents.
pub const COLUMNS_PLAIN: usize = 10;
/// Columns of a batch with tangents.
pub const COLUMNS_TANGENT: usize = 13;

/// A validated batch of tuples, stored row-major as `f32`.
///
/// Construction checks the shape and that every material value is an integer index into
/// the material table; direction problems (zero, NaN) are not batch errors but invalid
/// tuples, counted at evaluation (FORMULAS.md §1).
#[derive(Debug, Clone, PartialEq)]
pub struct Batch {
    data: Vec<f32>,
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

impl Batch {
    /// Wraps row-major data with `columns` (10 or 13) per row. `source` names the origin
    /// in errors; `material_count` is the size of the material table.
    pub fn new(
        data: Vec<f32>,
        columns: usize,
        material_count: usize,
        source: &Path,
    ) -> Result<Batch> {
        let err = |message: String| Error::Batch {
            path: source.to_owned(),
            message,
        };
        if columns != COLUMNS_PLAIN && columns != COLUMNS_TANGENT {
            return Err(err(format!(
                "expected 10 columns (Lx Ly Lz Vx Vy Vz Nx Ny Nz material) or 13 (plus Tx Ty Tz), found {columns}"
            )));
        }
        if data.len() % columns != 0 {
            return Err(err(format!(
                "{} values do not make whole rows of {columns}",
                data.len()
            )));
        }
        let batch = Batch { data, columns };
        if let Some((row, value)) = batch.first_bad_material(material_count) {
            return Err(err(format!(
                "row {row}: material value {value} is not an integer index in 0..{material_count} (the materials file defines {material_count})"
            )));
        }
        Ok(batch)
    }

    fn first_bad_material(&self, material_count: usize) -> Option<(usize, f32)> {
        self.data
            .chunks_exact(self.columns)
            .map(|row| row[9])
            .enumerate()
            .find(|&(_, m)| !(m >= 0.0 && m.fract() == 0.0 && (m as f64) < material_count as f64))
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

    /// Reads a batch from a `.npy` file: float32 or float64 (float64 is rounded to float32,
    /// the precision every backend evaluates from), C order, shape `(n, 10)` or `(n, 13)`.
    pub fn read_npy(path: &Path, material_count: usize) -> Result<Batch> {
        let (data, shape) = read_npy_f32(path)?;
        let err = |message: String| Error::Batch {
            path: path.to_owned(),
            message,
        };
        if shape.len() != 2 {
            return Err(err(format!(
                "expected a 2-D array of shape (n, 10) or (n, 13), found shape {shape:?}"
            )));
        }
        Batch::new(data, shape[1] as usize, material_count, path)
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
    let needs_tangent = |m: f32| {
        m >= 0.0
            && m.fract() == 0.0
            && materials
                .get(m as usize)
                .is_some_and(Material::is_anisotropic)
    };
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

/// Reads a C-order float32/float64 `.npy` file as `f32` with its shape.
pub fn read_npy_f32(path: &Path) -> Result<(Vec<f32>, Vec<u64>)> {
    let err = |message: String| Error::Batch {
        path: path.to_owned(),
        message,
    };
    let file = std::fs::File::open(path).map_err(|source| Error::Io {
        path: path.to_owned(),
        source,
    })?;
    let npy = npyz::NpyFile::new(std::io::BufReader::new(file))
        .map_err(|e| err(format!("not a valid .npy file: {e}")))?;
    if npy.order() != npyz::Order::C {
        return Err(err(
            "Fortran-order array; save it in C order (numpy.ascontiguousarray)".into(),
        ));
    }
    let shape = npy.shape().to_vec();
    let dtype = npy
        .dtype()
        .descr()
        .trim_matches(|c| c == '\'' || c == '"')
        .to_string();
    let data: Vec<f32> = match dtype.as_str() {
        "<f4" => npy.into_vec::<f32>().map_err(|e| truncated(path, e))?,
        "<f8" => npy
            .into_vec::<f64>()
            .map_err(|e| truncated(path, e))?
            .into_iter()
            .map(|x| x as f32)
            .collect(),
        other => {
            return Err(err(format!(
                "dtype {other} is not supported; use float32 ('<f4') or float64 ('<f8')"
            )))
        }
    };
    Ok((data, shape))
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

/// The path as a `PathBuf` for in-memory batches in errors.
pub fn memory_source() -> PathBuf {
    PathBuf::from("<memory>")
}
