//! The GPU backend's unit of extension: a method family. A family owns its pipelines and says
//! how to allocate its targets, whether targets of an earlier frame still fit, how to encode a
//! frame and how to read it back; [`run_frame`], written once, does the rest (reuse or
//! allocate, the CPU part of the frame, encode, submit, wait, time, read back).
//! [`crate::GpuRenderer`] holds one [`FamilySlot`] per family and picks it with one exhaustive
//! `match` over [`refract_scene::MethodParams`].

use std::sync::Arc;
use std::time::Instant;

use refract_core::Camera;
use refract_scene::{
    BackendId, Frame, FrameOutputs, FrameTiming, MethodId, MethodParams, Refractor, RenderError,
    Scene, TimingSource,
};

use crate::context::{GpuContext, GpuError};
use crate::passes::raster::RasterPipelines;
use crate::scene_buffers::GpuScene;
use crate::timestamps::Timestamps;

/// What every family's frame reads: the device, the shared raster pipelines, the scene (as
/// loaded and as uploaded), the camera, the method and what the frame writes.
#[derive(Clone, Copy)]
pub(crate) struct GpuFrameCx<'a> {
    pub context: &'a GpuContext,
    pub raster: &'a RasterPipelines,
    pub scene: &'a Scene,
    pub gpu_scene: &'a GpuScene,
    pub camera: &'a Camera,
    /// The method rendered: its pipeline, and its registry row's AOV layers.
    pub method: MethodId,
    /// All of its parameters (for messages).
    pub params: &'a MethodParams,
    pub outputs: FrameOutputs,
    /// Timestamp queries around the frame's passes, where the adapter has them.
    pub timestamps: Option<&'a Timestamps>,
    /// Whether the frame's outputs are copied to the readback buffers (and read into a
    /// [`Frame`]); without, the colour stays in [`GpuFamily::color`] for a later GPU pass (the
    /// viewer's window).
    pub readback: bool,
    /// The wavelength the frame traces (nm), `None` for the d line: every refractor's index is
    /// [`Refractor::ior_at`] it ([`refract_scene::render_dispersive`]).
    pub lambda_nm: Option<f32>,
    /// The previous frame rendered the same scene, camera and method at another wavelength of
    /// one dispersive frame: the family may keep the passes that do not depend on the index
    /// (the distance map's layers, the depth-peeled layers).
    pub repeat: bool,
}

impl GpuFrameCx<'_> {
    /// The frame's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.camera.width(), self.camera.height())
    }

    /// `refractor`'s index of refraction in this frame.
    pub fn ior(&self, refractor: &Refractor) -> f32 {
        refractor.ior_at(self.lambda_nm)
    }
}

/// A method family on the GPU.
pub(crate) trait GpuFamily {
    /// The parameters of one run of a method of the family.
    type Params;
    /// The family's render targets and buffers of one size (kept across frames).
    type Targets;
    /// The label of the frame's command encoder.
    const LABEL: &'static str;
    /// Whether the frame is timed by its passes' timestamp queries (where the adapter has
    /// them); `false`: by the wall clock, for a family that submits more than one command
    /// buffer a frame.
    const TIMESTAMPS: bool = true;

    /// Compiles the family's pipelines (with the backend's shared raster pipelines at hand).
    fn create(device: &wgpu::Device, raster: &RasterPipelines) -> Self
    where
        Self: Sized;

    /// Prepares per-scene state besides the uploaded scene (targets are dropped by the caller:
    /// they are bound to the old scene's buffers).
    fn prepare(&mut self, _scene: &Arc<Scene>) {}

    /// Whether `targets` serve a frame of `cx` with `params`.
    fn fits(&self, targets: &Self::Targets, cx: &GpuFrameCx<'_>, params: &Self::Params) -> bool;

    /// New targets for a frame of `cx` with `params`, checked against the adapter's limits.
    fn allocate(
        &self,
        cx: &GpuFrameCx<'_>,
        params: &Self::Params,
    ) -> Result<Self::Targets, GpuError>;

    /// The CPU part of a frame, before its targets are reused or allocated and its passes
    /// encoded (`pvrr`'s per-vertex plan; the reference's upload of a new scene); its time is
    /// part of the frame's.
    fn plan(&mut self, _cx: &GpuFrameCx<'_>, _params: &Self::Params) -> Result<(), RenderError> {
        Ok(())
    }

    /// Encodes every per-frame pass and the copies to the readback buffers.
    fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        params: &Self::Params,
        targets: &mut Self::Targets,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), RenderError>;

    /// The colour of the last frame encoded with `targets`: one `vec4<f32>` per pixel (RGB
    /// linear radiance, A unused), row-major from the top.
    fn color<'t>(&self, targets: &'t Self::Targets) -> &'t wgpu::Buffer;

    /// Reads the submitted frame into `frame`: the colour and, with
    /// [`FrameOutputs::ColorAndAovs`], exactly the layers of the method's registry row.
    fn read(
        &self,
        cx: &GpuFrameCx<'_>,
        targets: &Self::Targets,
        frame: &mut Frame,
    ) -> Result<(), RenderError>;
}

/// A family's targets could not be allocated (out of memory, a limit of the adapter).
#[derive(Debug, thiserror::Error)]
#[error("{method} ({params}): cannot allocate its GPU targets for a {width}x{height} frame")]
struct AllocationError {
    method: MethodId,
    params: String,
    width: u32,
    height: u32,
    #[source]
    source: GpuError,
}

/// A family and the targets of its last frame.
pub(crate) struct FamilySlot<F: GpuFamily> {
    pub family: F,
    targets: Option<F::Targets>,
}

impl<F: GpuFamily> FamilySlot<F> {
    pub(crate) fn new(family: F) -> Self {
        Self {
            family,
            targets: None,
        }
    }

    /// Drops the targets (bound to the old scene) and prepares the family for `scene`.
    pub(crate) fn prepare(&mut self, scene: &Arc<Scene>) {
        self.targets = None;
        self.family.prepare(scene);
    }

    /// The colour buffer of the last frame ([`GpuFamily::color`]), `None` before the first.
    pub(crate) fn color(&self) -> Option<&wgpu::Buffer> {
        self.targets.as_ref().map(|t| self.family.color(t))
    }

    /// One frame: the family's CPU part, targets reused when they fit (else the old ones are
    /// freed first, then new ones allocated), its passes encoded and submitted, the queue
    /// waited for, the time read (GPU timestamps plus the CPU part, or the wall clock of both
    /// without the allocation), the outputs read back into `frame` (when given; `cx.readback`
    /// must say the same).
    pub(crate) fn run_frame(
        &mut self,
        cx: &GpuFrameCx<'_>,
        params: &F::Params,
        frame: Option<&mut Frame>,
    ) -> Result<FrameTiming, RenderError> {
        let start = Instant::now();
        if let Some(timestamps) = cx.timestamps {
            timestamps.begin_frame();
        }
        self.family.plan(cx, params)?;
        let plan_ms = start.elapsed().as_secs_f64() * 1e3;
        let targets = match self.targets.take() {
            Some(targets) if self.family.fits(&targets, cx, params) => self.targets.insert(targets),
            stale => {
                drop(stale);
                let targets = self.family.allocate(cx, params).map_err(|source| {
                    let (width, height) = cx.size();
                    RenderError::backend(
                        BackendId::Gpu,
                        AllocationError {
                            method: cx.method,
                            params: cx.params.describe(),
                            width,
                            height,
                            source,
                        },
                    )
                })?;
                self.targets.insert(targets)
            }
        };
        let start = Instant::now();
        let mut encoder =
            cx.context
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some(F::LABEL),
                });
        self.family.encode(cx, params, targets, &mut encoder)?;
        let context = cx.context;
        context.checked(|| context.queue.submit([encoder.finish()]))?;
        context.wait()?;
        let wall_ms = plan_ms + start.elapsed().as_secs_f64() * 1e3;
        let timing = match cx.timestamps.filter(|_| F::TIMESTAMPS) {
            Some(timestamps) => FrameTiming {
                // The GPU's passes plus the CPU work the frame waited for.
                ms: timestamps.read_ms(context)? + plan_ms,
                source: TimingSource::GpuTimestamps,
            },
            None => FrameTiming {
                ms: wall_ms,
                source: TimingSource::Wall,
            },
        };
        if let Some(frame) = frame {
            self.family.read(cx, targets, frame)?;
        }
        Ok(timing)
    }
}
