//! Umenhoffer et al. 2007 (GPU Gems 3 ch. 17) on the GPU, method `distance-map`: every frame
//! the layered distance map is rendered (per layer six surface passes through mirrored 90°
//! cube-face cameras into array layers `layer·6 + face` of three `Rgba32Float` 2D array
//! textures: P, N, uv + object; WebGPU's face order and orientation), each layer's distance
//! range is reduced with atomics (min-max), the eye's surface pass of every mesh gives the
//! visible surface, and `distance_map.wgsl` (beside this module) runs the bounce loop per pixel. The twin of
//! `refract_cpu::distance_map`.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use refract_core::distance_map::{MAX_LAYERS, fresnel_code};
use refract_core::{Camera, CubeFace, TirPolicy};
use refract_scene::{
    Aov, DistanceMapParams, Frame, FrameOutputs, LayerValue, MethodId, PixelLayers, RenderError,
};

use crate::bindings::{array_entry, bind_group, storage_entry, texture_entry, uniform_entry};
use crate::context::{GpuContext, GpuError};
use crate::family::{GpuFamily, GpuFrameCx};
use crate::frame_uniforms::frame_uniforms;
use crate::passes::outputs::{OutputBuffers, check_limits};
use crate::passes::pipelines::MethodPipelines;
use crate::passes::raster::{
    DEPTH_FORMAT, PEEL_MARGIN, PeelUniforms, RasterKind, RasterPass, RasterPipelines,
    SurfaceTargets, TARGET_FORMAT, target,
};
use crate::scene_buffers::GpuScene;
use crate::shaders::{
    CORE, DISTANCE_SEARCH, ENVIRONMENT, FRAME, MATERIALS, PROCEDURAL_SKY, ShaderModule,
};
use refract_core::gpu::FrameUniforms;

/// The family's modules (its conformance is in the shared harness).
pub(crate) const SHADERS: &[ShaderModule] = &[SHADER];

/// The module of the distance-map passes and paths (Umenhoffer et al. 2007).
pub(crate) const SHADER: ShaderModule = ShaderModule {
    name: "distance_map",
    files: &[
        CORE,
        PROCEDURAL_SKY,
        FRAME,
        ENVIRONMENT,
        MATERIALS,
        DISTANCE_SEARCH,
        ("distance_map.wgsl", include_str!("distance_map.wgsl")),
    ],
};

/// The uniform block of `distance_map.wgsl` (beside this module) (`DmUniforms`, field for field).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct DmUniforms {
    center: [f32; 4],
    /// The specular object's material: `F0` (or `F_p`) and the sign code.
    refractor: [f32; 4],
    light_direction: [f32; 4],
    light_radiance: [f32; 4],
    light_ambient: [f32; 4],
    layers: u32,
    size: u32,
    min_steps: u32,
    max_steps: u32,
    secant_steps: u32,
    min_max: u32,
    max_depth: u32,
    fresnel: u32,
}

const _: () = assert!(core::mem::size_of::<DmUniforms>() == 112);

/// The per-pixel pipelines and the range reduction.
pub(crate) struct DistanceMapPipelines {
    methods: MethodPipelines,
    ranges: wgpu::ComputePipeline,
}

impl DistanceMapPipelines {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let methods = MethodPipelines::new(
            device,
            &SHADER,
            &[
                uniform_entry(0, wgpu::ShaderStages::COMPUTE),
                texture_entry(1),
                texture_entry(2),
                texture_entry(3),
                storage_entry(4, true),
                storage_entry(5, false),
                storage_entry(6, false),
                storage_entry(7, false),
                storage_entry(8, true),
                array_entry(9),
                array_entry(10),
                array_entry(11),
                storage_entry(12, false),
                uniform_entry(13, wgpu::ShaderStages::COMPUTE),
            ],
            |_: &DistanceMapParams| ("shade_distance_map", Vec::new()),
        );
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("distance_map ranges"),
            source: wgpu::ShaderSource::Wgsl(SHADER.source().into()),
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("distance_map ranges"),
            bind_group_layouts: &[Some(&methods.layout)],
            immediate_size: 0,
        });
        let ranges = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("distance-map ranges"),
            layout: Some(&layout),
            module: &module,
            entry_point: Some("dm_ranges"),
            compilation_options: Default::default(),
            cache: None,
        });
        Self { methods, ranges }
    }
}

/// The targets of distance-map frames at one frame size, face size and layer count.
pub(crate) struct DistanceMapTargets {
    key: (u32, u32, u32, u32),
    /// The eye pass of every mesh; its uniforms are the frame's (the kernel's binding 0).
    eye: SurfaceTargets,
    face_uniforms: Vec<wgpu::Buffer>,
    face_groups: Vec<wgpu::BindGroup>,
    /// Per layer and face: the P, N, uv+object views of array layer `layer·6 + face`.
    slices: Vec<[wgpu::TextureView; 3]>,
    face_depth: wgpu::TextureView,
    peel_uniforms: wgpu::Buffer,
    /// Per layer ≥ 3 and face: the previous layer's face, for depth peeling.
    peel_groups: Vec<wgpu::BindGroup>,
    dm_uniforms: wgpu::Buffer,
    ranges: wgpu::Buffer,
    shade_group: wgpu::BindGroup,
    /// Colour; (hit layer + 1, linear steps, secant steps, bounces); (covered, miss, tir, truncated).
    outputs: OutputBuffers,
}

impl GpuFamily for DistanceMapPipelines {
    type Params = DistanceMapParams;
    type Targets = DistanceMapTargets;
    const LABEL: &'static str = "distance-map frame";

    fn create(device: &wgpu::Device, _raster: &RasterPipelines) -> Self {
        Self::new(device)
    }

    fn fits(
        &self,
        targets: &DistanceMapTargets,
        cx: &GpuFrameCx<'_>,
        params: &DistanceMapParams,
    ) -> bool {
        targets.fits(cx.size(), params)
    }

    fn allocate(
        &self,
        cx: &GpuFrameCx<'_>,
        params: &DistanceMapParams,
    ) -> Result<DistanceMapTargets, GpuError> {
        DistanceMapTargets::new(cx.context, cx.raster, self, cx.gpu_scene, cx.size(), params)
    }

    fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        params: &DistanceMapParams,
        targets: &mut DistanceMapTargets,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), RenderError> {
        Ok(targets.encode(cx, self, params, encoder)?)
    }

    fn color<'t>(&self, targets: &'t Self::Targets) -> &'t wgpu::Buffer {
        &targets.outputs.outputs[0]
    }

    fn read(
        &self,
        cx: &GpuFrameCx<'_>,
        targets: &DistanceMapTargets,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        targets.read(cx.context, cx.outputs, frame)
    }
}

impl DistanceMapTargets {
    pub(crate) fn new(
        context: &GpuContext,
        raster: &RasterPipelines,
        pipelines: &DistanceMapPipelines,
        scene: &GpuScene,
        (width, height): (u32, u32),
        params: &DistanceMapParams,
    ) -> Result<Self, GpuError> {
        check_limits(context, width, height)?;
        let size = params.resolution;
        check_limits(context, size, size)?;
        let layers = params.layers.clamp(3, MAX_LAYERS as u32);
        let device = &context.device;
        context.checked(|| {
            let uniform = |label, bytes: usize| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: bytes as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            };
            let frame_size = std::mem::size_of::<FrameUniforms>();
            let eye = SurfaceTargets::new(device, raster, "eye", width, height);
            let face_uniforms: Vec<_> = (0..6)
                .map(|_| uniform("cube face uniforms", frame_size))
                .collect();
            let face_groups = face_uniforms
                .iter()
                .map(|u| {
                    bind_group(
                        device,
                        "cube face",
                        &raster.layout,
                        &[u.as_entire_binding()],
                    )
                })
                .collect();
            let arrays = ["layers P", "layers N", "layers uv, object"].map(|label| {
                device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: size,
                        height: size,
                        depth_or_array_layers: 6 * layers,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: TARGET_FORMAT,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                        | wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                })
            });
            let slices: Vec<[wgpu::TextureView; 3]> = (0..6 * layers)
                .map(|slice| {
                    arrays.each_ref().map(|t| {
                        t.create_view(&wgpu::TextureViewDescriptor {
                            dimension: Some(wgpu::TextureViewDimension::D2),
                            base_array_layer: slice,
                            array_layer_count: Some(1),
                            ..Default::default()
                        })
                    })
                })
                .collect();
            let array_views = arrays.each_ref().map(|t| {
                t.create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2Array),
                    ..Default::default()
                })
            });
            let face_depth = target(device, "cube face depth", size, size, DEPTH_FORMAT)
                .create_view(&wgpu::TextureViewDescriptor::default());
            let peel_uniforms = uniform("peel uniforms", std::mem::size_of::<PeelUniforms>());
            let peel_groups = (3..layers)
                .flat_map(|layer| (0..6).map(move |face| (layer, face)))
                .map(|(layer, face)| {
                    let previous = &slices[((layer - 1) * 6 + face) as usize];
                    bind_group(
                        device,
                        "peel",
                        &raster.peel_layout,
                        &[
                            wgpu::BindingResource::TextureView(&previous[0]),
                            wgpu::BindingResource::TextureView(&previous[1]),
                            peel_uniforms.as_entire_binding(),
                        ],
                    )
                })
                .collect();
            let dm_uniforms = uniform("distance-map uniforms", std::mem::size_of::<DmUniforms>());
            let ranges = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("layer ranges"),
                size: u64::from(2 * MAX_LAYERS as u32 * 4),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let outputs = OutputBuffers::new(
                device,
                &["colour", "counts", "flags"],
                u64::from(width) * u64::from(height),
            );
            let shade_group = bind_group(
                device,
                "distance map",
                &pipelines.methods.layout,
                &[
                    eye.uniforms().as_entire_binding(),
                    wgpu::BindingResource::TextureView(&eye.views[0]),
                    wgpu::BindingResource::TextureView(&eye.views[1]),
                    wgpu::BindingResource::TextureView(&eye.views[2]),
                    scene.environment_texels.as_entire_binding(),
                    outputs.outputs[0].as_entire_binding(),
                    outputs.outputs[1].as_entire_binding(),
                    outputs.outputs[2].as_entire_binding(),
                    scene.materials.as_entire_binding(),
                    wgpu::BindingResource::TextureView(&array_views[0]),
                    wgpu::BindingResource::TextureView(&array_views[1]),
                    wgpu::BindingResource::TextureView(&array_views[2]),
                    ranges.as_entire_binding(),
                    dm_uniforms.as_entire_binding(),
                ],
            );
            Self {
                key: (width, height, size, layers),
                eye,
                face_uniforms,
                face_groups,
                slices,
                face_depth,
                peel_uniforms,
                peel_groups,
                dm_uniforms,
                ranges,
                shade_group,
                outputs,
            }
        })
    }

    /// Whether these targets fit a frame of `size` with `params`.
    pub(crate) fn fits(&self, (width, height): (u32, u32), params: &DistanceMapParams) -> bool {
        self.key
            == (
                width,
                height,
                params.resolution,
                params.layers.clamp(3, MAX_LAYERS as u32),
            )
    }

    /// Encodes one frame: the layers, their ranges, the eye pass, the per-pixel paths.
    fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        pipelines: &DistanceMapPipelines,
        params: &DistanceMapParams,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        let GpuFrameCx {
            context,
            raster,
            gpu_scene,
            scene,
            camera,
            outputs,
            timestamps,
            ..
        } = *cx;
        let (width, height, size, layers) = self.key;
        let queue = &context.queue;
        let center = scene.refractor.mesh().bounding_sphere().center;
        let (near, far) = scene.cube_map_clip_planes(center);
        let ior = cx.ior(&scene.refractor);
        let frame = frame_uniforms(camera, &gpu_scene.environment, ior, TirPolicy::default());
        let face_cameras: Vec<Camera> = CubeFace::ALL
            .iter()
            .map(|&face| Camera::cube_face(center, face, size, near, far))
            .collect::<Result<_, _>>()
            .map_err(|e| GpuError::Wgpu(format!("distance map face camera: {e}")))?;
        for (buffer, face_camera) in self.face_uniforms.iter().zip(&face_cameras) {
            let u = frame_uniforms(
                face_camera,
                &gpu_scene.environment,
                ior,
                TirPolicy::default(),
            );
            queue.write_buffer(buffer, 0, bytemuck::bytes_of(&u));
        }
        queue.write_buffer(
            &self.peel_uniforms,
            0,
            bytemuck::bytes_of(&PeelUniforms {
                center: center.extend(1.0).to_array(),
                margin: PEEL_MARGIN,
                _padding: [0.0; 3],
            }),
        );
        let refractor = scene.refractor.texel_material_at(cx.lambda_nm);
        let refractor = refractor.rgb.extend(refractor.ior);
        let light = &scene.light;
        let search = &params.path.search;
        let uniforms = DmUniforms {
            center: center.extend(1.0).to_array(),
            refractor: refractor.to_array(),
            light_direction: light.direction.extend(0.0).to_array(),
            light_radiance: light.radiance.extend(0.0).to_array(),
            light_ambient: light.ambient.extend(0.0).to_array(),
            layers,
            size,
            min_steps: search.min_steps,
            max_steps: search.max_steps,
            secant_steps: search.secant_steps,
            min_max: u32::from(search.min_max),
            max_depth: params.path.max_depth,
            fresnel: fresnel_code(params.path.fresnel),
        };
        queue.write_buffer(&self.dm_uniforms, 0, bytemuck::bytes_of(&uniforms));
        // The layers, their ranges and the eye's surfaces do not depend on the index: kept for
        // the other wavelengths of a dispersive frame (the kernel's uniforms are rewritten).
        if cx.repeat {
            queue.write_buffer(self.eye.uniforms(), 0, bytemuck::bytes_of(&frame));
        } else {
            let cleared: Vec<u32> = (0..MAX_LAYERS)
                .flat_map(|_| [f32::INFINITY.to_bits(), 0])
                .collect();
            queue.write_buffer(&self.ranges, 0, bytemuck::cast_slice(&cleared));

            let objects: Vec<_> = gpu_scene.objects.iter().collect();
            for layer in 0..layers {
                let (kind, meshes): (RasterKind, Vec<_>) = match layer {
                    0 => (RasterKind::Surface, vec![&gpu_scene.refractor]),
                    1 => (RasterKind::SurfaceBack, vec![&gpu_scene.refractor]),
                    2 => (RasterKind::Surface, objects.clone()),
                    _ => (RasterKind::SurfacePeel, objects.clone()),
                };
                for face in CubeFace::ALL {
                    let f = face as usize;
                    let slice = &self.slices[(layer * 6) as usize + f];
                    let peel =
                        (layer >= 3).then(|| &self.peel_groups[((layer - 3) * 6) as usize + f]);
                    raster.encode(
                        encoder,
                        &RasterPass {
                            kind,
                            camera: &face_cameras[f],
                            uniforms: &self.face_groups[f],
                            peel,
                            meshes: &meshes,
                            targets: &[&slice[0], &slice[1], &slice[2]],
                            depth: &self.face_depth,
                        },
                        timestamps.and_then(|t| t.render_pass("cube-map faces")),
                    );
                }
            }
            let everything: Vec<_> = std::iter::once(&gpu_scene.refractor)
                .chain(gpu_scene.objects.iter())
                .collect();
            self.eye.encode(
                queue,
                raster,
                encoder,
                camera,
                &frame,
                &everything,
                timestamps.and_then(|t| t.render_pass("eye surfaces")),
            );
            // The ranges are read only by the min-max search.
            if search.min_max {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("distance-map ranges"),
                    timestamp_writes: timestamps.and_then(|t| t.compute_pass("min-max ranges")),
                });
                pass.set_pipeline(&pipelines.ranges);
                pass.set_bind_group(0, &self.shade_group, &[]);
                // DM_RANGE_RUN (32) texels of a row an invocation.
                pass.dispatch_workgroups(size.div_ceil(256), size.div_ceil(8), 6 * layers);
            }
        }
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("distance-map kernel"),
                timestamp_writes: timestamps.and_then(|t| t.compute_pass("distance-map kernel")),
            });
            pass.set_pipeline(pipelines.methods.get(MethodId::DistanceMap, outputs));
            pass.set_bind_group(0, &self.shade_group, &[]);
            pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
        }
        if let Some(timestamps) = timestamps {
            timestamps.resolve(encoder);
        }
        let copies = match outputs {
            FrameOutputs::ColorAndAovs => 3,
            FrameOutputs::Color => 1,
        };
        if cx.readback {
            self.outputs.copy(encoder, copies);
        }
        Ok(())
    }

    /// Reads the last submitted frame into `frame`.
    pub(crate) fn read(
        &self,
        context: &GpuContext,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let (width, height, _, _) = self.key;
        let color = self.outputs.read(context, 0)?;
        frame.resize_for_overwrite(width, height);
        for (out, c) in frame.color.iter_mut().zip(&color) {
            *out = Vec3::new(c[0], c[1], c[2]);
        }
        if outputs == FrameOutputs::Color {
            return Ok(());
        }
        let counts = self.outputs.read(context, 1)?;
        let flags = self.outputs.read(context, 2)?;
        let pixels: Vec<DistancePixel> = counts
            .into_iter()
            .zip(flags)
            .map(|(counts, flags)| DistancePixel { counts, flags })
            .collect();
        frame.write_row_layers(MethodId::DistanceMap, &pixels)?;
        Ok(())
    }
}

/// One pixel of the path outputs: counts (hit layer, linear steps, secant steps, bounces) and
/// flags (covered, miss, TIR), as the shader stores them.
struct DistancePixel {
    counts: [f32; 4],
    flags: [f32; 4],
}

impl PixelLayers for DistancePixel {
    fn value(&self, aov: Aov) -> Option<LayerValue> {
        let count = |k: usize| LayerValue::Count(self.counts[k].round() as u32);
        let flag = |k: usize| LayerValue::Flag(self.flags[k] > 0.5);
        Some(match aov {
            Aov::Covered => flag(0),
            Aov::Miss => flag(1),
            Aov::Tir => flag(2),
            Aov::HitLayer => count(0),
            Aov::LinearSteps => count(1),
            Aov::SecantSteps => count(2),
            Aov::Bounces => count(3),
            _ => return None,
        })
    }
}
