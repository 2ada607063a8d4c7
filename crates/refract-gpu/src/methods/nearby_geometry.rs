//! Wyman 2005b refraction of nearby geometry on the GPU (methods `kay-greenberg`, `ray-plane`,
//! `iterative`, `iterative-seeded`): the three passes of §5 — the refractor's back faces, every
//! opaque object from the NG camera into the NG targets (surface pass: P, N, uv + object id),
//! the refractor's front faces — then `shade_nearby` of `nearby_geometry.wgsl` (beside this module) as a
//! compute pass, one pipeline per method (`LOOKUP` fixed per pipeline).

use glam::Vec3;
use refract_core::Camera;
use refract_core::gpu::{FrameUniforms, NearbyUniforms, lookup_code};
use refract_core::nearby_geometry::guard_band_camera;
use refract_scene::{
    Aov, Frame, FrameOutputs, LayerValue, MethodId, NearbyParams, PixelLayers, RenderError,
};

use crate::bindings::bind_group;
use crate::context::{GpuContext, GpuError};
use crate::family::{GpuFamily, GpuFrameCx};
use crate::frame_uniforms::frame_uniforms;
use crate::passes::object_surfaces::{
    NearbyFrame, nearby_layout, nearby_resources, nearby_uniforms,
};
use crate::passes::outputs::{DecodedPixel, OutputBuffers, check_limits};
use crate::passes::pipelines::MethodPipelines;
use crate::passes::raster::{RasterPipelines, SurfaceTargets};
use crate::passes::refractor::RefractorTargets;
use crate::scene_buffers::GpuScene;
use crate::shaders::{
    CORE, ENVIRONMENT, FRAME, IMAGE_SPACE, MATERIALS, OBJECT_SURFACES, OBJECT_TEXTURE,
    PROCEDURAL_SKY, ShaderModule, TWO_INTERFACE, WgslFile,
};

/// The lookups (Wyman 2005b §4) over an `ng_surface` their includer provides.
const NEARBY_LOOKUP: WgslFile = ("nearby_lookup.wgsl", include_str!("nearby_lookup.wgsl"));

/// The family's modules: its pass, and its conformance module.
pub(crate) const SHADERS: &[ShaderModule] = &[SHADER, CONFORMANCE];

/// The conformance module (`nearby_conformance.wgsl`): the lookups over an analytic NG texture,
/// run by `crate::conformance::evaluate_family`.
pub(crate) const CONFORMANCE: ShaderModule = ShaderModule {
    name: "nearby-conformance",
    files: &[
        CORE,
        FRAME,
        OBJECT_SURFACES,
        NEARBY_LOOKUP,
        (
            "nearby_conformance.wgsl",
            include_str!("nearby_conformance.wgsl"),
        ),
    ],
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
        OBJECT_SURFACES,
        OBJECT_TEXTURE,
        NEARBY_LOOKUP,
        ("nearby_geometry.wgsl", include_str!("nearby_geometry.wgsl")),
    ],
};

/// The `shade_nearby` pipelines: one per nearby-geometry method (`LOOKUP` fixed per method).
pub(crate) struct NearbyPipelines(MethodPipelines);

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
        let kernel = params.two.kernel(cx.ior(&cx.scene.refractor))?;
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
        self.refractor
            .encode(cx, uniforms, Some(back), false, encoder);
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
