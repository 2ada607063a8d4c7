//! Wyman 2005b refraction of nearby geometry on the GPU (methods `kay-greenberg`, `ray-plane`,
//! `iterative`, `iterative-seeded`): the three passes of §5 — the refractor's back faces, every
//! opaque object from the NG camera into the NG targets (surface pass: P, N, uv + object id),
//! the refractor's front faces — then `shade_nearby` of `shaders/nearby_geometry.wgsl` as a
//! compute pass, one pipeline per method (`LOOKUP` fixed per pipeline).

use glam::{UVec2, Vec3};
use refract_core::Camera;
use refract_core::gpu::{FrameUniforms, NearbyUniforms, lookup_code, seed_spacing_code};
use refract_core::nearby_geometry::{
    MAX_PLANES, NearbyLookup, Plane, SeedSpacing, guard_band_camera,
};
use refract_scene::{
    Aov, DirectionalLight, Frame, FrameOutputs, LayerValue, MethodId, NearbyParams, PixelLayers,
    RenderError,
};

use crate::bindings::{bind_group, storage_entry, texture_entry, uniform_entry};
use crate::context::{GpuContext, GpuError};
use crate::family::{GpuFamily, GpuFrameCx};
use crate::frame_uniforms::frame_uniforms;
use crate::methods::MethodPipelines;
use crate::methods::image_space::{DecodedPixel, OutputBuffers, RefractorTargets, check_limits};
use crate::passes::raster::{RasterPipelines, SurfaceTargets};
use crate::scene_buffers::GpuScene;
use crate::shaders::{
    CORE, ENVIRONMENT, FRAME, IMAGE_SPACE, MATERIALS, PROCEDURAL_SKY, ShaderModule, TWO_INTERFACE,
};

/// The module of the nearby-geometry kernel (Wyman 2005b): the image-space path, then the lookups.
pub(crate) const SHADER: ShaderModule = ShaderModule {
    name: "nearby_geometry",
    files: &[
        CORE,
        PROCEDURAL_SKY,
        FRAME,
        ENVIRONMENT,
        TWO_INTERFACE,
        IMAGE_SPACE,
        MATERIALS,
        NEARBY_GEOMETRY_WGSL,
    ],
};

/// `shaders/nearby_geometry.wgsl`: the lookups and the NG texture's readers (`ng_surface`,
/// `ng_color`), which the engine family's shader reads its screen texture with.
pub(crate) const NEARBY_GEOMETRY_WGSL: crate::shaders::WgslFile = (
    "nearby_geometry.wgsl",
    include_str!("../../shaders/nearby_geometry.wgsl"),
);

/// The `shade_nearby` pipelines: one per nearby-geometry method (`LOOKUP` fixed per method).
pub(crate) struct NearbyPipelines(MethodPipelines);

/// What [`nearby_layout`] binds: the refractor's targets, the environment, six outputs, the
/// materials, the NG (or screen) targets and their uniforms.
pub(crate) fn nearby_resources<'a>(
    refractor: &'a RefractorTargets,
    scene: &'a GpuScene,
    outputs: &'a OutputBuffers,
    ng: &'a SurfaceTargets,
    nearby_uniforms: &'a wgpu::Buffer,
) -> Vec<wgpu::BindingResource<'a>> {
    let mut resources = vec![
        refractor.uniforms.as_entire_binding(),
        wgpu::BindingResource::TextureView(&refractor.front_p1),
        wgpu::BindingResource::TextureView(&refractor.front_n1),
        wgpu::BindingResource::TextureView(&refractor.back),
        scene.environment_texels.as_entire_binding(),
    ];
    resources.extend(outputs.outputs.iter().map(|o| o.as_entire_binding()));
    resources.push(scene.materials.as_entire_binding());
    resources.extend(ng.views.iter().map(wgpu::BindingResource::TextureView));
    resources.push(nearby_uniforms.as_entire_binding());
    resources
}

/// The bindings of `shade_nearby` (and of the engine family's `shade_engine`, which adds its own).
pub(crate) fn nearby_layout() -> Vec<wgpu::BindGroupLayoutEntry> {
    vec![
        uniform_entry(0, wgpu::ShaderStages::COMPUTE),
        texture_entry(1),
        texture_entry(2),
        texture_entry(3),
        storage_entry(4, true),
        storage_entry(5, false),
        storage_entry(6, false),
        storage_entry(7, false),
        storage_entry(8, false),
        storage_entry(9, false),
        storage_entry(10, false),
        storage_entry(11, true),
        texture_entry(12),
        texture_entry(13),
        texture_entry(14),
        uniform_entry(15, wgpu::ShaderStages::COMPUTE),
    ]
}

impl NearbyPipelines {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        Self(MethodPipelines::new(
            device,
            &SHADER,
            &nearby_layout(),
            |p: &NearbyParams| {
                (
                    "shade_nearby",
                    vec![("LOOKUP", f64::from(lookup_code(p.lookup)))],
                )
            },
        ))
    }
}

impl GpuFamily for NearbyPipelines {
    type Params = NearbyParams;
    type Targets = NearbyTargets;
    const LABEL: &'static str = "nearby-geometry frame";

    fn create(device: &wgpu::Device, _raster: &RasterPipelines) -> Self {
        Self::new(device)
    }

    fn fits(&self, targets: &NearbyTargets, cx: &GpuFrameCx<'_>, params: &NearbyParams) -> bool {
        let (ng_desc, _) = guard_band_camera(cx.camera.desc(), params.guard_band_percent);
        targets.fits(cx.size(), (ng_desc.width, ng_desc.height))
    }

    fn allocate(
        &self,
        cx: &GpuFrameCx<'_>,
        params: &NearbyParams,
    ) -> Result<NearbyTargets, GpuError> {
        let (ng_desc, _) = guard_band_camera(cx.camera.desc(), params.guard_band_percent);
        NearbyTargets::new(
            cx.context,
            cx.raster,
            self,
            cx.gpu_scene,
            cx.size(),
            (ng_desc.width, ng_desc.height),
        )
    }

    fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        params: &NearbyParams,
        targets: &mut NearbyTargets,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), RenderError> {
        let kernel = params.two.kernel(cx.scene.refractor.ior())?;
        let (ng_desc, pad) = guard_band_camera(cx.camera.desc(), params.guard_band_percent);
        let ng_camera =
            Camera::new(ng_desc).map_err(|err| RenderError::Parameter(err.to_string()))?;
        let planes = cx.scene.nearby_planes(cx.camera.look_dir());
        let nearby = NearbyFrame {
            ng_camera: &ng_camera,
            pad,
            planes: &planes,
            lookup: params.lookup,
            light: cx.scene.light,
        };
        let uniforms = frame_uniforms(
            cx.camera,
            &cx.gpu_scene.environment,
            kernel.ior(),
            kernel.tir_policy,
        );
        targets.encode(cx, self, &uniforms, &nearby, params.two.back, encoder);
        Ok(())
    }

    fn color<'t>(&self, targets: &'t Self::Targets) -> &'t wgpu::Buffer {
        &targets.outputs.outputs[0]
    }

    fn read(
        &self,
        cx: &GpuFrameCx<'_>,
        targets: &NearbyTargets,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        targets.read(cx.context, cx.method, cx.outputs, frame)
    }
}

/// What one frame of a nearby-geometry method needs besides the refractor's camera.
pub(crate) struct NearbyFrame<'a> {
    /// The NG camera (the eye's, widened by the guard band).
    pub ng_camera: &'a Camera,
    /// Guard band in texels.
    pub pad: UVec2,
    /// The planes of the ray-plane and iterative lookups.
    pub planes: &'a [Plane],
    /// The lookup.
    pub lookup: NearbyLookup,
    /// The scene's light.
    pub light: DirectionalLight,
}

impl<'a> NearbyFrame<'a> {
    /// The objects seen from the eye itself, pixel for pixel (no guard band, no lookup): the
    /// engine family's screen texture and the objects the image-space family draws.
    pub(crate) fn eye(camera: &'a Camera, light: DirectionalLight) -> Self {
        Self {
            ng_camera: camera,
            pad: UVec2::ZERO,
            planes: &[],
            lookup: NearbyLookup::KayGreenberg,
            light,
        }
    }
}

/// The targets of nearby-geometry frames at one frame and NG resolution.
pub(crate) struct NearbyTargets {
    size: (u32, u32, u32, u32),
    refractor: RefractorTargets,
    ng: SurfaceTargets,
    nearby_uniforms: wgpu::Buffer,
    shade_group: wgpu::BindGroup,
    /// Colour, T2, P~2, N2 (as the image-space methods), P_geom (w: hit + 2 converged),
    /// NG texel (x, y, object id, iterations).
    outputs: OutputBuffers,
}

impl NearbyTargets {
    /// Allocates targets for `width × height` frames with an `ng_width × ng_height` NG texture.
    pub(crate) fn new(
        context: &GpuContext,
        raster: &RasterPipelines,
        pipelines: &NearbyPipelines,
        scene: &GpuScene,
        (width, height): (u32, u32),
        (ng_width, ng_height): (u32, u32),
    ) -> Result<Self, GpuError> {
        check_limits(context, width, height)?;
        check_limits(context, ng_width, ng_height)?;
        let device = &context.device;
        context.checked(|| {
            let refractor = RefractorTargets::allocate(device, raster, width, height);
            let ng = SurfaceTargets::new(device, raster, "NG", ng_width, ng_height);
            let nearby_uniforms = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("nearby uniforms"),
                size: std::mem::size_of::<NearbyUniforms>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let outputs = OutputBuffers::new(
                device,
                &["colour", "T2", "P2", "N2", "P_geom", "NG texel"],
                u64::from(width) * u64::from(height),
            );
            let shade_group = bind_group(
                device,
                "nearby geometry",
                &pipelines.0.layout,
                &nearby_resources(&refractor, scene, &outputs, &ng, &nearby_uniforms),
            );
            Self {
                size: (width, height, ng_width, ng_height),
                refractor,
                ng,
                nearby_uniforms,
                shade_group,
                outputs,
            }
        })
    }

    /// Whether these targets are for these frame and NG sizes.
    pub(crate) fn fits(&self, frame: (u32, u32), ng: (u32, u32)) -> bool {
        self.size == (frame.0, frame.1, ng.0, ng.1)
    }

    /// Encodes the passes of one frame and the copies of its outputs.
    fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        pipelines: &NearbyPipelines,
        uniforms: &FrameUniforms,
        nearby: &NearbyFrame<'_>,
        back: refract_core::BackSurface,
        encoder: &mut wgpu::CommandEncoder,
    ) {
        let GpuFrameCx {
            context,
            raster,
            gpu_scene: scene,
            method: id,
            outputs,
            timestamps,
            ..
        } = *cx;
        let ng_frame = frame_uniforms(
            nearby.ng_camera,
            &scene.environment,
            uniforms.ior,
            refract_core::TirPolicy::default(),
        );
        context.queue.write_buffer(
            &self.nearby_uniforms,
            0,
            bytemuck::bytes_of(&nearby_uniforms(nearby)),
        );
        self.refractor.encode(cx, uniforms, Some(back), encoder);
        let objects: Vec<_> = scene.objects.iter().collect();
        self.ng.encode(
            &context.queue,
            raster,
            encoder,
            nearby.ng_camera,
            &ng_frame,
            &objects,
            timestamps.and_then(|t| t.render_pass("nearby-geometry texture")),
        );
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("nearby-geometry kernel"),
                timestamp_writes: timestamps.and_then(|t| t.compute_pass("nearby-geometry kernel")),
            });
            pass.set_pipeline(pipelines.0.get(id, outputs));
            pass.set_bind_group(0, &self.shade_group, &[]);
            let (width, height, _, _) = self.size;
            pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
        }
        if let Some(timestamps) = timestamps {
            timestamps.resolve(encoder);
        }
        let copies = match outputs {
            FrameOutputs::ColorAndAovs => 6,
            FrameOutputs::Color => 1,
        };
        if cx.readback {
            self.outputs.copy(encoder, copies);
        }
    }

    /// Reads the last submitted frame into `frame` (the colour and the registry row's AOVs).
    pub(crate) fn read(
        &self,
        context: &GpuContext,
        method: MethodId,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let (width, height, _, _) = self.size;
        let color = self.outputs.read(context, 0)?;
        frame.resize_for_overwrite(width, height);
        for (out, c) in frame.color.iter_mut().zip(&color) {
            *out = Vec3::new(c[0], c[1], c[2]);
        }
        if outputs == FrameOutputs::Color {
            return Ok(());
        }
        let planes: Vec<Vec<[f32; 4]>> = (1..6)
            .map(|i| self.outputs.read(context, i))
            .collect::<Result<_, _>>()?;
        let n = frame.pixel_count();
        let pixels: Vec<DecodedPixel> = (0..n)
            .map(|i| DecodedPixel::new(color[i], planes[0][i], planes[1][i], planes[2][i]))
            .collect();
        let pixels: Vec<NearbyPixel> = pixels
            .into_iter()
            .enumerate()
            .map(|(i, base)| NearbyPixel {
                base,
                p_geom: planes[3][i],
                ng: planes[4][i],
            })
            .collect();
        frame.write_row_layers(method, &pixels)?;
        Ok(())
    }
}

/// One pixel of the nearby-geometry outputs: the image-space ones, `P_geom` (w: 1 hit, + 2
/// converged) and the NG texel (x, y, object id, iterations).
struct NearbyPixel {
    base: DecodedPixel,
    p_geom: [f32; 4],
    ng: [f32; 4],
}

impl NearbyPixel {
    /// The lookup found a surface in the NG texture.
    fn hit(&self) -> bool {
        self.base.covered && self.p_geom[3] as u32 & 1 == 1
    }
}

impl PixelLayers for NearbyPixel {
    fn value(&self, aov: Aov) -> Option<LayerValue> {
        let (p, t) = (self.p_geom, self.ng);
        Some(match aov {
            Aov::PGeom if self.hit() => LayerValue::Vec3(Vec3::new(p[0], p[1], p[2])),
            Aov::NgTexel if self.hit() => LayerValue::Vec3(Vec3::new(t[0], t[1], t[2].round())),
            Aov::PGeom | Aov::NgTexel => LayerValue::Vec3(Vec3::NAN),
            Aov::Iterations if self.base.covered => LayerValue::Count(t[3].round() as u32),
            Aov::Iterations => LayerValue::Count(0),
            Aov::Converged => LayerValue::Flag(self.base.covered && p[3] as u32 & 2 == 2),
            other => return self.base.value(other),
        })
    }
}

/// The uniform block of the lookup.
pub(crate) fn nearby_uniforms(nearby: &NearbyFrame<'_>) -> NearbyUniforms {
    let camera = nearby.ng_camera;
    let mut planes = [[0.0; 4]; MAX_PLANES];
    for (slot, plane) in planes.iter_mut().zip(nearby.planes) {
        *slot = plane.normal.extend(plane.offset).to_array();
    }
    let (iterations, seeds, spacing) = match nearby.lookup {
        NearbyLookup::KayGreenberg | NearbyLookup::RayPlane => (0, 1, SeedSpacing::Screen),
        NearbyLookup::Iterative { iterations } => (iterations, 1, SeedSpacing::Screen),
        NearbyLookup::Seeded {
            iterations,
            seeds,
            spacing,
        } => (iterations, seeds, spacing),
    };
    let light = nearby.light;
    NearbyUniforms {
        world_to_clip: camera.world_to_clip().to_cols_array_2d(),
        eye: camera.eye().extend(1.0).to_array(),
        look_dir: camera.look_dir().extend(0.0).to_array(),
        light_direction: light.direction.extend(0.0).to_array(),
        light_radiance: light.radiance.extend(0.0).to_array(),
        light_ambient: light.ambient.extend(0.0).to_array(),
        planes,
        width: camera.width(),
        height: camera.height(),
        pad_x: nearby.pad.x,
        pad_y: nearby.pad.y,
        plane_count: nearby.planes.len().min(MAX_PLANES) as u32,
        iterations,
        seeds,
        spacing: seed_spacing_code(spacing),
    }
}
