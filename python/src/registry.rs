//! The registry (`refract methods`) and the built-in scenes as plain Python values.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use refract_scene::REGISTRY;
use refract_scene::registry::ParamKind;

/// Every method of the registry as a dict: `id`, `paper`, `section`, `family`, `summary`,
/// `params` (dicts: `name`, `doc`, `kind` = "choice" | "integer", `choices` or `min`/`max`,
/// `default`), `aovs` (layer names as in the EXR), `backends`.
#[pyfunction]
pub fn methods(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let rows = PyList::empty(py);
    for row in &REGISTRY {
        let method = PyDict::new(py);
        method.set_item("id", row.name)?;
        method.set_item("paper", row.paper)?;
        method.set_item("section", row.section)?;
        method.set_item("family", row.family.name())?;
        method.set_item("summary", row.summary)?;
        let params = PyList::empty(py);
        for spec in row.params {
            let param = PyDict::new(py);
            param.set_item("name", spec.name)?;
            param.set_item("doc", spec.doc)?;
            param.set_item("default", spec.default)?;
            match spec.kind {
                ParamKind::Choice(choices) => {
                    param.set_item("kind", "choice")?;
                    param.set_item("choices", choices.to_vec())?;
                }
                ParamKind::Integer { min, max } => {
                    param.set_item("kind", "integer")?;
                    param.set_item("min", min)?;
                    param.set_item("max", max)?;
                }
            }
            params.append(param)?;
        }
        method.set_item("params", params)?;
        let aovs: Vec<&str> = row.aovs.iter().map(|a| a.name()).collect();
        method.set_item("aovs", aovs)?;
        let backends: Vec<&str> = row.backends.iter().map(|b| b.id()).collect();
        method.set_item("backends", backends)?;
        rows.append(method)?;
    }
    Ok(rows)
}

/// The built-in scenes: `(name, description)` pairs, as `refract scenes` lists them.
#[pyfunction]
pub fn builtin_scenes() -> Vec<(&'static str, &'static str)> {
    refract_eval::BUILTIN_SCENES
        .iter()
        .map(|(name, line, _)| (*name, *line))
        .collect()
}
