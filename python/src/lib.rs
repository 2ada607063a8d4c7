//! `refract._refract`: the extension module behind `import refract` (python/refract/).
//!
//! Thin bindings over `refract-lab`, the library the `refract` CLI calls: a render from Python
//! runs [`refract_lab::render::Renders`] as `refract render` does, `compare` and `sweep` run
//! [`refract_lab::compare::run`] and [`refract_lab::sweep::run`]. The Python layer
//! (`refract/__init__.py`) turns the plain dicts returned here into dataclasses and records.
//!
//! Every call that renders releases the GIL; every Rust error becomes a Python exception
//! ([`errors`]) and a panic becomes a `refract.RenderError`, never a crash of the interpreter.

#![deny(unsafe_code)]

mod args;
mod errors;
mod experiments;
mod frame;
mod registry;
mod scene;
mod tracer;
mod workers;

use pyo3::prelude::*;

pyo3::create_exception!(
    refract,
    RenderError,
    pyo3::exceptions::PyRuntimeError,
    "A scene could not be prepared or a frame rendered (no GPU adapter, an unsupported method, \
     a file that could not be written, ...). The message is the one the CLI prints."
);

/// The extension module.
#[pymodule]
fn _refract(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // An older CPU than the build's instruction set: an ImportError that says how to rebuild,
    // rather than an illegal instruction later.
    refract_cpu::check_instruction_set()
        .map_err(|e| pyo3::exceptions::PyImportError::new_err(e.to_string()))?;
    m.add("RenderError", m.py().get_type::<RenderError>())?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<frame::Frame>()?;
    m.add_class::<tracer::Tracer>()?;
    m.add_function(wrap_pyfunction!(registry::methods, m)?)?;
    m.add_function(wrap_pyfunction!(registry::builtin_scenes, m)?)?;
    m.add_function(wrap_pyfunction!(frame::metrics, m)?)?;
    m.add_function(wrap_pyfunction!(frame::error_maps, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::compare, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::sweep, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
