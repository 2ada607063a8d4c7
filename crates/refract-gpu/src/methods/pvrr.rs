//! Kakimoto et al. 2007 on the GPU, method `pvrr`: the plan of the frame comes from
//! [`refract_scene::pvrr`] (per-vertex rays traced with the CPU BVH, as the paper does), then
//! every view is rendered on the GPU, deepest first, in one command buffer: a surface pass of
//! the diffuse objects (`fs_surface`) and of the view's reflectors with their vertices' map
//! positions as a second vertex buffer (`shaders/pvrr_raster.wgsl`), then `pvrr.wgsl` (beside this module)
//! shades the view into its map (one storage buffer holds every map of the frame) or, for the
//! eye, into the frame. The twin of `refract_cpu::pvrr`.

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use refract_core::TirPolicy;
use refract_core::pvrr::PvrrVertex;
use refract_scene::pvrr::{PvrrPlan, PvrrPlanner, ReflectorKind};
use refract_scene::{
    Aov, Frame, FrameOutputs, LayerValue, MethodId, PixelLayers, PvrrParams, RenderError, Scene,
    SceneMesh,
};

use crate::bindings::{bind_group, storage_entry, texture_entry, uniform_entry};
use crate::context::{GpuContext, GpuError};
use crate::family::{GpuFamily, GpuFrameCx};
use crate::frame_uniforms::frame_uniforms;
use crate::passes::outputs::{OutputBuffers, check_limits};
use crate::passes::pipelines::MethodPipelines;
use crate::passes::raster::{DEPTH_FORMAT, RasterPipelines, TARGET_FORMAT, target};
use crate::scene_buffers::{GpuMesh, GpuScene, Vertex};
use crate::shaders::{CORE, ENVIRONMENT, FRAME, MATERIALS, PROCEDURAL_SKY, ShaderModule};
use refract_core::gpu::FrameUniforms;

/// The family's modules (its conformance is in the shared harness).
pub(crate) const SHADERS: &[ShaderModule] = &[SHADER];

/// The module of the shading of `pvrr`'s views (Kakimoto et al. 2007).
pub(crate) const SHADER: ShaderModule = ShaderModule {
    name: "pvrr",
    files: &[
        CORE,
        PROCEDURAL_SKY,
        FRAME,
        ENVIRONMENT,
        MATERIALS,
        ("pvrr.wgsl", include_str!("pvrr.wgsl")),
    ],
};

/// `PvrrDraw` of `pvrr.wgsl` (beside this module): one reflector drawn in one view.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct GpuPvrrDraw {
    /// `F0` and the kind: 0 mirror, 1 lens.
    f0_kind: [f32; 4],
    map_offset: u32,
    map_width: u32,
    map_height: u32,
    has_map: u32,
}

const _: () = assert!(core::mem::size_of::<GpuPvrrDraw>() == 32);

/// `PvrrView` of `pvrr.wgsl` (beside this module).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct PvrrViewUniforms {
    light_direction: [f32; 4],
    light_radiance: [f32; 4],
    light_ambient: [f32; 4],
    out_offset: u32,
    is_eye: u32,
    _padding: [u32; 2],
}

const _: () = assert!(core::mem::size_of::<PvrrViewUniforms>() == 64);

/// The raster pipelines of the views (no culling: mirrors are two-sided, as on the CPU) and the
/// shading pipelines.
pub(crate) struct PvrrPipelines {
    methods: MethodPipelines,
    surface: wgpu::RenderPipeline,
    reflector: wgpu::RenderPipeline,
}

impl PvrrPipelines {
    pub(crate) fn new(device: &wgpu::Device, raster: &RasterPipelines) -> Self {
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
                storage_entry(7, true),
                storage_entry(8, false),
                storage_entry(9, true),
                uniform_entry(10, wgpu::ShaderStages::COMPUTE),
            ],
            |_: &PvrrParams| ("shade_pvrr", Vec::new()),
        );
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("raster.wgsl (pvrr)"),
            source: wgpu::ShaderSource::Wgsl(crate::shaders::RASTER_MODULE.source().into()),
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("pvrr raster"),
            bind_group_layouts: &[Some(&raster.layout)],
            immediate_size: 0,
        });
        let vertex_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<Vertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &Vertex::ATTRIBUTES,
        };
        const PVRR_ATTRIBUTES: [wgpu::VertexAttribute; 2] =
            wgpu::vertex_attr_array![5 => Float32x4, 6 => Float32x4];
        let pvrr_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<PvrrVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &PVRR_ATTRIBUTES,
        };
        let targets = vec![
            Some(wgpu::ColorTargetState {
                format: TARGET_FORMAT,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            });
            3
        ];
        let pipeline = |label, vs, fs, buffers: &[Option<wgpu::VertexBufferLayout<'_>>]| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let surface = pipeline(
            "pvrr diffuse surfaces",
            "vs_mesh",
            "fs_surface",
            &[Some(vertex_layout.clone())],
        );
        let reflector = pipeline(
            "pvrr reflectors",
            "vs_pvrr",
            "fs_pvrr",
            &[Some(vertex_layout), Some(pvrr_layout)],
        );
        Self {
            methods,
            surface,
            reflector,
        }
    }
}

/// Surface targets of one size: (P or R/B map positions), (N, 1), (uv + object or G map
/// position + draw + state), and depth.
struct ViewTargets {
    size: (u32, u32),
    views: [wgpu::TextureView; 3],
    depth: wgpu::TextureView,
}

impl ViewTargets {
    fn new(device: &wgpu::Device, label: &str, (width, height): (u32, u32)) -> Self {
        let view = |t: wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        Self {
            size: (width, height),
            views: ["a", "N", "b"].map(|what| {
                view(target(
                    device,
                    &format!("{label} {what}"),
                    width,
                    height,
                    TARGET_FORMAT,
                ))
            }),
            depth: view(target(
                device,
                &format!("{label} depth"),
                width,
                height,
                DEPTH_FORMAT,
            )),
        }
    }
}

/// Per-view uniforms and bind groups (one set per view of a frame, kept between frames).
struct ViewBindings {
    frame: wgpu::Buffer,
    view: wgpu::Buffer,
    raster: wgpu::BindGroup,
    /// The shading group with the eye's targets, and with the maps' targets.
    shade_eye: wgpu::BindGroup,
    shade_map: wgpu::BindGroup,
}

/// A storage or vertex buffer that grows to what a frame needs.
fn buffer(
    device: &wgpu::Device,
    label: &str,
    bytes: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(256).next_multiple_of(256),
        usage: usage | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The targets and buffers of `pvrr` frames at one frame size and map resolution.
pub(crate) struct PvrrTargets {
    key: (u32, u32, u32),
    eye: ViewTargets,
    map: ViewTargets,
    maps: wgpu::Buffer,
    draws: wgpu::Buffer,
    vertices: wgpu::Buffer,
    bindings: Vec<ViewBindings>,
    /// Colour; (covered, zoom, 0, 0).
    outputs: OutputBuffers,
}

/// The `pvrr` family: its pipelines and the per-vertex plan (kept between frames:
/// `update=on-change`), made on the CPU as part of each frame.
pub(crate) struct PvrrFamily {
    pipelines: PvrrPipelines,
    planner: PvrrPlanner,
}

impl PvrrFamily {
    pub(crate) fn new(device: &wgpu::Device, raster: &RasterPipelines) -> Self {
        Self {
            pipelines: PvrrPipelines::new(device, raster),
            planner: PvrrPlanner::default(),
        }
    }
}

impl GpuFamily for PvrrFamily {
    type Params = PvrrParams;
    type Targets = PvrrTargets;
    const LABEL: &'static str = "pvrr frame";

    fn create(device: &wgpu::Device, raster: &RasterPipelines) -> Self {
        Self::new(device, raster)
    }

    fn prepare(&mut self, scene: &Arc<Scene>) {
        self.planner.prepare(scene);
    }

    fn fits(&self, targets: &PvrrTargets, cx: &GpuFrameCx<'_>, params: &PvrrParams) -> bool {
        targets.fits(cx.size(), params)
    }

    fn allocate(&self, cx: &GpuFrameCx<'_>, params: &PvrrParams) -> Result<PvrrTargets, GpuError> {
        PvrrTargets::new(cx.context, cx.size(), params)
    }

    fn plan(&mut self, cx: &GpuFrameCx<'_>, params: &PvrrParams) -> Result<(), RenderError> {
        self.planner
            .plan_at(cx.scene, cx.camera, params, cx.lambda_nm)?;
        Ok(())
    }

    fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        _: &PvrrParams,
        targets: &mut PvrrTargets,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), RenderError> {
        Ok(targets.encode(cx, &self.pipelines, self.planner.last(), encoder)?)
    }

    fn color<'t>(&self, targets: &'t Self::Targets) -> &'t wgpu::Buffer {
        &targets.outputs.outputs[0]
    }

    fn read(
        &self,
        cx: &GpuFrameCx<'_>,
        targets: &PvrrTargets,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        targets.read(cx.context, cx.outputs, frame)
    }
}

impl PvrrTargets {
    pub(crate) fn new(
        context: &GpuContext,
        (width, height): (u32, u32),
        params: &PvrrParams,
    ) -> Result<Self, GpuError> {
        check_limits(context, width, height)?;
        let res = params.resolution;
        check_limits(context, res, res)?;
        let device = &context.device;
        context.checked(|| Self {
            key: (width, height, res),
            eye: ViewTargets::new(device, "pvrr eye", (width, height)),
            map: ViewTargets::new(device, "pvrr map", (res, res)),
            maps: buffer(device, "pvrr maps", 16, wgpu::BufferUsages::STORAGE),
            draws: buffer(device, "pvrr draws", 32, wgpu::BufferUsages::STORAGE),
            vertices: buffer(device, "pvrr vertices", 32, wgpu::BufferUsages::VERTEX),
            bindings: Vec::new(),
            outputs: OutputBuffers::new(
                device,
                &["colour", "flags"],
                u64::from(width) * u64::from(height),
            ),
        })
    }

    /// Whether these targets fit a frame of `size` with `params`.
    pub(crate) fn fits(&self, (width, height): (u32, u32), params: &PvrrParams) -> bool {
        self.key == (width, height, params.resolution)
    }

    /// Grows the storage buffers to the frame's maps, draws and vertices (dropping the bind
    /// groups that referenced the old ones) and makes one set of bindings per view.
    fn reserve(
        &mut self,
        context: &GpuContext,
        pipelines: &PvrrPipelines,
        raster: &RasterPipelines,
        scene: &GpuScene,
        (texels, draws, vertices, views): (u64, u64, u64, usize),
    ) -> Result<(), GpuError> {
        let device = &context.device;
        let limits = device.limits();
        let map_bytes = texels * 16;
        if map_bytes > limits.max_storage_buffer_binding_size || map_bytes > limits.max_buffer_size
        {
            return Err(GpuError::Wgpu(format!(
                "pvrr: the frame's maps need {map_bytes} bytes; the adapter binds at most {} (lower res or depth)",
                limits.max_storage_buffer_binding_size
            )));
        }
        let mut grown = false;
        if self.maps.size() < map_bytes {
            self.maps = buffer(device, "pvrr maps", map_bytes, wgpu::BufferUsages::STORAGE);
            grown = true;
        }
        if self.draws.size() < draws * 32 {
            self.draws = buffer(
                device,
                "pvrr draws",
                draws * 32,
                wgpu::BufferUsages::STORAGE,
            );
            grown = true;
        }
        if self.vertices.size() < vertices * 32 {
            self.vertices = buffer(
                device,
                "pvrr vertices",
                vertices * 32,
                wgpu::BufferUsages::VERTEX,
            );
        }
        if grown {
            self.bindings.clear();
        }
        while self.bindings.len() < views {
            let frame = buffer(
                device,
                "pvrr view frame uniforms",
                std::mem::size_of::<FrameUniforms>() as u64,
                wgpu::BufferUsages::UNIFORM,
            );
            let view = buffer(
                device,
                "pvrr view uniforms",
                std::mem::size_of::<PvrrViewUniforms>() as u64,
                wgpu::BufferUsages::UNIFORM,
            );
            let raster_group = bind_group(
                device,
                "pvrr raster",
                &raster.layout,
                &[frame.as_entire_binding()],
            );
            let shade = |targets: &ViewTargets| {
                bind_group(
                    device,
                    "pvrr shade",
                    &pipelines.methods.layout,
                    &[
                        frame.as_entire_binding(),
                        wgpu::BindingResource::TextureView(&targets.views[0]),
                        wgpu::BindingResource::TextureView(&targets.views[1]),
                        wgpu::BindingResource::TextureView(&targets.views[2]),
                        scene.environment_texels.as_entire_binding(),
                        self.outputs.outputs[0].as_entire_binding(),
                        self.outputs.outputs[1].as_entire_binding(),
                        scene.materials.as_entire_binding(),
                        self.maps.as_entire_binding(),
                        self.draws.as_entire_binding(),
                        view.as_entire_binding(),
                    ],
                )
            };
            let (shade_eye, shade_map) = (shade(&self.eye), shade(&self.map));
            self.bindings.push(ViewBindings {
                frame,
                view,
                raster: raster_group,
                shade_eye,
                shade_map,
            });
        }
        Ok(())
    }

    /// Encodes the frame of `plan` (every view, deepest first).
    fn encode(
        &mut self,
        cx: &GpuFrameCx<'_>,
        pipelines: &PvrrPipelines,
        plan: &PvrrPlan,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        let GpuFrameCx {
            context,
            raster,
            gpu_scene,
            scene,
            outputs,
            timestamps,
            ..
        } = *cx;
        // Where each view's map lives in `maps`, each draw in `draws` and its vertices.
        let mut map_offsets = vec![0u32; plan.views.len()];
        let mut texels = 0u64;
        for (v, view) in plan.views.iter().enumerate().skip(1) {
            map_offsets[v] = texels as u32;
            texels += u64::from(view.camera.width()) * u64::from(view.camera.height());
        }
        let mut draws = Vec::new();
        let mut vertices: Vec<PvrrVertex> = Vec::new();
        let mut vertex_offsets = Vec::new();
        // The global index of each view's first draw (the draws' instance indices).
        let mut first_draw = Vec::with_capacity(plan.views.len());
        for view in &plan.views {
            first_draw.push(draws.len() as u32);
            for draw in &view.draws {
                let (f0, kind) = match plan.reflectors[draw.reflector].kind {
                    ReflectorKind::Mirror { f0 } => (f0, 0.0),
                    ReflectorKind::Lens { .. } => (Vec3::ONE, 1.0),
                };
                let map = draw.map.map(|m| &plan.views[m]);
                draws.push(GpuPvrrDraw {
                    f0_kind: f0.extend(kind).to_array(),
                    map_offset: draw.map.map_or(0, |m| map_offsets[m]),
                    map_width: map.map_or(1, |m| m.camera.width()),
                    map_height: map.map_or(1, |m| m.camera.height()),
                    has_map: u32::from(map.is_some()),
                });
                vertex_offsets.push(vertices.len() as u64 * 32);
                vertices.extend_from_slice(&draw.vertices);
            }
        }
        self.reserve(
            context,
            pipelines,
            raster,
            gpu_scene,
            (
                texels,
                draws.len() as u64,
                vertices.len() as u64,
                plan.views.len(),
            ),
        )?;
        let queue = &context.queue;
        queue.write_buffer(&self.draws, 0, bytemuck::cast_slice(&draws));
        queue.write_buffer(&self.vertices, 0, bytemuck::cast_slice(&vertices));
        let light = &scene.light;
        for (v, view) in plan.views.iter().enumerate() {
            let b = &self.bindings[v];
            let u = frame_uniforms(
                &view.camera,
                &gpu_scene.environment,
                1.0,
                TirPolicy::default(),
            );
            queue.write_buffer(&b.frame, 0, bytemuck::bytes_of(&u));
            let uniforms = PvrrViewUniforms {
                light_direction: light.direction.extend(0.0).to_array(),
                light_radiance: light.radiance.extend(0.0).to_array(),
                light_ambient: light.ambient.extend(0.0).to_array(),
                out_offset: map_offsets[v],
                is_eye: u32::from(v == 0),
                _padding: [0; 2],
            };
            queue.write_buffer(&b.view, 0, bytemuck::bytes_of(&uniforms));
        }
        let diffuse: Vec<&GpuMesh> = scene
            .objects
            .iter()
            .zip(&gpu_scene.objects)
            .filter(|(o, _)| o.conductor().is_none())
            .map(|(_, m)| m)
            .collect();
        let mesh_of = |mesh: SceneMesh| match mesh {
            SceneMesh::Refractor => &gpu_scene.refractor,
            SceneMesh::Object(k) => &gpu_scene.objects[k],
        };
        for (v, view) in plan.views.iter().enumerate().rev() {
            let targets = if v == 0 { &self.eye } else { &self.map };
            let (width, height) = (view.camera.width(), view.camera.height());
            debug_assert!(width <= targets.size.0 && height <= targets.size.1);
            let b = &self.bindings[v];
            {
                let clear = |view| {
                    Some(wgpu::RenderPassColorAttachment {
                        view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    })
                };
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("pvrr view"),
                    color_attachments: &[
                        clear(&targets.views[0]),
                        clear(&targets.views[1]),
                        clear(&targets.views[2]),
                    ],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &targets.depth,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Discard,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: timestamps.and_then(|t| {
                        t.render_pass(if v == 0 {
                            "eye view"
                        } else {
                            "reflector views"
                        })
                    }),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_viewport(0.0, 0.0, width as f32, height as f32, 0.0, 1.0);
                pass.set_scissor_rect(0, 0, width, height);
                pass.set_bind_group(0, &b.raster, &[]);
                pass.set_pipeline(&pipelines.surface);
                for mesh in &diffuse {
                    mesh.draw(&mut pass);
                }
                pass.set_pipeline(&pipelines.reflector);
                for (k, draw) in view.draws.iter().enumerate() {
                    let global = first_draw[v] + k as u32;
                    let mesh = mesh_of(plan.reflectors[draw.reflector].mesh);
                    let offset = vertex_offsets[global as usize];
                    let bytes = draw.vertices.len() as u64 * 32;
                    pass.set_vertex_buffer(0, mesh.vertices.slice(..));
                    pass.set_vertex_buffer(1, self.vertices.slice(offset..offset + bytes));
                    pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..mesh.index_count, 0, global..global + 1);
                }
            }
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("pvrr shade"),
                timestamp_writes: timestamps.and_then(|t| {
                    t.compute_pass(if v == 0 {
                        "eye shading"
                    } else {
                        "view shading"
                    })
                }),
            });
            pass.set_pipeline(pipelines.methods.get(MethodId::Pvrr, outputs));
            pass.set_bind_group(0, if v == 0 { &b.shade_eye } else { &b.shade_map }, &[]);
            pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
        }
        if let Some(timestamps) = timestamps {
            timestamps.resolve(encoder);
        }
        let copies = match outputs {
            FrameOutputs::ColorAndAovs => 2,
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
        let (width, height, _) = self.key;
        let color = self.outputs.read(context, 0)?;
        frame.resize_for_overwrite(width, height);
        for (out, c) in frame.color.iter_mut().zip(&color) {
            *out = Vec3::new(c[0], c[1], c[2]);
        }
        if outputs == FrameOutputs::Color {
            return Ok(());
        }
        let flags = self.outputs.read(context, 1)?;
        let pixels: Vec<PvrrPixel> = flags.into_iter().map(PvrrPixel).collect();
        frame.write_row_layers(MethodId::Pvrr, &pixels)?;
        Ok(())
    }
}

/// One pixel's flags as the shader stores them: covered, zoom.
struct PvrrPixel([f32; 4]);

impl PixelLayers for PvrrPixel {
    fn value(&self, aov: Aov) -> Option<LayerValue> {
        match aov {
            Aov::Covered => Some(LayerValue::Flag(self.0[0] > 0.5)),
            Aov::Zoom => Some(LayerValue::Flag(self.0[1] > 0.5)),
            _ => None,
        }
    }
}
