//! `refract.compare` and `refract.sweep`: the CLI's experiments, run by the same library
//! functions ([`refract_lab::compare::run`], [`refract_lab::sweep::run`]), returning their
//! records as JSON text the Python layer parses.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

use pyo3::prelude::*;
use refract_core::TirPolicy;
use refract_lab::backends::{self, GpuPolicy};
use refract_lab::jobs::CompareOptions;
use refract_lab::{Note, Progress};
use refract_scene::{BackendId, MethodId};

use crate::errors::{OnSignal, interruptible, value_error};

/// The progress of an experiment run from Python: Ctrl-C (seen by the calling thread, which
/// sets `cancel`) stops it between frames or jobs; warnings and skip notes are kept for
/// `warnings.warn`.
#[derive(Default)]
struct PythonProgress {
    notes: Mutex<Vec<String>>,
    cancel: Arc<AtomicBool>,
}

impl Progress for PythonProgress {
    fn note(&self, note: Note) {
        if matches!(note, Note::Warning(_) | Note::Skipped(_)) {
            self.notes
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .push(note.to_string());
        }
    }

    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::SeqCst)
    }
}

impl PythonProgress {
    /// Issues the kept notes as Python warnings.
    fn warn(&self, py: Python<'_>) -> PyResult<()> {
        let warnings = py.import("warnings")?;
        for note in self
            .notes
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .drain(..)
        {
            warnings.call_method1(
                "warn",
                (note, py.get_type::<pyo3::exceptions::PyUserWarning>(), 2),
            )?;
        }
        Ok(())
    }
}

/// Runs an experiment that writes under `roots` without the GIL; directories it created stay
/// on success and go on failure (as in the CLI), and only its own: an experiment in another
/// thread keeps its directories and its files being written. Its notes become warnings.
fn run_experiment<T: Send + 'static>(
    py: Python<'_>,
    roots: &[&std::path::Path],
    work: impl FnOnce(&PythonProgress) -> refract_lab::Result<T> + Send + 'static,
) -> PyResult<T> {
    let progress = Arc::new(PythonProgress::default());
    let on_signal = OnSignal::Cancel(progress.cancel.clone());
    let worker = progress.clone();
    let result = interruptible(py, on_signal, move || work(&worker));
    match &result {
        Ok(_) => refract_lab::output_dirs::keep_created_under(roots),
        Err(_) => refract_lab::output_dirs::remove_created_under(roots),
    }
    progress.warn(py)?;
    result
}

/// Every method (default: all but the reference) against the reference on each scene, as
/// `refract compare` runs it: writes images, `metrics.json`, `report.md` and `index.html` into
/// `out`; returns the records (JSON text of a list of `metrics.json` rows). The reference is
/// traced by `reference_backend`: `"cpu"` (the CPU tracer) or `"gpu"` (the WGSL tracer).
/// `engines` (`"threejs"`) render each scene with the engines themselves beside the methods
/// (`docs/engines.md`); one that cannot run is an error.
#[pyfunction]
#[pyo3(signature = (scenes, methods=None, backends=vec!["cpu".to_owned()], res=256, spp=1, frames=3, params=None, out=PathBuf::from("out"), reference_backend="cpu", engines=vec![]))]
#[allow(clippy::too_many_arguments)]
pub fn compare(
    py: Python<'_>,
    scenes: Vec<PathBuf>,
    methods: Option<Vec<String>>,
    backends: Vec<String>,
    res: i64,
    spp: i64,
    frames: i64,
    params: Option<&Bound<'_, pyo3::types::PyDict>>,
    out: PathBuf,
    reference_backend: &str,
    engines: Vec<String>,
) -> PyResult<String> {
    let params = crate::scene::param_pairs(params)?;
    let backends = backends::parse_backends(&backends)
        .map_err(|err| value_error(err.to_string().replace("--backends", "backends")))?;
    let engines = refract_lab::engines::parse_engines(&engines)
        .map_err(|err| value_error(err.to_string().replace("--engines", "engines")))?;
    let reference_backend = match reference_backend {
        "cpu" => BackendId::Trace,
        "gpu" => BackendId::Gpu,
        other => {
            return Err(value_error(format!(
                "reference_backend = {other:?}: expected \"cpu\" or \"gpu\""
            )));
        }
    };
    let checked = |name: &str, v: i64, max: u32| {
        u32::try_from(v)
            .ok()
            .filter(|v| (1..=max).contains(v))
            .ok_or_else(|| value_error(format!("{name} = {v}: expected 1 to {max}")))
    };
    let (res, spp, frames) = (
        checked("res", res, refract_scene::MAX_FRAME_SIZE)?,
        checked("spp", spp, refract_scene::MAX_SPP)?,
        checked("frames", frames, 10000)?,
    );
    if scenes.is_empty() {
        return Err(value_error("scenes: expected at least one scene"));
    }
    let ids: Vec<MethodId> = match methods {
        Some(names) => names
            .iter()
            .map(|n| n.parse())
            .collect::<Result<_, refract_scene::registry::UnknownMethod>>()
            .map_err(|err| value_error(err.to_string()))?,
        None => MethodId::approximations().collect(),
    };
    if ids.contains(&MethodId::Reference) {
        return Err(value_error(
            "methods: the reference is always rendered; list the methods to compare with it",
        ));
    }
    let root = out.clone();
    let records = run_experiment(py, &[&root], move |progress| {
        let assignments: Vec<(&str, &str)> = params
            .iter()
            .map(|(n, v)| (n.as_str(), v.as_str()))
            .collect();
        let options = CompareOptions {
            backends,
            gpu_policy: GpuPolicy::Required,
            scenes: scenes.into_iter().map(PathBuf::into_os_string).collect(),
            methods: refract_lab::compare::method_params(
                &ids,
                TirPolicy::ClampToCritical,
                &assignments,
                "params",
            )?,
            res,
            spp,
            reference_backend,
            warm_up: 1,
            frames,
            engines,
            engine_policy: GpuPolicy::Required,
            out,
        };
        refract_lab::compare::run(&options, progress)
    })?;
    serde_json::to_string(&records).map_err(|err| value_error(err.to_string()))
}

/// Runs the jobs of a sweep file (of shard `(i, n)` when given) as `refract sweep` does,
/// resuming where an earlier run stopped; returns this shard's recorded results (JSON text
/// of a list of `jobs/<id>.json` objects).
#[pyfunction]
#[pyo3(signature = (path, shard=None, out=PathBuf::from("sweep-out"), cache=None))]
pub fn sweep(
    py: Python<'_>,
    path: PathBuf,
    shard: Option<(i64, i64)>,
    out: PathBuf,
    cache: Option<PathBuf>,
) -> PyResult<String> {
    let shard = shard
        .map(|(i, n)| {
            refract_lab::sweep::parse_shard(&format!("{i}/{n}"))
                .map_err(|err| value_error(format!("shard = ({i}, {n}): {err}")))
        })
        .transpose()?;
    let args = refract_lab::sweep::SweepArgs {
        file: path,
        shard,
        out,
        cache,
        list: false,
    };
    let roots = [Some(args.out.clone()), args.cache.clone()];
    let roots: Vec<&std::path::Path> = roots.iter().flatten().map(PathBuf::as_path).collect();
    let results = run_experiment(py, &roots, move |progress| {
        refract_lab::sweep::run(&args, progress)?;
        refract_lab::sweep::shard_results(&args)
    })?;
    serde_json::to_string(&results).map_err(|err| value_error(err.to_string()))
}
