//! vkbrdf's errors as the package's Python exceptions (`vkbrdf._errors`): each error kind
//! its class, which is also the built-in a caller catches (`ValueError`, `OSError`,
//! `MemoryError`, `KeyboardInterrupt`, …), carrying the CLI's message.

use pyo3::exceptions::PyKeyboardInterrupt;
use pyo3::prelude::*;
use std::path::Path;
use vkbrdf::Error;

/// The name the tuple array has in error messages (the CLI names its `.npy` file there).
pub(crate) const TUPLES: &str = "tuples";

/// An instance of the package's exception class `class` (in `vkbrdf._errors`) with
/// `message`, as a `PyErr`.
pub(crate) fn raise(py: Python<'_>, class: &str, message: String) -> PyErr {
    match error_instance(py, class, message, &[]) {
        Ok(e) => e,
        Err(e) => e,
    }
}

/// The exception `class(message)` with the attributes `attrs` set; the error of the
/// import or construction when that fails.
fn error_instance(
    py: Python<'_>,
    class: &str,
    message: String,
    attrs: &[(&str, Py<PyAny>)],
) -> PyResult<PyErr> {
    let cls = py.import("vkbrdf._errors")?.getattr(class)?;
    let value = cls.call1((message,))?;
    for (k, v) in attrs {
        value.setattr(*k, v)?;
    }
    Ok(PyErr::from_value(value))
}

/// The library's error as the package's exception: MaterialError, BatchError, FileError
/// (an OSError: FileNotFoundError / PermissionError subclasses where they apply),
/// DeviceError, TableError; `KeyboardInterrupt` for a cancelled call.
pub(crate) fn to_py(py: Python<'_>, e: Error) -> PyErr {
    let built = match &e {
        Error::Material(m) => error_instance(
            py,
            "MaterialError",
            e.to_string(),
            &[
                (
                    "source",
                    m.source_name
                        .clone()
                        .into_pyobject(py)
                        .unwrap()
                        .into_any()
                        .unbind(),
                ),
                (
                    "line",
                    m.line.into_pyobject(py).unwrap().into_any().unbind(),
                ),
                (
                    "material",
                    m.material
                        .clone()
                        .into_pyobject(py)
                        .unwrap()
                        .into_any()
                        .unbind(),
                ),
                (
                    "key",
                    m.key.clone().into_pyobject(py).unwrap().into_any().unbind(),
                ),
            ],
        ),
        Error::Batch { .. } => error_instance(py, "BatchError", e.to_string(), &[]),
        Error::InvalidTuples {
            invalid,
            total,
            first_row,
        } => error_instance(
            py,
            "BatchError",
            format!("{TUPLES}: {e} (strict=True)"),
            &[
                (
                    "invalid",
                    invalid.into_pyobject(py).unwrap().into_any().unbind(),
                ),
                (
                    "total",
                    total.into_pyobject(py).unwrap().into_any().unbind(),
                ),
                (
                    "first_invalid",
                    first_row.into_pyobject(py).unwrap().into_any().unbind(),
                ),
            ],
        ),
        Error::Io { path, source } => {
            file_error(py, source.raw_os_error(), source.to_string(), path)
        }
        Error::Output { path, message } => file_error(py, None, message.clone(), path),
        Error::Cancelled => Ok(PyKeyboardInterrupt::new_err("vkbrdf: cancelled")),
        Error::Vulkan { .. } | Error::NoDevice(_) | Error::Shader(_) | Error::Unsupported(_) => {
            error_instance(py, "DeviceError", e.to_string(), &[])
        }
        Error::Table(_) => error_instance(py, "TableError", e.to_string(), &[]),
        Error::Memory(_) => Ok(pyo3::exceptions::PyMemoryError::new_err(e.to_string())),
    };
    match built {
        Ok(err) => err,
        Err(err) => err,
    }
}

/// `FileError(errno, strerror, filename)` (or its FileNotFoundError / PermissionError
/// subclass), so `.errno`, `.strerror` and `.filename` are set as on any OSError; `message`
/// is used when the problem is not an OS error.
fn file_error(py: Python<'_>, errno: Option<i32>, message: String, path: &Path) -> PyResult<PyErr> {
    let value = py.import("vkbrdf._errors")?.getattr("file_error")?.call1((
        errno,
        message,
        path.display().to_string(),
    ))?;
    Ok(PyErr::from_value(value))
}
