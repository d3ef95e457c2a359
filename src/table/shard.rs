//! Table shards: `vkbrdf table slice|albedo|dfg|merl --shard K/N` evaluates one contiguous
//! band of the table's rows and writes it as a part with a JSON sidecar (`PART.shard.json`,
//! a [`TableSidecar`]); [`merge`] checks that the parts belong together and writes the file
//! the unsharded command writes, bit for bit.
//!
//! The bands: rows `[(K−1)·H/N, K·H/N)` of the output grid ([`Shard::rows`]) — θ_d rows of
//! a slice, roughness rows of an albedo or DFG table, the α columns of `E_avg` (its column
//! i is row i of E), the θ_h bins of a MERL file. A texel is computed the same way whatever
//! shard computes it: every sample is a function of its texel and sample index only
//! ([`super::albedo::UnitSample`]), each texel's sum runs over its own samples in order, and
//! the engine takes the path (device-made directions or host-made tuples) the whole table
//! would take ([`super::albedo::device_takes`], [`super::slice::compute_band`]).
//!
//! Part formats:
//! - EXR tables (slice, albedo, albedo-average, dfg): a `.npy` of float32, shape
//!   `(rows, texels per row, channels)`, the channels in the sidecar's layer order. Not an
//!   EXR: OpenEXR has no image of zero rows (a part is empty when N exceeds H), and float32
//!   keeps the values exact whatever `--half` says (merge rounds to float16 as the
//!   unsharded run does, clamping and warning the same way).
//! - MERL: a MERL binary of the band, dimensions `rows 90 180`, then its R, G and B blocks.

use super::exr_out::{self, Channel, Layer, Provenance};
use super::Grid;
use crate::cancel::Cancel;
use crate::error::{Error, Result};
use crate::stream::shard::{sidecar_path, Shard};
use std::collections::BTreeMap;
use std::io::Write;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Version of the table sidecar's layout.
pub const TABLE_SIDECAR_SCHEMA: u32 = 1;

/// What a table part's sidecar records.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TableSidecar {
    /// [`TABLE_SIDECAR_SCHEMA`].
    pub schema: u32,
    /// `slice`, `albedo`, `albedo-average`, `dfg` or `merl`.
    pub table: String,
    /// This part.
    pub shard: Shard,
    /// The band of rows it holds, `[start, end)`.
    pub rows: [u64; 2],
    /// Rows of the whole table.
    pub total_rows: u64,
    /// Texels per row (W; 1 for `albedo-average`; 90·180 for MERL).
    pub row_texels: u64,
    /// The EXR the merge writes, `[W, H]` (none for MERL).
    pub exr_size: Option<[usize; 2]>,
    /// The layers and their channels, in the part's channel order.
    pub layers: Vec<(String, Vec<String>)>,
    /// Every option that defines the table (material, size, samples, axes, …).
    pub options: BTreeMap<String, String>,
    /// The EXR's provenance (its `backend` is the engine's; none for MERL).
    pub provenance: Option<ProvenanceFields>,
    /// The EXR is written as float16.
    pub half: bool,
    /// Engine and device that evaluated it.
    pub engine: String,
    /// vkbrdf's version.
    pub version: String,
}

/// [`Provenance`] as the sidecar stores it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ProvenanceFields {
    /// See [`Provenance::table`].
    pub table: String,
    /// See [`Provenance::material`].
    pub material: String,
    /// See [`Provenance::convention`].
    pub convention: String,
    /// See [`Provenance::parameterisation`].
    pub parameterisation: String,
    /// See [`Provenance::samples`].
    pub samples: String,
}

impl ProvenanceFields {
    /// The fields of `p` (its backend is the sidecar's `engine`).
    pub fn of(p: &Provenance) -> ProvenanceFields {
        ProvenanceFields {
            table: p.table.clone(),
            material: p.material.clone(),
            convention: p.convention.clone(),
            parameterisation: p.parameterisation.clone(),
            samples: p.samples.clone(),
        }
    }

    fn with_backend(&self, backend: String) -> Provenance {
        Provenance {
            table: self.table.clone(),
            material: self.material.clone(),
            convention: self.convention.clone(),
            parameterisation: self.parameterisation.clone(),
            samples: self.samples.clone(),
            backend,
        }
    }
}

/// Whether the sidecar of `part` is a table part's (it names a `table`) rather than a
/// batch part's ([`crate::stream::shard::Sidecar`]).
pub fn is_table_part(part: &Path) -> Result<bool> {
    let path = sidecar_path(part);
    let text = std::fs::read_to_string(&path).map_err(|source| Error::Io {
        path: path.clone(),
        source,
    })?;
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| Error::Batch {
        path: path.clone(),
        message: format!("not a vkbrdf shard sidecar: {e}"),
    })?;
    Ok(value.get("table").is_some())
}

impl TableSidecar {
    /// Reads the sidecar of part `part`.
    pub fn read(part: &Path) -> Result<TableSidecar> {
        crate::stream::shard::read_sidecar(part, "table shard sidecar")
    }

    /// The sidecar as it is written (pretty JSON).
    pub fn to_json(&self) -> String {
        crate::stream::shard::sidecar_json(self)
    }

    fn band(&self) -> Range<usize> {
        self.rows[0] as usize..self.rows[1] as usize
    }

    fn channels(&self) -> usize {
        self.layers.iter().map(|(_, c)| c.len()).sum()
    }
}

/// What a sharded table command writes besides its band: the part's path, the shard, and
/// how the band maps onto the whole table.
#[derive(Debug, Clone, PartialEq)]
pub struct PartSpec {
    /// This part.
    pub shard: Shard,
    /// Rows of the whole table.
    pub total_rows: usize,
    /// Every option that defines the table.
    pub options: BTreeMap<String, String>,
}

impl PartSpec {
    /// The band of rows this part holds.
    pub fn band(&self) -> Range<usize> {
        let r = self.shard.rows(self.total_rows as u64);
        r.start as usize..r.end as usize
    }
}

/// Refuses a part name that does not end in `.npy`: a table part is a `.npy` band, not
/// the EXR its name would promise (`vkbrdf merge` writes the EXR).
pub fn check_part_name(output: &Path) -> Result<()> {
    if output.extension().and_then(|e| e.to_str()) != Some("npy") {
        return Err(Error::Table(format!(
            "{}: with --shard the table is written as a .npy band (OpenEXR has no empty image, \
             and N may exceed the rows); name the part PART.npy and join the parts with \
             `vkbrdf merge -o TABLE.exr PART…`",
            output.display()
        )));
    }
    Ok(())
}

/// An EXR table's band: `layers` hold the band's `rows × row_texels` values per channel.
/// Returns the part and sidecar, staged (for [`crate::atomic::commit`]).
#[allow(clippy::too_many_arguments)]
pub fn stage_exr_part(
    path: &Path,
    spec: &PartSpec,
    row_texels: usize,
    exr_size: Grid,
    layers: &[Layer],
    provenance: &Provenance,
    half: bool,
    cancel: &Cancel,
) -> Result<Vec<crate::atomic::Staged>> {
    let band = spec.band();
    let texels = band.len() * row_texels;
    let channels: Vec<&Channel> = layers.iter().flat_map(|l| &l.channels).collect();
    for c in &channels {
        if c.values.len() != texels {
            return Err(Error::Table(format!(
                "{}: channel {} holds {} values for a band of {texels} texels (a bug)",
                path.display(),
                c.name,
                c.values.len()
            )));
        }
    }
    let car = TableSidecar {
        schema: TABLE_SIDECAR_SCHEMA,
        table: provenance.table.clone(),
        shard: spec.shard,
        rows: [band.start as u64, band.end as u64],
        total_rows: spec.total_rows as u64,
        row_texels: row_texels as u64,
        exr_size: Some([exr_size.width, exr_size.height]),
        layers: layers
            .iter()
            .map(|l| {
                (
                    l.name.clone(),
                    l.channels.iter().map(|c| c.name.clone()).collect(),
                )
            })
            .collect(),
        options: spec.options.clone(),
        provenance: Some(ProvenanceFields::of(provenance)),
        half,
        engine: provenance.backend.clone(),
        version: super::VERSION.to_string(),
    };
    let header = crate::batch::npy_header_f32_shape(&format!(
        "{}, {row_texels}, {}",
        band.len(),
        channels.len()
    ));
    let data = crate::atomic::stage(path, cancel, |w| {
        w.write_all(&header)?;
        let mut buf = Vec::with_capacity(channels.len() * 4 * 4096);
        for t in 0..texels {
            for c in &channels {
                buf.extend_from_slice(&c.values[t].to_le_bytes());
            }
            if buf.len() >= channels.len() * 4 * 4096 {
                w.write_all(&buf)?;
                buf.clear();
            }
        }
        w.write_all(&buf)
    })?;
    let json = car.to_json();
    let side = crate::atomic::stage(&sidecar_path(path), cancel, |w| {
        w.write_all(json.as_bytes())
    })?;
    Ok(vec![data, side])
}

/// A MERL band: `values` are its R, G, B blocks (`3 · rows · 90 · 180` stored values),
/// written as a MERL binary of dimensions `rows 90 180` with its sidecar, atomically.
pub fn write_merl_part(
    path: &Path,
    spec: &PartSpec,
    values: &[f64],
    engine: &str,
    cancel: &Cancel,
) -> Result<()> {
    use crate::material::merl::{PHI_D_BINS, THETA_D_BINS};
    let band = spec.band();
    let row_texels = THETA_D_BINS * PHI_D_BINS;
    if values.len() != 3 * band.len() * row_texels {
        return Err(Error::Table(format!(
            "{}: {} values for a band of {} θ_h bins (a bug)",
            path.display(),
            values.len(),
            band.len()
        )));
    }
    let car = TableSidecar {
        schema: TABLE_SIDECAR_SCHEMA,
        table: "merl".into(),
        shard: spec.shard,
        rows: [band.start as u64, band.end as u64],
        total_rows: spec.total_rows as u64,
        row_texels: row_texels as u64,
        exr_size: None,
        layers: vec![("merl".into(), vec!["R".into(), "G".into(), "B".into()])],
        options: spec.options.clone(),
        provenance: None,
        half: false,
        engine: engine.into(),
        version: super::VERSION.to_string(),
    };
    let data = crate::atomic::stage(path, cancel, |w| {
        for dim in [band.len(), THETA_D_BINS, PHI_D_BINS] {
            w.write_all(&(dim as i32).to_le_bytes())?;
        }
        for x in values {
            w.write_all(&x.to_le_bytes())?;
        }
        Ok(())
    })?;
    let json = car.to_json();
    let side = crate::atomic::stage(&sidecar_path(path), cancel, |w| {
        w.write_all(json.as_bytes())
    })?;
    crate::atomic::commit(vec![data, side])
}

/// What [`merge`] wrote: the table kind, the parts, and the warnings to show.
#[derive(Debug, Clone, PartialEq)]
pub struct Merged {
    /// The table kind.
    pub table: String,
    /// Rows of the table.
    pub rows: u64,
    /// Warnings (float16 clamping, as the unsharded run prints them; parts of several
    /// engines).
    pub warnings: Vec<String>,
}

/// Joins table parts into `output`: every part of one N, each once, of the same table
/// (kind, options, size, channels, provenance), by the same engine and version unless
/// `allow_mixed`; writes the file the unsharded command writes, atomically.
pub fn merge(
    parts: &[PathBuf],
    output: &Path,
    allow_mixed: bool,
    cancel: &Cancel,
) -> Result<Merged> {
    let bad = |path: &Path, message: String| Error::Batch {
        path: path.to_owned(),
        message,
    };
    crate::stream::shard::check_merge_outputs(&[output], parts, &[])?;
    let (first, mut cars) = crate::stream::shard::read_parts(parts, output, TableSidecar::read)?;
    let base = cars[0].1.clone();
    for (p, c) in &cars {
        let differs = |what: &str, a: &dyn std::fmt::Debug, b: &dyn std::fmt::Debug| {
            crate::stream::shard::part_differs(p, first, what, a, b)
        };
        if c.schema != TABLE_SIDECAR_SCHEMA {
            return Err(bad(
                p,
                format!(
                    "table sidecar schema {} (this vkbrdf reads {TABLE_SIDECAR_SCHEMA})",
                    c.schema
                ),
            ));
        }
        if c.table != base.table {
            return Err(differs("the table kind", &c.table, &base.table));
        }
        if c.shard.n != base.shard.n {
            return Err(differs("the number of shards", &c.shard.n, &base.shard.n));
        }
        for (key, value) in &c.options {
            let theirs = base.options.get(key);
            if theirs != Some(value) {
                return Err(differs(
                    &format!("the option {key}"),
                    value,
                    &theirs.map_or("(not given)", String::as_str),
                ));
            }
        }
        if let Some(key) = base.options.keys().find(|k| !c.options.contains_key(*k)) {
            return Err(differs(
                &format!("the option {key}"),
                &"(not given)",
                &base.options[key],
            ));
        }
        if (c.total_rows, c.row_texels, c.exr_size)
            != (base.total_rows, base.row_texels, base.exr_size)
        {
            return Err(differs(
                "the table size (rows, texels per row, EXR size)",
                &(c.total_rows, c.row_texels, c.exr_size),
                &(base.total_rows, base.row_texels, base.exr_size),
            ));
        }
        if c.layers != base.layers || c.half != base.half {
            return Err(differs(
                "the layers, channels or --half",
                &(&c.layers, c.half),
                &(&base.layers, base.half),
            ));
        }
        if c.provenance != base.provenance {
            return Err(differs("the provenance", &c.provenance, &base.provenance));
        }
        if !allow_mixed && (c.engine != base.engine || c.version != base.version) {
            return Err(differs(
                "the engine or version (--allow-mixed accepts that)",
                &(&c.engine, &c.version),
                &(&base.engine, &base.version),
            ));
        }
        let want = c.shard.rows(c.total_rows);
        if c.rows != [want.start, want.end] {
            return Err(bad(
                p,
                format!(
                    "its sidecar says rows {:?}, but shard {}/{} of {} rows is {want:?}",
                    c.rows, c.shard.k, c.shard.n, c.total_rows
                ),
            ));
        }
    }
    let whole = format!(" of the {} table", base.table);
    crate::stream::shard::check_complete(&mut cars, |c| c.shard, base.shard.n, output, &whole)?;
    let mut warnings: Vec<String> =
        crate::stream::shard::mixed_engines_warning(cars.iter().map(|(_, c)| c.engine.as_str()))
            .into_iter()
            .collect();
    if base.table == "merl" {
        merge_merl(&cars, output, cancel)?;
    } else {
        let [w, h] = base
            .exr_size
            .ok_or_else(|| bad(first, "a table sidecar without an EXR size".into()))?;
        let grid = Grid::new(w, h)?;
        let channels = base.channels();
        super::check_memory(
            super::table_bytes(grid, 12 * channels as u64),
            "the merged table",
        )?;
        let mut values: Vec<Vec<f32>> = vec![Vec::with_capacity(grid.texels()); channels];
        for (p, c) in &cars {
            let texels = c.band().len() * c.row_texels as usize;
            let data = read_npy_part(p, [c.band().len(), c.row_texels as usize, channels])?;
            for (k, v) in values.iter_mut().enumerate() {
                v.extend((0..texels).map(|t| data[t * channels + k]));
            }
        }
        let mut values = values.into_iter();
        let layers: Vec<Layer> = base
            .layers
            .iter()
            .map(|(name, names)| Layer {
                name: name.clone(),
                channels: names
                    .iter()
                    .map(|n| Channel {
                        name: n.clone(),
                        values: values.next().expect("one vector per channel"),
                    })
                    .collect(),
            })
            .collect();
        let mut engines: Vec<&str> = Vec::new();
        for (_, c) in &cars {
            if !engines.contains(&c.engine.as_str()) {
                engines.push(&c.engine);
            }
        }
        let provenance = base
            .provenance
            .as_ref()
            .ok_or_else(|| bad(first, "a table sidecar without provenance".into()))?
            .with_backend(engines.join(" + "));
        let clamped = exr_out::write(output, grid, layers, &provenance, base.half, cancel)?;
        for c in clamped {
            warnings.push(format!(
                "{}: {} texel(s) of layer `{}` exceed float16's largest finite value and were written as {} (use float32, without --half, for the exact values)",
                output.display(),
                c.texels,
                c.layer,
                exr_out::HALF_MAX
            ));
        }
    }
    Ok(Merged {
        table: base.table,
        rows: base.total_rows,
        warnings,
    })
}

/// The float32 data of a part, checked to be a C-order `.npy` of `shape`.
fn read_npy_part(path: &Path, shape: [usize; 3]) -> Result<Vec<f32>> {
    let bad = |message: String| Error::Batch {
        path: path.to_owned(),
        message,
    };
    let bytes = std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_owned(),
        source,
    })?;
    let npy =
        npyz::NpyFile::new(&bytes[..]).map_err(|e| bad(format!("not a valid .npy file: {e}")))?;
    let dtype = npy.dtype().descr();
    let want: Vec<u64> = shape.iter().map(|&s| s as u64).collect();
    if npy.shape() != want.as_slice() || npy.order() != npyz::Order::C || !dtype.contains("<f4") {
        return Err(bad(format!(
            "shape {:?} dtype {dtype}, but its sidecar says float32 {want:?}",
            npy.shape()
        )));
    }
    npy.into_vec::<f32>()
        .map_err(|e| bad(format!("truncated or unreadable data: {e}")))
}

/// Joins MERL bands (R, G, B blocks each) into one MERL binary.
fn merge_merl(cars: &[(PathBuf, TableSidecar)], output: &Path, cancel: &Cancel) -> Result<()> {
    use crate::material::merl::{PHI_D_BINS, SAMPLES, THETA_D_BINS, THETA_H_BINS};
    let row = THETA_D_BINS * PHI_D_BINS;
    let mut values = vec![0.0f64; 3 * SAMPLES];
    for (p, c) in cars {
        let bad = |message: String| Error::Batch {
            path: p.clone(),
            message,
        };
        if c.total_rows != THETA_H_BINS as u64 || c.row_texels != row as u64 {
            return Err(bad(format!(
                "a MERL part of {} rows of {} bins; MERL has {THETA_H_BINS} of {row}",
                c.total_rows, c.row_texels
            )));
        }
        let band = c.band();
        let bytes = std::fs::read(p).map_err(|source| Error::Io {
            path: p.clone(),
            source,
        })?;
        let n = band.len() * row;
        let want = 12 + 3 * n * 8;
        let dims: Vec<i32> = bytes
            .chunks_exact(4)
            .take(3)
            .map(|b| i32::from_le_bytes(b.try_into().expect("4 bytes")))
            .collect();
        if bytes.len() != want
            || dims != [band.len() as i32, THETA_D_BINS as i32, PHI_D_BINS as i32]
        {
            return Err(bad(format!(
                "{} bytes with dimensions {dims:?}, but its sidecar says a MERL band of {} θ_h bins ({want} bytes, dimensions [{}, {THETA_D_BINS}, {PHI_D_BINS}])",
                bytes.len(),
                band.len(),
                band.len()
            )));
        }
        for ch in 0..3 {
            let from = &bytes[12 + ch * n * 8..12 + (ch + 1) * n * 8];
            let to = &mut values[ch * SAMPLES + band.start * row..ch * SAMPLES + band.end * row];
            for (x, b) in to.iter_mut().zip(from.chunks_exact(8)) {
                *x = f64::from_le_bytes(b.try_into().expect("8 bytes"));
            }
        }
    }
    super::merl_file::write_values_cancellable(output, &values, cancel)
}
