//! `refract.Scene`: a loaded scene with a settable camera, rendering frames.

use std::sync::{Arc, Mutex, PoisonError};

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use refract_core::CameraDesc;
use refract_lab::render::{FrameRequest, MAX_SIZE, Renders};
use refract_scene::{BackendId, FrameOutputs, MethodId, MethodParams};

use crate::args;
use crate::errors::{OnSignal, detached, interruptible, to_py, value_error};
use crate::frame::{Frame, Origin};
use crate::workers::ForkLocal;

/// A scene: a built-in one or a `.toml` scene file, with its own camera.
///
/// Renders share one prepared renderer per backend (the first frame on a backend prepares
/// the scene; later frames, of any camera or method, do not).
#[pyclass(module = "refract._refract", name = "Scene", frozen)]
pub struct Scene {
    scene: Arc<refract_scene::Scene>,
    /// Prepared renderers; a forked child prepares its own.
    renders: Arc<Mutex<ForkLocal<Renders>>>,
    camera: Mutex<CameraDesc>,
    warnings: Vec<String>,
}

/// `(x, y, z)` as a vector, each coordinate finite and at most
/// [`refract_eval::scene_file::MAX_COORDINATE`] in magnitude.
fn point(name: &str, (x, y, z): (f64, f64, f64)) -> PyResult<glam::Vec3> {
    let limit = f64::from(refract_eval::scene_file::MAX_COORDINATE);
    if [x, y, z].iter().all(|c| c.is_finite() && c.abs() <= limit) {
        Ok(glam::Vec3::new(x as f32, y as f32, z as f32))
    } else {
        Err(value_error(format!(
            "camera {name} = ({x}, {y}, {z}): expected finite coordinates of magnitude at most {limit:e}"
        )))
    }
}

fn tuple(v: glam::Vec3) -> (f32, f32, f32) {
    (v.x, v.y, v.z)
}

/// `params` (a dict of parameter names to `str` or `int` values, as `refract.methods()` lists
/// them) as `(name, value)` text pairs, as the CLI's `--param NAME=VALUE` takes them.
pub fn param_pairs(params: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, String)>> {
    let mut pairs = Vec::new();
    for (name, value) in params.into_iter().flat_map(|d| d.iter()) {
        let name: String = name
            .extract()
            .map_err(|_| PyTypeError::new_err("params: expected str keys (parameter names)"))?;
        let text = if value.is_instance_of::<pyo3::types::PyBool>() {
            None
        } else if let Ok(text) = value.extract::<String>() {
            Some(text)
        } else {
            value.extract::<i64>().ok().map(|v| v.to_string())
        };
        let text = text.ok_or_else(|| {
            PyTypeError::new_err(format!(
                "params[{name:?}]: expected a str or an int (see refract.methods())"
            ))
        })?;
        pairs.push((name, text));
    }
    Ok(pairs)
}

/// A method's parameters: its defaults with `params` applied.
fn method_params(id: MethodId, params: Option<&Bound<'_, PyDict>>) -> PyResult<MethodParams> {
    let mut method = MethodParams::defaults(id);
    let pairs = param_pairs(params)?;
    method
        .set_all(
            pairs
                .iter()
                .map(|(name, text)| (name.as_str(), text.as_str())),
            "params",
        )
        .map_err(|err| to_py(err.into()))?;
    Ok(method)
}

/// `res` as a checked `(width, height)`.
fn resolution((w, h): (i64, i64)) -> PyResult<(u32, u32)> {
    let ok = |v: i64| u32::try_from(v).ok().filter(|v| (1..=MAX_SIZE).contains(v));
    ok(w).zip(ok(h)).ok_or_else(|| {
        value_error(format!(
            "res = ({w}, {h}): expected a width and a height from 1 to {MAX_SIZE}"
        ))
    })
}

impl Scene {
    fn camera(&self) -> CameraDesc {
        *self.camera.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Sets the camera to `desc` if it makes a valid camera.
    fn set_camera(&self, desc: CameraDesc) -> PyResult<()> {
        refract_core::Camera::new(desc).map_err(|err| value_error(format!("camera: {err}")))?;
        *self.camera.lock().unwrap_or_else(PoisonError::into_inner) = desc;
        Ok(())
    }
}

#[pymethods]
impl Scene {
    /// Loads a built-in scene (see `Scene.builtin_names()`) or a `.toml` scene file
    /// (docs/scenes.md); `ior` replaces the refractor's index of refraction.
    #[staticmethod]
    #[pyo3(signature = (name_or_path, ior=None))]
    fn load(
        py: Python<'_>,
        #[pyo3(from_py_with = args::scene)] name_or_path: std::path::PathBuf,
        #[pyo3(from_py_with = args::ior)] ior: Option<f32>,
    ) -> PyResult<Self> {
        let loaded = detached(py, move || {
            let mut loaded = refract_eval::load_scene(&name_or_path)?;
            if let Some(ior) = ior {
                loaded.scene.refractor.set_ior(ior)?;
            }
            Ok(loaded)
        })?;
        let scene = Arc::new(loaded.scene);
        Ok(Self {
            camera: Mutex::new(scene.camera),
            renders: Arc::new(Mutex::new(ForkLocal::new(Renders::new(scene.clone())))),
            scene,
            warnings: loaded.warnings,
        })
    }

    /// The built-in scenes' names.
    #[staticmethod]
    fn builtin_names() -> Vec<&'static str> {
        refract_eval::BUILTIN_SCENES
            .iter()
            .map(|(name, _, _)| *name)
            .collect()
    }

    /// The scene's name (built-in name or file stem).
    #[getter]
    fn name(&self) -> &str {
        &self.scene.name
    }

    /// The refractor's index of refraction.
    #[getter]
    fn ior(&self) -> f32 {
        self.scene.refractor.ior()
    }

    /// Each refractor's roughness (glTF's `roughnessFactor`, 0 to 1; 0 is smooth), in the
    /// scene's refractor order; only the reference traces it (docs/reference.md).
    #[getter]
    fn roughness(&self) -> Vec<f32> {
        self.scene.refractors().map(|r| r.roughness()).collect()
    }

    /// Each refractor's Abbe number `V_d` (`inf`: no dispersion; glTF's
    /// `KHR_materials_dispersion` is `20 / V_d`), in the scene's refractor order; only the
    /// reference renders dispersion, spectrally (docs/reference.md).
    #[getter]
    fn abbe(&self) -> Vec<f32> {
        self.scene.refractors().map(|r| r.abbe()).collect()
    }

    /// What loading the scene fixed or noticed (mesh and environment quirks).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// The eye position (world space), `(x, y, z)`.
    #[getter]
    fn eye(&self) -> (f32, f32, f32) {
        tuple(self.camera().eye)
    }

    #[setter]
    fn set_eye(&self, eye: &Bound<'_, PyAny>) -> PyResult<()> {
        let eye = point("eye", args::point("eye", eye)?)?;
        self.set_camera(CameraDesc {
            eye,
            ..self.camera()
        })
    }

    /// The point looked at (world space), `(x, y, z)`.
    #[getter]
    fn target(&self) -> (f32, f32, f32) {
        tuple(self.camera().target)
    }

    #[setter]
    fn set_target(&self, target: &Bound<'_, PyAny>) -> PyResult<()> {
        let target = point("target", args::point("target", target)?)?;
        self.set_camera(CameraDesc {
            target,
            ..self.camera()
        })
    }

    /// The up direction (world space), `(x, y, z)`; not parallel to `target - eye`.
    #[getter]
    fn up(&self) -> (f32, f32, f32) {
        tuple(self.camera().up)
    }

    #[setter]
    fn set_up(&self, up: &Bound<'_, PyAny>) -> PyResult<()> {
        let up = point("up", args::point("up", up)?)?;
        self.set_camera(CameraDesc {
            up,
            ..self.camera()
        })
    }

    /// The vertical field of view in degrees, in `(0, 180)`.
    #[getter]
    fn fov(&self) -> f32 {
        self.camera().fov_y.to_degrees()
    }

    #[setter]
    fn set_fov(&self, degrees: &Bound<'_, PyAny>) -> PyResult<()> {
        let degrees = args::fov(degrees)?;
        if !(degrees > 0.0 && degrees < 180.0) {
            return Err(value_error(format!(
                "fov = {degrees}: expected degrees in (0, 180)"
            )));
        }
        self.set_camera(CameraDesc {
            fov_y: (degrees as f32).to_radians(),
            ..self.camera()
        })
    }

    /// Renders one frame of `method` (a registry id, or `"reference"`) on `backend` (`"cpu"`
    /// or `"gpu"`; the reference runs on the CPU tracer, or with `"gpu"` on the GPU's) at `res = (width, height)`, with
    /// `params` (names and values as `refract.methods()` lists them) applied to the method's
    /// defaults; `aovs=True` also computes the method's AOV layers (needed by
    /// `refract.metrics`). The GIL is released while rendering.
    #[pyo3(
        signature = (method, backend="cpu".to_owned(), res=(512, 512), params=None, aovs=false),
        text_signature = "(self, method, backend='cpu', res=(512, 512), params=None, aovs=False)"
    )]
    fn render(
        &self,
        py: Python<'_>,
        #[pyo3(from_py_with = args::method)] method: String,
        #[pyo3(from_py_with = args::backend)] backend: String,
        #[pyo3(from_py_with = args::res)] res: (i64, i64),
        #[pyo3(from_py_with = args::params)] params: Option<Bound<'_, PyDict>>,
        #[pyo3(from_py_with = args::aovs)] aovs: bool,
    ) -> PyResult<Frame> {
        let params = params.as_ref();
        let id: MethodId = method
            .parse()
            .map_err(|err: refract_scene::registry::UnknownMethod| value_error(err.to_string()))?;
        let backend = match backend.as_str() {
            "cpu" => BackendId::Cpu,
            "gpu" => BackendId::Gpu,
            other => {
                return Err(value_error(format!(
                    "backend = {other:?}: expected \"cpu\" or \"gpu\""
                )));
            }
        };
        let (width, height) = resolution(res)?;
        let method = method_params(id, params)?;
        let camera = CameraDesc {
            width,
            height,
            ..self.camera()
        };
        let outputs = if aovs {
            FrameOutputs::ColorAndAovs
        } else {
            FrameOutputs::Color
        };
        let (renders, scene) = (self.renders.clone(), self.scene.clone());
        let request_method = method;
        let (frame, timing) = interruptible(py, OnSignal::Abandon, move || {
            let mut renders = renders.lock().unwrap_or_else(PoisonError::into_inner);
            let renders = renders.get_mut(|| Renders::new(scene));
            let mut frame = refract_scene::Frame::default();
            let request = FrameRequest {
                method: &request_method,
                backend,
                camera,
                outputs,
            };
            let timing = renders.render(&request, &mut frame)?;
            Ok((frame, timing))
        })?;
        let backend = if id == MethodId::Reference && backend == BackendId::Cpu {
            BackendId::Trace
        } else {
            backend
        };
        Ok(Frame::new(
            frame,
            Some(Origin {
                scene: self.scene.clone(),
                camera,
                method,
                backend,
                timing,
            }),
        ))
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({:?}, ior={}, eye={:?}, target={:?}, fov={:.1})",
            self.scene.name,
            self.ior(),
            self.eye(),
            self.target(),
            self.fov()
        )
    }
}
