//! The viewer's exact reference, refined progressively in a background thread while the camera
//! rests: 1/8, 1/4, 1/2, then full resolution (the last with its AOVs, for the error maps); a
//! newer request (the camera moved) abandons older work between levels. It is traced on the GPU
//! (`refract_gpu::reference`, on the viewer's device) when the method runs there, else by the
//! CPU tracer; a GPU failure falls back to the CPU and says why in the level.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};

use refract_core::{Camera, CameraDesc};
use refract_gpu::GpuContext;
use refract_gpu::reference::{GpuReference, ReferencePipeline};
use refract_scene::{
    BackendId, Frame, FrameOutputs, MethodId, MethodParams, RenderError, Renderer, Scene,
    TraceSettings,
};
use refract_trace::ReferenceRenderer;

/// One level of a reference: the frame at `scale` of the requested size.
pub struct Level {
    /// The request it answers.
    pub generation: u64,
    /// The frame (colour; AOVs too at full resolution).
    pub frame: Frame,
    /// Whether this is the full-resolution level.
    pub full: bool,
    /// Where it was traced: [`BackendId::Gpu`] or [`BackendId::Trace`] (the CPU tracer).
    pub backend: BackendId,
    /// Why a GPU request was traced on the CPU instead.
    pub gpu_failure: Option<String>,
}

struct Request {
    generation: u64,
    scene: Arc<Scene>,
    camera: CameraDesc,
    /// The viewer's device when the method runs on the GPU.
    gpu: Option<GpuContext>,
}

/// The background worker.
pub struct ProgressiveReference {
    /// `None` once dropped (closing the channel ends the worker).
    requests: Option<Sender<Request>>,
    levels: Receiver<Level>,
    latest: Arc<AtomicU64>,
    /// The last request: its camera, whether on the GPU, its generation.
    requested: Option<(CameraDesc, bool, u64)>,
    /// The worker, joined on drop so that its GPU objects (on the viewer's device) are released
    /// before the device and the process go.
    worker: Option<std::thread::JoinHandle<()>>,
}

impl Drop for ProgressiveReference {
    /// Abandons the current request (the worker stops after the level it is tracing), closes
    /// the channel and waits for the worker.
    fn drop(&mut self) {
        self.latest.fetch_add(1, Ordering::Relaxed);
        self.requests = None;
        if let Some(worker) = self.worker.take() {
            let _ = worker.join();
        }
    }
}

/// The worker's GPU tracer: the pipeline compiled once per device, the scene uploaded once per
/// scene.
struct GpuTracer {
    context: GpuContext,
    pipeline: Arc<ReferencePipeline>,
    scene: Option<(Arc<Scene>, GpuReference)>,
}

impl GpuTracer {
    fn render(
        &mut self,
        scene: &Arc<Scene>,
        camera: &Camera,
        settings: &TraceSettings,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let reference = match &mut self.scene {
            Some((uploaded, reference)) if Arc::ptr_eq(uploaded, scene) => reference,
            slot => {
                let reference =
                    GpuReference::with_pipeline(&self.context, Arc::clone(&self.pipeline), scene)?;
                &mut slot.insert((Arc::clone(scene), reference)).1
            }
        };
        reference.render(&self.context, camera, settings, outputs, frame)
    }
}

/// The tracers of the worker thread.
struct Tracers {
    cpu: ReferenceRenderer,
    cpu_scene: Option<Arc<Scene>>,
    gpu: Option<GpuTracer>,
    settings: TraceSettings,
}

impl Tracers {
    /// Traces one level on the GPU when `gpu` is given (falling back to the CPU with the
    /// reason), else on the CPU.
    fn render(
        &mut self,
        request: &Request,
        camera: &Camera,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<(BackendId, Option<String>), RenderError> {
        let mut failure = None;
        if let Some(context) = &request.gpu {
            let settings = self.settings;
            let traced = self
                .gpu_tracer(context)
                .and_then(|gpu| gpu.render(&request.scene, camera, &settings, outputs, frame));
            match traced {
                Ok(()) => return Ok((BackendId::Gpu, None)),
                Err(err) => failure = Some(refract_scene::full_message(&err)),
            }
        }
        if !self
            .cpu_scene
            .as_ref()
            .is_some_and(|s| Arc::ptr_eq(s, &request.scene))
        {
            self.cpu.prepare(&request.scene)?;
            self.cpu_scene = Some(Arc::clone(&request.scene));
        }
        self.cpu.render(
            camera,
            &MethodParams::Reference(self.settings),
            outputs,
            frame,
        )?;
        Ok((BackendId::Trace, failure))
    }

    /// The GPU tracer on `context`'s device, compiled on first use.
    fn gpu_tracer(&mut self, context: &GpuContext) -> Result<&mut GpuTracer, RenderError> {
        Ok(match &mut self.gpu {
            Some(gpu) => gpu,
            empty => empty.insert(GpuTracer {
                context: context.clone(),
                pipeline: Arc::new(ReferencePipeline::new(context)?),
                scene: None,
            }),
        })
    }
}

impl ProgressiveReference {
    /// Starts the worker thread.
    pub fn start() -> Self {
        let (requests, inbox) = channel::<Request>();
        let (outbox, levels) = channel::<Level>();
        let latest = Arc::new(AtomicU64::new(0));
        let current = Arc::clone(&latest);
        let worker = std::thread::spawn(move || {
            let MethodParams::Reference(settings) = MethodParams::defaults(MethodId::Reference)
            else {
                return;
            };
            let mut tracers = Tracers {
                cpu: ReferenceRenderer::new(),
                cpu_scene: None,
                gpu: None,
                settings,
            };
            while let Ok(mut request) = inbox.recv() {
                // Only the newest request matters.
                while let Ok(newer) = inbox.try_recv() {
                    request = newer;
                }
                for divisor in [8u32, 4, 2, 1] {
                    if current.load(Ordering::Relaxed) != request.generation {
                        break;
                    }
                    let desc = CameraDesc {
                        width: (request.camera.width / divisor).max(1),
                        height: (request.camera.height / divisor).max(1),
                        ..request.camera
                    };
                    let Ok(camera) = Camera::new(desc) else {
                        break;
                    };
                    let outputs = if divisor == 1 {
                        FrameOutputs::ColorAndAovs
                    } else {
                        FrameOutputs::Color
                    };
                    let mut frame = Frame::default();
                    let Ok((backend, gpu_failure)) =
                        tracers.render(&request, &camera, outputs, &mut frame)
                    else {
                        break;
                    };
                    let level = Level {
                        generation: request.generation,
                        frame,
                        full: divisor == 1,
                        backend,
                        gpu_failure,
                    };
                    if outbox.send(level).is_err() {
                        return;
                    }
                }
            }
        });
        Self {
            requests: Some(requests),
            levels,
            latest,
            requested: None,
            worker: Some(worker),
        }
    }

    /// Asks for the reference of `camera`, traced on `gpu`'s device when given (no-op when it
    /// is the one last asked for); returns the request's generation.
    pub fn request(
        &mut self,
        scene: &Arc<Scene>,
        camera: CameraDesc,
        gpu: Option<&GpuContext>,
        force: bool,
    ) -> u64 {
        if let Some((previous, on_gpu, generation)) = self.requested
            && previous == camera
            && on_gpu == gpu.is_some()
            && !force
        {
            return generation;
        }
        let generation = self.latest.fetch_add(1, Ordering::Relaxed) + 1;
        self.requested = Some((camera, gpu.is_some(), generation));
        let Some(requests) = &self.requests else {
            return generation;
        };
        let _ = requests.send(Request {
            generation,
            scene: Arc::clone(scene),
            camera,
            gpu: gpu.cloned(),
        });
        generation
    }

    /// The newest finished level of `generation`, if any arrived.
    pub fn poll(&self, generation: u64) -> Option<Level> {
        let mut newest = None;
        while let Ok(level) = self.levels.try_recv() {
            if level.generation == generation {
                newest = Some(level);
            }
        }
        newest
    }
}
