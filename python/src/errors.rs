//! Rust errors as Python exceptions, with the message the CLI prints
//! ([`refract_scene::full_message`]): `FileNotFoundError` when a file is missing, `ValueError`
//! for an input out of range or of the wrong kind (an unknown method, scene or parameter, a
//! parameter value outside its range, a zero resolution), `KeyboardInterrupt` for a run Ctrl-C
//! stopped, `refract.RenderError` for the rest. A panic is caught and becomes a
//! `refract.RenderError` naming it.

use pyo3::exceptions::{PyFileNotFoundError, PyKeyboardInterrupt, PyValueError};
use pyo3::prelude::*;
use refract_lab::LabError;
use refract_scene::SceneError;

use crate::RenderError;

/// Whether a file the error chain names does not exist.
fn file_missing(error: &(dyn std::error::Error + 'static)) -> bool {
    let mut at = Some(error);
    while let Some(err) = at {
        // `LabError::Os` is transparent: its `source()` skips the OS error itself.
        // A `LabError` behind a `Context` is a `Box<LabError>` in the chain.
        let lab = err
            .downcast_ref::<LabError>()
            .or_else(|| err.downcast_ref::<Box<LabError>>().map(|b| &**b));
        let io = err.downcast_ref::<std::io::Error>().or(match lab {
            Some(LabError::Os(io)) => Some(io),
            _ => None,
        });
        if let Some(io) = io {
            return io.kind() == std::io::ErrorKind::NotFound;
        }
        at = err.source();
    }
    false
}

/// Whether the error is about an input (a value out of range or of the wrong kind).
fn bad_input(error: &LabError) -> bool {
    match error {
        LabError::Invalid(_) => true,
        LabError::Scene(scene) => matches!(
            scene,
            SceneError::Field { .. } | SceneError::Parse { .. } | SceneError::UnknownScene { .. }
        ),
        LabError::Context { source, .. } => bad_input(source),
        _ => false,
    }
}

/// The Python exception of `error`.
pub fn to_py(error: LabError) -> PyErr {
    let message = refract_scene::full_message(&error);
    if matches!(error, LabError::Cancelled) {
        PyKeyboardInterrupt::new_err(message)
    } else if file_missing(&error) {
        PyFileNotFoundError::new_err(message)
    } else if bad_input(&error) {
        PyValueError::new_err(message)
    } else {
        RenderError::new_err(message)
    }
}

/// A `ValueError` with `message`.
pub fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// Runs `work` without the GIL, catching a panic: its error or its panic as a Python
/// exception, then any signal (Ctrl-C) that arrived meanwhile.
pub fn detached<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> refract_lab::Result<T> + Send,
) -> PyResult<T> {
    let outcome = py.detach(|| std::panic::catch_unwind(std::panic::AssertUnwindSafe(work)));
    let result = match outcome {
        Ok(result) => result.map_err(to_py),
        Err(panic) => {
            let what = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_owned()))
                .unwrap_or_else(|| "unknown".to_owned());
            Err(RenderError::new_err(format!(
                "internal error (a panic in refract): {what}"
            )))
        }
    };
    py.check_signals()?;
    result
}
