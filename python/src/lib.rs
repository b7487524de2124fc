//! `interslice._native`: the Python extension behind the `interslice`
//! package. Every function takes and returns numpy arrays in (x, y, z) axis
//! order (nibabel's), releases the GIL while the Rust core works, and raises
//! `interslice.Error` (a `ValueError`) with the core's one-line message.
//!
//! The docstrings here are what `help(interslice.evaluate)` shows; the typed
//! signatures are in `interslice/_native.pyi`.
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

mod arrays;
mod interp;
mod metrics;
mod segment;
mod volumes;

create_exception!(
    interslice,
    Error,
    PyValueError,
    "Bad input to interslice (a file, an array, a parameter); the message is one line."
);

/// An `interslice.Error` carrying the one-line text of any error.
pub(crate) fn error(e: impl std::fmt::Display) -> PyErr {
    Error::new_err(e.to_string())
}

/// Parse an axis given as 0/1/2 or "x"/"y"/"z".
pub(crate) fn parse_axis(axis: &Bound<'_, PyAny>) -> PyResult<interslice_core::Axis> {
    use interslice_core::Axis;
    if let Ok(i) = axis.extract::<i64>() {
        return match i {
            0 => Ok(Axis::X),
            1 => Ok(Axis::Y),
            2 => Ok(Axis::Z),
            _ => Err(error(format!(
                "axis must be 0, 1, 2 or 'x', 'y', 'z', got {i}"
            ))),
        };
    }
    if let Ok(s) = axis.extract::<String>() {
        return match s.trim().to_ascii_lowercase().as_str() {
            "x" => Ok(Axis::X),
            "y" => Ok(Axis::Y),
            "z" => Ok(Axis::Z),
            _ => Err(error(format!(
                "axis must be 0, 1, 2 or 'x', 'y', 'z', got '{s}'"
            ))),
        };
    }
    Err(error("axis must be 0, 1, 2 or 'x', 'y', 'z'"))
}

/// A Python object from a serialisable value, through JSON text: the keys
/// keep their order and the floats are exactly what `--json` prints.
pub(crate) fn to_py<'py, T: serde::Serialize>(
    py: Python<'py>,
    value: &T,
) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(error)?;
    py.import("json")?.call_method1("loads", (text,))
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("Error", m.py().get_type::<Error>())?;
    m.add("DEFAULT_METHOD", interslice_interp::DEFAULT_METHOD)?;
    m.add(
        "DEFAULT_TOLERANCE",
        interslice_core::metrics::DEFAULT_TOLERANCE,
    )?;
    m.add_function(wrap_pyfunction!(volumes::read, m)?)?;
    m.add_function(wrap_pyfunction!(volumes::write, m)?)?;
    m.add_function(wrap_pyfunction!(volumes::phantom, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::overlap, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::staple, m)?)?;
    m.add_function(wrap_pyfunction!(interp::interpolate, m)?)?;
    m.add_function(wrap_pyfunction!(interp::methods, m)?)?;
    m.add_function(wrap_pyfunction!(interp::advise, m)?)?;
    m.add_function(wrap_pyfunction!(segment::threshold, m)?)?;
    Ok(())
}
