//! Refraction through any number of interfaces on the GPU (method `depth-peel`): the opaque
//! objects' surface pass from the eye (the engine family's screen texture), every refractor's
//! surfaces depth-peeled into `K` slices of three texture arrays (raster.wgsl's
//! `fs_surface` for layer 0, both orientations, then `fs_surface_peel` against the previous
//! slice with the eye as the reference point and the distance maps' margin: the CPU backend's
//! rule), then `shade_depth_peel` of `depth_peel_shade.wgsl` over `depth_peel.wgsl`, the twin
//! of [`refract_core::depth_peel`].

use glam::Vec3;
use refract_core::TirPolicy;
use refract_core::depth_peel::{PeelMedium, PeelUniforms};
use refract_core::gpu::FrameUniforms;
use refract_scene::{
    Aov, DepthPeelParams, Frame, FrameOutputs, LayerValue, MAX_REFRACTORS, MethodId, PixelLayers,
    RenderError,
};

use crate::bindings::{array_entry, bind_group, storage_entry, texture_entry, uniform_entry};
use crate::context::{GpuContext, GpuError};
use crate::family::{GpuFamily, GpuFrameCx};
use crate::frame_uniforms::frame_uniforms;
use crate::passes::object_surfaces::{NearbyFrame, nearby_uniforms};
use crate::passes::outputs::{OutputBuffers, check_limits};
use crate::passes::pipelines::MethodPipelines;
use crate::passes::raster::{
    DEPTH_FORMAT, PEEL_MARGIN, PeelUniforms as RasterPeel, RasterKind, RasterPass, RasterPipelines,
    SurfaceTargets, TARGET_FORMAT, target,
};
use crate::shaders::{
    CORE, ENVIRONMENT, FRAME, MATERIALS, OBJECT_SURFACES, OBJECT_TEXTURE, PROCEDURAL_SKY,
    ShaderModule, WgslFile,
};

/// The twin of `refract_core::depth_peel` over layer readers its includer provides.
pub(crate) const DEPTH_PEEL: WgslFile = ("depth_peel.wgsl", include_str!("depth_peel.wgsl"));

/// The family's modules: its pass and its conformance module.
pub(crate) const SHADERS: &[ShaderModule] = &[SHADER, CONFORMANCE];

/// The module of `depth-peel`: the environment, the objects' screen texture, the path, the
/// pass.
pub(crate) const SHADER: ShaderModule = ShaderModule {
    name: "depth-peel",
    files: &[
        CORE,
        PROCEDURAL_SKY,
        FRAME,
        ENVIRONMENT,
        MATERIALS,
        OBJECT_SURFACES,
        OBJECT_TEXTURE,
        DEPTH_PEEL,
        (
            "depth_peel_shade.wgsl",
            include_str!("depth_peel_shade.wgsl"),
        ),
    ],
};

/// The conformance module (`depth_peel_conformance.wgsl`): the path over analytic layers (two
/// glass spheres and a wall), run by `crate::conformance::evaluate_family`.
pub(crate) const CONFORMANCE: ShaderModule = ShaderModule {
    name: "depth-peel-conformance",
    files: &[
        CORE,
        FRAME,
        DEPTH_PEEL,
        (
            "depth_peel_conformance.wgsl",
            include_str!("depth_peel_conformance.wgsl"),
        ),
    ],
};

/// The `shade_depth_peel` pipelines.
pub(crate) struct DepthPeelPipelines(MethodPipelines);

impl GpuFamily for DepthPeelPipelines {
    type Params = DepthPeelParams;
    type Targets = DepthPeelTargets;
    const LABEL: &'static str = "depth-peel frame";

    fn create(device: &wgpu::Device, _raster: &RasterPipelines) -> Self {
        let entries = vec![
            uniform_entry(0, wgpu::ShaderStages::COMPUTE),
            array_entry(1),
            array_entry(2),
            array_entry(3),
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
            uniform_entry(16, wgpu::ShaderStages::COMPUTE),
            uniform_entry(17, wgpu::ShaderStages::COMPUTE),
        ];
        Self(MethodPipelines::new(
            device,
            &SHADER,
            &entries,
            |_: &DepthPeelParams| ("shade_depth_peel", Vec::new()),
        ))
    }

    fn fits(&self, targets: &DepthPeelTargets, cx: &GpuFrameCx<'_>, p: &DepthPeelParams) -> bool {
        targets.key == (cx.size(), p.layers)
    }

    fn allocate(
        &self,
        cx: &GpuFrameCx<'_>,
        p: &DepthPeelParams,
    ) -> Result<DepthPeelTargets, GpuError> {
        DepthPeelTargets::new(cx, self, p.layers)
    }

    fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        params: &DepthPeelParams,
        targets: &mut DepthPeelTargets,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), RenderError> {
        targets.encode(cx, self, params, encoder);
        Ok(())
    }

    fn color<'t>(&self, targets: &'t Self::Targets) -> &'t wgpu::Buffer {
        &targets.outputs.outputs[0]
    }

    fn read(
        &self,
        cx: &GpuFrameCx<'_>,
        targets: &DepthPeelTargets,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        targets.read(cx.context, cx.method, cx.outputs, frame)
    }
}

/// The targets of `depth-peel` frames at one resolution and layer count.
pub(crate) struct DepthPeelTargets {
    key: ((u32, u32), u32),
    frame_uniforms: wgpu::Buffer,
    raster_group: wgpu::BindGroup,
    /// Layer `k`'s P, (N, covered), (uv, refractor, covered) render views.
    slices: Vec<[wgpu::TextureView; 3]>,
    depth: wgpu::TextureView,
    raster_peel: wgpu::Buffer,
    /// Group 1 of layer `k + 1`'s peel pass: layer `k`'s P and N.
    peel_groups: Vec<wgpu::BindGroup>,
    screen: SurfaceTargets,
    nearby_uniforms: wgpu::Buffer,
    peel_uniforms: wgpu::Buffer,
    media: wgpu::Buffer,
    group: wgpu::BindGroup,
    /// Colour, T2 and P2 (w: the path has a second interaction), flags (off screen, lost, TIR,
    /// interfaces), P_geom (w: hit), the last direction (w: the refractors met, as bits).
    outputs: OutputBuffers,
}

impl DepthPeelTargets {
    fn new(
        cx: &GpuFrameCx<'_>,
        pipelines: &DepthPeelPipelines,
        layers: u32,
    ) -> Result<Self, GpuError> {
        let (width, height) = cx.size();
        let context = cx.context;
        check_limits(context, width, height)?;
        let device = &context.device;
        let raster = cx.raster;
        let scene = cx.gpu_scene;
        context.checked(|| {
            let uniform = |label, size: usize| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: size as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            };
            let frame_uniforms = uniform("frame uniforms", std::mem::size_of::<FrameUniforms>());
            let raster_group = bind_group(
                device,
                "raster",
                &raster.layout,
                &[frame_uniforms.as_entire_binding()],
            );
            let arrays = ["peeled P", "peeled N", "peeled uv, refractor"].map(|label| {
                device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width,
                        height,
                        depth_or_array_layers: layers,
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
            let slices: Vec<[wgpu::TextureView; 3]> = (0..layers)
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
            let depth = target(device, "peel depth", width, height, DEPTH_FORMAT)
                .create_view(&wgpu::TextureViewDescriptor::default());
            let raster_peel = uniform("peel raster uniforms", std::mem::size_of::<RasterPeel>());
            let peel_groups = slices
                .iter()
                .take(layers.saturating_sub(1) as usize)
                .map(|previous| {
                    bind_group(
                        device,
                        "peel",
                        &raster.peel_layout,
                        &[
                            wgpu::BindingResource::TextureView(&previous[0]),
                            wgpu::BindingResource::TextureView(&previous[1]),
                            raster_peel.as_entire_binding(),
                        ],
                    )
                })
                .collect();
            let screen = SurfaceTargets::new(device, raster, "screen", width, height);
            let nearby_uniforms = uniform(
                "screen uniforms",
                std::mem::size_of::<refract_core::gpu::NearbyUniforms>(),
            );
            let peel_uniforms = uniform("depth-peel uniforms", std::mem::size_of::<PeelUniforms>());
            let media = uniform(
                "depth-peel media",
                std::mem::size_of::<[PeelMedium; MAX_REFRACTORS]>(),
            );
            let outputs = OutputBuffers::new(
                device,
                &[
                    "colour",
                    "T2",
                    "P2",
                    "flags",
                    "P_geom",
                    "Tout, refractors met",
                ],
                u64::from(width) * u64::from(height),
            );
            let mut resources = vec![
                frame_uniforms.as_entire_binding(),
                wgpu::BindingResource::TextureView(&array_views[0]),
                wgpu::BindingResource::TextureView(&array_views[1]),
                wgpu::BindingResource::TextureView(&array_views[2]),
                scene.environment_texels.as_entire_binding(),
            ];
            resources.extend(outputs.outputs.iter().map(|o| o.as_entire_binding()));
            resources.push(scene.materials.as_entire_binding());
            resources.extend(screen.views.iter().map(wgpu::BindingResource::TextureView));
            resources.push(nearby_uniforms.as_entire_binding());
            resources.push(peel_uniforms.as_entire_binding());
            resources.push(media.as_entire_binding());
            let group = bind_group(device, "depth-peel", &pipelines.0.layout, &resources);
            Self {
                key: ((width, height), layers),
                frame_uniforms,
                raster_group,
                slices,
                depth,
                raster_peel,
                peel_groups,
                screen,
                nearby_uniforms,
                peel_uniforms,
                media,
                group,
                outputs,
            }
        })
    }

    /// Encodes one frame: the screen texture, the peeled layers, the per-pixel paths, the
    /// copies of the outputs.
    fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        pipelines: &DepthPeelPipelines,
        params: &DepthPeelParams,
        encoder: &mut wgpu::CommandEncoder,
    ) {
        let GpuFrameCx {
            context,
            raster,
            scene,
            gpu_scene,
            camera,
            method,
            outputs,
            timestamps,
            ..
        } = *cx;
        let queue = &context.queue;
        let uniforms = frame_uniforms(
            camera,
            &gpu_scene.environment,
            cx.ior(&scene.refractor),
            TirPolicy::default(),
        );
        queue.write_buffer(&self.frame_uniforms, 0, bytemuck::bytes_of(&uniforms));
        let settings = params.settings(scene);
        queue.write_buffer(
            &self.peel_uniforms,
            0,
            bytemuck::bytes_of(&PeelUniforms::from(&settings)),
        );
        let mut media = [PeelMedium::default(); MAX_REFRACTORS];
        for (slot, medium) in media.iter_mut().zip(params.media(scene, cx.lambda_nm)) {
            *slot = medium;
        }
        queue.write_buffer(&self.media, 0, bytemuck::cast_slice(&media));
        queue.write_buffer(
            &self.raster_peel,
            0,
            bytemuck::bytes_of(&RasterPeel {
                center: camera.eye().extend(1.0).to_array(),
                margin: PEEL_MARGIN,
                _padding: [0.0; 3],
            }),
        );
        queue.write_buffer(
            &self.nearby_uniforms,
            0,
            bytemuck::bytes_of(&nearby_uniforms(&NearbyFrame::eye(camera, scene.light))),
        );
        let refractors: Vec<_> = std::iter::once(&gpu_scene.refractor)
            .chain(&gpu_scene.other_refractors)
            .collect();
        // The peeled layers and the objects' surfaces do not depend on the index: kept for the
        // other wavelengths of a dispersive frame (the kernel's uniforms are rewritten).
        if cx.repeat {
            if !scene.objects.is_empty() {
                queue.write_buffer(self.screen.uniforms(), 0, bytemuck::bytes_of(&uniforms));
            }
        } else {
            for (k, slice) in self.slices.iter().enumerate() {
                let (kind, peel) = match k {
                    0 => (RasterKind::SurfaceBoth, None),
                    _ => (RasterKind::SurfacePeel, Some(&self.peel_groups[k - 1])),
                };
                raster.encode(
                    encoder,
                    &RasterPass {
                        kind,
                        camera,
                        uniforms: &self.raster_group,
                        peel,
                        meshes: &refractors,
                        targets: &[&slice[0], &slice[1], &slice[2]],
                        depth: &self.depth,
                    },
                    timestamps.and_then(|t| t.render_pass("peeled layers")),
                );
            }
            if !scene.objects.is_empty() {
                let objects: Vec<_> = gpu_scene.objects.iter().collect();
                self.screen.encode(
                    queue,
                    raster,
                    encoder,
                    camera,
                    &uniforms,
                    &objects,
                    timestamps.and_then(|t| t.render_pass("object surfaces")),
                );
            }
        }
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("depth-peel kernel"),
                timestamp_writes: timestamps.and_then(|t| t.compute_pass("depth-peel kernel")),
            });
            pass.set_pipeline(pipelines.0.get(method, outputs));
            pass.set_bind_group(0, &self.group, &[]);
            let ((width, height), _) = self.key;
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
    fn read(
        &self,
        context: &GpuContext,
        method: MethodId,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let ((width, height), _) = self.key;
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
        let pixels: Vec<PeelPixel> = (0..frame.pixel_count())
            .map(|i| PeelPixel {
                covered: color[i][3].round() as u32 == refract_core::gpu::COVERAGE_PATH,
                t2: planes[0][i],
                p2: planes[1][i],
                flags: planes[2][i],
                p_geom: planes[3][i],
                t_out: planes[4][i],
            })
            .collect();
        frame.write_row_layers(method, &pixels)?;
        Ok(())
    }
}

/// One pixel of the outputs as the shader stores them.
struct PeelPixel {
    covered: bool,
    t2: [f32; 4],
    p2: [f32; 4],
    flags: [f32; 4],
    p_geom: [f32; 4],
    /// The last direction; `w`: the refractors met, as bits.
    t_out: [f32; 4],
}

impl PixelLayers for PeelPixel {
    fn value(&self, aov: Aov) -> Option<LayerValue> {
        let xyz = |v: [f32; 4], valid: bool| {
            LayerValue::Vec3(if valid {
                Vec3::new(v[0], v[1], v[2])
            } else {
                Vec3::NAN
            })
        };
        let c = self.covered;
        Some(match aov {
            Aov::Covered => LayerValue::Flag(c),
            Aov::T2 => xyz(self.t2, c && self.t2[3] > 0.5),
            Aov::P2 => xyz(self.p2, c && self.p2[3] > 0.5),
            Aov::TOut => xyz(self.t_out, c),
            Aov::PGeom => xyz(self.p_geom, c && self.p_geom[3] > 0.5),
            Aov::OffScreen => LayerValue::Flag(c && self.flags[0] > 0.5),
            Aov::Miss => LayerValue::Flag(c && self.flags[1] > 0.5),
            Aov::Tir => LayerValue::Flag(c && self.flags[2] > 0.5),
            Aov::Interfaces => LayerValue::Count(if c { self.flags[3] as u32 } else { 0 }),
            Aov::RefractorsMet => LayerValue::Count(if c { self.t_out[3].to_bits() } else { 0 }),
            _ => return None,
        })
    }
}
