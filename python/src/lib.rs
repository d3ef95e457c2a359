//! `vkbrdf._native`: the compiled half of the `vkbrdf` Python package (PyO3 + rust-numpy).
//!
//! The Python half (`python/vkbrdf/__init__.py`) gives the API its NumPy conventions
//! (dtype conversion, broadcasting, named tuples); this module does the work: it parses
//! materials, borrows the tuple array without copying it, runs an engine on a worker thread
//! with the GIL released, and turns the library's [`vkbrdf::Error`] into the package's
//! exception classes (defined in `vkbrdf/_errors.py`, so that each can also derive from the
//! built-in a Python user catches: `ValueError`, `RuntimeError`, `OSError`).
//!
//! Ctrl-C: while the engine runs, the calling thread waits for it and checks for pending
//! signals (`Python::check_signals`) every 20 ms; on `KeyboardInterrupt` it sets
//! the engine's [`Cancel`] token, waits for the engine to stop at its next chunk, and
//! raises the interrupt.

use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Duration;
use vkbrdf::backend::{Backend, Counts, Request};
use vkbrdf::backend_choice::{self as choice, Kind};
use vkbrdf::batch::Batch;
use vkbrdf::cancel::Cancel;
use vkbrdf::gpu::{VulkanBackend, VulkanOptions};
use vkbrdf::material::{DistributionKind, Geometry, Material, Model};
use vkbrdf::precision::{self, Precision};
use vkbrdf::table::albedo::{self, Lobe, Microfacet};
use vkbrdf::table::{slice, texel_centre, Grid, Runner};
use vkbrdf::Error;

mod columns;
mod errors;
mod fit;
mod spectral;
use errors::{raise, to_py, TUPLES};

/// How often the calling thread looks for Ctrl-C while an engine runs.
const SIGNAL_POLL: Duration = Duration::from_millis(20);

/// A table of materials: what `load_materials`, `parse_materials` and `presets` return.
#[pyclass(frozen, module = "vkbrdf", name = "Materials")]
pub struct Materials {
    pub(crate) list: Arc<Vec<Material>>,
    source: String,
    origin: Origin,
}

/// What `Materials.__reduce__` returns: the rebuilding function and its arguments
/// (kind, payload, source).
type Reduced<'py> = (Bound<'py, PyAny>, (&'static str, String, String));

/// Where a [`Materials`] came from: what pickling sends to another process (a Dask or Ray
/// worker), which parses it again there.
#[derive(Clone)]
enum Origin {
    /// TOML text.
    Text(String),
    /// A file: its text as read when it was loaded (a file changed since does not change
    /// what unpickles) and its directory (relative MERL `file` keys resolve against it,
    /// so a measured material's data file must be at the same path in the receiving
    /// process).
    File { text: String, base: PathBuf },
    /// The presets.
    Presets,
}

#[pymethods]
impl Materials {
    /// The material names, in table order (a tuple row's material column indexes them).
    #[getter]
    fn names(&self) -> Vec<String> {
        self.list.iter().map(|m| m.name.clone()).collect()
    }

    /// Each material's model (`lambert`, `phong`, `blinn-phong`, `rtr`, `ward`,
    /// `cook-torrance`, `merl`).
    #[getter]
    fn models(&self) -> Vec<&'static str> {
        self.list.iter().map(|m| m.model.toml_name()).collect()
    }

    /// Where the table came from (a file name, `<string>`, `the presets`).
    #[getter]
    fn source(&self) -> &str {
        &self.source
    }

    /// Which materials need a tangent (anisotropic roughness `[mx, my]`).
    #[getter]
    fn anisotropic(&self) -> Vec<bool> {
        self.list.iter().map(Material::is_anisotropic).collect()
    }

    /// The index of the material called `name`; a `MaterialError` naming the defined
    /// ones when there is none.
    pub(crate) fn index(&self, py: Python<'_>, name: &str) -> PyResult<usize> {
        self.list
            .iter()
            .position(|m| m.name == name)
            .ok_or_else(|| {
                let names: Vec<&str> = self.list.iter().map(|m| m.name.as_str()).collect();
                raise(
                    py,
                    "MaterialError",
                    format!(
                        "material `{name}` is not defined in {}; it defines: {}",
                        self.source,
                        names.join(", ")
                    ),
                )
            })
    }

    /// Pickling: `vkbrdf._rebuild_materials(kind, payload, source)` parses the text, reads
    /// the file or takes the presets again in the receiving process.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Reduced<'py>> {
        let rebuild = py.import("vkbrdf")?.getattr("_rebuild_materials")?;
        let (kind, payload) = match &self.origin {
            Origin::Text(t) => ("text", t.clone()),
            Origin::File { text, base } => ("file", format!("{}\n{text}", base.display())),
            Origin::Presets => ("presets", String::new()),
        };
        Ok((rebuild, (kind, payload, self.source.clone())))
    }

    fn __len__(&self) -> usize {
        self.list.len()
    }

    fn __repr__(&self) -> String {
        let items: Vec<String> = self
            .list
            .iter()
            .map(|m| format!("{}: {}", m.name, m.model.toml_name()))
            .collect();
        format!(
            "<vkbrdf.Materials from {}: {}>",
            self.source,
            items.join(", ")
        )
    }
}

/// The engine named `name` (`auto`, `vulkan`, `cpu`, `reference`), or a `UsageError`.
pub(crate) fn parse_backend(py: Python<'_>, name: &str) -> PyResult<Kind> {
    name.parse::<Kind>()
        .map_err(|e| raise(py, "UsageError", format!("backend: {e}")))
}

fn parse_precision(py: Python<'_>, name: &str) -> PyResult<Precision> {
    match name {
        "exact" => Ok(Precision::Exact),
        "fast" => Ok(Precision::Fast),
        _ => Err(raise(
            py,
            "UsageError",
            format!("precision: unknown precision `{name}`; expected `exact` or `fast`"),
        )),
    }
}

/// Vulkan engines that earlier calls opened, kept for later calls (opening one, the device
/// and its pipelines, takes about 0.6 s on lavapipe), keyed by the process that opened
/// them and the `VKBRDF_DEVICE` value they were opened under. A call takes one out, so no
/// two calls share an engine; an engine whose call failed is dropped, not returned.
static VULKAN_POOL: Mutex<Vec<Pooled>> = Mutex::new(Vec::new());

/// A pooled engine: the id of the process that opened it, the `VKBRDF_DEVICE` value, the
/// engine.
type Pooled = (u32, Option<String>, VulkanBackend);

/// Engines kept in [`VULKAN_POOL`] at most (more calls at once open more engines).
const VULKAN_POOL_SIZE: usize = 4;

/// Whether `auto` picks Vulkan when `VKBRDF_DEVICE` is unset: asked once per process
/// (enumerating the devices takes tens of milliseconds).
static AUTO_IS_VULKAN: OnceLock<bool> = OnceLock::new();

fn device_env() -> Option<String> {
    std::env::var("VKBRDF_DEVICE")
        .ok()
        .filter(|s| !s.trim().is_empty())
}

/// `kind` with `auto` resolved to `vulkan` or `cpu` as the CLI resolves it.
fn resolve(kind: Kind) -> Kind {
    if kind != Kind::Auto {
        return kind;
    }
    let vulkan =
        device_env().is_some() || *AUTO_IS_VULKAN.get_or_init(|| choice::auto_choice(None).0);
    if vulkan {
        Kind::Vulkan
    } else {
        Kind::Cpu
    }
}

/// Runs `work` on a fresh engine of `kind`, or a pooled Vulkan one, with `cancel` set.
fn with_engine<T>(
    kind: Kind,
    cancel: &Cancel,
    work: impl FnOnce(&mut dyn Backend, &Cancel) -> vkbrdf::Result<T>,
) -> vkbrdf::Result<T> {
    let lock = || {
        VULKAN_POOL
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    };
    match resolve(kind) {
        Kind::Vulkan => {
            let key = device_env();
            let pid = std::process::id();
            let pooled = {
                let mut pool = lock();
                // A child made by fork() inherits the parent's engines but not its Vulkan
                // device: it must neither use nor destroy them (destroying would call into
                // the driver with the parent's handles), so they are forgotten.
                let mut i = 0;
                while i < pool.len() {
                    if pool[i].0 == pid {
                        i += 1;
                    } else {
                        std::mem::forget(pool.swap_remove(i));
                    }
                }
                let at = pool.iter().position(|(_, k, _)| *k == key);
                at.map(|i| pool.swap_remove(i).2)
            };
            let mut backend = match pooled {
                Some(b) => b,
                None => choice::open_vulkan(None, VulkanOptions::default())?,
            };
            backend.set_cancel(cancel.clone());
            let result = work(&mut backend, cancel);
            if result.is_ok() {
                let mut pool = lock();
                if pool.len() < VULKAN_POOL_SIZE {
                    pool.push((pid, key, backend));
                }
            }
            result
        }
        other => {
            let mut backend = choice::open(other, None, VulkanOptions::default())?;
            backend.set_cancel(cancel.clone());
            work(backend.as_mut(), cancel)
        }
    }
}

/// Runs `work` on an engine of `kind` on a worker thread, with the GIL released; Ctrl-C
/// (a pending `KeyboardInterrupt`) cancels it. Calls from several threads share nothing
/// but the immutable inputs (a pooled Vulkan engine serves one call at a time).
pub(crate) fn run_engine<T: Send>(
    py: Python<'_>,
    kind: Kind,
    work: impl FnOnce(&mut dyn Backend, &Cancel) -> vkbrdf::Result<T> + Send,
) -> PyResult<T> {
    let cancel = Cancel::new();
    let outcome: (vkbrdf::Result<T>, Option<PyErr>) = py.detach(|| {
        std::thread::scope(|scope| {
            let (tx, rx) = mpsc::channel();
            let token = cancel.clone();
            scope.spawn(move || {
                let result = with_engine(kind, &token, work);
                // The receiver waits for this message; it cannot have gone.
                let _ = tx.send(result);
            });
            let mut interrupt = None;
            loop {
                match rx.recv_timeout(SIGNAL_POLL) {
                    Ok(result) => return (result, interrupt),
                    Err(RecvTimeoutError::Timeout) => {
                        if interrupt.is_none() {
                            if let Err(e) = Python::attach(|py| py.check_signals()) {
                                cancel.cancel();
                                interrupt = Some(e);
                            }
                        }
                    }
                    Err(RecvTimeoutError::Disconnected) => {
                        return (
                            Err(Error::Unsupported(
                                "the engine thread stopped without a result".into(),
                            )),
                            interrupt,
                        )
                    }
                }
            }
        })
    });
    match outcome {
        // The signal handler's own exception (KeyboardInterrupt, or what a custom SIGINT
        // handler raised) wins over the engine's `Cancelled`.
        (_, Some(interrupt)) => Err(interrupt),
        (Ok(v), None) => Ok(v),
        (Err(e), None) => Err(to_py(py, e)),
    }
}

/// The result arrays of an evaluation, the counts, and whether the tuples were read in
/// place (no copy).
pub(crate) type Evaluated<'py> = (
    Bound<'py, PyArray2<f32>>,
    Option<Bound<'py, PyArray2<f32>>>,
    (u64, u64, u64, Option<u64>),
    bool,
);

/// A C-contiguous float32 `(n, 10)` or `(n, 13)` array as a batch over `materials`
/// materials, read in place (no copy); a `BatchError` for any other layout.
fn borrowed_batch<'a>(
    py: Python<'_>,
    tuples: &'a PyReadonlyArray2<'_, f32>,
    materials: usize,
) -> PyResult<Batch<'a>> {
    let columns = tuples.shape()[1];
    let data: &[f32] = tuples.as_slice().map_err(|e| {
        raise(
            py,
            "BatchError",
            format!("{TUPLES}: the array must be C-contiguous float32 here ({e})"),
        )
    })?;
    Batch::borrowed(data, columns, materials, Path::new(TUPLES)).map_err(|e| to_py(py, e))
}

/// The engine `backend` names and the materials in `precision`'s variant, as `vkbrdf eval`
/// chooses them: measured materials go to the reference unless a backend is named (only it
/// evaluates them).
pub(crate) fn engine_and_materials(
    py: Python<'_>,
    materials: &Materials,
    backend: &str,
    precision: &str,
) -> PyResult<(Kind, Vec<Material>)> {
    let mut kind = parse_backend(py, backend)?;
    let precision = parse_precision(py, precision)?;
    let list = precision::apply_all(&materials.list, precision);
    if kind == Kind::Auto && list.iter().any(|m| matches!(m.model, Model::Measured(_))) {
        kind = Kind::Reference;
    }
    Ok((kind, list))
}

/// Evaluates a C-contiguous float32 `(n, 10)` or `(n, 13)` tuple array in place.
#[pyfunction]
#[pyo3(signature = (materials, tuples, backend, terms, precision, strict))]
fn evaluate<'py>(
    py: Python<'py>,
    materials: &Materials,
    tuples: PyReadonlyArray2<'py, f32>,
    backend: &str,
    terms: bool,
    precision: &str,
    strict: bool,
) -> PyResult<Evaluated<'py>> {
    let (kind, list) = engine_and_materials(py, materials, backend, precision)?;
    let source = Path::new(TUPLES);
    let batch = borrowed_batch(py, &tuples, list.len())?;
    batch
        .check_tangents(&list, source)
        .map_err(|e| to_py(py, e))?;
    let in_place = batch.is_borrowed();
    let request = Request { terms };
    let out = run_engine(py, kind, |backend, _| {
        backend.evaluate(&batch, &list, &request)
    })?;
    let c: Counts = out.counts;
    refuse_invalid(py, strict, &c)?;
    let n = batch.len();
    let f = rows(py, out.brdf, n, 3)?;
    let t = match out.terms {
        Some(v) => Some(rows(py, v, n, vkbrdf::backend::TERM_COLUMNS)?),
        None => None,
    };
    Ok((
        f,
        t,
        (c.invalid, c.below_horizon, c.saturated, c.first_invalid),
        in_place,
    ))
}

/// `strict=True` with an invalid tuple: the `BatchError` naming the first.
pub(crate) fn refuse_invalid(py: Python<'_>, strict: bool, c: &Counts) -> PyResult<()> {
    if strict && c.invalid > 0 {
        return Err(to_py(
            py,
            Error::InvalidTuples {
                invalid: c.invalid,
                total: c.tuples,
                first_row: c.first_invalid.unwrap_or(0),
            },
        ));
    }
    Ok(())
}

/// The mirror spike's weight ρ_s (FORMULAS.md §8) of each row of a C-contiguous float32
/// `(n, 10)` or `(n, 13)` array, `(n, 3)`: every row's material must be HTSG's (a
/// `UsageError` names the first that is not); invalid and below-horizon rows give 0.
#[pyfunction]
fn spike<'py>(
    py: Python<'py>,
    materials: &Materials,
    tuples: PyReadonlyArray2<'py, f32>,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let list = &materials.list;
    let batch = borrowed_batch(py, &tuples, list.len())?;
    let v = vkbrdf::reference::htsg_spike_rows(&batch, list).map_err(|i| {
        let m = &list[batch.tuple(i).material];
        raise(
            py,
            "UsageError",
            format!(
                "spike=True: row {i} uses material `{}`, a {} material; the mirror spike's weight is defined for htsg materials only (FORMULAS.md §8)",
                m.name,
                m.model.toml_name()
            ),
        )
    })?;
    rows(py, v, batch.len(), 3)
}

/// `values` as an `(n, columns)` array, without a copy.
pub(crate) fn rows(
    py: Python<'_>,
    values: Vec<f32>,
    n: usize,
    columns: usize,
) -> PyResult<Bound<'_, PyArray2<f32>>> {
    let a = Array2::from_shape_vec((n, columns), values)
        .map_err(|e| raise(py, "Error", format!("internal: output shape: {e}")))?;
    Ok(a.into_pyarray(py))
}

/// Reads a materials file (TOML).
#[pyfunction]
fn load_materials(py: Python<'_>, path: PathBuf) -> PyResult<Materials> {
    let text = std::fs::read_to_string(&path).map_err(|source| {
        to_py(
            py,
            Error::Io {
                path: path.clone(),
                source,
            },
        )
    })?;
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let list = vkbrdf::material::parse_materials_in(&text, &path.display().to_string(), &base)
        .map_err(|e| to_py(py, Error::Material(e)))?;
    Ok(Materials {
        list: Arc::new(list),
        source: path.display().to_string(),
        origin: Origin::File { text, base },
    })
}

/// Rebuilds a file-loaded table from its pickled text and directory (see `__reduce__`).
#[pyfunction]
fn materials_from_file_text(py: Python<'_>, payload: &str, source: &str) -> PyResult<Materials> {
    let (base, text) = payload.split_once('\n').unwrap_or((".", payload));
    let base = PathBuf::from(base);
    let list = vkbrdf::material::parse_materials_in(text, source, &base)
        .map_err(|e| to_py(py, Error::Material(e)))?;
    Ok(Materials {
        list: Arc::new(list),
        source: source.to_string(),
        origin: Origin::File {
            text: text.to_string(),
            base,
        },
    })
}

/// Parses materials from TOML text; `source` names it in errors.
#[pyfunction]
#[pyo3(signature = (text, source = "<string>"))]
fn parse_materials(py: Python<'_>, text: &str, source: &str) -> PyResult<Materials> {
    let list = vkbrdf::material::parse_materials(text, source)
        .map_err(|e| to_py(py, Error::Material(e)))?;
    Ok(Materials {
        list: Arc::new(list),
        source: source.to_string(),
        origin: Origin::Text(text.to_string()),
    })
}

/// Every preset material, as one table.
#[pyfunction]
fn presets() -> Materials {
    Materials {
        list: Arc::new(vkbrdf::material::presets::all()),
        source: "the presets".to_string(),
        origin: Origin::Presets,
    }
}

fn grid(py: Python<'_>, width: usize, height: usize) -> PyResult<Grid> {
    Grid::new(width, height).map_err(|e| to_py(py, e))
}

/// The half/difference slice of `materials[index]`: f `(H, W, 3)` and, with `terms`, the
/// terms `(H, W, 6)`.
#[pyfunction]
#[pyo3(signature = (materials, index, width, height, linear, terms, backend))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn table_slice<'py>(
    py: Python<'py>,
    materials: &Materials,
    index: usize,
    width: usize,
    height: usize,
    linear: bool,
    terms: bool,
    backend: &str,
) -> PyResult<(Bound<'py, PyArray3<f32>>, Option<Bound<'py, PyArray3<f32>>>)> {
    let kind = parse_backend(py, backend)?;
    let g = grid(py, width, height)?;
    let material = materials.list.get(index).cloned().ok_or_else(|| {
        raise(
            py,
            "UsageError",
            format!(
                "material index {index} is out of range 0..{}",
                materials.list.len()
            ),
        )
    })?;
    let spacing = if linear {
        slice::Spacing::Linear
    } else {
        slice::Spacing::Sqrt
    };
    let (f, t) = run_engine(py, kind, |backend, cancel| {
        let mut runner = Runner::new(backend).with_cancel(cancel.clone());
        slice::compute(&mut runner, &material, g, spacing, terms)
    })?;
    let cube = |v: Vec<f32>, k: usize| {
        Array3::from_shape_vec((g.height, g.width, k), v)
            .map(|a| a.into_pyarray(py))
            .map_err(|e| raise(py, "Error", format!("internal: slice shape: {e}")))
    };
    let t = match t {
        Some(v) => Some(cube(v, vkbrdf::backend::TERM_COLUMNS)?),
        None => None,
    };
    Ok((cube(f, 3)?, t))
}

fn microfacet(py: Python<'_>, distribution: &str, geometry: &str) -> PyResult<Microfacet> {
    let d = DistributionKind::from_toml_name(distribution).ok_or_else(|| {
        let names: Vec<&str> = DistributionKind::ALL
            .iter()
            .map(|d| d.toml_name())
            .collect();
        raise(
            py,
            "UsageError",
            format!(
                "distribution: unknown `{distribution}`; expected one of: {}",
                names.join(", ")
            ),
        )
    })?;
    let g = Geometry::from_toml_name(geometry).ok_or_else(|| {
        let names: Vec<&str> = Geometry::ALL.iter().map(|g| g.toml_name()).collect();
        raise(
            py,
            "UsageError",
            format!(
                "geometry: unknown `{geometry}`; expected one of: {}",
                names.join(", ")
            ),
        )
    })?;
    let spec = Microfacet {
        lobe: Lobe::of(d).map_err(|e| to_py(py, e))?,
        geometry: g,
    };
    // The model must be legal (e.g. smith-fast needs beckmann), as `vkbrdf table` checks.
    spec.material(0.5).map_err(|e| to_py(py, e))?;
    Ok(spec)
}

/// `table albedo`: E(μ, α) `(H, W)` and, with `average`, E_avg(α) `(H,)`, both float64.
#[pyfunction]
#[pyo3(signature = (distribution, geometry, width, height, samples, average, backend))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn table_albedo<'py>(
    py: Python<'py>,
    distribution: &str,
    geometry: &str,
    width: usize,
    height: usize,
    samples: u32,
    average: bool,
    backend: &str,
) -> PyResult<(Bound<'py, PyArray2<f64>>, Option<Bound<'py, PyArray1<f64>>>)> {
    let kind = parse_backend(py, backend)?;
    let spec = microfacet(py, distribution, geometry)?;
    let g = grid(py, width, height)?;
    check_samples(py, samples)?;
    let (e, avg) = run_engine(py, kind, |backend, cancel| {
        let mut runner = Runner::new(backend).with_cancel(cancel.clone());
        let e = albedo::directional_albedo(&mut runner, &spec, &albedo::grid_points(g)?, samples)?;
        let avg = if average {
            let alphas: Vec<f64> = (0..g.height).map(|j| texel_centre(j, g.height)).collect();
            Some(albedo::average_albedo(
                &mut runner,
                &spec,
                &alphas,
                samples,
            )?)
        } else {
            None
        };
        Ok((e, avg))
    })?;
    let e = Array2::from_shape_vec((g.height, g.width), e)
        .map_err(|err| raise(py, "Error", format!("internal: albedo shape: {err}")))?
        .into_pyarray(py);
    Ok((e, avg.map(|a| a.into_pyarray(py))))
}

fn check_samples(py: Python<'_>, samples: u32) -> PyResult<()> {
    if !(1..=1 << 26).contains(&samples) {
        return Err(raise(
            py,
            "UsageError",
            format!("samples: {samples} is out of range 1 to 2^26 (67108864)"),
        ));
    }
    Ok(())
}

/// `table dfg`: the split-sum A, B `(H, W, 2)`, float64.
#[pyfunction]
#[pyo3(signature = (distribution, geometry, width, height, samples, backend))]
fn table_dfg<'py>(
    py: Python<'py>,
    distribution: &str,
    geometry: &str,
    width: usize,
    height: usize,
    samples: u32,
    backend: &str,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let kind = parse_backend(py, backend)?;
    let spec = microfacet(py, distribution, geometry)?;
    let g = grid(py, width, height)?;
    check_samples(py, samples)?;
    let ab = run_engine(py, kind, |backend, cancel| {
        let mut runner = Runner::new(backend).with_cancel(cancel.clone());
        vkbrdf::table::dfg::split_sum(&mut runner, &spec, &albedo::grid_points(g)?, samples)
    })?;
    let flat: Vec<f64> = ab.iter().flat_map(|v| [v[0], v[1]]).collect();
    Ok(Array3::from_shape_vec((g.height, g.width, 2), flat)
        .map_err(|err| raise(py, "Error", format!("internal: dfg shape: {err}")))?
        .into_pyarray(py))
}

/// `vkbrdf check`: one dict per combination.
#[pyfunction]
#[pyo3(signature = (backend, tuples, seed, only))]
fn check<'py>(
    py: Python<'py>,
    backend: &str,
    tuples: usize,
    seed: u64,
    only: Option<String>,
) -> PyResult<Bound<'py, PyList>> {
    let kind = parse_backend(py, backend)?;
    if !(1..=vkbrdf::check::MAX_TUPLES).contains(&tuples) {
        return Err(raise(
            py,
            "UsageError",
            format!(
                "tuples: {tuples} is out of range 1 to {}",
                vkbrdf::check::MAX_TUPLES
            ),
        ));
    }
    if let Some(o) = only.as_deref() {
        let names = vkbrdf::check::combinations(seed).map_err(|e| to_py(py, e))?;
        let spectral = |m: &str| vkbrdf::check::spectral_name(m).contains(o);
        if !names.iter().any(|c| c.name.contains(o))
            && !vkbrdf::check::spectral_materials().any(spectral)
        {
            return Err(raise(
                py,
                "UsageError",
                format!("only={o:?} matches no combination (names look like `cook-torrance modern ggx-aniso smith conductor`)"),
            ));
        }
    }
    let options = vkbrdf::check::CheckOptions { tuples, seed, only };
    let (name, reports) = run_engine(py, kind, |backend, _| {
        let mut reports = vkbrdf::check::run(backend, &options, &mut |_| {})?;
        reports.extend(vkbrdf::check::spectral::run(
            backend,
            &options,
            &mut |_| {},
        )?);
        Ok((backend.name(), reports))
    })?;
    let list = PyList::empty(py);
    for r in reports {
        let d = PyDict::new(py);
        d.set_item("combination", &r.combination)?;
        d.set_item("backend", &name)?;
        d.set_item("pass", r.pass())?;
        d.set_item("tuples", r.tuples)?;
        d.set_item("max_rel", r.max_rel)?;
        d.set_item("p99_rel", r.p99_rel)?;
        let columns = PyDict::new(py);
        for (c, v) in vkbrdf::check::COLUMNS.iter().zip(r.column_max) {
            columns.set_item(*c, v)?;
        }
        d.set_item("column_max_rel", columns)?;
        d.set_item("max_used", r.max_used)?;
        d.set_item("max_rel_well_conditioned", r.max_rel_well_conditioned)?;
        d.set_item("counts_match", r.counts_match)?;
        d.set_item("saturated", r.saturated)?;
        let worst = match &r.worst {
            Some(w) => {
                let wd = PyDict::new(py);
                wd.set_item("row", w.row)?;
                wd.set_item("column", w.column)?;
                wd.set_item("value", w.value)?;
                wd.set_item("reference", w.reference)?;
                wd.set_item("allowed", w.allowed)?;
                wd.set_item("l", w.tuple.l.to_vec())?;
                wd.set_item("v", w.tuple.v.to_vec())?;
                wd.set_item("n", w.tuple.n.to_vec())?;
                wd.set_item("t", w.tuple.t.map(|t| t.to_vec()))?;
                wd.set_item("material", format!("{:?}", w.material))?;
                Some(wd)
            }
            None => None,
        };
        d.set_item("worst", worst)?;
        list.append(d)?;
    }
    Ok(list)
}

/// The module `vkbrdf._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Materials>()?;
    m.add_function(wrap_pyfunction!(evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(columns::evaluate_columns, m)?)?;
    m.add_function(wrap_pyfunction!(spike, m)?)?;
    m.add_function(wrap_pyfunction!(spectral::evaluate_spectral, m)?)?;
    m.add_function(wrap_pyfunction!(load_materials, m)?)?;
    m.add_function(wrap_pyfunction!(materials_from_file_text, m)?)?;
    m.add_function(wrap_pyfunction!(parse_materials, m)?)?;
    m.add_function(wrap_pyfunction!(presets, m)?)?;
    m.add_function(wrap_pyfunction!(table_slice, m)?)?;
    m.add_function(wrap_pyfunction!(table_albedo, m)?)?;
    m.add_function(wrap_pyfunction!(table_dfg, m)?)?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add_function(wrap_pyfunction!(fit::fit, m)?)?;
    m.add("DEFAULT_SAMPLES", albedo::DEFAULT_SAMPLES)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
