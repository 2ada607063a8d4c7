//! The GPU backend as a [`Renderer`]: the device, the shared raster pipelines, the uploaded
//! scene and every family (`methods::Families`, which holds the backend's one
//! exhaustive `match` from [`MethodParams`] to a family). The frame routine (reuse or allocate,
//! encode, submit, read back, time) is `family::FamilySlot::run_frame`, written once.

use std::sync::Arc;

use refract_core::Camera;
use refract_scene::{
    BackendId, Frame, FrameOutputs, FrameTiming, MethodParams, RenderError, Renderer, Scene,
    SceneMesh, SurfaceTexel,
};

use crate::context::{GpuContext, GpuError};
use crate::family::GpuFrameCx;
use crate::methods::Families;
use crate::passes::raster::RasterPipelines;
use crate::passes::surfaces::rasterize_surface;
use crate::scene_buffers::GpuScene;
use crate::timestamps::Timestamps;
use refract_scene::PassTime;

impl From<GpuError> for RenderError {
    fn from(err: GpuError) -> Self {
        RenderError::backend(BackendId::Gpu, err)
    }
}

/// The GPU renderer: a device, the compiled pipelines, the uploaded scene and each family's
/// targets of the last resolution (reused for every camera and method at that size).
pub struct GpuRenderer {
    context: GpuContext,
    raster: RasterPipelines,
    timestamps: Option<Timestamps>,
    scene: Option<(Arc<Scene>, GpuScene)>,
    families: Families,
    /// One wavelength's colour of a dispersive frame ([`refract_scene::render_dispersive`]).
    wavelength_frame: Frame,
}

impl GpuRenderer {
    /// Opens the default adapter ([`GpuContext::new`]) and compiles the pipelines.
    pub fn new() -> Result<Self, GpuError> {
        Self::with_context(GpuContext::new()?)
    }

    /// Compiles the pipelines on `context`.
    pub fn with_context(context: GpuContext) -> Result<Self, GpuError> {
        let (raster, families) = context.checked(|| {
            let raster = RasterPipelines::new(&context.device);
            let families = Families::new(&context.device, &raster);
            (raster, families)
        })?;
        let timestamps = Timestamps::new(&context);
        Ok(Self {
            context,
            raster,
            timestamps,
            scene: None,
            families,
            wavelength_frame: Frame::default(),
        })
    }

    /// A renderer for a test: `None` (after printing `skipped: no GPU adapter`) without an
    /// adapter, unless `REFRACT_REQUIRE_GPU=1` ([`GpuContext::for_tests`]).
    pub fn for_tests() -> Option<Self> {
        let context = GpuContext::for_tests()?;
        match Self::with_context(context) {
            Ok(renderer) => Some(renderer),
            Err(err) => panic!("GPU pipelines: {err}"),
        }
    }

    /// The GPU time of the last frame's passes, summed per pass label in encoding order
    /// (timestamp queries); empty without TIMESTAMP_QUERY and for the reference.
    pub fn last_pass_times(&self) -> Vec<PassTime> {
        self.timestamps
            .as_ref()
            .map(Timestamps::last_passes)
            .unwrap_or_default()
    }

    /// The device and adapter.
    pub fn context(&self) -> &GpuContext {
        &self.context
    }

    /// The nearest front faces of mesh `which` of the prepared scene seen by `camera` (any
    /// camera, cube-map faces included), row-major from the top: the GPU twin of
    /// `refract_cpu::rasterize_surface`.
    pub fn rasterize_surface(
        &self,
        camera: &Camera,
        which: SceneMesh,
    ) -> Result<Vec<Option<SurfaceTexel>>, RenderError> {
        let (_, scene) = self
            .scene
            .as_ref()
            .ok_or(RenderError::NotPrepared(BackendId::Gpu))?;
        let mesh = match which {
            SceneMesh::Refractor => Some(&scene.refractor),
            SceneMesh::Object(k) => scene.objects.get(k),
        }
        .ok_or_else(|| RenderError::Parameter(format!("the scene has no mesh {which:?}")))?;
        Ok(rasterize_surface(
            &self.context,
            &self.raster,
            scene,
            mesh,
            camera,
        )?)
    }
}

impl Renderer for GpuRenderer {
    fn backend(&self) -> BackendId {
        BackendId::Gpu
    }

    fn last_pass_times(&self) -> Vec<PassTime> {
        GpuRenderer::last_pass_times(self)
    }

    fn device(&self) -> Option<String> {
        let info = &self.context.info;
        Some(format!("{} ({:?})", info.name, info.backend))
    }

    fn prepare(&mut self, scene: &Arc<Scene>) -> Result<(), RenderError> {
        let uploaded = self
            .context
            .checked(|| GpuScene::new(&self.context.device, scene))?;
        self.families.prepare(scene);
        self.scene = Some((Arc::clone(scene), uploaded));
        Ok(())
    }

    fn render(
        &mut self,
        camera: &Camera,
        method: &MethodParams,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<FrameTiming, RenderError> {
        let (scene, gpu_scene) = self
            .scene
            .as_ref()
            .ok_or(RenderError::NotPrepared(BackendId::Gpu))?;
        let id = method.id();
        refract_scene::scene_support(id, scene).map_err(RenderError::UnsupportedScene)?;
        let families = &mut self.families;
        let (context, raster, timestamps) = (&self.context, &self.raster, self.timestamps.as_ref());
        refract_scene::render_dispersive(
            scene,
            method,
            outputs,
            frame,
            &mut self.wavelength_frame,
            |lambda_nm, outputs, frame, repeat| {
                let cx = GpuFrameCx {
                    context,
                    raster,
                    scene,
                    gpu_scene,
                    camera,
                    method: id,
                    params: method,
                    outputs,
                    timestamps,
                    readback: true,
                    lambda_nm,
                    repeat,
                };
                families.render(&cx, method, Some(frame))
            },
        )
    }
}

/// A colour-only frame left on the GPU by [`GpuRenderer::render_on_gpu`].
pub struct GpuFrame<'a> {
    /// How long it took: the GPU's timestamps of its passes plus its CPU part, or the wall
    /// clock from encoding to the queue's completion.
    pub timing: FrameTiming,
    /// Its colour: one `vec4<f32>` per pixel (linear RGB radiance, A unused), row-major from the
    /// top, `width × height` of the camera; `STORAGE` usage, valid until the next frame.
    pub color: &'a wgpu::Buffer,
}

impl GpuRenderer {
    /// Renders a colour-only frame of `method` seen by `camera` and leaves it on the GPU: no
    /// copy to a readback buffer and no wait for a map, for a consumer on the same device (the
    /// viewer draws it into its window). [`Renderer::render`] is the same frame read back, except
    /// on dispersive glass, which this frame shows at its index at the d line (one frame, not
    /// the sum of [`refract_scene::render_dispersive`]'s wavelengths).
    pub fn render_on_gpu(
        &mut self,
        camera: &Camera,
        method: &MethodParams,
    ) -> Result<GpuFrame<'_>, RenderError> {
        let (scene, gpu_scene) = self
            .scene
            .as_ref()
            .ok_or(RenderError::NotPrepared(BackendId::Gpu))?;
        let id = method.id();
        refract_scene::scene_support(id, scene).map_err(RenderError::UnsupportedScene)?;
        let cx = GpuFrameCx {
            context: &self.context,
            raster: &self.raster,
            scene,
            gpu_scene,
            camera,
            method: id,
            params: method,
            outputs: FrameOutputs::Color,
            timestamps: self.timestamps.as_ref(),
            readback: false,
            lambda_nm: None,
            repeat: false,
        };
        let timing = self.families.render(&cx, method, None)?;
        let color = self
            .families
            .color(method)
            .ok_or(RenderError::Unsupported {
                backend: BackendId::Gpu,
                method: id,
            })?;
        Ok(GpuFrame { timing, color })
    }

    /// The colour buffer of the last frame of `method`'s family (as [`GpuFrame::color`]),
    /// `None` before its first frame.
    pub fn last_color(&self, method: &MethodParams) -> Option<&wgpu::Buffer> {
        self.families.color(method)
    }
}
