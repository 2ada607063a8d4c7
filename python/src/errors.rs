//! Rust errors as Python exceptions, with the message the CLI prints
//! ([`refract_scene::full_message`]): `FileNotFoundError` when a file is missing, `ValueError`
//! for an input out of range or of the wrong kind (an unknown method, scene or parameter, a
//! parameter value outside its range, a zero resolution), `KeyboardInterrupt` for a run Ctrl-C
//! stopped, `refract.RenderError` for the rest. A panic is caught and becomes a
//! `refract.RenderError` naming it.

use pyo3::exceptions::{PyFileNotFoundError, PyKeyboardInterrupt, PyValueError};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

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

/// Runs `work` without the GIL on this process's thread pool ([`crate::workers`]), catching a
/// panic: its error or its panic as a Python exception, then any signal (Ctrl-C) that arrived
/// meanwhile.
pub fn detached<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> refract_lab::Result<T> + Send,
) -> PyResult<T> {
    let result = as_python(py.detach(|| guarded(work)));
    py.check_signals()?;
    result
}

/// How often [`interruptible`] looks for a pending signal.
const SIGNAL_POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// What [`interruptible`] does when a signal (Ctrl-C) arrives while the work runs.
pub enum OnSignal {
    /// Raise the signal's exception at once; the work goes on in the background to its end and
    /// its result is dropped (nothing in refract stops a frame half-way).
    Abandon,
    /// Set the flag (the work's [`refract_lab::Progress::cancelled`] reads it) and wait for the
    /// work to stop at its next check, then return what it returns
    /// ([`refract_lab::LabError::Cancelled`]: `KeyboardInterrupt`), or the signal's own
    /// exception when the work finished before it looked at the flag.
    Cancel(Arc<AtomicBool>),
}

/// [`detached`] for work that may run long (a frame, an experiment): it runs on a thread of its
/// own while this one, the thread Python delivers signals to, waits without the GIL and looks
/// for a signal every 50 ms, then does what `on_signal` says. `work` owns what it uses, since
/// with [`OnSignal::Abandon`] it may outlive the call.
pub fn interruptible<T: Send + 'static>(
    py: Python<'_>,
    on_signal: OnSignal,
    work: impl FnOnce() -> refract_lab::Result<T> + Send + 'static,
) -> PyResult<T> {
    let (done, outcome) = std::sync::mpsc::sync_channel(1);
    std::thread::Builder::new()
        .name("refract-frame".to_owned())
        .spawn(move || {
            // The receiver is gone after an interrupt: nobody wants the result.
            let _ = done.send(guarded(work));
        })
        .map_err(|err| RenderError::new_err(format!("cannot start a render thread: {err}")))?;
    let mut outcome = outcome;
    // The signal taken while the work was asked to stop ([`OnSignal::Cancel`]).
    let mut taken: Option<PyErr> = None;
    loop {
        // The receiver goes into the GIL-free closure and back (a `&Receiver` is not `Send`).
        let (received, back) = py.detach(move || (outcome.recv_timeout(SIGNAL_POLL), outcome));
        outcome = back;
        match received {
            Ok(outcome) => {
                let result = as_python(outcome);
                return match taken {
                    // The work ended before it saw the flag: the signal still stands (a Ctrl-C
                    // is never lost to a result that arrived just after it).
                    Some(signal) if result.is_ok() => Err(signal),
                    Some(_) => result,
                    None => {
                        py.check_signals()?;
                        result
                    }
                };
            }
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                if taken.is_none()
                    && let Err(signal) = py.check_signals()
                {
                    match &on_signal {
                        OnSignal::Abandon => return Err(signal),
                        OnSignal::Cancel(flag) => {
                            flag.store(true, Ordering::SeqCst);
                            taken = Some(signal);
                        }
                    }
                }
            }
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                return Err(RenderError::new_err(
                    "internal error: the render thread ended without a result",
                ));
            }
        }
    }
}

/// What [`guarded`] returns: the pool could not start, or the work's result, or its panic.
type Guarded<T> = Result<std::thread::Result<refract_lab::Result<T>>, rayon::ThreadPoolBuildError>;

/// `work` on this process's pool, a panic caught.
fn guarded<T: Send>(work: impl FnOnce() -> refract_lab::Result<T> + Send) -> Guarded<T> {
    crate::workers::run(|| std::panic::catch_unwind(std::panic::AssertUnwindSafe(work)))
}

/// The outcome of [`guarded`] as a Python result.
fn as_python<T>(outcome: Guarded<T>) -> PyResult<T> {
    match outcome {
        Err(build) => Err(RenderError::new_err(format!(
            "cannot start the worker threads: {build}"
        ))),
        Ok(Ok(result)) => result.map_err(to_py),
        Ok(Err(panic)) => {
            let what = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_owned()))
                .unwrap_or_else(|| "unknown".to_owned());
            Err(RenderError::new_err(format!(
                "internal error (a panic in refract): {what}"
            )))
        }
    }
}
