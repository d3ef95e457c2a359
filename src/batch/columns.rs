//! A batch given as columns ([`ColumnBatch`]): each direction one vector for every row or
//! one a row (3 floats a row, as an `(n, 3)` array holds them), the material one index or
//! one a row. The Python package's broadcast form (`l=`, `v=`, `n=`) is this; an engine
//! that reads columns evaluates it in place ([`crate::backend::Backend::evaluate_columns_into`]),
//! the others get its rows a chunk at a time ([`ColumnBatch::rows`]). Either way its
//! results, counts and errors are those of the same rows given as one `(n, 10)` or
//! `(n, 13)` array.

use super::material_column::{material_in_range, material_index};
use super::{Batch, Tuple, COLUMNS_PLAIN, COLUMNS_TANGENT};
use crate::error::{Error, Result};
use crate::material::Material;
use std::path::Path;

/// One direction of a [`ColumnBatch`].
#[derive(Debug, Clone, Copy)]
pub enum Column<'a> {
    /// The same vector for every row.
    Every([f32; 3]),
    /// One vector a row: `x y z` of row `i` at `3i..3i + 3`.
    Each(&'a [f32]),
}

impl Column<'_> {
    /// Row `i`'s vector.
    #[inline]
    pub fn at(&self, i: usize) -> [f32; 3] {
        match self {
            Column::Every(x) => *x,
            Column::Each(c) => [c[3 * i], c[3 * i + 1], c[3 * i + 2]],
        }
    }

    fn new<'a>(
        name: &str,
        values: &'a [f32],
        len: usize,
    ) -> std::result::Result<Column<'a>, String> {
        match values.len() {
            3 => Ok(Column::Every([values[0], values[1], values[2]])),
            n if n == 3 * len => Ok(Column::Each(values)),
            n => Err(format!(
                "{name}: {n} values, neither one vector (3) nor one a row ({})",
                3 * len
            )),
        }
    }
}

/// The material of each row of a [`ColumnBatch`] (validated: an index into the table).
#[derive(Debug, Clone, Copy)]
pub enum MaterialColumn<'a> {
    /// The same material for every row.
    Every(usize),
    /// One material index a row (as a float, as in a row's tenth column).
    Each(&'a [f32]),
}

/// A batch as columns (see the module docs). Validated on construction as [`Batch`]'s
/// rows are: the material indices, and a tangent wherever an anisotropic material needs
/// one.
#[derive(Debug, Clone, Copy)]
pub struct ColumnBatch<'a> {
    l: Column<'a>,
    v: Column<'a>,
    n: Column<'a>,
    t: Option<Column<'a>>,
    material: MaterialColumn<'a>,
    len: usize,
}

impl<'a> ColumnBatch<'a> {
    /// `len` rows from `l`, `v`, `n` (and `t`), each 3 values (one vector for every row)
    /// or `3·len`, and `material`, 1 value or `len`. Errors name `source` and, for a bad
    /// material or a missing tangent, the first such row.
    pub fn new(
        [l, v, n]: [&'a [f32]; 3],
        t: Option<&'a [f32]>,
        material: &'a [f32],
        len: usize,
        materials: &[Material],
        source: &Path,
    ) -> Result<ColumnBatch<'a>> {
        let err = |message: String| Error::Batch {
            path: source.to_owned(),
            message,
        };
        let count = materials.len();
        let bad = |row: usize, m: f32| {
            err(format!(
                "row {row}: material value {m} is not an integer index in 0..{count} (the materials file defines {count})"
            ))
        };
        let material = match material {
            &[m] => MaterialColumn::Every(material_index(m, count).ok_or_else(|| bad(0, m))?),
            each if each.len() == len => {
                // One pass the compiler vectorises, then the first bad row found again.
                if !each.iter().all(|&m| material_in_range(m, count)) {
                    let row = each.iter().position(|&m| !material_in_range(m, count));
                    let row = row.expect("a value failed the test");
                    return Err(bad(row, each[row]));
                }
                MaterialColumn::Each(each)
            }
            other => {
                return Err(err(format!(
                    "material: {} values, neither one index nor one a row ({len})",
                    other.len()
                )))
            }
        };
        let batch = ColumnBatch {
            l: Column::new("l", l, len).map_err(err)?,
            v: Column::new("v", v, len).map_err(err)?,
            n: Column::new("n", n, len).map_err(err)?,
            t: t.map(|t| Column::new("t", t, len))
                .transpose()
                .map_err(err)?,
            material,
            len,
        };
        if batch.t.is_none() && materials.iter().any(Material::is_anisotropic) {
            let needs = |i: usize| materials[i].is_anisotropic();
            let row = match batch.material {
                MaterialColumn::Every(i) => needs(i).then_some(0),
                MaterialColumn::Each(m) => m.iter().position(|&m| needs(m as usize)),
            };
            if let Some(row) = row.filter(|_| len > 0) {
                let i = batch.material(row);
                return Err(err(format!(
                    "row {row}: material {i} (`{}`) is anisotropic (roughness [mx, my]) and needs a tangent, but the batch has none; give t (one vector, or one a row)",
                    materials[i].name
                )));
            }
        }
        Ok(batch)
    }

    /// Rows.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether it has no rows.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// L, V and N.
    pub fn directions(&self) -> [Column<'a>; 3] {
        [self.l, self.v, self.n]
    }

    /// The tangent, when given.
    pub fn tangent(&self) -> Option<Column<'a>> {
        self.t
    }

    /// The material column.
    pub fn materials(&self) -> MaterialColumn<'a> {
        self.material
    }

    /// Row `i`'s material index.
    #[inline]
    pub fn material(&self, i: usize) -> usize {
        match self.material {
            MaterialColumn::Every(m) => m,
            MaterialColumn::Each(m) => m[i] as usize,
        }
    }

    /// Row `i` as a tuple.
    pub fn tuple(&self, i: usize) -> Tuple {
        Tuple {
            l: self.l.at(i),
            v: self.v.at(i),
            n: self.n.at(i),
            material: self.material(i),
            t: self.t.map(|t| t.at(i)),
        }
    }

    /// The columns its rows have: 13 with a tangent, else 10.
    pub fn columns(&self) -> usize {
        if self.t.is_some() {
            COLUMNS_TANGENT
        } else {
            COLUMNS_PLAIN
        }
    }

    /// Rows `range` as an ordinary batch (rows `range.start..` of this one), written into
    /// `buffer`'s allocation: for the engines that read rows. Split over the cores (the
    /// engine waits for it), and column by column within a part (a pass each), which the
    /// compiler vectorises where a pass writing whole rows is not.
    pub fn rows(&self, range: std::ops::Range<usize>, buffer: Vec<f32>) -> Batch<'static> {
        /// Rows below which a part costs more in a thread than it saves.
        const MIN_PART: usize = 16 << 10;
        let width = self.columns();
        let mut data = buffer;
        data.clear();
        data.resize(range.len() * width, 0.0);
        // Read once: on Linux the count comes from the cgroup's files.
        static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
        let cores =
            *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |c| c.get()));
        let parts = cores.min(range.len() / MIN_PART).max(1);
        if parts == 1 {
            self.gather(range.start, &mut data);
        } else {
            let per_part = range.len().div_ceil(parts);
            std::thread::scope(|s| {
                for (i, piece) in data.chunks_mut(per_part * width).enumerate() {
                    s.spawn(move || self.gather(range.start + i * per_part, piece));
                }
            });
        }
        Batch {
            data: data.into(),
            columns: width,
        }
    }

    /// The rows from `first` on into `out` (whole rows of [`ColumnBatch::columns`]).
    fn gather(&self, first: usize, out: &mut [f32]) {
        let width = self.columns();
        let len = out.len() / width;
        let mut put = |at: usize, c: Column| {
            let rows = out.chunks_exact_mut(width);
            match c {
                Column::Every(x) => rows.for_each(|r| r[at..at + 3].copy_from_slice(&x)),
                Column::Each(c) => rows
                    .zip(c[3 * first..3 * (first + len)].chunks_exact(3))
                    .for_each(|(r, x)| r[at..at + 3].copy_from_slice(x)),
            }
        };
        put(0, self.l);
        put(3, self.v);
        put(6, self.n);
        if let Some(t) = self.t {
            put(10, t);
        }
        let rows = out.chunks_exact_mut(width);
        match self.material {
            MaterialColumn::Every(m) => rows.for_each(|r| r[9] = m as f32),
            MaterialColumn::Each(m) => rows
                .zip(&m[first..first + len])
                .for_each(|(r, &x)| r[9] = x),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::parse_materials;

    fn gold() -> Vec<Material> {
        parse_materials(
            "[[material]]\nname = \"g\"\nmodel = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = 0.3\ngeometry = \"smith\"\nfresnel = \"none\"\n\
             [[material]]\nname = \"a\"\nmodel = \"cook-torrance\"\ndistribution = \"ggx\"\nroughness = [0.1, 0.4]\ngeometry = \"smith\"\nfresnel = \"none\"\n",
            "t",
        )
        .unwrap()
    }

    /// The rows it gives are the rows the columns make, broadcast vectors repeated.
    #[test]
    fn rows_are_the_columns_side_by_side() {
        let l = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let (v, n, m) = ([0.0, 0.0, 1.0], [0.5, 0.5, 0.5], [0.0, 0.0]);
        let b = ColumnBatch::new([&l, &v, &n], None, &m, 2, &gold()[..1], Path::new("x")).unwrap();
        let rows = b.rows(0..2, Vec::new());
        assert_eq!(
            rows.as_slice(),
            [
                1.0, 2.0, 3.0, 0.0, 0.0, 1.0, 0.5, 0.5, 0.5, 0.0, //
                4.0, 5.0, 6.0, 0.0, 0.0, 1.0, 0.5, 0.5, 0.5, 0.0
            ]
        );
        assert_eq!(b.rows(1..2, Vec::new()).as_slice()[..3], [4.0, 5.0, 6.0]);
        assert_eq!(b.tuple(1).l, [4.0, 5.0, 6.0]);
    }

    /// A bad material names its row; a wrong length names its column; an anisotropic
    /// material without a tangent names the first row that uses it.
    #[test]
    fn errors_name_the_row_or_the_column() {
        let ms = gold();
        let x = [0.0, 0.0, 1.0];
        let message = |r: Result<ColumnBatch>| r.unwrap_err().to_string();
        let e = message(ColumnBatch::new(
            [&x, &x, &x],
            None,
            &[0.0, 0.0, 1.5],
            3,
            &ms[..1],
            Path::new("x"),
        ));
        assert!(e.contains("row 2: material value 1.5"), "{e}");
        let e = message(ColumnBatch::new(
            [&x, &[0.0; 6], &x],
            None,
            &[0.0],
            3,
            &ms[..1],
            Path::new("x"),
        ));
        assert!(e.contains("v: 6 values"), "{e}");
        let e = message(ColumnBatch::new(
            [&x, &x, &x],
            None,
            &[0.0, 1.0, 1.0],
            3,
            &ms,
            Path::new("x"),
        ));
        assert!(e.contains("row 1: material 1 (`a`) is anisotropic"), "{e}");
        assert!(ColumnBatch::new(
            [&x, &x, &x],
            Some(&x),
            &[0.0, 1.0, 1.0],
            3,
            &ms,
            Path::new("x")
        )
        .is_ok());
    }
}
