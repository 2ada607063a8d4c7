//! The GPU backend as a [`Renderer`]: one exhaustive `match` from [`MethodParams`] to the module
//! of the method's family, so a new method does not compile until it is handled or declined.

use std::sync::Arc;
use std::time::Instant;

use refract_core::Camera;
use refract_core::kernel::ImageSpaceParams;
use refract_core::nearby_geometry::guard_band_camera;
use refract_scene::{
    BackendId, Frame, FrameOutputs, FrameTiming, MethodId, MethodParams, NearbyParams, RenderError,
    Renderer, Scene, SceneMesh, SurfaceTexel, TimingSource,
};

use crate::context::{GpuContext, GpuError};
use crate::frame_uniforms::frame_uniforms;
use crate::methods::distance_map::{DistanceMapPipelines, DistanceMapTargets};
use crate::methods::image_space::{ImageSpaceKernel, ImageSpacePipelines, ImageSpaceTargets};
use crate::methods::nearby_geometry::{NearbyFrame, NearbyPipelines, NearbyTargets};
use crate::methods::pvrr::{PvrrPipelines, PvrrTargets};
use crate::passes::raster::RasterPipelines;
use crate::passes::surfaces::rasterize_surface;
use crate::scene_buffers::GpuScene;
use crate::timestamps::Timestamps;
use refract_scene::pvrr::PvrrPlanner;

impl From<GpuError> for RenderError {
    fn from(err: GpuError) -> Self {
        RenderError::backend(BackendId::Gpu, err)
    }
}

/// Keeps the targets in `slot` when they fit (`fits`), else replaces them with new ones from
/// `make` (the old ones are freed first): targets live across frames of one size.
fn reuse_or_allocate<T>(
    slot: &mut Option<T>,
    fits: impl Fn(&T) -> bool,
    make: impl FnOnce() -> Result<T, GpuError>,
) -> Result<(), GpuError> {
    if !slot.as_ref().is_some_and(fits) {
        *slot = None;
        *slot = Some(make()?);
    }
    Ok(())
}

/// The GPU renderer: a device, the compiled pipelines, the uploaded scene and the targets of
/// the last resolution (reused for every camera and method at that size).
pub struct GpuRenderer {
    context: GpuContext,
    raster: RasterPipelines,
    image_space: ImageSpacePipelines,
    nearby: NearbyPipelines,
    distance_map: DistanceMapPipelines,
    pvrr: PvrrPipelines,
    timestamps: Option<Timestamps>,
    scene: Option<(Arc<Scene>, GpuScene)>,
    targets: Option<ImageSpaceTargets>,
    nearby_targets: Option<NearbyTargets>,
    distance_targets: Option<DistanceMapTargets>,
    pvrr_targets: Option<PvrrTargets>,
    /// The per-vertex plan of `pvrr` (kept between frames: `update=on-change`).
    pvrr_planner: PvrrPlanner,
}

impl GpuRenderer {
    /// Opens the default adapter ([`GpuContext::new`]) and compiles the pipelines.
    pub fn new() -> Result<Self, GpuError> {
        Self::with_context(GpuContext::new()?)
    }

    /// Compiles the pipelines on `context`.
    pub fn with_context(context: GpuContext) -> Result<Self, GpuError> {
        let (raster, image_space, nearby, distance_map, pvrr) = context.checked(|| {
            let raster = RasterPipelines::new(&context.device);
            let pvrr = PvrrPipelines::new(&context.device, &raster);
            (
                raster,
                ImageSpacePipelines::new(&context.device),
                NearbyPipelines::new(&context.device),
                DistanceMapPipelines::new(&context.device),
                pvrr,
            )
        })?;
        let timestamps = Timestamps::new(&context);
        Ok(Self {
            context,
            raster,
            image_space,
            nearby,
            distance_map,
            pvrr,
            timestamps,
            scene: None,
            targets: None,
            nearby_targets: None,
            distance_targets: None,
            pvrr_targets: None,
            pvrr_planner: PvrrPlanner::default(),
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

    fn image_space(
        &mut self,
        camera: &Camera,
        kernel: ImageSpaceKernel,
        id: MethodId,
        params: ImageSpaceParams,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<FrameTiming, RenderError> {
        let (_, scene) = self
            .scene
            .as_ref()
            .ok_or(RenderError::NotPrepared(BackendId::Gpu))?;
        let (width, height) = (camera.width(), camera.height());
        reuse_or_allocate(
            &mut self.targets,
            |t| t.fits(width, height),
            || {
                ImageSpaceTargets::new(
                    &self.context,
                    &self.raster,
                    &self.image_space,
                    scene,
                    width,
                    height,
                )
            },
        )?;
        let Some(targets) = &self.targets else {
            unreachable!("allocated above")
        };
        let uniforms = frame_uniforms(camera, &scene.environment, params.ior(), params.tir_policy);
        let start = Instant::now();
        let mut encoder =
            self.context
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("image-space frame"),
                });
        targets.encode(
            &self.context,
            &self.raster,
            &self.image_space,
            scene,
            camera,
            &uniforms,
            kernel,
            id,
            outputs,
            self.timestamps.as_ref(),
            &mut encoder,
        );
        let timing = self.submit(encoder, start)?;
        targets.read(&self.context, id, outputs, frame)?;
        Ok(timing)
    }

    /// Submits a frame's commands, waits for them and reads its timing.
    fn submit(
        &self,
        encoder: wgpu::CommandEncoder,
        start: Instant,
    ) -> Result<FrameTiming, RenderError> {
        self.context
            .checked(|| self.context.queue.submit([encoder.finish()]))?;
        self.context.wait()?;
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(match &self.timestamps {
            Some(timestamps) => FrameTiming {
                ms: timestamps.read_ms(&self.context)?,
                source: TimingSource::GpuTimestamps,
            },
            None => FrameTiming {
                ms: wall_ms,
                source: TimingSource::Wall,
            },
        })
    }

    /// One frame of `distance-map` (Umenhoffer et al. 2007).
    fn distance_map(
        &mut self,
        camera: &Camera,
        params: &refract_scene::DistanceMapParams,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<FrameTiming, RenderError> {
        let (scene, gpu_scene) = self
            .scene
            .as_ref()
            .ok_or(RenderError::NotPrepared(BackendId::Gpu))?;
        let size = (camera.width(), camera.height());
        reuse_or_allocate(
            &mut self.distance_targets,
            |t| t.fits(size, params),
            || {
                DistanceMapTargets::new(
                    &self.context,
                    &self.raster,
                    &self.distance_map,
                    gpu_scene,
                    size,
                    params,
                )
            },
        )?;
        let Some(targets) = &self.distance_targets else {
            unreachable!("allocated above")
        };
        let start = Instant::now();
        let mut encoder =
            self.context
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("distance-map frame"),
                });
        targets.encode(
            &self.context,
            &self.raster,
            &self.distance_map,
            gpu_scene,
            scene,
            camera,
            params,
            outputs,
            self.timestamps.as_ref(),
            &mut encoder,
        )?;
        let timing = self.submit(encoder, start)?;
        targets.read(&self.context, outputs, frame)?;
        Ok(timing)
    }

    /// One frame of `pvrr` (Kakimoto et al. 2007).
    fn pvrr(
        &mut self,
        camera: &Camera,
        params: &refract_scene::PvrrParams,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<FrameTiming, RenderError> {
        let (scene, gpu_scene) = self
            .scene
            .as_ref()
            .ok_or(RenderError::NotPrepared(BackendId::Gpu))?;
        let size = (camera.width(), camera.height());
        reuse_or_allocate(
            &mut self.pvrr_targets,
            |t| t.fits(size, params),
            || PvrrTargets::new(&self.context, size, params),
        )?;
        let Some(targets) = &mut self.pvrr_targets else {
            unreachable!("allocated above")
        };
        let start = Instant::now();
        let plan = self.pvrr_planner.plan(scene, camera, params)?;
        let plan_ms = start.elapsed().as_secs_f64() * 1e3;
        let mut encoder =
            self.context
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("pvrr frame"),
                });
        targets.encode(
            &self.context,
            &self.raster,
            &self.pvrr,
            gpu_scene,
            scene,
            plan,
            outputs,
            self.timestamps.as_ref(),
            &mut encoder,
        )?;
        let mut timing = self.submit(encoder, start)?;
        if timing.source == TimingSource::GpuTimestamps {
            // The GPU's timestamps plus the per-vertex plan the CPU made for it.
            timing.ms += plan_ms;
        }
        if let Some(targets) = &self.pvrr_targets {
            targets.read(&self.context, outputs, frame)?;
        }
        Ok(timing)
    }

    /// One frame of a nearby-geometry method (Wyman 2005b).
    fn nearby_geometry(
        &mut self,
        camera: &Camera,
        params: &NearbyParams,
        id: MethodId,
        kernel: ImageSpaceParams,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<FrameTiming, RenderError> {
        let (scene, gpu_scene) = self
            .scene
            .as_ref()
            .ok_or(RenderError::NotPrepared(BackendId::Gpu))?;
        let (ng_desc, pad) = guard_band_camera(camera.desc(), params.guard_band_percent);
        let ng_camera =
            Camera::new(ng_desc).map_err(|err| RenderError::Parameter(err.to_string()))?;
        let size = (camera.width(), camera.height());
        let ng_size = (ng_camera.width(), ng_camera.height());
        reuse_or_allocate(
            &mut self.nearby_targets,
            |t| t.fits(size, ng_size),
            || {
                NearbyTargets::new(
                    &self.context,
                    &self.raster,
                    &self.nearby,
                    gpu_scene,
                    size,
                    ng_size,
                )
            },
        )?;
        let Some(targets) = &self.nearby_targets else {
            unreachable!("allocated above")
        };
        let planes = scene.nearby_planes(camera.look_dir());
        let nearby = NearbyFrame {
            ng_camera: &ng_camera,
            pad,
            planes: &planes,
            lookup: params.lookup,
            light: scene.light,
        };
        let uniforms = frame_uniforms(
            camera,
            &gpu_scene.environment,
            kernel.ior(),
            kernel.tir_policy,
        );
        let start = Instant::now();
        let mut encoder =
            self.context
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("nearby-geometry frame"),
                });
        targets.encode(
            &self.context,
            &self.raster,
            &self.nearby,
            gpu_scene,
            camera,
            &uniforms,
            &nearby,
            params.two.back,
            id,
            outputs,
            self.timestamps.as_ref(),
            &mut encoder,
        );
        let timing = self.submit(encoder, start)?;
        targets.read(&self.context, id, outputs, frame)?;
        Ok(timing)
    }
}

impl Renderer for GpuRenderer {
    fn backend(&self) -> BackendId {
        BackendId::Gpu
    }

    fn supports(&self, method: MethodId) -> bool {
        match MethodParams::defaults(method) {
            MethodParams::Reference(_) => false,
            MethodParams::Single
            | MethodParams::TwoInterface(_)
            | MethodParams::NearbyGeometry(_)
            | MethodParams::DistanceMap(_) => true,
            MethodParams::Pvrr(_) => true,
        }
    }

    fn prepare(&mut self, scene: &Arc<Scene>) -> Result<(), RenderError> {
        let uploaded = self
            .context
            .checked(|| GpuScene::new(&self.context.device, scene))?;
        self.targets = None; // bound to the old scene's environment buffer
        self.nearby_targets = None;
        self.distance_targets = None;
        self.pvrr_targets = None;
        self.pvrr_planner.prepare(scene);
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
        let scene = &self
            .scene
            .as_ref()
            .ok_or(RenderError::NotPrepared(BackendId::Gpu))?
            .0;
        let ior = scene.refractor.ior();
        let id = method.id();
        refract_scene::scene_support(id, scene).map_err(RenderError::UnsupportedScene)?;
        if let MethodParams::DistanceMap(p) = method {
            return self.distance_map(camera, p, outputs, frame);
        }
        if let MethodParams::Pvrr(p) = method {
            return self.pvrr(camera, p, outputs, frame);
        }
        let unsupported = || RenderError::Unsupported {
            backend: BackendId::Gpu,
            method: id,
        };
        let params = method.image_space_kernel(ior).ok_or_else(unsupported)??;
        let kernel = match method {
            MethodParams::Reference(_) | MethodParams::DistanceMap(_) | MethodParams::Pvrr(_) => {
                return Err(unsupported());
            }
            MethodParams::Single => ImageSpaceKernel::Single,
            MethodParams::TwoInterface(p) => ImageSpaceKernel::TwoInterface { back: p.back },
            MethodParams::NearbyGeometry(p) => {
                return self.nearby_geometry(camera, p, id, params, outputs, frame);
            }
        };
        self.image_space(camera, kernel, id, params, outputs, frame)
    }
}
