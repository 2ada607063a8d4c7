//! One frame of one method (or the reference) of one scene, seen by one camera: what
//! `refract render` and the Python package's `Scene.render` call, so that both produce the same
//! frame bit for bit.
//!
//! A [`Renders`] keeps one prepared renderer per backend for its scene: a script that orbits
//! the camera or renders several methods prepares the scene once per backend.

use std::sync::Arc;

use refract_core::CameraDesc;
use refract_cpu::CpuRenderer;
use refract_gpu::GpuRenderer;
use refract_scene::{
    BackendId, Frame, FrameOutputs, FrameTiming, MethodId, MethodParams, Renderer, Scene,
};
use refract_trace::ReferenceRenderer;

/// The largest width or height of a rendered frame (pixels): [`refract_scene::MAX_FRAME_SIZE`].
pub const MAX_SIZE: u32 = refract_scene::MAX_FRAME_SIZE;

/// The frames one scene renders, with a renderer per backend prepared once.
pub struct Renders {
    scene: Arc<Scene>,
    renderers: Vec<Box<dyn Renderer + Send>>,
    adapter: Option<String>,
}

/// What [`Renders::render`] renders.
#[derive(Clone, Debug)]
pub struct FrameRequest<'a> {
    /// The method and its parameters (`MethodParams::Reference` for the reference).
    pub method: &'a MethodParams,
    /// The backend of a method: `cpu` or `gpu` (`trace` is refused for a method). For the
    /// reference, `gpu` runs the GPU tracer (`refract_gpu::reference`) and anything else the CPU
    /// tracer.
    pub backend: BackendId,
    /// The camera; its `width` and `height` are the frame's, each in `1..=`[`MAX_SIZE`].
    pub camera: CameraDesc,
    /// Colour only, or colour and the method's AOV layers.
    pub outputs: FrameOutputs,
}

impl Renders {
    /// No renderer is opened until a frame asks for one.
    pub fn new(scene: Arc<Scene>) -> Self {
        Self {
            scene,
            renderers: Vec::new(),
            adapter: None,
        }
    }

    /// The GPU adapter the GPU renders ran on (name, graphics API, device type), once one has
    /// opened; `None` before or without one.
    pub fn adapter(&self) -> Option<&str> {
        self.adapter.as_deref()
    }

    /// The scene.
    pub fn scene(&self) -> &Arc<Scene> {
        &self.scene
    }

    /// The backend that runs `request`: the tracer for the reference.
    fn backend_of(request: &FrameRequest<'_>) -> crate::Result<BackendId> {
        if request.method.id() != MethodId::Reference {
            crate::ensure!(
                request.backend != BackendId::Trace,
                "backend `trace`: the tracer runs the reference only; expected cpu or gpu"
            );
            return Ok(request.backend);
        }
        // The reference runs on the tracer (asked for as cpu) or on the GPU
        // (refract_gpu::reference, every mode and sample count).
        Ok(match request.backend {
            BackendId::Gpu => BackendId::Gpu,
            _ => BackendId::Trace,
        })
    }

    /// The prepared renderer of `backend`, opened and prepared on first use.
    fn renderer(&mut self, backend: BackendId) -> crate::Result<&mut Box<dyn Renderer + Send>> {
        let at = match self.renderers.iter().position(|r| r.backend() == backend) {
            Some(at) => at,
            None => {
                let mut renderer: Box<dyn Renderer + Send> = match backend {
                    BackendId::Cpu => Box::new(CpuRenderer::new()),
                    BackendId::Gpu => {
                        let gpu = GpuRenderer::new()?;
                        let info = &gpu.context().info;
                        self.adapter = Some(format!(
                            "{} ({:?}, {:?})",
                            info.name, info.backend, info.device_type
                        ));
                        Box::new(gpu)
                    }
                    BackendId::Trace => Box::new(ReferenceRenderer::new()),
                };
                renderer.prepare(&self.scene)?;
                self.renderers.push(renderer);
                self.renderers.len() - 1
            }
        };
        Ok(&mut self.renderers[at])
    }

    /// Renders `request` into `frame` (its memory reused): checks the size, that the frame fits
    /// in memory, that the backend runs the method and that the scene suits it, then renders.
    /// Returns the frame's time as the renderer measured it.
    pub fn render(
        &mut self,
        request: &FrameRequest<'_>,
        frame: &mut Frame,
    ) -> crate::Result<FrameTiming> {
        let (width, height) = (request.camera.width, request.camera.height);
        crate::ensure!(
            (1..=MAX_SIZE).contains(&width) && (1..=MAX_SIZE).contains(&height),
            "resolution {width}x{height}: expected a width and a height from 1 to {MAX_SIZE}"
        );
        let backend = Self::backend_of(request)?;
        crate::memory::check_method(
            "this render",
            request.method,
            width,
            height,
            request.outputs == FrameOutputs::ColorAndAovs,
            &[backend],
        )?;
        let id = request.method.id();
        if let Err(reason) = refract_scene::scene_support(id, &self.scene) {
            crate::bail!("method `{id}` on scene `{}`: {reason}", self.scene.name);
        }
        let camera = refract_core::Camera::new(request.camera)
            .map_err(|err| crate::LabError::invalid(format!("camera: {err}")))?;
        let renderer = self.renderer(backend)?;
        if !renderer.supports(id) {
            return Err(refract_scene::RenderError::Unsupported {
                backend,
                method: id,
            }
            .into());
        }
        Ok(renderer.render(&camera, request.method, request.outputs, frame)?)
    }
}
