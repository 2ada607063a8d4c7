//! Arguments from Python, each read by a function that names the argument in its error:
//! `TypeError("res = 'big' (str): expected (width, height), two ints")` rather than PyO3's
//! bare `'str' object is not an instance of 'tuple'`. Used with `#[pyo3(from_py_with = ...)]`
//! (and called by the property setters); ranges are checked where the value is used.
//! `refract.compare` and `refract.sweep` check theirs in Python (`refract/__init__.py`).

use std::path::PathBuf;

use pyo3::conversion::FromPyObjectOwned;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The most characters of a value's `repr` an error message quotes.
const MAX_REPR_CHARS: usize = 60;

/// `value` as Python shows it, shortened, with its type: `'big' (str)`.
fn describe(value: &Bound<'_, PyAny>) -> String {
    let repr = value
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "<no repr>".to_owned());
    let repr = match repr.char_indices().nth(MAX_REPR_CHARS) {
        Some((end, _)) => format!("{}...", &repr[..end]),
        None => repr,
    };
    let type_name = value
        .get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".to_owned());
    format!("{repr} ({type_name})")
}

/// `value` as `T`, or a `TypeError` naming `name`, the value and what was `expected`.
pub fn extract<'py, T: FromPyObjectOwned<'py>>(
    name: &str,
    expected: &str,
    value: &Bound<'py, PyAny>,
) -> PyResult<T> {
    value.extract::<T>().map_err(|_| {
        PyTypeError::new_err(format!("{name} = {}: expected {expected}", describe(value)))
    })
}

/// `value` as `T`, `None` as `None`.
fn optional<'py, T: FromPyObjectOwned<'py>>(
    name: &str,
    expected: &str,
    value: &Bound<'py, PyAny>,
) -> PyResult<Option<T>> {
    if value.is_none() {
        Ok(None)
    } else {
        extract(name, &format!("{expected} or None"), value).map(Some)
    }
}

/// What a path argument takes.
const PATH: &str = "a path (str or os.PathLike)";

/// `Scene.render`'s `method`.
pub fn method(value: &Bound<'_, PyAny>) -> PyResult<String> {
    extract(
        "method",
        "a method id, a str (see refract.methods())",
        value,
    )
}

/// `Scene.render`'s `backend`.
pub fn backend(value: &Bound<'_, PyAny>) -> PyResult<String> {
    extract("backend", "\"cpu\" or \"gpu\"", value)
}

/// `Scene.render`'s `res`.
pub fn res(value: &Bound<'_, PyAny>) -> PyResult<(i64, i64)> {
    extract("res", "(width, height), two ints", value)
}

/// `Scene.render`'s `aovs`.
pub fn aovs(value: &Bound<'_, PyAny>) -> PyResult<bool> {
    extract("aovs", "True or False", value)
}

/// `params` of `Scene.render` and `refract.compare`.
pub fn params<'py>(value: &Bound<'py, PyAny>) -> PyResult<Option<Bound<'py, PyDict>>> {
    optional(
        "params",
        "a dict of parameter names to str or int values",
        value,
    )
}

/// `Scene.load`'s `name_or_path`.
pub fn scene(value: &Bound<'_, PyAny>) -> PyResult<PathBuf> {
    extract(
        "name_or_path",
        "a built-in scene name or a path (str or os.PathLike)",
        value,
    )
}

/// `Scene.load`'s `ior`.
pub fn ior(value: &Bound<'_, PyAny>) -> PyResult<Option<f32>> {
    optional("ior", "a number", value)
}

/// The `path` of `Frame.save` and `Frame.load`.
pub fn path(value: &Bound<'_, PyAny>) -> PyResult<PathBuf> {
    extract("path", PATH, value)
}

/// `Frame.aov`'s `name`.
pub fn layer(value: &Bound<'_, PyAny>) -> PyResult<String> {
    extract("name", "a layer name, a str (see Frame.aovs)", value)
}

/// A camera vector (`eye`, `target`, `up`).
pub fn point(name: &str, value: &Bound<'_, PyAny>) -> PyResult<(f64, f64, f64)> {
    extract(name, "(x, y, z), three numbers", value)
}

/// `Scene.fov`.
pub fn fov(value: &Bound<'_, PyAny>) -> PyResult<f64> {
    extract("fov", "a number of degrees", value)
}
