//! `refract.Frame`: a rendered frame as numpy arrays, and the metrics of one frame against the
//! reference.

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use refract_core::CameraDesc;
use refract_eval::FrameFiles;
use refract_scene::{Aov, BackendId, FrameTiming, Layer, MethodId, MethodParams, TimingSource};

use crate::errors::{detached, value_error};

/// Where a rendered frame came from: what its metrics need.
pub struct Origin {
    /// The scene (shared with the `Scene` that rendered it).
    pub scene: Arc<refract_scene::Scene>,
    /// The camera, at the frame's size.
    pub camera: CameraDesc,
    /// The method and its parameters.
    pub method: MethodParams,
    /// The backend that ran it (`trace` for the reference on the CPU tracer).
    pub backend: BackendId,
    /// Its time, as the renderer measured it.
    pub timing: FrameTiming,
}

/// A frame: linear RGB colour and the AOV layers its method wrote.
#[pyclass(module = "refract._refract", name = "Frame", frozen)]
pub struct Frame {
    frame: refract_scene::Frame,
    origin: Option<Origin>,
    color: OnceLock<Py<numpy::PyArray3<f32>>>,
}

impl Frame {
    /// A frame, rendered (`origin`) or read from a file.
    pub fn new(frame: refract_scene::Frame, origin: Option<Origin>) -> Self {
        Self {
            frame,
            origin,
            color: OnceLock::new(),
        }
    }

    fn shape(&self) -> [usize; 2] {
        [self.frame.height as usize, self.frame.width as usize]
    }
}

/// `values` as an array of `shape` (`values` is moved into numpy, not copied).
fn array<'py, T: numpy::Element, D: numpy::ndarray::IntoDimension>(
    py: Python<'py>,
    values: Vec<T>,
    shape: D,
) -> PyResult<Bound<'py, PyAny>> {
    Ok(PyArray1::from_vec(py, values).reshape(shape)?.into_any())
}

#[pymethods]
impl Frame {
    /// Width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.frame.width
    }

    /// Height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.frame.height
    }

    /// Linear RGB, `float32` of shape `(height, width, 3)`, rows from the top. The same
    /// array on every access (made on the first: the one copy out of the renderer's frame).
    #[getter]
    fn color<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        if let Some(color) = self.color.get() {
            return Ok(color.bind(py).clone().into_any());
        }
        // One memcpy (glam's Vec3 is three packed f32): 4x faster than element-wise.
        let values: Vec<f32> = bytemuck::cast_slice(&self.frame.color).to_vec();
        let [h, w] = self.shape();
        let color = PyArray1::from_vec(py, values).reshape([h, w, 3])?;
        // Another thread may have set it meanwhile: return the one kept.
        let kept = self.color.get_or_init(|| color.unbind());
        Ok(kept.bind(py).clone().into_any())
    }

    /// The colour as the CLI's PNGs show it: ACES filmic tonemapped, sRGB-encoded, `uint8` of
    /// shape `(height, width, 3)` (for figures; the metrics use the linear colour).
    fn srgb8<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let values: Vec<u8> = self
            .frame
            .color
            .iter()
            .flat_map(|&c| refract_scene::tonemap::to_srgb8(c))
            .collect();
        let [h, w] = self.shape();
        array(py, values, [h, w, 3])
    }

    /// The names of the AOV layers this frame has (as in the EXR: `T2`, `covered`, ...).
    #[getter]
    fn aovs(&self) -> Vec<&'static str> {
        self.frame.aovs().map(Aov::name).collect()
    }

    /// One AOV layer: vectors as `float32` `(height, width, 3)` (NaN where the quantity does
    /// not exist), counts as `uint32` `(height, width)`, flags as `bool` `(height, width)`.
    fn aov<'py>(
        &self,
        py: Python<'py>,
        #[pyo3(from_py_with = crate::args::layer)] name: String,
    ) -> PyResult<Bound<'py, PyAny>> {
        let name = name.as_str();
        let missing = || {
            let have = self.aovs().join(", ");
            value_error(format!(
                "aov {name:?}: this frame has no such layer; it has: {}{}",
                if have.is_empty() { "none" } else { &have },
                if self.origin.is_some() && have.is_empty() {
                    " (render with aovs=True)"
                } else {
                    ""
                }
            ))
        };
        let (_, layer) = self
            .frame
            .layers()
            .find(|(aov, _)| aov.name() == name)
            .ok_or_else(missing)?;
        let [h, w] = self.shape();
        match layer {
            Layer::Vec3(values) => {
                let flat: Vec<f32> = bytemuck::cast_slice(values).to_vec();
                array(py, flat, [h, w, 3])
            }
            Layer::Count(values) => array(py, values.clone(), [h, w]),
            Layer::Flag(values) => array(py, values.clone(), [h, w]),
        }
    }

    /// The frame's time: `{"ms": milliseconds, "source": "wall" | "gpu-timestamps"}` (every
    /// per-frame pass, not the scene's preparation, not the copy into numpy); `None` for a
    /// frame read from a file.
    #[getter]
    fn timing<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(origin) = &self.origin else {
            return Ok(None);
        };
        let timing = PyDict::new(py);
        timing.set_item("ms", origin.timing.ms)?;
        timing.set_item(
            "source",
            match origin.timing.source {
                TimingSource::Wall => "wall",
                TimingSource::GpuTimestamps => "gpu-timestamps",
            },
        )?;
        Ok(Some(timing))
    }

    /// The method id (`None` for a frame read from a file).
    #[getter]
    fn method(&self) -> Option<&'static str> {
        self.origin.as_ref().map(|o| o.method.id().name())
    }

    /// The backend that rendered it: `cpu`, `gpu` or `trace` (the reference on the CPU tracer).
    #[getter]
    fn backend(&self) -> Option<&'static str> {
        self.origin.as_ref().map(|o| o.backend.id())
    }

    /// The method's parameters, every one, as text (`{}` for a frame read from a file).
    #[getter]
    fn params(&self) -> Vec<(&'static str, String)> {
        let Some(origin) = &self.origin else {
            return Vec::new();
        };
        origin
            .method
            .id()
            .info()
            .params
            .iter()
            .filter_map(|p| origin.method.get(p.name).map(|v| (p.name, v)))
            .collect()
    }

    /// The scene's name (`None` for a frame read from a file).
    #[getter]
    fn scene(&self) -> Option<&str> {
        self.origin.as_ref().map(|o| o.scene.name.as_str())
    }

    /// Writes the frame: `.exr` (linear colour and every AOV layer, 32-bit float, as
    /// `refract render` writes it) or `.png` (tonemapped sRGB colour).
    fn save(
        &self,
        py: Python<'_>,
        #[pyo3(from_py_with = crate::args::path)] path: PathBuf,
    ) -> PyResult<()> {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let exr = match extension.as_deref() {
            Some("exr") => true,
            Some("png") => false,
            _ => {
                return Err(value_error(format!(
                    "path = {}: expected a .png or .exr file",
                    path.display()
                )));
            }
        };
        detached(py, || {
            if exr {
                self.frame.write_exr(&path)?;
            } else {
                self.frame.write_png(&path)?;
            }
            Ok(())
        })
    }

    /// Reads a frame an `.exr` of `refract render`, `Frame.save` or `refract compare` holds.
    #[staticmethod]
    fn load(
        py: Python<'_>,
        #[pyo3(from_py_with = crate::args::path)] path: PathBuf,
    ) -> PyResult<Self> {
        let frame = detached(py, || Ok(refract_scene::Frame::read_exr(&path)?))?;
        Ok(Self::new(frame, None))
    }

    fn __repr__(&self) -> String {
        match &self.origin {
            Some(o) => format!(
                "Frame({} {} on {}, {}x{}, {:.2} ms)",
                o.scene.name,
                o.method.id(),
                o.backend,
                self.frame.width,
                self.frame.height,
                o.timing.ms
            ),
            None => format!("Frame({}x{})", self.frame.width, self.frame.height),
        }
    }
}

/// The rendered origins of `frame` and `reference`, checked to be comparable.
fn comparable<'a>(frame: &'a Frame, reference: &'a Frame) -> PyResult<(&'a Origin, &'a Origin)> {
    let (Some(ours), Some(truth)) = (&frame.origin, &reference.origin) else {
        return Err(value_error(
            "metrics: both frames must be rendered by Scene.render (a frame read from a file has no camera or scene)",
        ));
    };
    if truth.method.id() != MethodId::Reference {
        return Err(value_error(format!(
            "metrics: the second frame must be the reference (it is {})",
            truth.method.id()
        )));
    }
    if !Arc::ptr_eq(&ours.scene, &truth.scene) || ours.camera != truth.camera {
        return Err(value_error(
            "metrics: the frames differ in scene, camera or resolution; render both from one Scene with one camera and res",
        ));
    }
    for (what, f) in [("frame", frame), ("reference", reference)] {
        if !f.frame.has(Aov::Covered) {
            return Err(value_error(format!(
                "metrics: the {what} has no AOV layers; render it with aovs=True"
            )));
        }
    }
    Ok((ours, truth))
}

/// `refract_eval::metrics::evaluate_method` of two comparable frames (`ours` is the frame's
/// origin).
fn evaluate(
    frame: &Frame,
    reference: &Frame,
    ours: &Origin,
) -> refract_lab::Result<(
    refract_eval::metrics::MetricsRecord,
    refract_eval::metrics::ErrorMaps,
)> {
    let camera = refract_core::Camera::new(ours.camera)
        .map_err(|err| refract_lab::LabError::invalid(format!("camera: {err}")))?;
    Ok(refract_eval::metrics::evaluate_method(
        &reference.frame,
        &frame.frame,
        &camera,
        &ours.scene,
        &ours.method,
    ))
}

/// The metrics of `frame` against `reference` (both rendered with `aovs=True` from one scene
/// and camera): a dict with every field of `metrics.json` (docs/metrics.md), as
/// `refract compare` computes it.
#[pyfunction]
pub fn metrics<'py>(
    py: Python<'py>,
    frame: &Frame,
    reference: &Frame,
) -> PyResult<Bound<'py, PyAny>> {
    let (ours, _) = comparable(frame, reference)?;
    let json = detached(py, || {
        let (mut record, _) = evaluate(frame, reference, ours)?;
        record.scene.clone_from(&ours.scene.name);
        record.method = ours.method.id().name().to_owned();
        record.backend = ours.backend.id().to_owned();
        record.params = ours.method.describe();
        record.ms_per_frame = Some(ours.timing.ms);
        Ok(serde_json::to_string(&record)?)
    })?;
    py.import("json")?.call_method1("loads", (json,))
}

/// The per-pixel error maps of `frame` against `reference` (as `metrics`), `float32`
/// `(height, width)` each, NaN where undefined: `flip` (FLIP, 0-1), `t2_deg` (angle between
/// the `T2` directions, degrees), `p2_rel` (distance between the exit points over the
/// refractor's diameter).
#[pyfunction]
pub fn error_maps<'py>(
    py: Python<'py>,
    frame: &Frame,
    reference: &Frame,
) -> PyResult<Bound<'py, PyDict>> {
    let (ours, _) = comparable(frame, reference)?;
    let maps = detached(py, || Ok(evaluate(frame, reference, ours)?.1))?;
    let shape = frame.shape();
    let out = PyDict::new(py);
    out.set_item("flip", array(py, maps.flip, shape)?)?;
    out.set_item("t2_deg", array(py, maps.t2_deg, shape)?)?;
    out.set_item("p2_rel", array(py, maps.p2_rel, shape)?)?;
    Ok(out)
}
